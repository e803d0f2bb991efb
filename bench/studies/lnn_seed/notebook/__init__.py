"""The LNN seed's double pendulum as the seed ran it (Cranmer et al. 2020): the experiment,
claim 9's verdict rule, its table beside the seed's numbers, and a figure.

The pure LNN and a qddot-predicting baseline are trained on instantaneous accelerations at
random states of the unit double pendulum and scored by the energy error of their rollouts, as
a share of the potential's range. The seed's protocol, ours, and where they differ (the state
distribution, the network, the optimiser, the metric's scale): docs/studies/lnn_seed.md.

This module holds the report's table and figure and registers the study; the experiments and
the rule are in ``_experiments`` and ``_rule``.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from ....core import (
    Study,
    experiment_rows,
    load_runs,
    pick_profile,
    register_study,
)
from ....kit import (
    Protocol,
    bad_rows,
    by_seed_set,
    protocol_table,
    save_figure,
    subplots,
)
from ....kit import fmt as _f
from ....kit import gmean as _gm
from ..._claims import CLAIM_TITLES, UNIT_DOUBLE_PENDULUM
from . import _commands  # noqa: F401 - registers diagnose-lnn
from . import _diagnosis as diagnosis
from ._experiments import (
    EXPERIMENTS,
    LNN_SEED,
    LNN_SEED_NOTEBOOK,
    MEASURED,
    NOTEBOOK_BOX,
    NOTEBOOK_LR,
    NOTEBOOK_STEPS,
    SEED_NUMBERS,
    SEED_SCALE,
    notebook_lr,
)
from ._rule import _seed_rows, claim_9, reading

__all__ = [
    "EXPERIMENTS",
    "LNN_SEED",
    "LNN_SEED_NOTEBOOK",
    "MEASURED",
    "NOTEBOOK_BOX",
    "NOTEBOOK_LR",
    "STUDY",
    "UNIT_DOUBLE_PENDULUM",
    "claim_9",
    "diagnosis",
    "figure",
    "notebook_lr",
    "reading",
    "section",
]


# ------------------------------------------------------------------------ table and figure
def _rows(results_dir, experiment=LNN_SEED) -> tuple[pd.DataFrame, str | None]:
    runs = load_runs(results_dir)
    if not len(runs):
        return runs, None
    profile = pick_profile(runs, results_dir)
    if profile is not None:
        runs = runs[runs["profile"] == profile].reset_index(drop=True)
    notebook = experiment is LNN_SEED_NOTEBOOK
    return _seed_rows(experiment_rows(runs, experiment.name, profile), notebook), profile


def _protocols(results_dir: Path) -> list[str]:
    """The two readings side by side (:func:`kit.protocol_table`)."""
    text, profile = _rows(results_dir)
    notebook, _ = _rows(results_dir, LNN_SEED_NOTEBOOK)
    runs = load_runs(results_dir)

    def steps(rows, fallback):
        seen = sorted({int(x) for x in rows["steps"]}) if len(rows) else []
        return ", ".join(map(str, seen)) if seen else fallback

    metric = "energy error, % of max V - min V, 40 rollouts of 10 s"
    ours = Protocol(
        {
            "data": "the dataset's trajectories, 4 states 0.1 s apart",
            "targets": "dz/dt",
            "loss": "squared error",
            "optimiser": "AdamW 1e-3, cosine, clipping, batch 32",
            "steps": steps(text, "-"),
            "metric": metric,
        },
        by_seed_set(text, profile, reading, LNN_SEED.name, runs),
    )
    seeds = Protocol(
        {
            "data": "fresh uniform states every batch, qdot in [-10, 10]",
            "targets": "dz/dt",
            "loss": "L1",
            "optimiser": "Adam, OneCycle, batch 512",
            "steps": f"{steps(notebook, '-')} (the notebook's {NOTEBOOK_STEPS})",
            "metric": metric,
        },
        by_seed_set(notebook, profile, reading, LNN_SEED_NOTEBOOK.name, runs),
    )
    differs = (
        "steps (lr raised by the same factor); the baseline's initialisation; the test set "
        "(ours: 10 s from the suite's starts; the notebook's: 100 s from rest)"
    )
    return protocol_table(ours, seeds, differs)


def section(results_dir) -> str:
    """The seed's double-pendulum numbers beside ours, per model."""
    rows, profile = _rows(Path(results_dir))
    lines = [
        "## LNN seed: the double pendulum as the seed ran it (claim 9)",
        "",
        "Unit double pendulum, trained on instantaneous accelerations at random states ("
        f"profile {profile or '-'}; geometric means over seeds, min-max in brackets). Energy: "
        "|E(zhat) - E(z)| with the true E along 40 test rollouts of 100 points (dt 0.1 s), as % "
        "of the potential's range 6 g (the seed divides by 3 g: its scale is 2x ours, column "
        "'seed scale'); mean over time (the seed's text) and at the last step (its notebook). "
        "Test loss: mean squared error of dz/dt at the test states (the seed's final loss is "
        "its training loss, L1 in its notebook). Protocol and where ours "
        "differs: `bench/studies/lnn_seed/notebook/`.",
        "",
        "| model | seeds | failed | energy %, mean over t | median over seeds | seed scale | "
        "seed's number | energy %, last step | test loss dz/dt | seed's final loss | "
        "rollout error |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    diag = [*_protocols(Path(results_dir)), *_diagnosis_lines(Path(results_dir))]
    notebook, _ = _rows(Path(results_dir), LNN_SEED_NOTEBOOK)
    if not len(rows) and not len(notebook):
        return "\n".join([*lines, "| (no runs) | | | | | | | | | | |", *diag])
    for model, label, g in (
        (m, f"{name}{tag}", src[src["model"] == m] if len(src) else src)
        for tag, src in (("", rows), (", notebook", notebook))
        for m, name in (
            ("lnn", "LNN (pure, pinv)"),
            ("node_so", "baseline (NODE+SO)"),
            ("constant_velocity", "constant velocity"),
        )
    ):
        if not len(g):
            continue
        ok = g[~bad_rows(g, "energy_pct_max_pe")]
        e = pd.to_numeric(ok["energy_pct_max_pe"], errors="coerce")
        rng = f" [{_f(e.min())}, {_f(e.max())}]" if len(e) else ""
        lines.append(
            f"| {label} | {g['seed'].nunique()} | {len(g) - len(ok)} | {_f(_gm(e))}{rng} | "
            f"{_f(float(e.median()) if len(e) else math.nan)} | "
            f"{_f(SEED_SCALE * _gm(e))} | {_f(SEED_NUMBERS['energy_pct'].get(model, math.nan))} | "
            f"{_f(_gm(ok['energy_pct_max_pe_last'] if 'energy_pct_max_pe_last' in ok else []))} | "
            f"{_f(_gm(ok['derivative_mse_test']))} | "
            f"{_f(SEED_NUMBERS['loss'].get(model, math.nan))} | {_f(_gm(ok['rollout_error']))} |"
        )
    return "\n".join([*lines, *diag])


def _diagnosis_lines(results_dir: Path) -> list[str]:
    """The diagnosis table (``python -m bench diagnose-lnn``), where the folder has one."""
    path = results_dir / diagnosis.FILE
    if not path.exists():
        return ["", "(No LNN diagnosis in this folder: `python -m bench diagnose-lnn`.)"]
    return ["", diagnosis.summary(pd.read_csv(path))]


def figure(results_dir) -> list[Path]:
    """Energy % of max PE (mean over time) and test loss per model, seeds as dots, the seed's
    numbers (on our scale) as black marks."""

    rows, _ = _rows(Path(results_dir))
    rows = rows[~bad_rows(rows, "energy_pct_max_pe")] if len(rows) else rows
    if not len(rows):
        return []
    fig, axes = subplots(1, 2, figsize=(8, 3.2))
    names = (("lnn", "LNN"), ("node_so", "baseline"), ("constant_velocity", "const. vel."))
    for ax, metric, key, label in (
        (axes[0], "energy_pct_max_pe", "energy_pct", "energy error, % of max V - min V"),
        (axes[1], "derivative_mse_test", "loss", "test loss on dz/dt"),
    ):
        for i, (m, _) in enumerate(names):
            x = pd.to_numeric(rows.loc[rows["model"] == m, metric], errors="coerce").dropna()
            x = x[x > 0]
            if len(x):
                ax.bar(i, _gm(x), 0.6, color=f"C{i}")
                ax.plot(np.full(len(x), i), x, "k.", ms=4)
            seed = SEED_NUMBERS[key].get(m)
            if seed is not None:
                ax.plot(i, seed / (SEED_SCALE if key == "energy_pct" else 1.0), "k_", ms=14, mew=2)
        ax.set_yscale("log")
        ax.set_xticks(range(len(names)), [n for _, n in names])
        ax.set_ylabel(label)
    fig.suptitle(
        "LNN seed, double pendulum: ours (bars, seeds as dots), seed's numbers (marks)", fontsize=9
    )
    fig.tight_layout()
    return save_figure(fig, Path(results_dir) / "figures", "fig_lnn_seed")


STUDY = register_study(
    Study(
        name="lnn_seed",
        experiments=EXPERIMENTS,
        claim=9,
        title=CLAIM_TITLES[9],
        rule=claim_9,
        stem="fig_lnn_seed",
        results_figure=figure,
        section=section,
        section_title="LNN seed: the double pendulum as the seed ran it (claim 9)",
    )
)
