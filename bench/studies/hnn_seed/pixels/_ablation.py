"""Why a pixel protocol's models do not learn: the protocol's runs beside the same runs with one
element changed (``python -m bench diagnose-vin``, ``python -m bench diagnose-hnn-seed-pixels``;
one CSV per diagnosis in the results folder). Each diagnosis is one :class:`Ablation`: an
experiment, its variants, the file it writes.

**The VIN's auxiliary loss** (claim 12, :data:`VIN`). The pixel protocol
(``bench/core/_pixels.py``) trains every latent model with the HNN seed's auxiliary loss
cc = mean (dw_i - (w_{i+1} - w_i))^2 on the latent state z = (w, dw): it makes the second half of
the latent a forward difference of the first. The VIN's velocity-Verlet step (unit latent step,
mass matrix M, learned potential U) predicts instead

    w_{i+1} - w_i = dw_i - 1/2 M^-1 grad U(w_i),

so cc and the dynamics loss hold together only where the learned force vanishes: the loss asks
the VIN for a pendulum without gravity. The HNN and the ResNet have no such identity between
their state and its difference. The VIN seed itself encodes positions only (no cc). The variant
trains the VIN with cc's weight 0.

**The HNN seed's optimiser and training step** (claim 11, :data:`HNN_SEED`). The seed's
protocol (``pixel_pendulum_hnn_seed``: Adam with the weight decay as an L2 term in the
gradient, constant lr, no clipping, an explicit Euler training step z + f(z) against an RK4
test rollout of f, the seed's initialisation) is changed one element at a time toward ours, both
models each time: the L2 term off and the RK4 training step on every seed; the schedule
(cosine), the optimiser (AdamW with clipping) and the initialisation (ours) on seed 0; and the
two elements that matter, together, on every seed. Why the training step matters to the MLP
and not to the HNN: for a pendulum turning by an angle a per frame, the Euler step asks f for
the increment (R_a - I) z, a field the MLP can represent, whose flow (RK4 at the test) spirals
in with rate 1 - cos a; the HNN's field is divergence-free, cannot contract, and learns the
nearest rotation. The mismatch handicaps the baseline, not the HNN. (The HNN without the
auxiliary loss, claim 11 (c), is a further reading of the claim, not a variant here: ``_aux``.)

A variant's run is read from a folder's stored rows where its configuration (by
``config_hash``) is there: the results folder (the protocol's runs: the campaign's), or a folder
given with ``--runs-from`` (runs of the same configurations made elsewhere, e.g. by
``python -m bench run``); else it is trained here. ``train_seconds`` of a row trained here is
the wall clock of its training, compile included (a stored run's excludes the compile).
``pixel_loss_test`` is the protocol's loss (cc weight 1) for every row, the ablation's included:
it charges an ablation for a term it was not trained on; the pixel MSEs compare alike. Every
number comes from trained models; none is typed in.
"""

from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path

import numpy as np
import pandas as pd

from ....core import build_pixels, evaluate_pixels, expand, read_rows, train_pixels
from ....kit import bad_rows, policy
from ....kit import gmean as _gm

PROFILES = ("smoke", "quick", "paper-core")
COLUMNS = (
    "pixel_mse",
    "pixel_mse_late",
    "pixel_mse_static",
    "recon_mse",
    "pixel_loss_test",
    "decoded_energy_mse",
    "seed_energy_mse",
    "latent_energy_drift",
    "final_loss",
    "train_seconds",
)
PROTOCOL = "protocol"


@dataclasses.dataclass(frozen=True)
class Variant:
    """One element of the protocol changed: ``changes`` (RunConfig fields, e.g. ``aux_weight``
    0: no auxiliary loss), for ``models`` (None: every model of the experiment) on ``seeds``
    (None: the profile's)."""

    name: str
    changes: tuple[tuple[str, object], ...] = ()
    models: tuple[str, ...] | None = None
    seeds: tuple[int, ...] | None = None

    def applies(self, c) -> bool:
        return (self.models is None or c.model in self.models) and (
            self.seeds is None or c.seed in self.seeds
        )

    def config(self, c):
        return dataclasses.replace(c, **dict(self.changes)) if self.changes else c


@dataclasses.dataclass(frozen=True)
class Ablation:
    """A diagnosis: ``experiment``'s runs under each of ``variants`` (the first the protocol's
    own), written to ``file`` by the command ``command``; ``lead`` heads its table."""

    command: str
    experiment: str
    file: str
    variants: tuple[Variant, ...]
    lead: str
    help: str


