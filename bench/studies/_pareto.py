"""Pareto fronts and seed aggregation of a runs table in (cost, error): pure functions."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from ..core import aggregate, field_names

__all__ = ["COSTS", "ERROR", "aggregate_seeds", "cheapest_within", "pareto_front"]

COSTS = ("rollout_seconds_per_traj", "nfe", "train_seconds")
ERROR = "rollout_error"


def pareto_front(df: pd.DataFrame, cost: str, error: str = ERROR) -> pd.DataFrame:
    """The rows of ``df`` that no other row dominates in (cost, error), sorted by cost.

    Row a dominates b when cost_a <= cost_b and error_a <= error_b with one strictly smaller.
    Rows with a missing or non-finite cost or error are ignored; of exact duplicates in
    (cost, error) the first is kept.
    """
    for col in (cost, error):
        if col not in df.columns:
            raise ValueError(f"unknown column {col!r}; columns: {', '.join(map(str, df.columns))}")
    c = pd.to_numeric(df[cost], errors="coerce")
    e = pd.to_numeric(df[error], errors="coerce")
    ok = np.isfinite(c) & np.isfinite(e)
    d = df[ok].assign(_c=c[ok], _e=e[ok])
    d = d.sort_values(["_c", "_e"], kind="mergesort")
    keep, best = [], np.inf
    for idx, err in zip(d.index, d["_e"], strict=True):
        if err < best:  # cheapest-first: a row survives only by beating every cheaper one
            keep.append(idx)
            best = err
    return d.loc[keep].drop(columns=["_c", "_e"])


def aggregate_seeds(df: pd.DataFrame, error: str = ERROR, costs: Sequence[str] = COSTS):
    """One row per configuration (every RunConfig field but ``seed``) over its ``ok`` runs,
    from the seed aggregation (:func:`bench.core._query.aggregate`).

    ``error``: geometric mean over seeds (errors are compared on a log scale); costs: mean;
    ``n_seeds``: how many ok runs entered; ``diverged``: how many runs did not end ``ok``.
    """
    keys = [f for f in field_names() if f != "seed" and f in df.columns]
    if not len(df):
        return df.copy()
    d = df.copy()
    for col in keys:  # tuples and None group badly: group on their text
        d[col] = d[col].map(lambda v: v if isinstance(v, int | float | str | bool) else str(v))
    status = d["status"] if "status" in d else pd.Series("ok", index=d.index)
    ok = status == "ok"
    x = pd.to_numeric(d[error], errors="coerce")
    d["_error"] = x.where(ok & np.isfinite(x) & (x > 0))  # only ok runs with a usable error
    d["_diverged"] = (~ok).astype(float)

    def agg(column: str) -> pd.DataFrame:
        return aggregate(d, keys, column, bootstrap=False, sort=False)

    err = agg("_error")
    out = err[keys].copy()
    out[error] = err["gmean"]
    for col in costs:
        if col in d:
            d["_cost"] = pd.to_numeric(d[col], errors="coerce").where(ok)
            out[col] = agg("_cost")["mean"]
    out["n_seeds"] = err["n"]
    div = agg("_diverged")  # mean of the 0/1 flags over all the runs of the configuration
    out["diverged"] = (div["mean"] * div["n"]).round().astype(int)
    return out


def cheapest_within(
    df: pd.DataFrame,
    cost: str,
    error: str = ERROR,
    tolerance: float = 0.1,
    by: Sequence[str] = ("system", "k"),
) -> pd.DataFrame:
    """Per scene (group of ``by``), the cheapest row whose error <= (1 + tolerance) * best.

    ``best`` is the smallest finite error of the scene. The result has the chosen row's
    columns plus ``best_error`` and ``error_ratio`` (its error / best). Ties in cost go to the
    smaller error.
    """
    if not (np.isfinite(tolerance) and tolerance >= 0):
        raise ValueError(f"tolerance must be a finite number >= 0; got {tolerance!r}")
    for col in (cost, error, *by):
        if col not in df.columns:
            raise ValueError(f"unknown column {col!r}; columns: {', '.join(map(str, df.columns))}")
    c = pd.to_numeric(df[cost], errors="coerce")
    e = pd.to_numeric(df[error], errors="coerce")
    ok = np.isfinite(c) & np.isfinite(e)
    d = df[ok].assign(_c=c[ok], _e=e[ok])
    out = []
    for _, g in d.groupby(list(by), dropna=False, sort=True):
        best = g["_e"].min()
        cand = g[g["_e"] <= (1.0 + tolerance) * best]
        pick = cand.sort_values(["_c", "_e"], kind="mergesort").iloc[0]
        rec = pick.drop(labels=["_c", "_e"]).to_dict()
        rec["best_error"] = float(best)
        rec["error_ratio"] = float(pick["_e"] / best) if best > 0 else 1.0
        out.append(rec)
    return pd.DataFrame(out)
