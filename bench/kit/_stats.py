"""A claim's parts: one-sided t tests of paired per-seed effects against a policy margin.

A part compares the mean of per-seed values (log ratios for ratios) with a margin from
:mod:`.policy`: *greater* holds when the lower one-sided (1 - alpha) bound is above the margin
and is contradicted when the upper one is below it; *at most* is the mirror image; *equivalent*
is TOST within +-margin; *band* and *below* test a slope against a centre; *share* tests a share
of a gap. Each part can re-judge itself at another margin or level (``Part.decide``).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy import special

from . import policy

__all__ = [
    "ALPHA",
    "Part",
    "at_most",
    "band",
    "below",
    "equivalent",
    "greater",
    "share",
    "t_bounds",
    "t_bounds_jackknife",
    "undecided",
]


# The level of every one-sided test, and the fewest paired seeds that give a verdict.
ALPHA = 0.05


@dataclass
class Part:
    """One tested part of a claim: ``point`` (the effect, a mean of per-seed values, on the log
    scale for ratios), ``lo``/``hi`` (its one-sided (1 - alpha) bounds, together the two-sided
    90% interval at alpha = 0.05), ``n`` seeds, the ``status`` its test gives, and what the
    test was: ``kind`` (see the module docstring), ``margin`` (its label), ``quantity`` and
    ``margin_value`` (from :mod:`bench.kit.policy`), ``test`` and ``alpha`` (the
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
    center: float = 0.0  # a band's centre (``band``, ``below``), on the test scale

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
    half = _t_quantile(alpha, n - 1) * sd / math.sqrt(n)
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
    half = _t_quantile(alpha, n - 1) * se
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
        return point, (hi - lo) / (2 * _t_quantile(ALPHA, n - 1)), n - 1, n
    v = np.asarray(list(d), dtype=float)
    v = v[np.isfinite(v)]
    n = len(v)
    if n < 2:
        return (float(v.mean()) if n else math.nan), math.nan, 0, n
    return float(v.mean()), float(np.std(v, ddof=1)) / math.sqrt(n), n - 1, n


@functools.lru_cache(maxsize=4096)
def _t_quantile(alpha: float, df: int) -> float:
    """``stats.t.ppf(1 - alpha, df)``, through scipy.special's inverse of the t distribution
    directly: the verdicts ask for thousands of quantiles, and the distribution object's
    argument checks cost 200 us a call."""
    return float(special.stdtrit(df, 1 - alpha))


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
            f"a part's margin must come from bench.kit.policy (margin() or stated()); got {mg!r}"
        )


def _part(kind: str, name: str, d, mg, note: str = "", center: float = 0.0) -> Part:
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
    return Part(
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
        center=center,
    )


def greater(name: str, d, mg, note: str = "") -> Part:
    """An ordering: the effect (a log ratio) exceeds the margin."""
    return _part("greater", name, d, mg, note)


def at_most(name: str, d, mg, note: str = "") -> Part:
    """ "No gain" / "no better" / "matches or beats": the effect stays below the margin."""
    return _part("at most", name, d, mg, note)


def equivalent(name: str, d, mg, note: str = "") -> Part:
    """Equivalence (TOST): the effect lies within +-margin."""
    return _part("equivalent", name, d, mg, note)


def band(name: str, values, center: float, mg, note: str = "") -> Part:
    """The mean of ``values`` lies within ``center +- margin`` (both one-sided tests), outside
    it (one of them the other way), or undecided."""
    return _part("band", name, values, mg, note, center)


def below(name: str, values, center: float, mg, note: str = "") -> Part:
    """The mean of ``values`` lies below ``center + margin``."""
    return _part("below", name, values, mg, note, center)


def share(name: str, closed, gap, mg, note: str = "") -> Part:
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
    return Part(
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


def undecided(name: str, note: str, role: str = "part") -> Part:
    """A part that could not be tested at all (no runs, no curves)."""
    return Part(name, "undecided", math.nan, math.nan, math.nan, 0, note, role=role)
