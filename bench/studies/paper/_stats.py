"""The statistics of the verdicts: scores, paired per-seed effects, parts, gates and Holm.

Every claim is a function ``claim_N(runs, curves=None) -> Verdict`` (claim 4: a list). A claim
is split into *parts*; each part is a t test on paired per-seed values (log ratios for
ratios) against a margin from :mod:`bench.studies.paper.policy`:

- *greater* ("A is worse than B"): holds when the lower one-sided bound is above the margin,
  contradicts when the upper one is below it; *at most* ("no better", "matches or beats") the
  mirror image; *equivalent* ("slightly", TOST) within +-margin; *band* / *below* (slopes)
  against a centre and the slope tolerance; *above* (a share of a gap).
- Failed and diverged runs are scored, never dropped: the worst error, 1 (or the table's worst
  finite value, at least 1, for metrics without that bound).
- A part whose models did not learn, or whose stated condition ("at similar loss") does not
  hold, reads *not tested* (:func:`gated`, :func:`learned`, :func:`condition`).
- Holm's step-down correction runs across a claim's tested parts, for *holds* and for
  *contradicts* alike (:func:`holm`); each part shows the margins at which it holds, is
  undecided and is contradicted (:func:`margin_ranges`).
"""

from __future__ import annotations

import contextlib
import contextvars
import functools
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import stats

from ...core._query import initial_state, option, select
from . import policy

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


# A model succeeds when it beats the best trivial predictor by this factor (the policy's).
TRIVIAL_FACTOR = policy.POLICY["learning"].margin
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


@dataclass(frozen=True)
class Gate:
    """A precondition of a comparison: ``open`` True (met), False (not met: the part it gates
    reads *not tested*) or None (unknown: no trivial-predictor runs; the part is judged,
    flagged). ``text`` says what was measured against what."""

    label: str
    open: bool | None
    text: str


@dataclass
class _Part:
    """One tested part of a claim: ``point`` (the effect, a mean of per-seed values, on the log
    scale for ratios), ``lo``/``hi`` (its one-sided (1 - alpha) bounds, together the two-sided
    90% interval at alpha = 0.05), ``n`` seeds, the ``status`` its test gives, and what the
    test was: ``kind`` (see the module docstring), ``margin`` (its label), ``quantity`` and
    ``margin_value`` (from :mod:`bench.studies.paper.policy`), ``test`` and ``alpha`` (the
    level after Holm's correction). ``decide(margin value, level)`` re-judges the part at
    another margin or level; ``gates`` are its preconditions; ``role`` is "part" (a statement
    of the claim) or "condition" (a stated condition of other parts, "at similar loss": shown,
    never a finding of its own); ``ranges`` are (status, from, to) margin segments."""

    name: str
    status: str  # "holds" | "contradicts" | "undecided" | "not tested"
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
    quantity: str = ""
    margin_value: float = math.nan
    gates: tuple = ()
    role: str = "part"
    ranges: tuple = ()
    decide: Callable | None = field(default=None, repr=False, compare=False)
    levels: tuple[float, float] = (ALPHA, ALPHA)  # Holm's levels for holds / contradicts

    def text(self) -> str:
        ci = f"[{self.lo:.3g}, {self.hi:.3g}]" if np.isfinite(self.lo) else "[n/a]"
        s = f"{self.name}: {self.point:.3g} {ci}, n={self.n} -> {self.status}"
        return s + (f" ({self.note})" if self.note else "")

    def range_text(self) -> str:
        """The margins at which the part holds, is undecided and is contradicted, e.g.
        "holds below 1.41x; undecided 1.41x-1.72x; contradicts from 1.72x"."""
        if not self.ranges:
            return "-"
        q = policy.POLICY.get(self.quantity)
        unit = (lambda x: f"{x:.3g}x") if q is None or q.ratio else (lambda x: f"{x:.3g}")
        out = []
        for i, (status, a, b) in enumerate(self.ranges):
            if len(self.ranges) == 1:
                where = "at every margin"
            elif i == 0:
                where = f"below {unit(b)}"
            elif i == len(self.ranges) - 1:
                where = f"from {unit(a)}"
            else:
                where = f"{unit(a)}-{unit(b)}"
            out.append(f"{status} {where}")
        return "; ".join(out)

    def as_row(self) -> dict:
        return {
            "part": self.name,
            "role": self.role,
            "status": self.status,
            "effect": self.point,
            "lo": self.lo,
            "hi": self.hi,
            "n": self.n,
            "kind": self.kind,
            "quantity": self.quantity,
            "margin": self.margin,
            "margin range": self.range_text(),
            "test": self.test,
            "alpha": self.alpha,
            "note": self.note,
        }


