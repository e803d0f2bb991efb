"""The HNN seed's three-body task (Greydanus et al. 2019, Appendix B): claim 14's experiment,
its verdict rule, its table beside the seed's numbers and a figure.

The seed's baseline and HNN are trained on time-derivative targets in canonical coordinates and
scored by the energy MSE of their rollouts, as on its two-body task. The seed's protocol, ours
and the budgets: docs/studies/three_body.md.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from ....core import Experiment, RunConfig, Study, register_study
from ....kit import (
    bad_rows,
    fmt,
    gated,
    gmean,
    greater,
    learned_cell,
    paired,
    per_system_discrimination,
    policy,
    save_figure,
    subplots,
    verdict,
)
from ..._claims import CLAIM_TITLES
from ..tasks import rollout_any, seed_rows

SYSTEM = "three_body"
# (model, coordinates): the seed's two models on (q, p) and the trivial predictor on (q, qdot)
CELLS = (("node", "momentum"), ("hnn", "momentum"), ("constant_velocity", "velocity"))
BASELINE = {"model": "node", "coordinates": "momentum"}
HNN = {"model": "hnn", "coordinates": "momentum"}
TRIVIAL = {"model": "constant_velocity", "coordinates": "velocity"}

# The seed's own numbers (greydanus/hamiltonian-nn README, "Numbers", row "3 body problem":
# baseline NN, HNN), the means of its test loss on derivatives and of its energy MSE along
# rollouts (analyze-3body.ipynb: 15 draws, 500 points on [0, 3]).
SEED_NUMBERS = {
    "train_loss": (9.5573e-02, 8.0346e-02),
    "test_loss": (3.8000e-01, 4.8809e-01),
    "energy_mse": (1.0906e02, 4.1926e-02),
}

# The seed's experiment-3body/data.py and train.py: 5000 orbits of 20 points on [0, 5] (the
# first 20% of the states, i.e. of the orbits, for testing), no observation noise; MLPs of width
# 200, two hidden layers, tanh; Adam at lr 1e-3 with L2 weight decay 1e-4, 600 states a step,
# 10000 steps.
_PAPER = {
    "train_target": "derivative",
    "width": 200,
    "depth": 2,
    "activation": "tanh",
    "lr": 1e-3,
    "optimizer": "adam_l2",
    "lr_schedule": "constant",
    "weight_decay": 1e-4,
    "dt": 5.0 / 19,
    "chunk": 20,
    "duration": 5.0,
    "test_chunks": 1,
    "n_generated": 4000,
    "n_train": 4000,
    "n_test": 1000,
    "noise": 0.0,
    "batch": 30,  # 30 orbits x 20 points = the seed's 600 states a step
    "steps": 10000,
    "eval_integrator": "adaptive",  # the seed's notebook: solve_ivp's adaptive RK45
    "eval_checkpoints": 0,
    "dtype": "float32",
}
# quick: a quarter of the seed's orbits, a fifth of its steps
_QUICK = {"n_generated": 1000, "n_train": 1000, "n_test": 250, "steps": 2000}
_SMOKE = {"n_generated": 4, "n_train": 4, "n_test": 2, "steps": 20, "width": 16, "batch": 4}


def _include(c: RunConfig) -> bool:
    return (c.model, c.coordinates) in CELLS


EXPERIMENT = Experiment(
    name="hnn_seed_three_body",
    paper="hnn",
    title="HNN seed: three-body from states, derivative targets",
    axes={
        "model": tuple(dict.fromkeys(m for m, _ in CELLS)),
        "coordinates": ("momentum", "velocity"),
    },
    fixed={"system": SYSTEM, **_PAPER},
    profile_overrides={
        "smoke": {**_SMOKE, "seeds": (0,)},
        "quick": _QUICK,
        "paper-core": {},  # the seed's budget: part of the CPU campaign
    },
    include=_include,
    claim=14,
)
EXPERIMENTS = (EXPERIMENT,)


def claim_14(runs: pd.DataFrame, curves: pd.DataFrame | None = None):
    """Claim 14 (HNN seed, Appendix B): on the three-body problem "the HNN outperforms its
    baseline by a considerable margin" (Greydanus et al. 2019), with "a relative advantage to using
    the HNN over the baseline model. However, both models struggled" (line 136).

    One part, (a): a *greater* part on ``log(energy MSE baseline / energy MSE HNN)`` at the
    policy's energy margin squared (an MSE; the seed states no number), judged where the HNN
    learned (the fit gate: rollout error on (q, qdot) against the trivial predictor). Gates by
    role: the MLP baseline is the foil the seed says "struggled", so its failure is the claim's
    content and it is never gated. "Both
    struggle" is no comparison and is reported beside, not tested: each model's rollout error
    and the test losses. Failed runs score the worst value.
    """
    r = runs[runs["system"] == SYSTEM] if len(runs) and "system" in runs else runs.iloc[0:0]
    if len(r) and "train_target" in r:
        r = r[(r["train_target"] == "derivative") | (r["model"] == TRIVIAL["model"])]
    models = r[r["model"] != TRIVIAL["model"]] if len(r) else r
    if not len(models):
        return verdict(14, CLAIM_TITLES[14], [], None, 0, "log energy-MSE ratio MLP / HNN")
    r = r.assign(rollout_error_any=rollout_any(r))
    e = paired(r, BASELINE, HNN, "energy_mse")
    part = gated(
        greater(
            "(a) three_body: log(energy MSE MLP / HNN)",
            e.to_numpy(),
            policy.margin("energy", squared=True),
        ),
        learned_cell(r, HNN, "HNN on three_body", "rollout_error_any"),
    )
    n_failed = int(bad_rows(models, "energy_mse").sum())
    return verdict(
        14,
        CLAIM_TITLES[14],
        [part],
        part,
        len(e),
        "log energy-MSE ratio MLP / HNN (three-body)",
        "both struggle, not tested: " + _struggle(r),
        discs=per_system_discrimination(
            r.assign(rollout_error=r["rollout_error_any"]), "rollout_error"
        ),
        n_failed=n_failed,
    )


def _struggle(r: pd.DataFrame) -> str:
    """Geometric means of the rollout error (q, qdot) and test loss per model."""
    out = []
    for name, cell in (("MLP", BASELINE), ("HNN", HNN), ("trivial", TRIVIAL)):
        g = r[(r["model"] == cell["model"]) & (r["coordinates"] == cell["coordinates"])]
        text = f"{name} rollout error {fmt(gmean(g['rollout_error_any']))}"
        if name != "trivial" and "derivative_mse_test" in g:
            text += f", test loss {fmt(gmean(g['derivative_mse_test']))}"
        out.append(text)
    return "; ".join(out)


# ------------------------------------------------------------------------ table and figure
def _cell(rows: pd.DataFrame, cell: dict) -> pd.DataFrame:
    return rows[(rows["model"] == cell["model"]) & (rows["coordinates"] == cell["coordinates"])]


def section(results_dir) -> str:
    """The seed's Table 2 beside ours."""
    rows, profile = seed_rows(Path(results_dir), (EXPERIMENT,))
    lines = [
        "## HNN seed: three-body (claim 14)",
        "",
        "The HNN seed's Appendix B table (greydanus/hamiltonian-nn README, baseline MLP -> HNN) "
        f"beside ours (profile {profile or '-'}; geometric means over seeds, each a mean over "
        "the test states or rollouts). Losses: mean squared error of the learned dz/dt; energy "
        "MSE: (H(zhat) - H(z))^2 along rollouts from held-out states; rollout error on "
        "(q, qdot), the trivial predictor's beside. Protocol: docs/studies/three_body.md.",
        "",
        "| seeds | train loss MLP / HNN (seed) | train loss (ours) | test loss MLP / HNN (seed) "
        "| test loss (ours) | energy MSE MLP / HNN (seed) | energy MSE (ours) | rollout error "
        "MLP / HNN / trivial (ours) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    if not len(rows):
        return "\n".join([*lines, "| (no runs) | | | | | | | |"])
    rows = rows[~bad_rows(rows, "energy_mse") | (rows["model"] == TRIVIAL["model"])]
    mlp, hnn, triv = _cell(rows, BASELINE), _cell(rows, HNN), _cell(rows, TRIVIAL)

    def pair(col):
        return f"{fmt(gmean(mlp[col]))} / {fmt(gmean(hnn[col]))}"

    def seed(key):
        a, b = SEED_NUMBERS[key]
        return f"{fmt(a)} / {fmt(b)}"

    ro = " / ".join(fmt(gmean(g["rollout_error_any"])) for g in (mlp, hnn, triv))
    lines.append(
        f"| {rows['seed'].nunique()} | {seed('train_loss')} | {pair('derivative_mse_train')} | "
        f"{seed('test_loss')} | {pair('derivative_mse_test')} | {seed('energy_mse')} | "
        f"{pair('energy_mse')} | {ro} |"
    )
    return "\n".join(lines)


def figure(results_dir) -> list[Path]:
    """Test loss and energy MSE per model (geometric mean, min-max over seeds), the seed's
    numbers as black marks."""
    rows, _ = seed_rows(Path(results_dir), (EXPERIMENT,))
    rows = rows[~bad_rows(rows, "energy_mse")] if len(rows) else rows
    if not len(rows):
        return []
    fig, axes = subplots(1, 2, figsize=(7.0, 3.2))
    for ax, metric, key, label in (
        (axes[0], "derivative_mse_test", "test_loss", "test loss on dz/dt"),
        (axes[1], "energy_mse", "energy_mse", "energy MSE along rollouts"),
    ):
        for j, (name, cell) in enumerate((("MLP", BASELINE), ("HNN", HNN))):
            x = pd.to_numeric(_cell(rows, cell)[metric], errors="coerce").to_numpy(float)
            x = x[np.isfinite(x) & (x > 0)]
            if len(x):
                ax.bar(j, float(np.exp(np.mean(np.log(x)))), 0.6, color=f"C{j}", label=name)
                ax.vlines(j, x.min(), x.max(), color="k", lw=1)
            ax.plot(j, SEED_NUMBERS[key][j], "k_", ms=14, mew=2)
        ax.set_yscale("log")
        ax.set_xticks([0, 1], ["MLP", "HNN"])
        ax.set_ylabel(label)
    axes[0].plot([], [], "k_", ms=12, mew=2, label="seed's number")
    axes[0].legend(fontsize=7, loc="lower left")
    fig.suptitle("HNN seed, three-body: bars ours (geometric mean, min-max over seeds)", fontsize=9)
    return save_figure(fig, Path(results_dir) / "figures", "fig_three_body")


STUDY = register_study(
    Study(
        name="three_body",
        experiments=EXPERIMENTS,
        claim=14,
        title=CLAIM_TITLES[14],
        rule=claim_14,
        stem="fig_three_body",
        results_figure=figure,
        section=section,
        section_title="HNN seed: three-body (claim 14)",
    )
)
