"""Verdicts on the eight claims of REFERENCE.md, computed from the stored runs.

Every claim is a function ``claim_N(runs, curves=None) -> Verdict`` (claim 4: a list, one
verdict per metric and spring initial state). The runs table is the store's
``results/runs.parquet`` (one row per run: every ``RunConfig`` field and the metrics); the curves
table is ``results/curves.parquet`` (``config_hash, t, rel_error, energy_violation``).

Rules shared by all claims (issue 20: statistics a referee can sign):

* Failed and diverged runs are never dropped: a run whose ``status`` is not ``"ok"`` or whose
  metric is not finite scores the worst error, 1 (the relative error of predicting nothing; for
  metrics without that bound, the worst finite value of the table, at least 1). Every verdict
  counts them (``n_failed``) and the report lists them.
* Comparisons are paired by seed: for two cells A and B (same system, k, ..., different model),
  the per-seed effect is ``d_s = log(err_A,s / err_B,s)``, and the seeds that have both cells are
  the sample (at least :data:`MIN_SEEDS` = 5 for a verdict).
* The test: a one-sided t test on the per-seed values at level :data:`ALPHA` = 0.05, in each
  direction that the part needs; equivalently, the part compares the one-sided 95% bounds
  ``mean -/+ t(0.95, n - 1) * sd / sqrt(n)`` (together: the two-sided 90% interval the report
  prints) with its *margin*, the smallest ratio that matters, ``delta = log(margin)``. A
  difference inside the margin is a tie, never an ordering, and no part holds by default:
  every status is the outcome of a test.
* Part kinds (``_Part.kind``):
  - *greater* ("A is worse than B", an ordering): holds when ``lo > delta`` (A is worse by more
    than the margin, p < alpha), contradicts when ``hi < delta`` (a difference of the margin is
    ruled out: a tie or the reverse), else undecided;
  - *at most* ("no gain", "no better", "matches or beats": the upper of the two one-sided tests
    of an equivalence test, because the other side also satisfies the claim: a regulariser that
    hurts gives "no gain"): holds when ``hi < delta``, contradicts when ``lo > delta``;
  - *equivalent* ("slightly", two one-sided tests, TOST): holds when ``-delta < lo`` and
    ``hi < delta``, contradicts when ``lo > delta`` or ``hi < -delta``;
  - *band* / *threshold* (slopes of energy growth, shares of a gap): the same bounds against a
    stated interval or threshold.
  Margins come from the paper's effect sizes (its headline ratios are 2x to 10x): 1.25x for
  errors (:data:`DELTA`), 2x for energy violations, "matches" and "slightly" (:data:`DELTA_2`).
* Trivial predictors (issue 10). Every experiment runs ``constant_velocity`` (and ``at_rest`` in
  damped scenes) on the same test trajectories; only finished trivial runs count. A model
  *succeeds* when it beats the best trivial predictor by :data:`TRIVIAL_FACTOR` (2x) on every
  seed. An experiment whose best model does not is *not discriminating*: the test set cannot
  tell a model that works from one that does not, and the verdict is "inconclusive" whatever
  its parts say. Without finished trivial-predictor runs discrimination is "unknown" and the
  verdict stands, flagged.
* The verdict is one of :data:`VERDICTS`: "reproduced" when every part holds; "partly
  reproduced" when some parts hold and others are contradicted; "not reproduced" when parts are
  contradicted and none holds; "inconclusive" otherwise (undecided parts), with fewer than
  :data:`MIN_SEEDS` seeds, or when the experiment is not discriminating. Each carries its
  parts, effect, interval, seeds, profile and the count of failed runs. The report judges each
  claim again on a disjoint seed set and without each seed (``bench._report``).
"""

from __future__ import annotations