# --------------------------------------------------------------------------- statistics


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


def _stat(d) -> tuple[float, float, int, int]:
    """(point, standard error, degrees of freedom, n) of per-seed values, or of a precomputed
    ``(point, lo, hi, n)`` whose ``lo``/``hi`` are one-sided (1 - alpha) t bounds (the standard
    error is read back from their width)."""
    if isinstance(d, tuple):
        point, lo, hi = (float(x) for x in d[:3])
        n = int(d[3]) if len(d) > 3 else -1
        if n < 2 or not (np.isfinite(lo) and np.isfinite(hi)):
            return point, math.nan, max(n - 1, 0), n
        return point, (hi - lo) / (2 * float(stats.t.ppf(1 - ALPHA, n - 1))), n - 1, n
    v = np.asarray(list(d), dtype=float)
    v = v[np.isfinite(v)]
    n = len(v)
    if n < 2:
        return (float(v.mean()) if n else math.nan), math.nan, 0, n
    return float(v.mean()), float(np.std(v, ddof=1)) / math.sqrt(n), n - 1, n


@functools.lru_cache(maxsize=4096)
def _t_quantile(alpha: float, df: int) -> float:
    return float(stats.t.ppf(1 - alpha, df))


def _t_interval(point: float, se: float, df: int, alpha: float) -> tuple[float, float]:
    if not (np.isfinite(se) and df >= 1):
        return math.nan, math.nan
    half = _t_quantile(float(alpha), int(df)) * se
    return point - half, point + half


# what each kind of part asks of its bounds (lo, hi) at the margin m on the test scale
_RULES: dict[str, tuple[Callable, Callable]] = {
    "greater": (lambda lo, hi, m, c: lo > m, lambda lo, hi, m, c: hi < m),
    "at most": (lambda lo, hi, m, c: hi < m, lambda lo, hi, m, c: lo > m),
    "equivalent": (
        lambda lo, hi, m, c: -m < lo and hi < m,
        lambda lo, hi, m, c: lo > m or hi < -m,
    ),
    "band": (
        lambda lo, hi, m, c: c - m < lo and hi < c + m,
        lambda lo, hi, m, c: hi < c - m or lo > c + m,
    ),
    "below": (lambda lo, hi, m, c: hi < c + m, lambda lo, hi, m, c: lo > c + m),
    "above": (lambda lo, hi, m, c: lo > m, lambda lo, hi, m, c: hi < m),
}
_TESTS = {
    "greater": "one-sided t, H1: effect > margin",
    "at most": "one-sided t, H1: effect < margin",
    "equivalent": "TOST: two one-sided t",
    "band": "one-sided t at both ends of center +- margin",
    "below": "one-sided t, H1: effect < center + margin",
    "above": "one-sided t, H1: effect > margin",
}


def _status(kind: str, lo: float, hi: float, m: float, center: float) -> str:
    if not (np.isfinite(lo) and np.isfinite(hi)):
        return "undecided"
    holds, contradicts = _RULES[kind]
    if holds(lo, hi, m, center):
        return "holds"
    return "contradicts" if contradicts(lo, hi, m, center) else "undecided"


def _check_margin(mg) -> None:
    if not isinstance(mg, policy.Margin):
        raise TypeError(
            "a part's margin must come from bench.studies.paper.policy (margin() or stated()); "
            f"got {mg!r}"
        )


def _part(kind: str, name: str, d, mg, note: str = "", center: float = 0.0) -> _Part:
    """A part of ``kind`` on per-seed values ``d`` (or precomputed bounds) at margin ``mg``."""
    _check_margin(mg)
    point, se, df, n = _stat(d)
    to_test = math.log if mg.ratio else float

    def decide(value: float, alpha: float) -> str:
        lo, hi = _t_interval(point, se, df, alpha)
        if np.isfinite(se) and se == 0:
            lo = hi = point
        return _status(kind, lo, hi, to_test(value), center)

    lo, hi = _t_interval(point, se, df, ALPHA)
    if np.isfinite(se) and se == 0:
        lo = hi = point
    label = mg.label()
    if kind == "equivalent":
        label = f"1/{label} to {label}" if mg.ratio else f"+-{label}"
    elif kind in ("band", "below"):
        label = f"{center:g} +- {label}" if kind == "band" else f"{center:g} + {label}"
    return _Part(
        name,
        decide(mg.value, ALPHA),
        point,
        lo,
        hi,
        n,
        note,
        kind=kind,
        margin=label + (f" (stated: {mg.source})" if mg.quote else ""),
        test=_TESTS[kind],
        quantity=mg.quantity,
        margin_value=mg.value,
        decide=decide,
    )


