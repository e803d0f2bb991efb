"""Verdicts along the learning curve: every claim judged again at each training checkpoint.

The runs table at checkpoint i is the runs table with every trained run's scores, status and
training seconds replaced by those of its i-th checkpoint (trivial predictors keep theirs); each
claim's own rule judges it. A verdict's settling budget is the first checkpoint from which it no
longer changes.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

import models

from ..core import CHECKPOINT_METRICS as SCORES  # what a checkpoint replaces
from ..kit import claim_studies, evaluate_claims, restrict

__all__ = [
    "along_row",
    "curves_at",
    "runs_at",
    "settling",
    "settling_table",
    "is_trained",
    "verdicts_along_curve",
]


def is_trained(runs: pd.DataFrame) -> pd.Series:
    known = set(models.available())
    return runs["model"].map(lambda m: not (m in known and models.spec(m).trivial))


def runs_at(
    runs: pd.DataFrame, checkpoints: pd.DataFrame, position: int
) -> tuple[pd.DataFrame, set]:
    """(the runs table at checkpoint ``position`` counted from each run's first, the
    config hashes of trained runs that have no such checkpoint and were dropped)."""
    out = runs.copy()
    trained = is_trained(out)
    cp = checkpoints[checkpoints["config_hash"].isin(out["config_hash"])]
    cp = cp.sort_values(["config_hash", "step"])
    at = cp.groupby("config_hash").nth(position) if len(cp) else cp
    at = at.set_index("config_hash") if len(at) else at
    has = out["config_hash"].isin(at.index) if len(at) else pd.Series(False, index=out.index)
    missing = set(out.loc[trained & ~has, "config_hash"])
    out = out[~trained | has].copy()
    rows = out["config_hash"].isin(at.index) if len(at) else pd.Series(False, index=out.index)
    if rows.any():
        src = at.loc[out.loc[rows, "config_hash"]]
        for col in (*SCORES, "status", "train_seconds"):
            if col in src.columns:
                out.loc[rows, col] = src[col].to_numpy()
        out.loc[rows, "checkpoint_step"] = src["step"].to_numpy()
    return out.reset_index(drop=True), missing


def curves_at(curves: pd.DataFrame, cp_curves: pd.DataFrame, runs_i: pd.DataFrame) -> pd.DataFrame:
    """Per-time curves of ``runs_i`` (a :func:`runs_at` table): a trained run's at its
    checkpoint step, a trivial predictor's own."""
    if "checkpoint_step" not in runs_i:
        return curves
    steps = runs_i.dropna(subset=["checkpoint_step"])[["config_hash", "checkpoint_step"]]
    parts = []
    if len(steps) and len(cp_curves):
        keyed = cp_curves.merge(
            steps.rename(columns={"checkpoint_step": "step"}).astype({"step": int}),
            on=["config_hash", "step"],
        )
        parts.append(keyed.drop(columns=["step"]))
    rest = runs_i.loc[runs_i["checkpoint_step"].isna(), "config_hash"]
    if len(curves):
        parts.append(curves[curves["config_hash"].isin(rest)])
    return pd.concat(parts, ignore_index=True) if parts else curves.iloc[0:0]


def settling(verdicts) -> int:
    """The first index from which ``verdicts`` no longer change (``len - 1`` when the last one
    differs from the one before; 0 when all agree)."""
    verdicts = list(verdicts)
    i = len(verdicts) - 1
    while i > 0 and verdicts[i - 1] == verdicts[-1]:
        i -= 1
    return max(i, 0)


def along_row(v, position: int, n: int, steps: pd.Series) -> dict:
    """One row of a verdicts-along-the-curve table: verdict ``v`` at checkpoint ``position``
    of ``n`` (nominal fraction 2^(position - n + 1)), at the median of ``steps``."""
    return {
        "key": v.key,
        "claim": v.claim,
        "position": position,
        "fraction": 2.0 ** (position - n + 1),
        "step": float(np.nanmedian(steps)) if len(steps) else math.nan,
        "verdict": v.verdict,
        "effect": v.effect,
    }


def verdicts_along_curve(
    runs: pd.DataFrame,
    curves: pd.DataFrame,
    checkpoints: pd.DataFrame,
    cp_curves: pd.DataFrame,
    profile: str | None,
) -> pd.DataFrame:
    """One row per (verdict, checkpoint): key, claim, position, fraction (nominal, of the
    budget), step (median over the claim's trained runs; NaN where they train for different
    numbers of steps), verdict, effect. Claims whose trained
    runs lack checkpoints are left out. Empty when no run has checkpoints. At a checkpoint a
    run has its checkpoint metrics (:data:`SCORES`); what a run records only at its end (the
    achieved symplectic error of claim 2) stays the final value."""
    cols = ["key", "claim", "position", "fraction", "step", "verdict", "effect"]
    if not len(checkpoints) or not len(runs):
        return pd.DataFrame(columns=cols)
    cp = checkpoints[checkpoints["config_hash"].isin(runs["config_hash"])]
    if not len(cp):
        return pd.DataFrame(columns=cols)
    n = int(cp.groupby("config_hash").size().max())
    judged = {}
    for study in claim_studies():
        mine = restrict(runs, study, profile)
        if not len(mine):
            continue
        hashes = set(mine.loc[is_trained(mine), "config_hash"])
        per_run = cp[cp["config_hash"].isin(hashes)].groupby("config_hash").size()
        if hashes and len(per_run) == len(hashes) and (per_run == n).all():
            judged[study.claim] = hashes
    # a claim whose runs train for different numbers of steps (claim 7: two protocols, one per
    # reading) has no one step per checkpoint: its rows give the fraction only (step NaN)
    budgets = {
        c: runs.loc[runs["config_hash"].isin(h), "steps"].nunique() for c, h in judged.items()
    }
    out = []
    for position in range(n):
        runs_i, _ = runs_at(runs, cp, position)
        curves_i = curves_at(curves, cp_curves, runs_i)
        for v in evaluate_claims(runs_i, curves_i, profile):
            if v.claim not in judged:
                continue
            steps = runs_i.loc[runs_i["config_hash"].isin(judged[v.claim]), "checkpoint_step"]
            if budgets[v.claim] > 1:
                steps = steps.iloc[0:0]  # no one step: NaN
            out.append(along_row(v, position, n, steps))
    return pd.DataFrame(out, columns=cols)


def settling_table(along: pd.DataFrame) -> pd.DataFrame:
    """Per verdict key: the verdict at each checkpoint, the settling step and whether the
    verdict changed at the last checkpoint (``settled`` False)."""
    rows = []
    for key, g in along.groupby("key", sort=False):
        g = g.sort_values("position")
        i = settling(g["verdict"])
        rows.append(
            {
                "key": key,
                "claim": int(g["claim"].iloc[0]),
                "verdicts": list(g["verdict"]),
                "steps": list(g["step"]),
                "settles_at": float(g["step"].iloc[i]),
                "settles_fraction": float(g["fraction"].iloc[i]),
                "settled": bool(len(g) == 1 or i < len(g) - 1),
            }
        )
    return pd.DataFrame(rows)