import contextlib
import contextvars
import math
from collections.abc import Callable, Mapping
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
# The level of every one-sided test, and the fewest paired seeds that give a verdict.
ALPHA = 0.05
MIN_SEEDS = 5
T_TEST = "one-sided t test on paired per-seed log ratios"
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
    scored as the worst error; ``pending`` is ``(stored, declared)`` runs of the claim while a
    campaign (a selection such as ``paper-core``) has not stored them all, else None;
    ``primary`` is the verdict on the profile's own seeds where the replication checks demoted
    it to an inconclusive one, with ``readings`` the seed sets' verdicts that did
    (:func:`bench.studies.paper._replication.judge`), else None and ""."""

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
    parts: tuple = ()  # the tested parts (``_Part``), for the report's parts table
    pending: tuple[int, int] | None = None
    primary: str | None = None
    readings: str = ""

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
    """One tested part of a claim: ``point`` (the effect, a mean of per-seed values, on the log
    scale for ratios), ``lo``/``hi`` (its one-sided (1 - alpha) bounds, together the two-sided
    90% interval at alpha = 0.05), ``n`` seeds, the ``status`` its test gives, and what the
    test was: ``kind`` (see the module docstring), ``margin`` (the ratio, or the threshold or
    band on the effect's own scale when ``log_scale`` is False), ``test`` and ``alpha``."""

    name: str
    status: str  # "holds" | "contradicts" | "undecided"
    point: float
    lo: float
    hi: float
    n: int
    note: str = ""
    extra: dict = field(default_factory=dict)
    kind: str = ""
    margin: str = ""
    test: str = ""
    alpha: float = ALPHA

    def text(self) -> str:
        ci = f"[{self.lo:.3g}, {self.hi:.3g}]" if np.isfinite(self.lo) else "[n/a]"
        s = f"{self.name}: {self.point:.3g} {ci}, n={self.n} -> {self.status}"
        return s + (f" ({self.note})" if self.note else "")

    def as_row(self) -> dict:
        return {
            "part": self.name,
            "status": self.status,
            "effect": self.point,
            "lo": self.lo,
            "hi": self.hi,
            "n": self.n,
            "kind": self.kind,
            "margin": self.margin,
            "test": self.test,
            "alpha": self.alpha,
            "note": self.note,
        }


def t_bounds(values, alpha: float = ALPHA) -> tuple[float, float, float]:
    """(mean, lower, upper): the one-sided (1 - alpha) t bounds of the mean of ``values``
    (``scipy.stats.t``); NaN bounds with fewer than two values; the mean itself when they do
    not vary."""
    v = np.asarray(list(values), dtype=float)
    v = v[np.isfinite(v)]
    n = len(v)
    point = float(np.mean(v)) if n else math.nan
    if n < 2:
        return point, math.nan, math.nan
    sd = float(np.std(v, ddof=1))
    half = float(stats.t.ppf(1 - alpha, n - 1)) * sd / math.sqrt(n)
    return point, point - half, point + half


def t_bounds_jackknife(stat: Callable, n: int, alpha: float = ALPHA):
    """(point, lower, upper) of a statistic of ``n`` seeds (``stat(index array)``) with the
    leave-one-seed-out jackknife standard error and ``t(1 - alpha, n - 1)``: the bounds of a
    pooled estimate, e.g. a regression over every seed's runs."""
    idx = np.arange(n)
    point = float(stat(idx))
    if n < 2:
        return point, math.nan, math.nan
    loo = np.array([stat(np.delete(idx, i)) for i in range(n)], dtype=float)
    se = math.sqrt((n - 1) / n * float(np.sum((loo - loo.mean()) ** 2)))
    half = float(stats.t.ppf(1 - alpha, n - 1)) * se
    return point, point - half, point + half


def _bounds(d) -> tuple[float, float, float, int]:
    if isinstance(d, tuple):
        return (*d[:3], d[3] if len(d) > 3 else -1)
    values = np.asarray(list(d), dtype=float)
    return (*t_bounds(values), int(np.isfinite(values).sum()))


def _decide(lo: float, holds, contradicts) -> str:
    """A part's status from its test: undecided without bounds, else "holds" when ``holds()``,
    "contradicts" when ``contradicts()``, undecided otherwise."""
    if not np.isfinite(lo):
        return "undecided"
    if holds():
        return "holds"
    return "contradicts" if contradicts() else "undecided"


def _fmt_margin(delta: float) -> str:
    return f"{math.exp(delta):.3g}x"


def _greater(name: str, d, delta: float = DELTA, note: str = "") -> _Part:
    """An ordering: the effect (a log ratio) exceeds the margin ``exp(delta)``."""
    point, lo, hi, n = _bounds(d)
    status = _decide(lo, lambda: lo > delta, lambda: hi < delta)
    return _Part(
        name,
        status,
        point,
        lo,
        hi,
        n,
        note,
        kind="greater",
        margin=_fmt_margin(delta),
        test="one-sided t, H1: effect > margin",
    )


def _at_most(name: str, d, delta: float = DELTA, note: str = "") -> _Part:
    """ "No gain" / "no better" / "matches or beats": the effect stays below the margin."""
    point, lo, hi, n = _bounds(d)
    status = _decide(lo, lambda: hi < delta, lambda: lo > delta)
    return _Part(
        name,
        status,
        point,
        lo,
        hi,
        n,
        note,
        kind="at most",
        margin=_fmt_margin(delta),
        test="one-sided t, H1: effect < margin",
    )


def _equivalent(name: str, d, delta: float = DELTA_2, note: str = "") -> _Part:
    """Equivalence (TOST): the effect lies within ``+-delta``."""
    point, lo, hi, n = _bounds(d)
    status = _decide(lo, lambda: -delta < lo and hi < delta, lambda: lo > delta or hi < -delta)
    return _Part(
        name,
        status,
        point,
        lo,
        hi,
        n,
        note,
        kind="equivalent",
        margin=f"1/{_fmt_margin(delta)} to {_fmt_margin(delta)}",
        test="TOST: two one-sided t",
    )


def _band(name: str, values, low: float, high: float, note: str = "") -> _Part:
    """The mean of ``values`` lies inside ``[low, high]`` (both one-sided tests), outside it
    (one of them the other way), or undecided."""
    point, lo, hi, n = _bounds(values)
    status = _decide(lo, lambda: lo > low and hi < high, lambda: hi < low or lo > high)
    return _Part(
        name,
        status,
        point,
        lo,
        hi,
        n,
        note,
        kind="band",
        margin=f"[{low:g}, {high:g}]",
        test="one-sided t at both ends",
    )


def _threshold(name: str, values, threshold: float, note: str = "", above: bool = True) -> _Part:
    """The mean of ``values`` lies above ``threshold`` (``above``; below otherwise): holds when
    its one-sided bound is past the threshold, contradicts when the other bound is short of it."""
    point, lo, hi, n = _bounds(values)
    status = _decide(
        lo,
        lambda: (lo > threshold) if above else (hi < threshold),
        lambda: (hi < threshold) if above else (lo > threshold),
    )
    return _Part(
        name,
        status,
        point,
        lo,
        hi,
        n,
        note,
        kind="above" if above else "below",
        margin=f"{threshold:g}",
        test=f"one-sided t test on per-seed values, H1 mean {'>' if above else '<'} {threshold:g}",
    )


def _positive(name: str, d, delta: float = DELTA, note="") -> _Part:
    """An ordering (kept name): see :func:`_greater`."""
    return _greater(name, d, delta, note)
