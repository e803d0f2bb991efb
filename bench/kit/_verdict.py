"""The verdict of a claim from its parts: reproduced, partly, not reproduced or inconclusive."""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

from ._discrimination import Discrimination
from ._gates import apply_gates
from ._holm import holm
from ._seeds import WORST_ERROR, required_seeds
from ._stats import Part

__all__ = [
    "INCONCLUSIVE",
    "NOT_REPRODUCED",
    "PARTLY",
    "REPRODUCED",
    "VERDICTS",
    "Verdict",
    "verdict",
]


REPRODUCED = "reproduced"

PARTLY = "partly reproduced"

NOT_REPRODUCED = "not reproduced"

INCONCLUSIVE = "inconclusive"

VERDICTS = (REPRODUCED, PARTLY, NOT_REPRODUCED, INCONCLUSIVE)


@dataclass(frozen=True)
class Verdict:
    """The outcome of one claim: ``effect`` (meaning in ``effect_name``) with its 95% CI.

    ``variant`` names a sub-verdict (claim 4: metric and spring initial state); ``discriminating``
    is True/False, or None when no trivial-predictor runs exist; ``n_failed`` counts the runs
    scored as the worst error; ``pending`` is ``(stored, declared)`` runs of the claim while a
    campaign (a selection such as ``paper-core``) has not stored them all, else None;
    ``primary`` is the verdict on the profile's own seeds where the replication checks demoted
    it to an inconclusive one, with ``readings`` the seed sets' verdicts that did
    (:func:`bench.kit._replication.judge`), else None and ""; ``other_readings``
    the verdicts of the claim's other protocols where one protocol decides."""

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
    # False where the claim's evidence has no trivial predictor to beat (an embedding's
    # structure): each part is gated on its own model's learning instead, and the report's
    # discriminating column reads n/a rather than unknown
    has_trivial: bool = True
    # the systems or cells whose test set does not discriminate where others do: only their
    # parts went untested, and the verdict stands on the rest (empty where none, or where no
    # part could be read: then the claim is inconclusive)
    undiscriminating: tuple[str, ...] = ()
    parts: tuple = ()  # the tested parts (``Part``), for the report's parts table
    pending: tuple[int, int] | None = None
    primary: str | None = None
    readings: str = ""
    # the claim's other readings (another protocol's verdict), as (name, verdict) pairs; the
    # detail names them too (``_protocols.decided_by``)
    other_readings: tuple[tuple[str, str], ...] = ()
    # the status of the headline part (the paper's central sentence) where it is one of the
    # tested parts, else "" (a headline that summarises several parts)
    headline_status: str = ""
    headline_name: str = ""
    # the headline's margin on its test scale (log for ratios; NaN where it has none), its kind
    # and a band's centre: the headline figure's unit
    headline_margin: float = math.nan
    headline_kind: str = ""
    headline_center: float = 0.0

    def label(self) -> str:
        """The verdict with the headline's status beside it where the verdict alone would hide
        it (*partly reproduced*: which half is the paper's central sentence?), e.g.
        "partly reproduced: headline contradicted"; an inconclusive verdict whose headline was
        not tested (a model it gates on did not learn, or its condition failed) says so:
        "inconclusive: headline untested"."""
        if self.verdict == PARTLY and self.headline_status:
            said = {"contradicts": "contradicted"}.get(self.headline_status, self.headline_status)
            return f"{self.verdict}: headline {said}"
        if self.verdict == INCONCLUSIVE and self.headline_status == "not tested":
            return f"{self.verdict}: headline untested"
        return self.verdict

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


def _stems(group: str) -> tuple[str, ...]:
    """The prefixes by which a part names the system or cell of a discrimination group:
    ``"spring_pendulum (paper)"`` -> ``spring_pendulum``, ``spring``."""
    name = group.split(" (")[0].strip()
    return tuple(dict.fromkeys(x for x in (name, name.split("_")[0]) if x))


def _void_undiscriminating(parts: list[Part], not_disc: list[Discrimination]) -> bool:
    """Discrimination per system or cell: a group whose best model does not beat the trivial
    predictors voids only its own parts (those whose name starts with the group's system,
    :func:`_stems`), which read *not tested* with the reason. True where a group names no part
    (the parts pool its system with others): then nothing the claim tests can be read, and the
    whole claim is inconclusive."""
    void_all = False
    for d in not_disc:
        stems = _stems(d.group)
        mine = [p for p in parts if p.name.startswith(stems)]
        if not mine:
            void_all = True
        for p in mine:
            p.status = "not tested"
            reason = f"not discriminating on {d.group}"
            p.note = f"{reason}; {p.note}" if p.note else reason
    return void_all


