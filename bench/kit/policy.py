"""The margin policy: one smallest difference that matters per quantity, for every rule.

A part of a claim compares an effect with a *margin*. The margin belongs to the quantity
compared, never to the word the paper uses: "better", "matches", "no better", "negligible",
"slightly" and "as accurate as" about rollout errors all use the error margin. A rule asks
:func:`margin` for it; only where a seed states a number ("several orders of magnitude") does
a rule use :func:`stated`, which records the quote and its source for the report.

Ratios of squared quantities (MSEs, losses, energy MSEs) take the square of their quantity's
margin: a 1.25x error is a 1.5625x mean squared error. Each quantity also declares the band of
margins a reasonable reader might pick; :func:`override` re-judges the claims at another margin
(the report's margin-dependent claims).
"""

from __future__ import annotations

import contextlib
import contextvars
import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass

__all__ = ["POLICY", "Margin", "Quantity", "margin", "override", "stated", "stated_margins"]


@dataclass(frozen=True)
class Quantity:
    """A compared quantity: its ``margin`` (a factor for ratios, on the log scale in the tests;
    an absolute value for shares and slopes), the plausible ``band`` of margins, and the words
    of the papers it covers."""

    name: str
    label: str
    margin: float
    band: tuple[float, float]
    ratio: bool
    words: str
    why: str


POLICY: dict[str, Quantity] = {
    q.name: q
    for q in (
        Quantity(
            "error",
            "rollout-error ratio",
            1.25,
            (1.1, 2.0),
            True,
            "better, outperforms, worse, matches, no better, slightly, as accurate as",
            "a quarter of the error; the papers' headline effects are 2x-10x",
        ),
        Quantity(
            "energy",
            "energy-violation ratio",
            1.25,
            (1.1, 2.0),
            True,
            "conserves better, no better, far better, dramatically, bounded vs growing",
            "the relative energy error is first order in the state error, as the rollout "
            "error is (Fig. 2: the two on one line), so the same factor matters",
        ),
        Quantity(
            "loss",
            "loss ratio (mean squared error)",
            1.25**2,
            (1.1**2, 2.0**2),
            True,
            "similar loss, tied on loss, comparable losses",
            "a mean of squares: the square of the error margin",
        ),
        Quantity(
            "cost",
            "cost ratio (training seconds)",
            1.25,
            (1.1, 2.0),
            True,
            "cheaper, less compute",
            "as for errors: a quarter of the time",
        ),
        Quantity(
            "share",
            "share of a gap",
            0.5,
            (0.5, 0.75),
            False,
            "most, much of, more closely matches",
            'more than half: NODE+SO "more closely matches HNNs than vanilla NODEs" '
            "(Gruver et al. 2022)",
        ),
        Quantity(
            "slope",
            "log-log slope tolerance",
            0.5,
            (0.25, 0.75),
            False,
            "grows linearly (slope 1), bounded (slope 0)",
            "half-way to the nearest other growth law: 0.5 is a random walk",
        ),
        Quantity(
            "proportionality",
            "log-log slope of energy violation on rollout error, tolerance about 1",
            0.5,
            (0.25, 0.75),
            False,
            "Rollout Error proportional to Energy Violation, scattered around the line x = y",
            'slope 1: "Rollout Error proportional to Energy Violation", "scattered around '
            'the line x = y" on log axes (Gruver et al. 2022, Fig. 2 left; Appendix B.1: '
            "the violation is first order in the dynamics error); 0.5 is half-way to the "
            "nearest other law, a quadratic one (slope 2) or none (slope 0); the paper "
            "states no number",
        ),
        Quantity(
            "correlation",
            "rank correlation, on Fisher's z scale (z = atanh rho)",
            math.atanh(0.3),
            (math.atanh(0.1), math.atanh(0.5)),
            False,
            "not positively correlated, negatively correlated",
            'a positive rank correlation of practical size: rho = 0.3 (z = 0.31), a "medium" '
            'correlation; the band runs from a "small" 0.1 to a "large" 0.5 (Cohen\'s '
            'conventions). The paper states no number: "not positively correlated ... in '
            'some cases even negatively" (Gruver et al. 2022; Fig. 3 right)',
        ),
        Quantity(
            "embedding",
            "embedding defect (1 - trustworthiness, or the share of steps that jump)",
            0.05,
            (0.025, 0.1),
            False,
            "consistent with the ground truth, fails to capture the global structure, "
            "discontinuous with respect to time",
            "one neighbour or time step in twenty out of place: an embedding continuous and "
            "one-to-one on the true circle with small noise scores 0.01-0.03, a cut crossed "
            "on every swing 0.06, a fold 0.2-0.3 (bench.core._embedding)",
        ),
        Quantity(
            "learning",
            "learning gate (error ratio, best trivial predictor / model)",
            2.0,
            (1.5, 4.0),
            True,
            "learns, succeeds, fails, fits poorly",
            "a model that does not halve the error of a parameter-free predictor learned "
            "nothing that a comparison could credit to its bias",
        ),
    )
}