VIN = Ablation(
    command="diagnose-vin",
    experiment="pixel_pendulum_vin",
    file="vin_diagnosis.csv",
    variants=(
        Variant(PROTOCOL),
        Variant("no auxiliary loss", changes=(("aux_weight", 0.0),), models=("vin",)),
    ),
    lead="VIN diagnosis (`python -m bench diagnose-vin`): the HNN seed's auxiliary latent loss "
    "ties the VIN's velocity to a forward difference its Verlet step contradicts; the VIN "
    "trained again without it (aux weight 0), beside the protocol's VIN and ResNet",
    help="the latent VIN of the pixel pendulum trained again without the auxiliary latent "
    "loss, beside the protocol's VIN and ResNet (claim 12): <results>/vin_diagnosis.csv",
)
_SCREEN = {"seeds": (0,)}
_NO_L2, _RK4 = ("weight_decay", 0.0), ("train_integrator", "rk4_38")
HNN_SEED = Ablation(
    command="diagnose-hnn-seed-pixels",
    experiment="pixel_pendulum_hnn_seed",
    file="hnn_seed_pixel_diagnosis.csv",
    variants=(
        Variant(PROTOCOL),
        Variant("no L2 (weight decay 0)", changes=(_NO_L2,)),
        Variant("RK4 training step", changes=(_RK4,)),
        Variant("no L2 and RK4 training step", changes=(_NO_L2, _RK4)),
        Variant("cosine lr", changes=(("lr_schedule", "cosine"),), **_SCREEN),
        Variant("AdamW, clipped", changes=(("optimizer", "adamw"),), **_SCREEN),
        Variant("our initialisation", changes=(("model_options", ()),), **_SCREEN),
    ),
    lead="HNN seed's pixel protocol diagnosis (`python -m bench diagnose-hnn-seed-pixels`): the "
    "seed's protocol with one element changed toward ours (every seed for its L2 term and its "
    "Euler training step, and for both together; seed 0 for the others)",
    help="the HNN seed's pixel protocol (claim 11) with one element changed toward ours "
    "(its L2 term, training step, schedule, optimiser, initialisation): "
    "<results>/hnn_seed_pixel_diagnosis.csv",
)
ABLATIONS = (VIN, HNN_SEED)


def _run(c) -> dict:
    """Train and evaluate one pixel run."""
    system, data, model = build_pixels(c)
    t0 = time.perf_counter()
    model, meta = train_pixels(c, model, data)
    seconds = time.perf_counter() - t0
    metrics, _ = evaluate_pixels(c, system, data, model)
    return {**metrics, "final_loss": meta["final_loss"], "train_seconds": seconds}


def _stored(folders) -> dict[str, tuple[dict, str]]:
    """The ok rows of ``folders`` by config hash, with where they were read (the first folder
    is the results folder: "stored run"; the others are named)."""
    out = {}
    for i, d in enumerate(folders):
        source = "stored run" if i == 0 else f"stored run ({Path(d).name})"
        for r in read_rows(d):
            if r.get("status") == "ok":
                out.setdefault(r["config_hash"], (r, source))
    return out


def diagnose(
    ablation: Ablation,
    profile: str,
    results_dir,
    seeds=None,
    runs_from=(),
    progress: bool = True,
) -> pd.DataFrame:
    """One row per (model, seed, variant) of ``ablation``, written to ``results_dir / file``;
    a row that file holds already is kept, not trained again (delete the file to retrain).
    ValueError (one line) for a profile outside :data:`PROFILES` or a ``runs_from`` folder that
    does not exist."""
    if profile not in PROFILES:
        allowed = ", ".join(PROFILES)
        raise ValueError(f"{ablation.command}: profile must be one of {allowed}, got {profile!r}")
    for d in runs_from:
        if not Path(d).is_dir():
            raise ValueError(f"{ablation.command}: --runs-from {d} is not a folder")
    results_dir = Path(results_dir)
    configs = expand(ablation.experiment, profile, seeds=seeds)
    if not configs:
        raise ValueError(f"{ablation.command}: {ablation.experiment} has no runs at {profile!r}")
    stored = _stored([results_dir, *runs_from])
    before = _own_rows(ablation, results_dir)
    rows = []
    for base in configs:
        for v in ablation.variants:
            if not v.applies(base):
                continue
            c = v.config(base)
            key = (c.config_hash, v.name, c.aux_weight)
            if key in before:  # this diagnosis's own row, from an earlier call: kept as it was
                rows.append(before.pop(key))
                continue
            if c.config_hash in stored:
                r, source = stored[c.config_hash]
                values = {k: r.get(k) for k in COLUMNS}
            else:
                if progress:
                    print(f"{ablation.command}: {c.model} seed {c.seed}, {v.name}", flush=True)
                values, source = _run(c), "trained here"
            rows.append(
                {
                    "profile": profile,
                    "model": c.model,
                    "seed": c.seed,
                    "variant": v.name,
                    "aux_weight": c.aux_weight,
                    "source": source,
                    "config_hash": c.config_hash,
                    **{k: _num(values.get(k)) for k in COLUMNS},
                }
            )
    df = pd.DataFrame([*rows, *before.values()])  # other seeds' and profiles' rows stay
    results_dir.mkdir(parents=True, exist_ok=True)
    df.to_csv(results_dir / ablation.file, index=False)
    return df


