"""Learning from pixels: the HNN seed's pixel pendulum (claim 11) and the VIN seed's pixel
forecasts (claim 12), their verdict rules, a table beside the seeds' numbers and a figure of
predicted frames against the truth.

An autoencoder maps two stacked 28 x 28 frames of the pendulum to a 2-number latent on which a
registered dynamics model (HNN, MLP field, VIN, ResNet) runs. Claim 11 is read twice: under our
protocol (``pixel_pendulum_hnn``) and under the HNN seed's (``pixel_pendulum_hnn_seed``: its
optimiser, latent step, initialisation and energy metric); the verdict is the seed's where it
has runs. The task, the models, the budgets, the seed's protocol read from its code, and why
quick's latent HNN does not learn the motion: docs/studies/pixels.md.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pandas as pd

from ...core._experiments import Experiment
from ...core._query import experiment_rows, pick_profile
from ...core._store import read_rows
from ...core._studies import Study, register_study
from .._figure import new_figure, save_figure
from . import _vin_diagnosis, policy
from ._protocols import HEADER as PROTOCOL_HEADER
from ._protocols import learned_text
from ._rules import CLAIM_TITLES
from .kit import (
    Discrimination,
    Gate,
    at_most,
    bad_rows,
    condition,
    gated,
    greater,
    learned,
    paired,
    scored,
    verdict,
)

# The HNN seed's pixel-pendulum row (greydanus/hamiltonian-nn README, baseline -> HNN)
SEED_ENERGY_MSE = (9.27e-3, 1.53e-4)
HNN, BASELINE = {"model": "hnn"}, {"model": "node"}
VIN_CELL, RESNET = {"model": "vin"}, {"model": "resnet"}
PAPER_CPU_S = 4 * 5 * 430.0  # 10000 steps at ~40 ms (width 200, batch 200) + evaluation

_COMMON = {
    "system": "pendulum",
    "observation": "pixels",
    "dt": 0.08,
    "chunk": 3,  # the seed's (x_t, x_t+1): three frames, two observations, one latent step
    "duration": 8.0,  # 100 frames per trajectory
    "n_generated": 160,
    "n_train": 160,
    "n_test": 40,
    "test_chunks": 34,  # 102 frames: 101 observations, the seed's trajectory length
    "width": 200,
    "depth": 2,
    "batch": 200,
    "lr": 1e-3,
    "steps": 10000,
    "eval_checkpoints": 0,
    "dtype": "float32",
}
_QUICK = {
    "n_generated": 40,
    "n_train": 40,
    "n_test": 20,
    "duration": 4.0,
    "test_chunks": 20,
    "width": 128,
    "batch": 64,
    "steps": 1500,
}
_SMOKE = {
    "n_generated": 4,
    "n_train": 4,
    "n_test": 2,
    "duration": 0.8,
    "test_chunks": 3,
    "width": 8,
    "batch": 4,
    "steps": 4,
    "seeds": (0,),
}


def _experiment(
    name: str, title: str, models: tuple[str, ...], claim: int, paper: str
) -> Experiment:
    return Experiment(
        name=name,
        title=title,
        axes={"model": models},
        fixed=_COMMON,
        profile_overrides={"smoke": _SMOKE, "quick": _QUICK, "paper-core": {}},
        claim=claim,
        paper=paper,
    )


PIXEL_HNN = _experiment(
    "pixel_pendulum_hnn", "HNN seed: pixel pendulum, latent HNN vs MLP", ("hnn", "node"), 11, "hnn"
)
PIXEL_VIN = _experiment(
    "pixel_pendulum_vin",
    "VIN seed: pixel pendulum, latent VIN vs ResNet",
    ("vin", "resnet"),
    12,
    "vin",
)
# The HNN seed's protocol (greydanus/hamiltonian-nn: experiment-pixels/train.py, hnn.py,
# nn_models.py and the analysis notebook analyze-pixels.ipynb; docs/studies/pixels.md):
# PyTorch's Adam with weight_decay=1e-5 (an L2 term in the gradient), lr 1e-3 held constant, no
# clipping; the latent step z + f(z) in the loss (explicit Euler, one unit of latent time per
# frame); the auxiliary weight 1 and the dynamics weight 0.1 (ours too: bench.core._pixels);
# batch 200, 10000 steps; the dynamics network initialised as PyTorch builds the seed's MLP
# (init "hnn_seed": orthogonal at gain 1, PyTorch's uniform biases). Under that L2 our own
# initialisation (gain 0.5, zero biases: an H with no curvature at the origin) decays to a zero
# field (docs/studies/pixels.md). Its energy: the notebook's, an affine map from the latent to
# the state fitted on the training encodings, the true H (``seed_energy_mse``). Its test rollout
# is scipy's RK45 at a unit step per frame (the text: "a fourth-order Runge-Kutta
# integrator"): RK4 here. The data, the autoencoder and the three-term loss are the suite's, as
# in ``pixel_pendulum_hnn``.
SEED_PROTOCOL = {
    "optimizer": "adam_l2",
    "lr_schedule": "constant",
    "weight_decay": 1e-5,
    "train_integrator": "euler",
    "eval_integrator": "rk4",
    "model_options": (("init", "hnn_seed"),),
}
SEED_STEPS = 10000
PIXEL_HNN_SEED = Experiment(
    name="pixel_pendulum_hnn_seed",
    paper="hnn",
    title="HNN seed: pixel pendulum as the seed trained and scored it (Adam + L2, Euler step)",
    axes={"model": ("hnn", "node")},
    fixed={**_COMMON, **SEED_PROTOCOL, "steps": SEED_STEPS},
    # quick keeps the seed's steps (the latent HNN needs 5000-10000 of them, module docs) at
    # quick's data, width and batch
    profile_overrides={
        "smoke": _SMOKE,
        "quick": {**_QUICK, "steps": SEED_STEPS},
        "paper-core": {},
    },
    claim=11,
)
EXPERIMENTS = (PIXEL_HNN, PIXEL_VIN)
ALL_EXPERIMENTS = (*EXPERIMENTS, PIXEL_HNN_SEED)
CLAIM_TITLES[11] = (
    "HNN seed, pixels: the latent HNN conserves energy far better than the MLP at similar loss"
)
CLAIM_TITLES[12] = "VIN seed, pixels: the latent VIN forecasts better than a ResNet, long horizons"


def _pixels(runs: pd.DataFrame, models: tuple[str, ...]) -> pd.DataFrame:
    if not len(runs) or "observation" not in runs:
        return runs.iloc[0:0]
    return runs[(runs["observation"] == "pixels") & runs["model"].isin(models)]


def _disc(r: pd.DataFrame) -> list[Discrimination]:
    """Discriminating: the best model (lowest mean log pixel MSE) beats holding the first
    observation by the learning margin (squared: an MSE) on every seed."""
    ok = r[~bad_rows(r, "pixel_mse")]
    if not len(ok):
        return []
    per = np.log(pd.to_numeric(ok["pixel_mse"])).groupby([ok["model"], ok["seed"]]).mean()
    means = per.groupby(level=0).mean().sort_values()
    best = str(means.index[0])
    triv = np.log(pd.to_numeric(ok["pixel_mse_static"])).groupby(ok["seed"]).mean()
    m = (triv - per.loc[best]).dropna()
    if not len(m):
        return [Discrimination("pixels", "unknown")]
    worst = float(m.min())
    status = "yes" if worst >= policy.margin("learning", squared=True).test else "no"
    return [Discrimination("pixels", status, best, worst, float(np.exp(triv).mean()))]


def _learned(r: pd.DataFrame, model: str) -> Gate:
    """The learning gate of a pixel model: its per-seed pixel MSE against holding the first
    frame (``pixel_mse_static``, the test set's, the same for every model of a seed), at the
    learning margin squared (an MSE); failed runs at the worst pixel MSE."""
    static = pd.to_numeric(
        r.get("pixel_mse_static", pd.Series(np.nan, index=r.index)), errors="coerce"
    )
    static = static[np.isfinite(static) & (static > 0)]
    triv = np.log(static).groupby(r.loc[static.index, "seed"]).mean()
    g = r[r["model"] == model]
    own = np.log(scored(g, "pixel_mse")).groupby(g["seed"]).mean() if len(g) else None
    return learned(SHORT[model], own, triv if len(triv) else None, squared=True)


def seed_protocol(r: pd.DataFrame) -> pd.Series:
    """Which rows ran the HNN seed's protocol (:data:`SEED_PROTOCOL`: Adam with L2 and the
    Euler latent step; ``pixel_pendulum_hnn_seed``); the others ran ours (AdamW, cosine,
    RK4)."""

    def col(name, default):
        if name not in r:
            return pd.Series(default, index=r.index)
        return r[name].where(r[name].notna(), default).astype(str)

    return (col("optimizer", "adamw") == SEED_PROTOCOL["optimizer"]) & (
        col("train_integrator", "rk4_38") == SEED_PROTOCOL["train_integrator"]
    )


# The two readings of claim 11: rows, the energy metric tested, its label, the other metric
READINGS = {
    "ours": ("decoded_energy_mse", "decoded energy MSE", "seed_energy_mse", "the seed's energy"),
    "seed": ("seed_energy_mse", "energy MSE (the seed's)", "decoded_energy_mse", "decoded energy"),
}


def reading(r: pd.DataFrame, protocol: str):
    """Claim 11 on the rows ``r`` of one protocol (``"ours"`` or ``"seed"``, :data:`READINGS`):
    (a) *greater* on ``log(energy MSE MLP / HNN)`` at the energy margin squared (an MSE), the
    energy ours (``decoded_energy_mse``: read off the decoded frames) or the seed's
    (``seed_energy_mse``: the latent mapped to the state, the true H); judged under (b), the
    condition "comparable losses" (*at most* on ``log(test loss HNN / MLP)`` at the loss
    margin), and where both models learned the motion. The other energy metric is reported
    beside it, not tested. Failed runs score the worst value."""
    metric, label, other, other_label = READINGS[protocol]
    effect = f"log {label} ratio MLP / HNN"
    if not len(r):
        return verdict(11, CLAIM_TITLES[11], [], None, 0, effect)
    e = paired(r, BASELINE, HNN, metric)
    loss = paired(r, HNN, BASELINE, "pixel_loss_test")
    similar = at_most("(b) log(test loss HNN / MLP)", loss.to_numpy(), policy.margin("loss"))
    energy = greater(
        f"(a) log({label} MLP / HNN)", e.to_numpy(), policy.margin("energy", squared=True)
    )
    parts = [gated(energy, condition(similar), _learned(r, "hnn"), _learned(r, "node")), similar]
    drift = pd.to_numeric(r[r["model"] == "hnn"]["latent_energy_drift"], errors="coerce")
    extra = f"HNN latent H drift (range / spread over starts) {np.nanmean(drift):.3g}"
    if other in r:  # over the rows that have it (rows stored before it existed do not)
        o = paired(r[~bad_rows(r, other)], BASELINE, HNN, other)
        if len(o):
            extra += f"; {other_label} MSE MLP / HNN {math.exp(o.mean()):.3g}x (not tested)"
    return verdict(
        11,
        CLAIM_TITLES[11],
        parts,
        parts[0],
        min(len(e), len(loss)),
        effect,
        extra,
        discs=_disc(r),
        n_failed=int(bad_rows(r, metric).sum()),
    )


def readings(runs: pd.DataFrame) -> dict:
    """Claim 11's verdict on our protocol's rows and on the seed's (``{"ours": ..., "seed":
    ...}``; a protocol without rows reads inconclusive)."""
    r = _pixels(runs, ("hnn", "node"))
    seed = seed_protocol(r) if len(r) else pd.Series(False, index=r.index)
    return {"ours": reading(r[~seed], "ours"), "seed": reading(r[seed], "seed")}


def claim_11(runs: pd.DataFrame, curves: pd.DataFrame | None = None):
    """Claim 11 (HNN seed, Table 1's pixel pendulum): "The HNN and its baseline reached
    comparable train and test losses, but once again, the HNN dramatically outperformed the
    baseline on the energy metric" (seeds/003 line 60).

    Two readings, each by :func:`reading`: ours (``pixel_pendulum_hnn``: AdamW with the suite's
    cosine decay and clipping, an RK4 latent step in the loss; the energy read off the decoded
    frames, ``decoded_energy_mse``) and the seed's protocol (``pixel_pendulum_hnn_seed``: Adam
    with an L2 weight decay of 1e-5, constant lr, the Euler step z + f(z); the seed's energy
    metric, ``seed_energy_mse``: the latent mapped to the state by an affine fit on the training
    encodings, the true H against the true states). They differ in the optimisation and,
    above all, in the metric: ours follows the decoder's noise through a finite-difference
    velocity, the seed's reads the state through the encoder. The verdict is the seed's
    protocol's where it has runs, ours otherwise; the other reading's verdict is named in the
    detail. Headline (a)."""
    both = readings(runs)
    r = _pixels(runs, ("hnn", "node"))
    if not len(r) or not seed_protocol(r).any():
        return both["ours"]
    s = both["seed"]
    detail = f"{s.detail}; the seed's protocol (ours: {both['ours'].verdict})"
    return dataclasses.replace(s, detail=detail)


def reading_ours(runs: pd.DataFrame):
    """Claim 12 (VIN seed, pixels) on our pixel protocol (the claim's rule over both readings is
    ``vin_blog.claim_12``): *greater* on ``log(pixel MSE ResNet / VIN)`` at the error
    margin squared (an MSE) over (a) the whole horizon and (b) its last third, each judged
    where both models learned the motion. Headline (a)."""
    r = _pixels(runs, ("vin", "resnet"))
    if not len(r):
        return verdict(12, CLAIM_TITLES[12], [], None, 0, "log pixel-MSE ratio")
    a = paired(r, RESNET, VIN_CELL, "pixel_mse")
    b = paired(r, RESNET, VIN_CELL, "pixel_mse_late")
    mg = policy.margin("error", squared=True)
    gates = (_learned(r, "vin"), _learned(r, "resnet"))
    parts = [
        gated(greater("(a) log(pixel MSE ResNet / VIN)", a.to_numpy(), mg), *gates),
        gated(greater("(b) log(late pixel MSE ResNet / VIN)", b.to_numpy(), mg), *gates),
    ]
    drift = pd.to_numeric(r[r["model"] == "vin"]["latent_energy_drift"], errors="coerce")
    extra = f"VIN latent energy drift (range / spread over starts) {np.nanmean(drift):.3g}"
    return verdict(
        12,
        CLAIM_TITLES[12],
        parts,
        parts[0],
        min(len(a), len(b)),
        "log pixel-MSE ratio ResNet / VIN",
        extra,
        discs=_disc(r),
        n_failed=int(bad_rows(r, "pixel_mse").sum()),
    )


# ------------------------------------------------------------------------ table and figure
LABELS = {"hnn": "HNN", "node": "MLP (HNN seed's baseline)", "vin": "VIN", "resnet": "ResNet"}
SHORT = {"hnn": "HNN", "node": "MLP", "vin": "VIN", "resnet": "ResNet"}


def _rows(results_dir, experiments=None) -> tuple[list[dict], pd.DataFrame, str | None]:
    """(row dicts with their curves, runs table, profile) of ``experiments`` (default: the
    pixel experiments, the seed's protocol included)."""
    from ...core._store import load_runs

    experiments = ALL_EXPERIMENTS if experiments is None else experiments
    runs = load_runs(results_dir)
    if not len(runs):
        return [], runs, None
    profile = pick_profile(runs)
    if profile is not None:
        runs = runs[runs["profile"] == profile]
    parts = [experiment_rows(runs, e.name, profile) for e in experiments]
    parts = [p for p in parts if len(p)]
    table = pd.concat(parts, ignore_index=True) if parts else runs.iloc[0:0]
    if len(table):
        table = table.drop_duplicates("config_hash").reset_index(drop=True)
    hashes = set(table["config_hash"]) if len(table) else set()
    rows = [r for r in read_rows(results_dir) if r.get("config_hash") in hashes]
    return rows, table, profile


def _gm(x) -> float:
    x = pd.to_numeric(pd.Series(x), errors="coerce").to_numpy(float)
    x = x[np.isfinite(x) & (x > 0)]
    return float(np.exp(np.mean(np.log(x)))) if len(x) else math.nan


def _f(x) -> str:
    return "-" if not np.isfinite(x) else f"{x:.3g}"


def _span(lo: float, hi: float, fmt=_f) -> str:
    """``lo - hi``, or one number where they print alike."""
    a, b = fmt(lo), fmt(hi)
    return a if a == b else f"{a} - {b}"


_TABLE_COLUMNS = (
    "pixel_loss_test",
    "recon_mse",
    "pixel_mse",
    "pixel_mse_late",
    "pixel_mse_static",
    "decoded_energy_mse",
    "seed_energy_mse",
    "seed_energy_mse_floor",
)


def section(results_dir) -> str:
    """The pixel models side by side, the HNN seed's pixel row beside ours; claim 11's two
    protocols side by side with their verdicts; which seeds learn, and why not."""
    _, t, profile = _rows(Path(results_dir))
    lines = [
        "## Learning from pixels (claims 11 and 12)",
        "",
        f"Pendulum rendered to 28 x 28 frames, two stacked per observation (profile "
        f"{profile or '-'}; geometric means over seeds). Pixel MSE: decoded latent rollouts "
        "against the true frames over the test horizon (late: its last third; static: holding "
        "the first observation). Decoded energy MSE (ours): the true energy of the state read "
        "off the decoded frames (the angle of each frame, a finite-difference velocity over one "
        "frame) against the same reading of the true ones. Seed's energy MSE: the HNN seed's "
        "metric, the decoded frames encoded again and mapped to the state by an affine map "
        "fitted on the training encodings, the true energy against the true states' (floor: "
        "the map applied to the encoded true frames). The seed's printed numbers are of its "
        "Gym pendulum and its energy scale: compare orders of magnitude only. Latent drift: "
        "range of the learned conserved scalar along a rollout over its spread across test "
        "starts. Protocol: `bench/studies/paper/pixels.py`, `bench/core/_pixels.py`.",
        "",
        "| model | protocol | seeds | test loss | recon MSE | pixel MSE | late pixel MSE | "
        "static | decoded energy MSE (ours) | seed's energy MSE | its floor | "
        "energy MSE (HNN seed's number) | latent drift |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    if not len(t):
        return "\n".join([*lines, "| (no runs) |" + " |" * 12])

    seed_numbers = {"node": SEED_ENERGY_MSE[0], "hnn": SEED_ENERGY_MSE[1]}
    protocol = seed_protocol(t)
    for model in ("hnn", "node", "vin", "resnet"):
        for is_seed, name in ((False, "ours"), (True, "seed's")):
            g = t[(t["model"] == model) & (protocol == is_seed) & ~bad_rows(t, "pixel_mse")]
            if not len(g):
                continue
            cells = [_gm(g[c]) if c in g else math.nan for c in _TABLE_COLUMNS]
            lines.append(
                f"| {LABELS[model]} | {name} | {g['seed'].nunique()} | "
                + " | ".join(_f(x) for x in cells)
                + f" | {_f(seed_numbers.get(model, math.nan))} | "
                f"{_f(_gm(g.get('latent_energy_drift')))} |"
            )
    diag = _vin_diagnosis_frame(Path(results_dir), profile)
    return "\n".join(
        [
            *lines,
            "",
            *protocol_table(t, profile),
            "",
            *seed_lines(t, diag),
            *_vin_diagnosis_lines(Path(results_dir)),
        ]
    )


_OPTIMISERS = {
    "adamw": "AdamW (decoupled weight decay), gradient clipped at norm 1",
    "adam_l2": "Adam with the weight decay as an L2 term in the gradient, no clipping",
}
_SCHEDULES = {
    "cosine": "cosine decay",
    "constant": "constant",
    "onecycle": "one-cycle",
}


_INITS = {
    "orthogonal": "orthogonal at gain 0.5, zero biases (the paper's)",
    "hnn_seed": "orthogonal at gain 1, PyTorch's uniform biases (the seed's)",
}


def _config(exp: Experiment, profile: str | None):
    from ...core._experiments import expand

    for p in (profile, "paper"):
        try:
            cfgs = expand(exp, p) if p else []
        except (KeyError, ValueError):
            cfgs = []
        if cfgs:
            return cfgs[0]
    return None


def protocol_table(t: pd.DataFrame, profile: str | None) -> list[str]:
    """Claim 11 under our protocol and under the seed's, side by side: what each trains on,
    how, what it scores, and its verdict (from the rows ``t``; the configurations are the
    experiments' at ``profile``)."""
    from ...core._pixels import AE_LOSS, CC_LOSS, DYN_LOSS, WEIGHT_DECAY

    v = readings(t) if len(t) else {}
    cols = {"ours": _config(PIXEL_HNN, profile), "seed": _config(PIXEL_HNN_SEED, profile)}
    desc = {
        "euler": "explicit Euler z + f(z)",
        "rk4": "classical RK4",
        "rk4_38": "RK4 (3/8 rule)",
    }

    def cell(key, what):
        c = cols[key]
        if c is None:
            return "-"
        if what == "data":
            frames = max(c.chunk, round(c.duration / c.dt))
            return (
                f"{c.n_train} trajectories of {frames} frames {c.dt:g} s apart, windows of "
                f"{c.chunk} frames; test {c.n_test} of {c.chunk * c.test_chunks} frames"
            )
        if what == "targets":
            return (
                f"the next observation's encoding after one latent step "
                f"({desc.get(c.train_integrator, c.train_integrator)}, unit step per frame)"
            )
        if what == "loss":
            return (
                f"{AE_LOSS:g} x pixel L2 + {CC_LOSS:g} x auxiliary latent loss + "
                f"{DYN_LOSS:g} x latent dynamics"
            )
        if what == "optimiser":
            wd = WEIGHT_DECAY if c.weight_decay is None else c.weight_decay
            return (
                f"{_OPTIMISERS.get(c.optimizer, c.optimizer)}; lr {c.lr:g} "
                f"{_SCHEDULES.get(c.lr_schedule, c.lr_schedule)}, weight decay {wd:g}, batch "
                f"{c.batch}, width {c.width}"
            )
        if what == "steps":
            return f"{c.steps}"
        if what == "init":
            init = dict(c.model_options).get("init", "orthogonal")
            return _INITS.get(init, init)
        if what == "metric":
            roll = desc.get(c.eval_integrator, c.eval_integrator)
            if key == "ours":
                return (
                    f"decoded energy MSE: latent rollout ({roll}), decoded, angle and "
                    "finite-difference velocity read off the frames, true H against the truth "
                    "read alike"
                )
            return (
                f"seed's energy MSE: latent rollout ({roll}), decoded, encoded again, affine "
                "map to the state fitted on the training encodings, true H against the true "
                "states' (decoded energy MSE beside it, not tested)"
            )
        x = v.get(key)
        if x is None or not x.n_seeds:
            return "no runs"
        head = x.parts[0]
        why = f"; (a) {head.status}" + (f": {head.note}" if head.note else "")
        disc = "; not discriminating" if x.discriminating is False else ""
        return (
            f"**{x.verdict}** ({x.n_seeds} seeds; {x.effect_name} {x.effect:.3g} = "
            f"{math.exp(x.effect):.3g}x{why}{disc})"
        )

    names = {
        "data": "data",
        "targets": "targets",
        "loss": "loss",
        "optimiser": "optimiser",
        "steps": "steps",
        "init": "dynamics network's initialisation",
        "metric": "energy metric (tested)",
        "verdict": "verdict",
    }
    lines = [
        "Claim 11 under two protocols (the verdict is the seed's protocol's where it has runs; "
        "`claim_11`):",
        "",
        PROTOCOL_HEADER,
        "|---|---|---|",
    ]
    for what, label in names.items():
        lines.append(f"| {label} | {cell('ours', what)} | {cell('seed', what)} |")
    lines.append(f"| learned | {learned_text(v.get('ours'))} | {learned_text(v.get('seed'))} |")
    lines.append(
        "| still differs from the seed's code | - | our pendulum and renderer (the seed: Gym's "
        "Pendulum-v0); zero autoencoder biases; both observations reconstructed (the seed: the "
        "first); RK4 test rollouts (the seed: RK45); every test trajectory (the seed: one) |"
    )
    return lines


def _gain(g: pd.DataFrame) -> pd.Series:
    """Holding the first frame's pixel MSE over the model's, per row (failed rows: 0)."""
    x = pd.to_numeric(g["pixel_mse_static"], errors="coerce") / pd.to_numeric(
        g["pixel_mse"], errors="coerce"
    )
    return x.where(~bad_rows(g, "pixel_mse"), 0.0)


def seed_lines(t: pd.DataFrame, diag: pd.DataFrame | None = None) -> list[str]:
    """Which models learn the motion on which seed (pixel MSE below holding the first frame by
    the learning gate), the seed's autoencoder reconstruction, and for a seed where no model
    learns, what its runs and the VIN diagnosis (``diag``, trained without the auxiliary loss,
    the same data and autoencoder initialisation) say about it. Every number from the rows."""
    if not len(t) or "pixel_mse_static" not in t:
        return []
    gate = policy.margin("learning", squared=True).value
    t = t.assign(_gain=_gain(t), _protocol=np.where(seed_protocol(t), "seed's", "ours"))
    t = t.assign(_learned=t["_gain"] >= gate)
    ablation = None
    if diag is not None and len(diag):
        ablation = diag[pd.to_numeric(diag["aux_weight"], errors="coerce") == 0].copy()
        ablation["_gain"] = _gain(ablation)
    lines = [
        f"Per seed: the models that learn the motion (pixel MSE {gate:g}x below holding the "
        "first frame, the claims' gate), the rest with their factor, and the autoencoder's "
        "reconstruction MSE over the seed's runs (every model, both protocols).",
        "",
        "| seed | learned | not learned (x below holding the first frame) | recon MSE "
        "| VIN without the auxiliary loss: recon MSE, x below |",
        "|---|---|---|---|---|",
    ]

    def label(r):
        return f"{SHORT[r['model']]} ({r['_protocol']})"

    recon = pd.to_numeric(t.get("recon_mse", pd.Series(np.nan, index=t.index)), errors="coerce")
    learned_recon = float(np.median(recon[t["_learned"]])) if t["_learned"].any() else math.nan
    notes = []
    for s, g in t.groupby("seed"):
        ok = [label(r) for _, r in g.iterrows() if r["_learned"]]
        bad = [f"{label(r)} {r['_gain']:.2g}" for _, r in g.iterrows() if not r["_learned"]]
        rec = recon[g.index]
        abl = ablation[ablation["seed"] == s] if ablation is not None else None
        abl_text = "-"
        if abl is not None and len(abl):
            a = abl.iloc[0]
            abl_text = f"{_f(float(a['recon_mse']))}, {a['_gain']:.3g}x"
        lines.append(
            f"| {s} | {', '.join(ok) or 'none'} | {', '.join(bad) or '-'} | "
            f"{_span(rec.min(), rec.max())} | {abl_text} |"
        )
        if ok or not t["_learned"].any():
            continue
        note = f"Seed {s}: no model learns the motion ({len(g)} runs)"
        if np.isfinite(learned_recon) and rec.notna().any():
            ratio = _span(
                rec.min() / learned_recon, rec.max() / learned_recon, lambda x: f"{x:.2g}"
            )
            note += (
                f"; they reconstruct at {_span(rec.min(), rec.max())}, {ratio}x the median "
                f"of the runs that learn ({_f(learned_recon)})"
            )
        note += "."
        if abl is not None and len(abl):
            a = abl.iloc[0]
            if a["_gain"] >= gate:
                note += (
                    f" Trained without the auxiliary latent loss (the VIN diagnosis: the same "
                    f"frames and autoencoder initialisation) it reconstructs at "
                    f"{_f(float(a['recon_mse']))} and learns ({a['_gain']:.3g}x below holding "
                    "the first frame): the seed's frames and autoencoder initialisation can be "
                    "learned, so its runs' failure is not the autoencoder's alone; it comes with "
                    "the protocol's loss, which every run of the table shares."
                )
            else:
                note += (
                    f" Trained without the auxiliary latent loss (the VIN diagnosis) it "
                    f"reconstructs at {_f(float(a['recon_mse']))} and does not learn either "
                    f"({a['_gain']:.3g}x)."
                )
        notes.append(note)
    return [*lines, *([""] + notes if notes else [])]


def _vin_diagnosis_frame(results_dir: Path, profile: str | None) -> pd.DataFrame | None:
    """The VIN diagnosis rows of ``profile`` (None where the folder has none)."""
    path = results_dir / _vin_diagnosis.FILE
    if not path.exists():
        return None
    d = pd.read_csv(path)
    if profile is not None and "profile" in d:
        d = d[d["profile"] == profile]
    return d if len(d) else None


def _vin_diagnosis_lines(results_dir: Path) -> list[str]:
    """The VIN diagnosis table (``python -m bench diagnose-vin``), where the folder has one."""
    path = results_dir / _vin_diagnosis.FILE
    if not path.exists():
        return ["", "(No VIN diagnosis in this folder: `python -m bench diagnose-vin`.)"]
    return ["", _vin_diagnosis.summary(pd.read_csv(path))]


def figure(results_dir) -> list[Path]:
    """Predicted frames against the truth (first test trajectory of the lowest seed, first
    frame of each observation at a few times) and pixel MSE against time per model."""

    rows, _, _ = _rows(Path(results_dir), EXPERIMENTS)
    rows = [
        r for r in rows if r.get("status") == "ok" and (r.get("curves") or {}).get("frames_pred")
    ]
    if not rows:
        return []
    order = {m: i for i, m in enumerate(("hnn", "node", "vin", "resnet"))}
    first = {}
    for r in sorted(rows, key=lambda r: (order.get(r["model"], 9), r["seed"])):
        first.setdefault(r["model"], r)
    picked = list(first.values())
    c0 = picked[0]["curves"]
    n = len(c0["frame_index"])
    fig = new_figure(figsize=(1.1 * n + 3.6, 1.1 * (len(picked) + 1) + 0.4))
    # n frame columns, a spacer, the curves
    grid = fig.add_gridspec(len(picked) + 1, n + 2, width_ratios=[1] * n + [0.3, 3.2])
    dt = c0["t"][1] - c0["t"][0] if len(c0["t"]) > 1 else 1.0
    panels = [("truth", c0["frames_true"])] + [
        (f"{SHORT[r['model']]} s{r['seed']}", r["curves"]["frames_pred"]) for r in picked
    ]
    for i, (label, frames) in enumerate(panels):
        for j in range(n):
            ax = fig.add_subplot(grid[i, j])
            ax.imshow(np.asarray(frames[j]), cmap="gray", vmin=0, vmax=1)
            ax.set_xticks([])
            ax.set_yticks([])
            if j == 0:  # one short horizontal label per row, left of its first frame
                ax.set_ylabel(label, fontsize=8, rotation=0, ha="right", va="center", labelpad=6)
            if i == 0:
                ax.set_title(f"t={c0['frame_index'][j] * dt:.1f}s", fontsize=7)
    grid.update(wspace=0.08, hspace=0.12)
    ax = fig.add_subplot(grid[:, n + 1])
    ax.set_yscale("log")  # before the ticks move: a scale change resets them
    for r in rows:
        c = r["curves"]
        color = f"C{order.get(r['model'], 4)}"
        ax.plot(c["t"][1:], c["pixel_mse"][1:], color=color, lw=0.8, alpha=0.6)
    for m, i in order.items():
        if m in first:
            ax.plot([], [], color=f"C{i}", label=LABELS[m])
    static = [_gm([r["pixel_mse_static"]]) for r in rows]
    ax.axhline(np.nanmean(static), color="k", ls=":", lw=1, label="hold first frame")
    # ticks and their label on the right, clear of the frames on the left
    ax.yaxis.tick_right()
    ax.yaxis.set_label_position("right")
    ax.tick_params(axis="y", which="both", left=False, labelleft=False, right=True, labelright=True)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("pixel MSE (per seed)", rotation=270, va="bottom", labelpad=4)
    ax.legend(fontsize=6)
    fig.suptitle("Pixel pendulum: decoded latent rollouts against the true frames", fontsize=9)
    return save_figure(fig, Path(results_dir) / "figures", "fig_pixels")


STUDY_HNN = register_study(
    Study(
        name="pixel_pendulum_hnn",
        experiments=(PIXEL_HNN, PIXEL_HNN_SEED),
        claim=11,
        title=CLAIM_TITLES[11],
        rule=claim_11,
        stem="fig_pixels",
        results_figure=figure,
        section=section,
        section_title="Learning from pixels (claims 11 and 12)",
    )
)
STUDY_VIN = register_study(
    Study(
        name="pixel_pendulum_vin",
        experiments=(PIXEL_VIN,),
        claim=12,
        title=CLAIM_TITLES[12],
        # ours alone; bench.studies.paper.vin_blog registers it again with the seed's
        # protocol's experiment and the rule over both readings (vin_blog.claim_12)
        rule=reading_ours,
    )
)
