"""Verdicts on the eight claims of REFERENCE.md, computed from the stored runs.

Every claim is a function ``claim_N(runs, curves=None) -> Verdict`` (claim 4: a list, one
verdict per metric and spring initial state). The runs table is the store's
``results/runs.parquet`` (one row per run: every ``RunConfig`` field and the metrics); the curves
table is ``results/curves.parquet`` (``config_hash, t, rel_error, energy_violation``).

Rules shared by all claims:

* Failed and diverged runs are never dropped: a run whose ``status`` is not ``"ok"`` or whose
  metric is not finite scores the worst error, 1 (the relative error of predicting nothing; for
  metrics without that bound, the worst finite value of the table, at least 1). Every verdict
  counts them (``n_failed``) and the report lists them.
* Comparisons are paired by seed: for two cells A and B (same system, k, ..., different model),
  the per-seed effect is ``d_s = log(err_A,s / err_B,s)``, and the seeds that have both cells are
  the sample. The effect is ``mean_s d_s`` and its 95% interval is a percentile bootstrap over
  seeds (``scipy.stats.bootstrap``, 2000 resamples, fixed generator). With 3 seeds that interval
  is about ``[min_s d_s, max_s d_s]``: "significant" then means every seed agrees.
* A *positive* part ("A is worse than B", an effect expected to be > 0) holds when
  ``ci_low > 0``, contradicts when ``ci_high < delta`` (any effect there is below the smallest
  ratio that matters, ``exp(delta)``), and is undecided otherwise.
* A *null* part ("no real gain") holds when ``ci_high < delta`` (a meaningful gain is ruled out),
  contradicts when ``ci_low > 0`` and the mean exceeds ``delta`` (a significant, meaningful gain),
  and is undecided otherwise.
* Trivial predictors (issue 10). Every experiment runs ``constant_velocity`` (and ``at_rest`` in
  damped scenes) on the same test trajectories; only finished trivial runs count. A model
  *succeeds* when it beats the best trivial predictor by :data:`TRIVIAL_FACTOR` (2x) on every
  seed. An experiment whose best model does not is *not discriminating*: the test set cannot
  tell a model that works from one that does not, and the verdict is "inconclusive" whatever
  its parts say. Factor 2: the paper's effects are factors of 1.25 to 10; a model within 2x of
  holding the velocity fixed has learned little that the test window can show. Without
  finished trivial-predictor runs (results older than issue 10) discrimination is "unknown"
  and the verdict stands, flagged.
* The verdict is one of :data:`VERDICTS`: "reproduced" when every part holds; "partly
  reproduced" when some parts hold and others are contradicted; "not reproduced" when parts are
  contradicted and none holds; "inconclusive" otherwise (undecided parts), with fewer than two
  seeds, or when the experiment is not discriminating. Each carries its effect, interval, seeds,
  profile and the count of failed runs.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import stats

from ...core._query import initial_state, option, select

__all__ = [
    "MODEL_LABELS",
    "TRIVIAL_FACTOR",
    "VERDICTS",
    "Verdict",
    "scored",
]

REPRODUCED = "reproduced"
PARTLY = "partly reproduced"
NOT_REPRODUCED = "not reproduced"
INCONCLUSIVE = "inconclusive"
VERDICTS = (REPRODUCED, PARTLY, NOT_REPRODUCED, INCONCLUSIVE)

# Smallest error ratio that "matters": log(1.25). Chosen before looking at results; the paper's
# headline effects (Figs. 4-6) are factors of 2 to 10.
DELTA = math.log(1.25)
# Energy violations and "matching" are judged at a factor of 2.
DELTA_2 = math.log(2.0)
# A model succeeds when it beats the best trivial predictor by this factor on every seed.
TRIVIAL_FACTOR = 2.0
# The score of a failed or diverged run (relative errors are ~1 for a prediction of nothing).
WORST_ERROR = 1.0

MODEL_LABELS = {
    "node": "NODE",
    "node_so": "NODE+SO",
    "hnn": "HNN",
    "hnn_so": "HNN+SO",
    "hnn_so_diss": "HNN+SO + Rayleigh dissipation",
    "mixture_hnn": "mixture HNN (paper's damped HNN)",
    "node_symreg": "NODE + symplectic reg.",
    "node_so_symreg": "NODE+SO + symplectic reg.",
    "lnn": "LNN",
    "vin": "VIN",
    "resnet": "ResNet",
    "constant_velocity": "constant velocity (trivial)",
    "at_rest": "at rest (trivial)",
}


@dataclass(frozen=True)
class Verdict:
    """The outcome of one claim: ``effect`` (meaning in ``effect_name``) with its 95% CI.

    ``variant`` names a sub-verdict (claim 4: metric and spring initial state); ``discriminating``
    is True/False, or None when no trivial-predictor runs exist; ``n_failed`` counts the runs
    scored as the worst error."""

    claim: int
    title: str
    verdict: str
    effect: float
    ci_low: float
    ci_high: float
    n_seeds: int
    detail: str
    effect_name: str = ""
    variant: str = ""
    profile: str | None = None
    n_failed: int = 0
    discriminating: bool | None = None

    @property
    def key(self) -> str:
        return f"{self.claim}" + (f" ({self.variant})" if self.variant else "")

    def as_row(self) -> dict:
        return {
            "claim": self.claim,
            "variant": self.variant,
            "title": self.title,
            "verdict": self.verdict,
            "effect": self.effect,
            "effect_name": self.effect_name,
            "ci_low": self.ci_low,
            "ci_high": self.ci_high,
            "n_seeds": self.n_seeds,
            "profile": self.profile,
            "n_failed": self.n_failed,
            "discriminating": self.discriminating,
            "detail": self.detail,
        }


# ----------------------------------------------------------------------------- table helpers


def _paper_spring(runs: pd.DataFrame) -> pd.DataFrame:
    """Drop the spring rows that are not the paper figures' cells: the paper's initial state
    where any spring row has it, else (older results) the equilibrium rows as they are."""
    spring = runs["system"] == "spring_pendulum" if "system" in runs else None
    if spring is None or not spring.any():
        return runs
    init = initial_state(runs)
    if (init[spring] == "paper").any():
        return runs[~spring | (init == "paper")]
    return runs


def _bad(runs: pd.DataFrame, metric: str = "rollout_error") -> pd.Series:
    """Rows that did not finish or whose ``metric`` is not a finite positive number."""
    x = pd.to_numeric(runs[metric], errors="coerce") if metric in runs else None
    bad = pd.Series(True, index=runs.index) if x is None else ~(np.isfinite(x) & (x > 0))
    if "status" in runs:
        bad |= runs["status"] != "ok"
    return bad


def scored(runs: pd.DataFrame, metric: str = "rollout_error") -> pd.Series:
    """``metric`` per row, failed and diverged rows (and non-finite values) set to the worst
    error: 1 for the relative rollout errors, else the worst finite value of the table (>= 1)."""
    if metric not in runs:
        return pd.Series(np.nan, index=runs.index)
    x = pd.to_numeric(runs[metric], errors="coerce").astype(float)
    bad = _bad(runs, metric)
    if metric.startswith("rollout_error"):
        worst = WORST_ERROR
    else:
        good = x[~bad]
        worst = max(1.0, float(good.max())) if len(good) else 1.0
    return x.where(~bad, worst)


def _n_bad(runs: pd.DataFrame) -> int:
    return int(_bad(runs).sum()) if len(runs) else 0


def _boot(values: np.ndarray, stat: Callable | None = None) -> tuple[float, float, float]:
    """(point, ci_low, ci_high): mean (or ``stat`` of an index sample) with a seed bootstrap."""
    values = np.asarray(values, dtype=float)
    n = len(values)
    if stat is None:
        point = float(np.mean(values)) if n else math.nan
        if n < 2:
            return point, math.nan, math.nan
        if np.ptp(values) == 0:
            return point, point, point
        res = stats.bootstrap(
            (values,),
            np.mean,
            n_resamples=2000,
            method="percentile",
            rng=np.random.default_rng(0),
        )
        return point, float(res.confidence_interval.low), float(res.confidence_interval.high)
    idx = np.arange(n, dtype=float)
    point = float(stat(idx.astype(int)))
    if n < 2:
        return point, math.nan, math.nan
    res = stats.bootstrap(
        (idx,),
        lambda s: stat(np.asarray(s).astype(int)),
        n_resamples=999,
        method="percentile",
        vectorized=False,
        rng=np.random.default_rng(0),
    )
    lo, hi = float(res.confidence_interval.low), float(res.confidence_interval.high)
    if not np.isfinite(lo):  # a degenerate bootstrap distribution (all resamples equal)
        lo = hi = point
    return point, lo, hi


def _cell(runs: pd.DataFrame, cell: Mapping) -> pd.DataFrame:
    """Rows of one cell (failed rows kept). Keys ``opt:<name>`` match a model option."""
    fields = {k: v for k, v in cell.items() if not k.startswith("opt:")}
    out = select(runs, ok=False, **fields)
    for k, v in cell.items():
        if k.startswith("opt:"):
            o = option(out, k[4:])
            out = out[o.isna()] if v is None else out[o.map(lambda x, v=v: x == v)]
    return out


def _log_per_seed(runs: pd.DataFrame, cell: Mapping, metric: str = "rollout_error") -> pd.Series:
    """Per-seed mean log score of one cell (failed runs at the worst error)."""
    r = _cell(runs, cell)
    if not len(r):
        return pd.Series(dtype=float)
    s = np.log(scored(r, metric))
    return s.groupby(r["seed"]).mean().dropna()


def _paired(runs: pd.DataFrame, a: Mapping, b: Mapping, metric: str = "rollout_error") -> pd.Series:
    """Per-seed ``log(metric_A / metric_B)`` over the seeds that have both cells."""
    d = (_log_per_seed(runs, a, metric) - _log_per_seed(runs, b, metric)).dropna()
    return d[np.isfinite(d)]


@dataclass
class _Part:
    name: str
    status: str  # "holds" | "contradicts" | "undecided"
    point: float
    lo: float
    hi: float
    n: int
    note: str = ""
    extra: dict = field(default_factory=dict)

    def text(self) -> str:
        ci = f"[{self.lo:.3g}, {self.hi:.3g}]" if np.isfinite(self.lo) else "[n/a]"
        s = f"{self.name}: {self.point:.3g} {ci}, n={self.n} -> {self.status}"
        return s + (f" ({self.note})" if self.note else "")


def _positive(name: str, d: Iterable[float] | tuple, delta: float = DELTA, note="") -> _Part:
    point, lo, hi = d if isinstance(d, tuple) else _boot(np.asarray(list(d), dtype=float))
    n = -1 if isinstance(d, tuple) else len(list(d))
    if not np.isfinite(point) or not np.isfinite(lo):
        status = "undecided"
    elif lo > 0:
        status = "holds"
    elif hi < delta:
        status = "contradicts"
    else:
        status = "undecided"
    return _Part(name, status, point, lo, hi, n, note)


def _null(name: str, d, delta: float = DELTA, note="") -> _Part:
    point, lo, hi = d if isinstance(d, tuple) else _boot(np.asarray(list(d), dtype=float))
    n = -1 if isinstance(d, tuple) else len(list(d))
    if not np.isfinite(point) or not np.isfinite(lo):
        status = "undecided"
    elif lo > 0 and point > delta:
        status = "contradicts"
    elif hi < delta:
        status = "holds"
    else:
        status = "undecided"
    return _Part(name, status, point, lo, hi, n, note)


def _threshold(name: str, values, threshold: float, note: str = "") -> _Part:
    """Holds when the CI lies above ``threshold``, contradicts when below, else undecided."""
    values = np.asarray(list(values), dtype=float)
    point, lo, hi = _boot(values)
    if len(values) < 2 or not np.isfinite(lo):
        status = "undecided"
    elif lo > threshold:
        status = "holds"
    elif hi < threshold:
        status = "contradicts"
    else:
        status = "undecided"
    return _Part(name, status, point, lo, hi, len(values), note)
