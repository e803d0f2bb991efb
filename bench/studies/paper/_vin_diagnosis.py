"""Why the latent VIN does not learn the pixel pendulum (claim 12): the auxiliary latent loss,
on and off (``python -m bench diagnose-vin --profile paper-core``; ``vin_diagnosis.csv`` in the
results folder).

The pixel protocol (``bench/core/_pixels.py``) trains every latent model with the HNN seed's
auxiliary loss cc = mean (dw_i - (w_{i+1} - w_i))^2 on the latent state z = (w, dw): it makes
the second half of the latent a forward difference of the first. The VIN's velocity-Verlet step
(unit latent step, mass matrix M, learned potential U) predicts instead

    w_{i+1} - w_i = dw_i - 1/2 M^-1 grad U(w_i),

so cc and the dynamics loss hold together only where the learned force vanishes: the loss asks
the VIN for a pendulum without gravity. The HNN and the ResNet have no such identity between
their state and its difference. The VIN seed itself encodes positions only (no cc).

The diagnosis trains the claim-12 VIN of each seed again with cc's weight 0, everything else as
the protocol, and sets it beside the protocol's own VIN (cc weight 1) and ResNet. The protocol's
runs are read from the folder's stored rows where they are there (the campaign's runs), else
trained here. ``train_seconds`` of a row trained here is the wall clock of its training, compile
included (a stored run's excludes the compile). ``pixel_loss_test`` is the protocol's loss (cc
weight 1) for every row, the ablation's included: it charges the ablation for a term it was not
trained on; the pixel MSEs compare alike. Every number comes from trained models; none is typed in.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np
import pandas as pd

from ...core._experiments import expand
from ...core._pixel_eval import evaluate_pixels
from ...core._pixels import CC_LOSS, build, train_pixels
from ...core._store import read_rows
from ._plot import _gmean as _gm

FILE = "vin_diagnosis.csv"
EXPERIMENT = "pixel_pendulum_vin"
WEIGHTS = (CC_LOSS, 0.0)  # the protocol's auxiliary weight, and none
PROFILES = ("smoke", "quick", "paper-core")
COLUMNS = (
    "pixel_mse",
    "pixel_mse_late",
    "pixel_mse_static",
    "recon_mse",
    "pixel_loss_test",
    "decoded_energy_mse",
    "latent_energy_drift",
    "final_loss",
    "train_seconds",
)


def _run(c, aux_weight: float) -> dict:
    """Train and evaluate one pixel run with the auxiliary weight ``aux_weight``."""
    system, data, model = build(c)
    t0 = time.perf_counter()
    model, meta = train_pixels(c, model, data, aux_weight=aux_weight)
    seconds = time.perf_counter() - t0
    metrics, _ = evaluate_pixels(c, system, data, model)
    return {**metrics, "final_loss": meta["final_loss"], "train_seconds": seconds}


def diagnose(profile: str, results_dir, seeds=None, progress: bool = True) -> pd.DataFrame:
    """One row per (model, seed, auxiliary weight): the VIN at both weights, the ResNet at the
    protocol's; written to ``results_dir / FILE``."""
    if profile not in PROFILES:
        allowed = ", ".join(PROFILES)
        raise ValueError(f"diagnose-vin: profile must be one of {allowed}, got {profile!r}")
    results_dir = Path(results_dir)
    configs = expand(EXPERIMENT, profile, seeds=seeds)
    if not configs:
        raise ValueError(f"diagnose-vin: {EXPERIMENT} has no runs at profile {profile!r}")
    # the protocol's own runs, where the folder stores them (read, not retrained)
    stored = {r["config_hash"]: r for r in read_rows(results_dir) if r.get("status") == "ok"}
    rows = []
    for c in configs:
        for w in WEIGHTS if c.model == "vin" else WEIGHTS[:1]:
            if w == CC_LOSS and c.config_hash in stored:
                r, source = stored[c.config_hash], "stored run"
                values = {k: r.get(k) for k in COLUMNS}
            else:
                if progress:
                    print(f"diagnose-vin: {c.model} seed {c.seed}, aux weight {w:g}", flush=True)
                values, source = _run(c, w), "trained here"
            rows.append(
                {
                    "profile": profile,
                    "model": c.model,
                    "seed": c.seed,
                    "aux_weight": w,
                    "source": source,
                    "config_hash": c.config_hash,
                    **{k: _num(values.get(k)) for k in COLUMNS},
                }
            )
    df = pd.DataFrame(rows)
    results_dir.mkdir(parents=True, exist_ok=True)
    df.to_csv(results_dir / FILE, index=False)
    return df


def _num(x) -> float:
    """A stored value as a float (None, a missing value: NaN)."""
    try:
        return float(x)
    except (TypeError, ValueError):
        return math.nan


def summary(df: pd.DataFrame) -> str:
    """The diagnosis as a markdown table: per model and weight, the geometric-mean pixel MSE,
    how many seeds learn the motion (pixel MSE 2x below holding the first frame, claim 12's
    gate), and the per-seed ratio to holding the first frame."""

    def f(x):
        return "-" if not np.isfinite(x) else f"{x:.3g}"

    lines = [
        "VIN diagnosis (`python -m bench diagnose-vin`): the HNN seed's auxiliary latent loss "
        "ties the VIN's velocity to a forward difference its Verlet step contradicts; the VIN "
        "trained again without it (aux weight 0), beside the protocol's VIN and ResNet "
        "(geometric means over seeds; learned: pixel MSE 2x below holding the first frame).",
        "",
        "| model | aux weight | seeds | learned | pixel MSE | late pixel MSE | static / pixel MSE "
        "per seed | decoded energy MSE | test loss (the seed's, cc included) | source |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for (model, w), g in df.groupby(["model", "aux_weight"], sort=False):
        gain = pd.to_numeric(g["pixel_mse_static"]) / pd.to_numeric(g["pixel_mse"])
        learned = int((gain > 2).sum())
        per_seed = ", ".join(f"{s}: {x:.3g}" for s, x in zip(g["seed"], gain, strict=True))
        lines.append(
            f"| {model} | {w:g} | {g['seed'].nunique()} | {learned} of {len(g)} | "
            f"{f(_gm(g['pixel_mse']))} | {f(_gm(g['pixel_mse_late']))} | {per_seed} | "
            f"{f(_gm(g['decoded_energy_mse']))} | {f(_gm(g['pixel_loss_test']))} | "
            f"{', '.join(sorted(set(g['source'])))} |"
        )
    return "\n".join(lines)
