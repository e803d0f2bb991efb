"""Verdicts that replicate: every claim judged on the profile's seeds, again on a disjoint
seed set, pooled where the two agree, and without each seed.

- *Primary*: the profile's own seeds (``quick`` and ``paper``: 0-4; for a profile that declares
  fewer than a verdict needs, ``smoke``, every stored seed outside the replication set).
- *Replication*: the replication seeds (5-9). Where both sets read the same verdict, the final
  reading is the *pooled* ten seeds: two disjoint sets that agree add evidence. Where they
  differ, the claim is *inconclusive (does not replicate)*, both readings shown. A claim whose
  replication runs are partly stored (a campaign under way) reads *pending* and keeps its
  primary reading.
- *Leave one seed out*: the final reading's seeds without each one in turn (one seed fewer
  required). It flags an influential seed, and demotes the verdict to *inconclusive (changes
  without a seed)* only where dropping that seed reverses a part (holds <-> contradicts); a
  part that merely loses significance on fewer seeds is not evidence against it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field

import pandas as pd

from ...core._experiments import PROFILES, expand
from ._rules import claim_studies, evaluate_claims, restrict_all
from ._seeds import seed_sets, seed_span
from .kit import INCONCLUSIVE, Verdict, min_seeds, required_seeds

DOES_NOT_REPLICATE = "inconclusive (does not replicate)"
CHANGES_WITHOUT_A_SEED = "inconclusive (changes without a seed)"


@dataclass
class Judgement:
    """Every claim's verdicts: ``final`` (what the report states), ``primary`` (the profile's
    seeds), ``replication`` (the replication seeds; empty when none are stored), ``pooled``
    (both sets, where they agree), ``loso`` (key -> [(dropped seed, verdict)] over the final
    reading's seeds), with the seed sets used."""

    final: list[Verdict]
    primary: dict[str, Verdict]
    replication: dict[str, Verdict] = field(default_factory=dict)
    loso: dict[str, list[tuple[int, Verdict]]] = field(default_factory=dict)
    primary_seeds: tuple[int, ...] = ()
    replication_seeds: tuple[int, ...] = ()
    # key -> (stored, declared) replication runs of a claim whose replication is under way:
    # not judged until all are stored (a partial reading is not a replication)
    replication_pending: dict[str, tuple[int, int]] = field(default_factory=dict)
    pooled: dict[str, Verdict] = field(default_factory=dict)
    # key -> both sets pooled for every claim whose replication is judged: the final reading
    # where they agree, for information only where they do not (it decides nothing there)
    pooled_any: dict[str, Verdict] = field(default_factory=dict)

    def replicates(self, key: str) -> bool | None:
        r = self.replication.get(key)
        if r is None or r.n_seeds == 0:
            return None
        return r.verdict == self.primary[key].verdict

    def reading(self, key: str) -> Verdict:
        """The reading the final verdict rests on: pooled where the seed sets agree, else the
        primary seeds'."""
        return self.pooled.get(key) or self.primary[key]

    def reading_seeds(self, key: str) -> tuple[int, ...]:
        if key in self.pooled:
            return tuple(sorted({*self.primary_seeds, *self.replication_seeds}))
        return self.primary_seeds

    def loso_changes(self, key: str) -> list[tuple[int, Verdict]]:
        """The dropped seeds whose absence changes the reading's verdict (flagged)."""
        base = self.reading(key).verdict
        return [(s, v) for s, v in self.loso.get(key, []) if v.verdict != base]

    def loso_reversals(self, key: str) -> list[tuple[int, list[str]]]:
        """The dropped seeds whose absence reverses a part (holds <-> contradicts), with the
        reversed parts' names (these demote the verdict)."""
        return [
            (s, parts)
            for s, w in self.loso.get(key, [])
            if (parts := reversed_parts(self.reading(key), w))
        ]


def reversed_parts(a: Verdict, b: Verdict) -> list[str]:
    """The parts that hold in one verdict and are contradicted in the other."""
    other = {q.name: q.status for q in b.parts}
    flip = {("holds", "contradicts"), ("contradicts", "holds")}
    return [q.name for q in a.parts if (q.status, other.get(q.name)) in flip]


def stored_counts(runs: pd.DataFrame, profile: str | None, seeds=None) -> dict[int, tuple]:
    """``{claim: (stored, declared)}``: how many of the runs each claim's experiments declare
    at ``profile`` (on ``seeds`` instead of its own) are in ``runs``; {} for an unknown
    profile."""
    if profile not in PROFILES:
        return {}
    from ...core._studies import studies

    done = set(runs["config_hash"]) if len(runs) and "config_hash" in runs else set()
    judged = {s.claim for s in claim_studies()}
    declared: dict[int, set] = {}
    for study in studies():  # a claim's experiments may be declared by several studies
        if study.claim in judged:
            declared.setdefault(study.claim, set()).update(
                c.config_hash for e in study.experiments for c in expand(e, profile, seeds=seeds)
            )
    return {n: (len(hashes & done), len(hashes)) for n, hashes in sorted(declared.items())}


def _on(runs: pd.DataFrame, seeds) -> pd.DataFrame:
    if not len(runs) or "seed" not in runs:
        return runs
    return runs[runs["seed"].isin(list(seeds))].reset_index(drop=True)


def judge(
    runs: pd.DataFrame,
    curves: pd.DataFrame | None = None,
    profile: str | None = None,
    *,
    loso: bool = True,
    restricted: Mapping[int, pd.DataFrame] | None = None,
) -> Judgement:
    """Judge every claim on the primary seeds, the replication seeds (where stored), both
    pooled (where they agree) and without each seed of the final reading (``loso``;
    ``loso=False`` skips that check and its demotion). Runs of other seeds are ignored; a
    folder whose profile is unknown is judged on all its seeds, without replication.
    ``restricted``: each claim's rows of ``runs`` already restricted (:func:`restrict_all`), for
    callers that need them too."""
    declared, rep_seeds = seed_sets(profile)
    stored = sorted(int(s) for s in runs["seed"].unique()) if len(runs) and "seed" in runs else []
    if len(declared) >= required_seeds():
        primary_seeds = declared
    else:
        primary_seeds = tuple(s for s in stored if s not in rep_seeds)
    cache = restrict_all(runs, profile) if restricted is None else restricted

    def evaluate(seeds):
        return evaluate_claims(runs, curves, profile, seeds=seeds, restricted=cache)

    prim = evaluate(primary_seeds)
    primary = {v.key: v for v in prim}
    replication, rep_pending, pooled, pooled_any = {}, {}, {}, {}
    if rep_seeds and len(_on(runs, rep_seeds)):
        replication = {v.key: v for v in evaluate(rep_seeds)}
        counts = stored_counts(_on(runs, rep_seeds), profile, rep_seeds)
        for key, r in list(replication.items()):
            n, m = counts.get(r.claim, (0, 0))
            if 0 < n < m:
                rep_pending[key] = (n, m)
            if 0 < n < m or r.n_seeds == 0:
                del replication[key]
        agree = [k for k, r in replication.items() if r.verdict == primary[k].verdict]
        if replication:
            both = tuple(sorted({*primary_seeds, *rep_seeds}))
            every = {v.key: v for v in evaluate(both)}
            pooled = {k: every[k] for k in agree if k in every}
            pooled_any = {k: every[k] for k in replication if k in every}
    out_loso: dict[str, list[tuple[int, Verdict]]] = {}
    if loso:
        groups: dict[tuple[int, ...], list[str]] = {}
        for key in primary:
            seeds = tuple(sorted({*primary_seeds, *rep_seeds})) if key in pooled else primary_seeds
            groups.setdefault(seeds, []).append(key)
        for seeds, keys in groups.items():
            present = sorted(set(_on(runs, seeds)["seed"])) if len(runs) else []
            if len(present) < 2:
                continue
            with min_seeds(max(2, required_seeds() - 1)):
                for s in present:
                    rest = [x for x in present if x != s]
                    for v in evaluate(rest):
                        if v.key in keys:
                            out_loso.setdefault(v.key, []).append((int(s), v))
    j = Judgement([], primary, replication, out_loso, primary_seeds, rep_seeds, rep_pending)
    j.pooled, j.pooled_any = pooled, pooled_any
    for v in prim:
        r = replication.get(v.key)
        if r is not None and r.n_seeds > 0 and r.verdict != v.verdict:
            readings = (
                f"seeds {seed_span(primary_seeds)}: {v.verdict}; seeds {seed_span(rep_seeds)}: "
                + (r.verdict)
            )
            v = dataclasses.replace(
                v,
                verdict=DOES_NOT_REPLICATE,
                detail=f"{readings}. {v.detail}",
                primary=v.verdict,
                readings=readings,
            )
            j.final.append(v)
            continue
        v = j.reading(v.key)
        if settled(v.verdict) and (rev := j.loso_reversals(v.key)):
            without = "; ".join(f"without seed {s}: {', '.join(ps)} reversed" for s, ps in rev)
            readings = f"seeds {seed_span(j.reading_seeds(v.key))}: {v.verdict}; {without}"
            v = dataclasses.replace(
                v,
                verdict=CHANGES_WITHOUT_A_SEED,
                detail=f"{readings}. {v.detail}",
                primary=v.verdict,
                readings=readings,
            )
        j.final.append(v)
    return j


def _effect(q) -> str:
    from .._text import fmt

    ci = f" [{fmt(q.lo)}, {fmt(q.hi)}]" if q.lo == q.lo and q.hi == q.hi else ""
    return f"{fmt(q.point)}{ci}"


def why_not_replicated(j: Judgement, key: str) -> str | None:
    """Why a claim's seed sets read different verdicts, from its parts: those whose status
    differs, each with its effect and 90% interval on both sets; whether any reverses (holds
    <-> contradicts: the sets disagree) or none does (one set leaves undecided or untested
    what the other signs); and the pooled reading, which decides nothing here. None where the
    claim replicates or is not judged."""
    p, r = j.primary.get(key), j.replication.get(key)
    if p is None or r is None or r.n_seeds == 0 or r.verdict == p.verdict:
        return None
    ps, rs = seed_span(j.primary_seeds), seed_span(j.replication_seeds)
    theirs = {q.name: q for q in r.parts}
    moved = [
        f"{q.name}: {q.status} on seeds {ps} ({_effect(q)}), {theirs[q.name].status} on seeds {rs} "
        f"({_effect(theirs[q.name])})"
        for q in p.parts
        if q.name in theirs and theirs[q.name].status != q.status
    ]
    flipped = reversed_parts(p, r)
    n = len(flipped)
    lead = (
        f"**{n} part{'s reverse' if n > 1 else ' reverses'}** (the seed sets disagree)"
        if flipped
        else "no part reverses (holds <-> contradicts): the sets differ only in what reaches "
        "significance or gets tested"
    )
    if not moved:  # the same statuses, a different verdict: a gate or the discrimination check
        moved = [f"seeds {ps}: {p.verdict}; seeds {rs}: {r.verdict} ({r.detail[:160]})"]
    pooled = j.pooled_any.get(key)
    tail = (
        f"; pooled {seed_span({*j.primary_seeds, *j.replication_seeds})}, for information: "
        f"{pooled.verdict}"
        if pooled
        else ""
    )
    return f"{lead}: " + "; ".join(moved) + tail


def pooled_moves(j: Judgement, key: str) -> str | None:
    """Where two seed sets agree and their pooled reading (the final one) differs from what
    both read: the parts whose pooled status differs from the one both sets gave it, with the
    pooled effect and interval (ten seeds resolve what five left undecided). None elsewhere."""
    p, r, pooled = j.primary.get(key), j.replication.get(key), j.pooled.get(key)
    if pooled is None or p is None or r is None or pooled.verdict == p.verdict:
        return None
    first, second = ({q.name: q.status for q in v.parts} for v in (p, r))
    both = seed_span({*j.primary_seeds, *j.replication_seeds})
    moved = [
        f"{q.name}: {q.status} on {both} ({_effect(q)}), {first[q.name]} on each set alone"
        for q in pooled.parts
        if first.get(q.name) == second.get(q.name) and q.status != first.get(q.name)
    ]
    text = "; ".join(moved) or pooled.detail[:160]
    return f"both seed sets read {p.verdict}, pooled {pooled.verdict}: {text}"


def settled(verdict: str) -> bool:
    """Whether a final verdict is a finding (not inconclusive of either kind)."""
    return verdict not in (INCONCLUSIVE, DOES_NOT_REPLICATE, CHANGES_WITHOUT_A_SEED)
