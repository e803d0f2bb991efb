"""Per-seed values of a results table: scores, cells, paired log ratios and curve slopes.

Failed and diverged runs are scored, never dropped: the worst error, 1 for relative rollout
errors (a prediction of nothing), else the table's worst finite value (at least 1).
"""

from __future__ import annotations

import contextlib
import contextvars
from collections.abc import Mapping

import numpy as np
import pandas as pd

from ..core import SELECTIONS, initial_state, option, profile_defaults, replication_seeds, select

__all__ = [
    "BOUNDED_SLOPE",
    "LINEAR_SLOPE",
    "MIN_SEEDS",
    "WORST_ERROR",
    "at_lr",
    "bad_rows",
    "cell_rows",
    "curve_slopes",
    "log_per_seed",
    "min_seeds",
    "n_bad",
    "paired",
    "paper_spring",
    "required_seeds",
    "scored",
    "seed_sets",
    "seed_span",
]

# The fewest paired seeds that give a verdict.


MIN_SEEDS = 5

_MIN_SEEDS = contextvars.ContextVar("min_seeds", default=MIN_SEEDS)


@contextlib.contextmanager
def min_seeds(n: int):
    """Within the block, a verdict needs ``n`` paired seeds (the leave-one-seed-out check
    judges 4 of 5 seeds with the same rules)."""
    token = _MIN_SEEDS.set(int(n))
    try:
        yield
    finally:
        _MIN_SEEDS.reset(token)


def required_seeds() -> int:
    return _MIN_SEEDS.get()


# The score of a failed or diverged run (relative errors are ~1 for a prediction of nothing).
WORST_ERROR = 1.0


def paper_spring(runs: pd.DataFrame) -> pd.DataFrame:
    """Drop the spring rows that are not the paper figures' cells: the paper's initial state
    where any spring row has it, else (older results) the equilibrium rows as they are."""
    spring = runs["system"] == "spring_pendulum" if "system" in runs else None
    if spring is None or not spring.any():
        return runs
    init = initial_state(runs)
    if (init[spring] == "paper").any():
        return runs[~spring | (init == "paper")]
    return runs


def _values(runs: pd.DataFrame, metric: str) -> np.ndarray | None:
    """``metric`` per row as floats (NaN where it is not a number); None without the column."""
    if metric not in runs:
        return None
    return pd.to_numeric(runs[metric], errors="coerce").to_numpy(dtype=float, na_value=np.nan)


def _bad(runs: pd.DataFrame, x: np.ndarray | None) -> np.ndarray:
    """:func:`bad_rows` as an array, given the metric's values ``x`` (:func:`_values`)."""
    bad = np.ones(len(runs), dtype=bool) if x is None else ~(np.isfinite(x) & (x > 0))
    if "status" in runs:
        bad |= (runs["status"] != "ok").to_numpy(dtype=bool)
    return bad


def bad_rows(runs: pd.DataFrame, metric: str = "rollout_error") -> pd.Series:
    """Rows that did not finish or whose ``metric`` is not a finite positive number."""
    x = _values(runs, metric)
    return pd.Series(_bad(runs, x), index=runs.index, name=None if x is None else metric)


def _worst(metric: str, good: np.ndarray) -> float:
    """The score of a failed run: 1 for the relative rollout errors, else the worst of the
    finite ``good`` values (at least 1)."""
    if metric.startswith("rollout_error"):
        return WORST_ERROR
    return max(1.0, float(good.max())) if len(good) else 1.0


def scored(runs: pd.DataFrame, metric: str = "rollout_error") -> pd.Series:
    """``metric`` per row, failed and diverged rows (and non-finite values) set to the worst
    error: 1 for the relative rollout errors, else the worst finite value of the table (>= 1)."""
    x = _values(runs, metric)
    if x is None:
        return pd.Series(np.nan, index=runs.index)
    bad = _bad(runs, x)
    return pd.Series(np.where(bad, _worst(metric, x[~bad]), x), index=runs.index, name=metric)