_OVERRIDE: contextvars.ContextVar[Mapping[str, float] | None] = contextvars.ContextVar(
    "margin_override", default=None
)


@dataclass(frozen=True)
class Margin:
    """The margin of one part: ``value`` in the quantity's units (a factor for ratios),
    ``power`` 2 for a ratio of squared quantities, ``quote``/``source`` where a seed states it."""

    quantity: str
    value: float
    power: int = 1
    quote: str = ""
    source: str = ""

    @property
    def ratio(self) -> bool:
        return POLICY[self.quantity].ratio

    @property
    def test(self) -> float:
        """The margin on the scale the tests use: ``log(value)`` for ratios."""
        return math.log(self.value) if self.ratio else self.value

    def label(self) -> str:
        return f"{self.value:.3g}x" if self.ratio else f"{self.value:g}"

    def at(self, value: float) -> Margin:
        """The same margin at another ``value`` (a stated margin does not move)."""
        if self.quote:
            return self
        return Margin(self.quantity, value, self.power)


def margin(quantity: str, *, squared: bool = False) -> Margin:
    """The policy's margin for ``quantity`` (``squared``: a ratio of mean squares, the square of
    the margin). Unknown names raise, naming the quantities."""
    if quantity not in POLICY:
        raise ValueError(f"unknown quantity {quantity!r}; the policy has {', '.join(POLICY)}")
    base = (_OVERRIDE.get() or {}).get(quantity, POLICY[quantity].margin)
    power = 2 if squared else 1
    return Margin(quantity, base**power, power)


_STATED: dict[tuple, Margin] = {}


def stated(quantity: str, value: float, quote: str, source: str) -> Margin:
    """A margin a seed states as a number, with its ``quote`` and ``source`` (seed file and
    line): used instead of the policy's and never varied."""
    if quantity not in POLICY:
        raise ValueError(f"unknown quantity {quantity!r}; the policy has {', '.join(POLICY)}")
    m = Margin(quantity, float(value), 1, quote, source)
    _STATED[(quantity, value, quote)] = m
    return m


def stated_margins() -> list[Margin]:
    """Every stated margin declared so far (the rules declare theirs at import)."""
    return list(_STATED.values())


@contextlib.contextmanager
def override(**values: float) -> Iterator[None]:
    """Within the block, :func:`margin` gives ``values[quantity]`` (a base margin; squared
    quantities square it) instead of the policy's."""
    bad = [q for q in values if q not in POLICY]
    if bad:
        raise ValueError(f"unknown quantity {bad[0]!r}; the policy has {', '.join(POLICY)}")
    token = _OVERRIDE.set({**(_OVERRIDE.get() or {}), **{k: float(v) for k, v in values.items()}})
    try:
        yield
    finally:
        _OVERRIDE.reset(token)


def band_points(quantity: str, n: int = 3) -> list[float]:
    """``n`` margins spanning the plausible band, its ends included (log-spaced for ratios)."""
    q = POLICY[quantity]
    lo, hi = q.band
    if q.ratio:
        pts = [
            math.exp(math.log(lo) + (math.log(hi) - math.log(lo)) * i / (n - 1)) for i in range(n)
        ]
    else:
        pts = [lo + (hi - lo) * i / (n - 1) for i in range(n)]
    return sorted(set(pts))