def _greater(name: str, d, mg, note: str = "") -> _Part:
    """An ordering: the effect (a log ratio) exceeds the margin."""
    return _part("greater", name, d, mg, note)


def _at_most(name: str, d, mg, note: str = "") -> _Part:
    """ "No gain" / "no better" / "matches or beats": the effect stays below the margin."""
    return _part("at most", name, d, mg, note)


def _equivalent(name: str, d, mg, note: str = "") -> _Part:
    """Equivalence (TOST): the effect lies within +-margin."""
    return _part("equivalent", name, d, mg, note)


def _band(name: str, values, center: float, mg, note: str = "") -> _Part:
    """The mean of ``values`` lies within ``center +- margin`` (both one-sided tests), outside
    it (one of them the other way), or undecided."""
    return _part("band", name, values, mg, note, center)


def _below(name: str, values, center: float, mg, note: str = "") -> _Part:
    """The mean of ``values`` lies below ``center + margin``."""
    return _part("below", name, values, mg, note, center)


def _share(name: str, closed, gap, mg, note: str = "") -> _Part:
    """ "Most of the gap": per seed ``closed - s * gap > 0`` at the share margin ``s`` (a
    one-sided t test); the effect printed is the share ``mean(closed) / mean(gap)``, its bounds
    those of ``closed - s * gap`` read as a share (the gap held at its mean)."""
    _check_margin(mg)
    closed, gap = np.asarray(closed, float), np.asarray(gap, float)
    mean_gap = float(np.mean(gap)) if len(gap) else math.nan

    def bounds(s: float, alpha: float) -> tuple[float, float]:
        point, se, df, _ = _stat(closed - s * gap)
        lo, hi = _t_interval(point, se, df, alpha)
        if np.isfinite(se) and se == 0:
            lo = hi = point
        return lo, hi

    def decide(s: float, alpha: float) -> str:
        lo, hi = bounds(s, alpha)
        return _status("above", lo, hi, 0.0, 0.0)

    s = mg.value
    lo, hi = bounds(s, ALPHA)
    share = float(np.mean(closed)) / mean_gap if mean_gap else math.nan
    ends = sorted(x / mean_gap + s for x in (lo, hi)) if mean_gap and np.isfinite(lo) else None
    return _Part(
        name,
        decide(s, ALPHA),
        share,
        ends[0] if ends else math.nan,
        ends[1] if ends else math.nan,
        len(closed),
        note,
        kind="above",
        margin=mg.label(),
        test=f"one-sided t, H1: closed - {s:g} gap > 0",
        quantity=mg.quantity,
        margin_value=s,
        decide=decide,
    )


def undecided(name: str, note: str, role: str = "part") -> _Part:
    """A part that could not be tested at all (no runs, no curves)."""
    return _Part(name, "undecided", math.nan, math.nan, math.nan, 0, note, role=role)


# --------------------------------------------------------------------------- gates


def learned(label: str, model_log: pd.Series, trivial_log: pd.Series, *, squared=False) -> Gate:
    """The learning gate: the model's per-seed log score beats the best trivial predictor's by
    the policy's learning margin, as a geometric mean over the paired seeds (``squared``: the
    scores are mean squares, the margin squared). Unknown without paired trivial runs."""
    mg = policy.margin("learning", squared=squared)
    if model_log is None or not len(model_log):
        return Gate(label, None, f"{label} has no runs")
    if trivial_log is None:
        return Gate(label, None, f"{label}: no paired trivial-predictor runs")
    d = (trivial_log - model_log).dropna()
    d = d[np.isfinite(d)]
    if not len(d):
        return Gate(label, None, f"{label}: no paired trivial-predictor runs")
    ratio = math.exp(float(d.mean()))
    ok = bool(float(d.mean()) >= mg.test)
    return Gate(
        label,
        ok,
        f"{label} {'learned' if ok else 'did not learn'}: {ratio:.3g}x below the best trivial "
        f"predictor (geometric mean over {len(d)} seeds; the gate is {mg.label()})",
    )