def verdict(
    claim: int,
    title: str,
    parts: list[Part],
    headline: Part | None,
    n_seeds: int,
    effect_name: str,
    extra: str = "",
    *,
    discs: Iterable[Discrimination] = (),
    n_failed: int = 0,
    variant: str = "",
    universal: bool = False,
) -> Verdict:
    """Combine a claim's parts. First each part is settled: one tested on fewer seeds than a
    verdict needs is undecided; one with a closed gate reads *not tested*; Holm's correction
    runs across the rest; each part gets its margin ranges. Then: *reproduced* when every part
    holds, *not reproduced* when some contradict and none holds, *partly reproduced* when some
    hold and some contradict (the claim's separate statements), else *inconclusive*; a part
    not tested never counts against the claim. Condition parts (``role == "condition"``) are
    shown, not counted. ``universal``: the parts are instances of one statement over a grid
    ("no gain at any weight"), so one contradicting instance refutes it (*not reproduced*,
    never *partly*)."""
    discs = list(discs)
    need = required_seeds()
    for p in parts:  # a part tested on fewer seeds than a verdict needs decides nothing
        if 0 <= p.n < need and p.status not in ("undecided", "not tested"):
            p.note = (p.note + "; " if p.note else "") + f"{p.status} on {p.n} < {need} seeds"
            p.status = "undecided"
            p.decide = None
    not_disc = [d for d in discs if d.status == "no"]
    void_all = _void_undiscriminating(parts, not_disc)
    # a claim that declares its discrimination but has no trivial-predictor runs to compute it
    # (e.g. a GPU folder of trained models only) signs nothing: whether the test set can tell
    # models apart is unknown
    unknown = bool(discs) and all(d.status == "unknown" for d in discs)
    apply_gates(parts)
    holm(parts)
    claim_parts = [p for p in parts if p.role == "part"]
    statuses = [p.status for p in claim_parts]
    if discs and all(d.status == "yes" for d in discs):
        discriminating = True
    elif not_disc:
        discriminating = False
    else:
        discriminating = None
    if n_seeds < need or not claim_parts or void_all or unknown:
        reading = INCONCLUSIVE
    elif all(s == "holds" for s in statuses):
        reading = REPRODUCED
    elif "contradicts" in statuses:
        reading = PARTLY if "holds" in statuses and not universal else NOT_REPRODUCED
    else:
        reading = INCONCLUSIVE
    detail = "; ".join(p.text() for p in parts) or "no runs"
    if unknown:
        detail = f"DISCRIMINATION UNKNOWN (no trivial-predictor runs: nothing signed); {detail}"
    if void_all:
        detail = f"NOT DISCRIMINATING ({'; '.join(d.text() for d in not_disc)}); {detail}"
    elif discs:
        detail = f"{detail}; " + "; ".join(d.text() for d in discs)
    if not_disc and not void_all:
        groups = ", ".join(d.group for d in not_disc)
        detail = f"not discriminating on {groups}: its parts not tested; {detail}"
    if n_seeds < need and parts:
        detail = f"fewer than {need} paired seeds or a missing cell; {detail}"
    if n_failed:
        detail = f"{detail}; {n_failed} failed/diverged runs scored as error {WORST_ERROR:g}"
    if extra:
        detail = f"{detail}; {extra}"
    h = headline or (parts[0] if parts else None)
    return Verdict(
        claim=claim,
        title=title,
        verdict=reading,
        effect=h.point if h else math.nan,
        ci_low=h.lo if h else math.nan,
        ci_high=h.hi if h else math.nan,
        n_seeds=int(n_seeds),
        detail=detail,
        effect_name=effect_name,
        variant=variant,
        n_failed=int(n_failed),
        discriminating=discriminating,
        undiscriminating=(
            tuple(d.group for d in not_disc)
            if not void_all and any(d.status == "yes" for d in discs)
            else ()
        ),
        has_trivial=bool(discs) or not parts or n_seeds == 0,
        parts=tuple(parts),
        headline_status=h.status if h is not None and any(h is p for p in parts) else "",
        headline_name=h.name if h is not None else "",
        headline_margin=_test_margin(h),
        headline_kind=h.kind if h is not None else "",
        headline_center=h.center if h is not None else 0.0,
    )


def _test_margin(part: Part | None) -> float:
    """A part's margin on its test scale (log of the factor for ratios), NaN without one."""
    from . import policy

    if part is None or part.quantity not in policy.POLICY or not math.isfinite(part.margin_value):
        return math.nan
    v = part.margin_value
    return math.log(v) if policy.POLICY[part.quantity].ratio else float(v)
