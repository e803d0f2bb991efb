"""Margin dependence: each claim's final reading judged again across the plausible band of every
margin its parts use (one quantity at a time, the others at the policy's), so that no verdict
hides its knob. A claim whose verdict changes somewhere in a band is *margin-dependent*."""

from __future__ import annotations

from dataclasses import dataclass

import pandas as pd

from . import policy
from ._claims import evaluate_claims, restrict_all


@dataclass(frozen=True)
class Dependence:
    """One claim's verdicts across a quantity's band: ``points`` are (margin, verdict)."""

    key: str
    quantity: str
    points: tuple[tuple[float, str], ...]
    at_policy: str

    @property
    def changes(self) -> bool:
        return any(v != self.at_policy for _, v in self.points)

    def text(self) -> str:
        q = policy.POLICY[self.quantity]
        unit = (lambda x: f"{x:.3g}x") if q.ratio else (lambda x: f"{x:.3g}")
        return "; ".join(f"{unit(m)}: {v}" for m, v in self.points)


def quantities(verdict) -> list[str]:
    """The policy quantities a verdict's parts and gates use (learning always: every claim's
    gates and discrimination read it)."""
    used = {p.quantity for p in verdict.parts if p.quantity and not _stated(p)}
    return [q for q in policy.POLICY if q in used or q == "learning"]


def _stated(part) -> bool:
    return "(stated:" in (part.margin or "")


def margin_dependence(
    runs: pd.DataFrame, curves: pd.DataFrame | None, profile: str | None, judgement
) -> list[Dependence]:
    """Every (claim, quantity) whose verdict changes within the quantity's plausible band, the
    claim judged on its final reading's seeds (pooled or primary) at the band's ends and
    middle (:func:`policy.band_points`) beside the policy's own margin."""
    out = []
    cache = restrict_all(runs, profile)
    judged = {}  # a claim's verdicts (claim 4 has several) per seed set, quantity and margin

    def evaluate(claim, seeds, q, m):
        key = (claim, tuple(sorted(seeds)) if seeds is not None else None, q, m)
        if key not in judged:
            with policy.override(**{q: m}):
                judged[key] = evaluate_claims(
                    runs, curves, profile, [claim], seeds=seeds, restricted=cache
                )
        return judged[key]

    for v in judgement.final:
        reading = judgement.reading(v.key)
        seeds = judgement.reading_seeds(v.key)
        for q in quantities(reading):
            pts = [(policy.POLICY[q].margin, reading.verdict)]
            for m in policy.band_points(q):
                if m == policy.POLICY[q].margin:
                    continue
                got = evaluate(v.claim, seeds, q, m)
                match = [w for w in got if w.key == v.key]
                pts.append((m, match[0].verdict if match else "no verdict"))
            d = Dependence(v.key, q, tuple(sorted(pts)), reading.verdict)
            if d.changes:
                out.append(d)
    return out