def condition(part: _Part) -> Gate:
    """A stated condition of other parts ("at similar loss"): open when ``part`` holds. The
    part becomes a *condition*: shown, never a finding of its own."""
    part.role = "condition"
    return Gate(part.name, part.status == "holds", f"condition {part.name}: {part.status}")


def gated(part: _Part, *gates: Gate) -> _Part:
    """``part`` judged only where every gate is open (:func:`apply_gates`)."""
    part.gates = (*part.gates, *gates)
    return part


def apply_gates(parts: list[_Part]) -> None:
    """A part with a closed gate reads *not tested*, its reasons in the note."""
    for p in parts:
        closed = [g for g in p.gates if g.open is False]
        if closed:
            p.status = "not tested"
            p.note = "; ".join([*(g.text for g in closed), *([p.note] if p.note else [])])
        elif any(g.open is None for g in p.gates):
            unknown = "; ".join(g.text for g in p.gates if g.open is None)
            p.note = f"{p.note}; gate unknown: {unknown}" if p.note else f"gate unknown: {unknown}"


# --------------------------------------------------------------------------- Holm, ranges


def _p_value(decide: Callable, value: float, status: str) -> float:
    """The smallest level at which ``decide`` gives ``status`` at margin ``value`` (1 when it
    does not even at 0.5): the part's p-value for that direction."""
    if decide(value, 0.5) != status:
        return 1.0
    lo, hi = 1e-12, 0.5
    if decide(value, lo) == status:
        return lo
    for _ in range(50):
        mid = math.sqrt(lo * hi)
        if decide(value, mid) == status:
            hi = mid
        else:
            lo = mid
    return hi


def holm(parts: list[_Part], alpha: float = ALPHA) -> None:
    """Holm's step-down correction across the claim's tested parts, for *holds* and for
    *contradicts* alike: the part with the i-th smallest p-value (of m) is tested at
    ``alpha / (m - i)``, and the steps stop at the first that fails. Sets each part's status,
    ``levels`` and ``alpha`` (the level its status was decided at)."""
    family = [
        p
        for p in parts
        if p.decide is not None
        and p.role == "part"
        and p.status in ("holds", "contradicts", "undecided")
    ]
    m = len(family)
    if not m:
        return
    result = {id(p): "undecided" for p in family}
    levels = {id(p): [alpha, alpha] for p in family}
    for j, direction in enumerate(("holds", "contradicts")):
        ps = sorted(
            ((_p_value(p.decide, p.margin_value, direction), p) for p in family), key=lambda x: x[0]
        )
        stopped = False
        for i, (pv, p) in enumerate(ps):
            level = alpha / (m - i)
            levels[id(p)][j] = level
            if not stopped and pv <= level:
                result[id(p)] = direction
            else:
                stopped = True
    for p in family:
        p.status = result[id(p)]
        p.levels = tuple(levels[id(p)])
        p.alpha = p.levels[1] if p.status == "contradicts" else p.levels[0]
        if m > 1:
            p.test = f"{p.test}; Holm over {m} parts"


def margin_ranges(part: _Part, n_grid: int = 241) -> tuple:
    """``(status, from, to)`` segments over the margins: for ratios 1x to 1e4x (log grid), for
    shares and slopes 0 to 1 and 0 to 2; *holds* judged at the part's Holm level for holds,
    *contradicts* at its level for contradicts, each boundary refined by bisection."""
    if part.decide is None or not part.quantity:
        return ()
    q = policy.POLICY[part.quantity]
    lh, lc = part.levels

    def status(v: float) -> str:
        if part.decide(v, lh) == "holds":
            return "holds"
        return "contradicts" if part.decide(v, lc) == "contradicts" else "undecided"

    if q.ratio:
        top = max(1e4, part.margin_value * 10)
        grid = np.exp(np.linspace(0.0, math.log(top), n_grid))
        mid = lambda a, b: math.sqrt(a * b)  # noqa: E731
    else:
        top = 1.0 if part.quantity == "share" else 2.0
        grid = np.linspace(0.0, top, n_grid)
        mid = lambda a, b: (a + b) / 2  # noqa: E731
    segs = []
    prev = status(float(grid[0]))
    start = float(grid[0])
    for a, b in zip(grid, grid[1:], strict=False):
        s = status(float(b))
        if s == prev:
            continue
        lo, hi = float(a), float(b)
        for _ in range(40):
            c = mid(lo, hi)
            if status(c) == prev:
                lo = c
            else:
                hi = c
        segs.append((prev, start, hi))
        prev, start = s, hi
    segs.append((prev, start, math.inf))
    return tuple(segs)