def _own_rows(ablation: Ablation, results_dir) -> dict:
    """The rows ``ablation`` wrote to ``results_dir`` before, by (config hash, variant, aux
    weight), each as written; a failed run's row counts (it is the run's result), a row of a
    variant no longer declared stays in the file."""
    d = read(ablation, results_dir)
    if d is None or not {"config_hash", "variant", "aux_weight"} <= set(d.columns):
        return {}
    return {
        (r["config_hash"], r["variant"], float(r["aux_weight"])): r for r in d.to_dict("records")
    }


def _num(x) -> float:
    """A stored value as a float (None, a missing value: NaN)."""
    try:
        return float(x)
    except (TypeError, ValueError):
        return math.nan


def gain(g: pd.DataFrame) -> pd.Series:
    """Holding the first frame's pixel MSE over the run's, per row (how far below the trivial
    forecast; failed rows: 0)."""
    x = pd.to_numeric(g["pixel_mse_static"], errors="coerce") / pd.to_numeric(
        g["pixel_mse"], errors="coerce"
    )
    return x.where(~bad_rows(g, "pixel_mse"), 0.0)


def read(ablation: Ablation, results_dir, profile: str | None = None) -> pd.DataFrame | None:
    """The diagnosis rows of ``profile`` stored in ``results_dir`` (None where there are none)."""
    path = Path(results_dir) / ablation.file
    if not path.exists():
        return None
    d = pd.read_csv(path)
    if profile is not None and "profile" in d:
        d = d[d["profile"] == profile]
    return d if len(d) else None


def summary(ablation: Ablation, df: pd.DataFrame) -> str:
    """The diagnosis as a markdown table: per model and variant, the geometric-mean pixel MSE,
    how many seeds learn the motion (pixel MSE below holding the first frame by the claims'
    learning gate), the per-seed factor, the energy MSEs and the autoencoder's fit."""
    gate = policy.margin("learning", squared=True).value

    def f(x):
        return "-" if not np.isfinite(x) else f"{x:.3g}"

    lines = [
        f"{ablation.lead} (geometric means over seeds; learned: pixel MSE {gate:g}x below "
        "holding the first frame, the claims' gate).",
        "",
        "| model | variant | aux weight | seeds | learned | pixel MSE | late pixel MSE | "
        "static / pixel MSE per seed | recon MSE | decoded energy MSE | seed's energy MSE | "
        "test loss (the protocol's) | source |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for (model, name), g in df.groupby(["model", "variant"], sort=False):
        x = gain(g)
        per_seed = ", ".join(f"{s}: {v:.3g}" for s, v in zip(g["seed"], x, strict=True))
        cols = ("pixel_mse", "pixel_mse_late")
        lines.append(
            f"| {model} | {name} | {g['aux_weight'].iloc[0]:g} | {g['seed'].nunique()} | "
            f"{int((x >= gate).sum())} of {len(g)} | "
            + " | ".join(f(_gm(g[c])) for c in cols)
            + f" | {per_seed} | "
            + " | ".join(
                f(_gm(g[c])) if c in g else "-"
                for c in ("recon_mse", "decoded_energy_mse", "seed_energy_mse", "pixel_loss_test")
            )
            + f" | {', '.join(sorted(set(g['source'])))} |"
        )
    return "\n".join(lines)


def lines(results_dir, profile: str | None) -> list[str]:
    """Every diagnosis's table the folder stores for ``profile``, or how to make it."""
    out = []
    for a in ABLATIONS:
        d = read(a, results_dir, profile)
        out += [
            "",
            summary(a, d) if d is not None else f"(No `{a.file}`: `python -m bench {a.command}`.)",
        ]
    return out