def velocity_scores(runs: pd.DataFrame, metric: str = "rollout_error") -> tuple[pd.Series, str]:
    """Scores on (q, qdot), as claim 7 reads them: ``metric`` for velocity runs,
    ``<metric>_velocity`` (the prediction decoded to velocities) for momentum runs; failed runs
    at the worst error.
    Returns (scores, note); rows from before the velocity column fall back to ``metric``."""
    s = scored(runs, metric)
    mom = runs["coordinates"] == "momentum" if len(runs) else pd.Series(dtype=bool)
    col = f"{metric}_velocity"
    note = ""
    if mom.any():
        if col in runs and pd.to_numeric(runs.loc[mom, col], errors="coerce").notna().any():
            s = s.where(~mom, scored(runs, col))
        else:
            note = f"no {col} column: the (q, p) HNN is scored in (q, p)"
    return s, note


def n_bad(runs: pd.DataFrame) -> int:
    return int(bad_rows(runs).sum()) if len(runs) else 0


def at_lr(rows: pd.DataFrame, lr: float) -> pd.DataFrame:
    """The rows trained at learning rate ``lr`` (all of them where the table has no ``lr``)."""
    if not len(rows) or "lr" not in rows:
        return rows
    return rows[np.isclose(pd.to_numeric(rows["lr"], errors="coerce"), lr, rtol=1e-9)]


def cell_rows(runs: pd.DataFrame, cell: Mapping) -> pd.DataFrame:
    """Rows of one cell (failed rows kept). Keys ``opt:<name>`` match a model option."""
    fields = {k: v for k, v in cell.items() if not k.startswith("opt:")}
    out = select(runs, ok=False, **fields)
    for k, v in cell.items():
        if k.startswith("opt:"):
            o = option(out, k[4:])
            out = out[o.isna()] if v is None else out[o.map(lambda x, v=v: x == v)]
    return out


def log_per_seed(runs: pd.DataFrame, cell: Mapping, metric: str = "rollout_error") -> pd.Series:
    """Per-seed mean log score of one cell (failed runs at the worst error)."""
    r = cell_rows(runs, cell)
    if not len(r):
        return pd.Series(dtype=float)
    s = np.log(scored(r, metric))
    return s.groupby(r["seed"]).mean().dropna()


def paired(runs: pd.DataFrame, a: Mapping, b: Mapping, metric: str = "rollout_error") -> pd.Series:
    """Per-seed ``log(metric_A / metric_B)`` over the seeds that have both cells."""
    d = (log_per_seed(runs, a, metric) - log_per_seed(runs, b, metric)).dropna()
    return d[np.isfinite(d)]


# Claim 1 (b) and claim 8 (c): slopes of log EV against log t over the late half of the horizon.
# Linear growth has slope 1, a bounded oscillation 0; the tolerance around them is the policy's
# slope margin (0.5: a random walk, sqrt t, lies half-way between the two).
LINEAR_SLOPE = 1.0

BOUNDED_SLOPE = 0.0


def curve_slopes(runs: pd.DataFrame, curves: pd.DataFrame | None, t_min_frac: float = 0.0):
    """Per-run least-squares slope of log(energy_violation) vs log(t), t > t_min_frac * t_max."""
    cols = ["config_hash", "seed", "model", "slope"]
    if curves is None or not len(curves) or not len(runs):
        return pd.DataFrame(columns=cols)
    c = curves[curves["config_hash"].isin(runs["config_hash"])]
    run = runs.drop_duplicates("config_hash").set_index("config_hash")  # one row per run
    rows = []
    for h, g in c.groupby("config_hash"):
        t = g["t"].to_numpy(float)
        ev = g["energy_violation"].to_numpy(float)
        keep = (t > t_min_frac * t.max()) & (t > 0) & np.isfinite(ev) & (ev > 0)
        if keep.sum() < 3:
            continue
        slope = np.polyfit(np.log(t[keep]), np.log(ev[keep]), 1)[0]
        seed, model = run.at[h, "seed"], run.at[h, "model"]
        rows.append({"config_hash": h, "seed": seed, "model": model, "slope": slope})
    return pd.DataFrame(rows, columns=cols)


def seed_sets(profile: str | None) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """(primary seeds, replication seeds) of a profile (a selection: its base profile's)."""
    if profile is None:
        return (), ()
    base = SELECTIONS.get(profile, profile)
    try:
        primary = profile_defaults(base)[1]
    except ValueError:
        return (), ()
    return tuple(primary), replication_seeds(base)


def seed_span(seeds) -> str:
    seeds = sorted(seeds)
    if seeds and seeds == list(range(seeds[0], seeds[-1] + 1)) and len(seeds) > 2:
        return f"{seeds[0]}-{seeds[-1]}"
    return ", ".join(map(str, seeds))
