"""Holm's step-down correction across a claim's parts, and the margins at which each holds.

Both directions are corrected: *holds* and *contradicts* each run their own step-down at
``alpha / (m - i)`` over the claim's m tested parts.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from . import policy
from ._stats import ALPHA, Part

__all__ = ["holm", "margin_ranges"]


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


def holm(parts: list[Part], alpha: float = ALPHA) -> None:
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


def margin_ranges(part: Part, n_grid: int = 241) -> tuple:
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
