"""The engine's power: how often a part signs at its observed effect and spread, and how many
seeds would decide the parts that are undecided.

Each tested part is a one-sided t test on per-seed values against a margin
(:mod:`._stats`). Its observed mean and the spread of its per-seed values (recovered from its
90% interval: ``sd = half-width / t(0.95, n - 1) * sqrt(n)``) define a normal model of a seed's
value. The simulation draws ``n`` seeds from it many times, computes the part's interval as the
part does (one-sided ``1 - alpha`` t bounds), and applies the part's own rule
(``_stats._status``): the share of draws that *hold*, and that *contradict*, at 5 and at 10
seeds. For a part left undecided, :func:`seeds_to_decide` finds the fewest seeds at which one of
the two reaches 80%; where none does within :data:`MAX_SEEDS`, its effect sits on the margin
and more seeds will not decide it.

What this leaves out, and says so: the level is each part's own before Holm's correction
(Holm lowers it where a claim has several parts, so the figures are upper bounds); parts
read off a pooled fit or a jackknife (claim 1 (a) and (c)) are modelled by their interval as if
it came from per-seed values; gates and the discrimination check are taken as they are.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy import special

from . import policy
from ._stats import _RULES, ALPHA, Part

POWER = 0.8
MAX_SEEDS = 200
SIMULATIONS = 2000
SETS = (5, 10)


def _quantile(df: int) -> float:
    return float(special.stdtrit(df, 1 - ALPHA))


def spread(part: Part) -> float:
    """The standard deviation of a seed's value implied by the part's interval; NaN where the
    part has no finite interval or fewer than two seeds."""
    if part.n < 2 or not (math.isfinite(part.lo) and math.isfinite(part.hi)):
        return math.nan
    return (part.hi - part.lo) / (2 * _quantile(part.n - 1)) * math.sqrt(part.n)


def _margin(part: Part) -> float:
    q = policy.POLICY.get(part.quantity)
    if q is None or not math.isfinite(part.margin_value):
        return math.nan
    return math.log(part.margin_value) if q.ratio else float(part.margin_value)


def simulable(part: Part) -> bool:
    """A tested part of a kind the simulation knows, with an interval and a margin."""
    return (
        part.role == "part"
        and part.kind in _RULES
        and part.status in ("holds", "contradicts", "undecided")
        and math.isfinite(part.point)
        and math.isfinite(spread(part))
        and math.isfinite(_margin(part))
    )


def sign_rates(
    part: Part, n: int, effect: float | None = None, sims: int = SIMULATIONS, seed: int = 0
) -> tuple[float, float]:
    """(P(holds), P(contradicts)) of ``part`` at ``n`` seeds drawn at ``effect`` (default its
    observed one) with its observed spread."""
    mu = part.point if effect is None else effect
    sd = spread(part)
    rng = np.random.default_rng(seed)
    x = rng.normal(mu, sd, size=(sims, n))
    mean = x.mean(axis=1)
    half = _quantile(n - 1) * x.std(axis=1, ddof=1) / math.sqrt(n)
    lo, hi = mean - half, mean + half
    holds_rule, contra_rule = _RULES[part.kind]
    m, c = _margin(part), part.center
    h = np.array([holds_rule(a, b, m, c) for a, b in zip(lo, hi, strict=True)], dtype=bool)
    k = np.array([contra_rule(a, b, m, c) for a, b in zip(lo, hi, strict=True)], dtype=bool)
    return float(h.mean()), float((k & ~h).mean())


def seeds_to_decide(part: Part, sims: int = 400) -> int | None:
    """The fewest seeds at which the part, at its observed effect and spread, holds or is
    contradicted with probability :data:`POWER`; None where no number up to
    :data:`MAX_SEEDS` does (the effect sits on the margin)."""

    def decides(n: int) -> bool:
        return max(sign_rates(part, n, sims=sims)) >= POWER

    if not decides(MAX_SEEDS):
        return None
    lo, hi = 2, MAX_SEEDS
    if decides(lo):
        return lo
    while hi - lo > 1:  # the rate grows with n: bisect
        mid = (lo + hi) // 2
        lo, hi = (lo, mid) if decides(mid) else (mid, hi)
    return hi


def power_table(verdicts, sims: int = SIMULATIONS) -> pd.DataFrame:
    """One row per simulable part of ``verdicts``: claim key, part, status, effect, spread,
    the rates of signing (holding or contradicting) at 5 and at 10 seeds, and, for an
    undecided part, the seeds that would decide it (``-1``: none up to :data:`MAX_SEEDS`)."""
    rows = []
    for v in verdicts:
        for q in v.parts:
            if not simulable(q):
                continue
            row = {
                "claim": v.key,
                "part": q.name,
                "status": q.status,
                "n": q.n,
                "effect": q.point,
                "spread": spread(q),
            }
            for n in SETS:
                h, c = sign_rates(q, n, sims=sims)
                row[f"holds_{n}"], row[f"contradicts_{n}"] = h, c
            if q.status == "undecided":
                need = seeds_to_decide(q, sims=min(sims, 400))
                row["seeds_to_decide"] = -1 if need is None else need
            else:
                row["seeds_to_decide"] = math.nan
            rows.append(row)
    return pd.DataFrame(rows)


def power_lines(table: pd.DataFrame) -> list[str]:
    """The report's table of the undecided parts: what more seeds would do."""
    if not len(table):
        return []
    und = table[table["status"] == "undecided"]
    if not len(und):
        return []
    out = [
        "### What more seeds would decide",
        "",
        "Each undecided part simulated at its observed effect and per-seed spread (normal "
        "seeds, the part's own test at its level before Holm's correction: upper bounds): the "
        "chance that it signs (holds or is contradicted) at 5 and at 10 seeds, and the fewest "
        f"seeds that sign it with {POWER:.0%} probability (*on the margin*: none up to "
        f"{MAX_SEEDS}). `python -m bench power` writes the whole table. The count sizes a new "
        "study, not an extension of this one: seeds added to these until a part signs would "
        "test it again and again (optional stopping) and sign it more often than the level "
        "says; a fresh seed set judged on its own, as the replication set is, keeps the level.",
        "",
        "| claim | part | effect | spread | signs at 5 seeds | at 10 | seeds to decide |",
        "| --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in und.itertuples(index=False):
        need = "on the margin" if r.seeds_to_decide == -1 else str(int(r.seeds_to_decide))
        p5 = r.holds_5 + r.contradicts_5
        p10 = r.holds_10 + r.contradicts_10
        out.append(
            f"| {r.claim} | {r.part} | {r.effect:.3g} | {r.spread:.3g} | {p5:.0%} | "
            f"{p10:.0%} | {need} |"
        )
    return [*out, ""]
