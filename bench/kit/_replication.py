"""Verdicts that replicate: every claim judged on the profile's seeds, again on a disjoint
seed set, pooled where the two agree, and without each seed.

- *Primary*: the profile's own seeds (``quick`` and ``paper``: 0-4; for a profile that declares
  fewer than a verdict needs, ``smoke``, every stored seed outside the replication set).
- *Replication*: the replication seeds (5-9). Replication adds evidence: the final reading is
  the *pooled* ten seeds, unless the sets disagree (:func:`disagreement`): a part reverses
  (holds on one set, contradicted on the other) or its two estimates differ beyond chance
  (Welch's test, Holm's step-down across the claim's parts) and the sets do not sign it alike.
  Then the claim is *inconclusive (does not replicate)*, both readings shown. One set signing a
  part that the other leaves undecided is no disagreement, nor are two sets that sign a part
  alike at different sizes (the report names those): more seeds that agree can never weaken a
  verdict. Each set's own reading stays in the report. A claim whose replication runs are
  partly stored (a campaign under way) reads *pending* and keeps its primary reading.
- *Leave one seed out*: the final reading's seeds without each one in turn (one seed fewer
  required). It flags an influential seed, and demotes the verdict to *inconclusive (changes
  without a seed)* only where dropping that seed reverses a part (holds <-> contradicts); a
  part that merely loses significance on fewer seeds is not evidence against it.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import pandas as pd

from ..core import PROFILES, expand, is_supplementary
from ._claims import claim_studies, evaluate_claims, restrict_all
from ._seeds import min_seeds, required_seeds, seed_sets, seed_span
from ._stats import ALPHA
from ._verdict import INCONCLUSIVE, Verdict

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
        """Whether the seed sets add up (:func:`disagreement` finds nothing); None where the
        replication is not judged."""
        r = self.replication.get(key)
        if r is None or r.n_seeds == 0 or key not in self.pooled_any:
            return None
        return key in self.pooled

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


def heterogeneity_p(a, b) -> float:
    """The two-sided p-value of Welch's test that two seed sets' estimates of one part differ
    (``scipy.stats.ttest_ind_from_stats``), from each set's mean and its one-sided (1 - ALPHA)
    t bounds (the standard error is the bounds' half-width over the t quantile); NaN where a
    set has fewer than two seeds or no finite bounds."""
    from scipy import stats

    sds = []
    for q in (a, b):
        ok = q.n >= 2 and all(math.isfinite(x) for x in (q.point, q.lo, q.hi))
        if not ok:
            return math.nan
        se = (q.hi - q.lo) / (2 * stats.t.ppf(1 - ALPHA, q.n - 1))
        sds.append(se * math.sqrt(q.n))
    if sds[0] == 0 and sds[1] == 0:
        return 0.0 if a.point != b.point else 1.0
    res = stats.ttest_ind_from_stats(
        a.point, sds[0], a.n, b.point, sds[1], b.n, equal_var=False, alternative="two-sided"
    )
    return float(res.pvalue)


def _differing(a: Verdict, b: Verdict, alpha: float) -> list[tuple[float, str, bool]]:
    """The parts whose two estimates differ beyond chance: Welch's test
    (:func:`heterogeneity_p`) with Holm's step-down across the claim's parts tested on both
    sets, at ``alpha``; each as ``(p, name, alike)``, ``alike`` where both sets sign the part
    the same way (both hold, or both contradict)."""
    theirs = {q.name: q for q in b.parts}
    tested = ("holds", "contradicts", "undecided")
    ps = sorted(
        (pv, q.name, q.status == o.status and q.status in ("holds", "contradicts"))
        for q in a.parts
        if q.role == "part"
        and (o := theirs.get(q.name)) is not None
        and q.status in tested
        and o.status in tested
        and math.isfinite(pv := heterogeneity_p(q, o))
    )
    out = []
    for i, found in enumerate(ps):  # Holm's step-down
        if found[0] > alpha / (len(ps) - i):
            break
        out.append(found)
    return out


def disagreement(a: Verdict, b: Verdict, alpha: float = ALPHA) -> list[str]:
    """Why two seed sets' readings of a claim cannot be pooled, one line per reason (empty: they
    add up). A part *reverses* (holds on one set, contradicted on the other), or its estimates
    differ beyond chance (:func:`_differing`) where the sets do not sign it alike. A part that
    one set signs and the other leaves undecided is no disagreement by itself: the pooled seeds
    decide it. Nor is a part both sets sign alike, however far apart its two estimates: each
    set reaches the same finding on its own, which is what replication asks
    (:func:`estimates_differ` names it)."""
    out = [f"{name} reverses" for name in reversed_parts(a, b)]
    for pv, name, alike in _differing(a, b, alpha):
        if not alike and f"{name} reverses" not in out:
            out.append(f"{name}: the seed sets' estimates differ (Welch p = {pv:.2g})")
    return out


def estimates_differ(j: Judgement, key: str, alpha: float = ALPHA) -> str | None:
    """Where the seed sets add up although a part's two estimates differ beyond chance, both
    sets signing it alike: the parts, each with its effect and 90% interval on both sets (the
    finding replicates; its size does not, and the pooled interval understates the spread
    between the sets). None elsewhere."""
    p, r = j.primary.get(key), j.replication.get(key)
    if p is None or r is None or key not in j.pooled:
        return None
    ps, rs = seed_span(j.primary_seeds), seed_span(j.replication_seeds)
    mine, theirs = ({q.name: q for q in v.parts} for v in (p, r))
    lines = [
        f"{name}: {mine[name].status} on both, {_effect(mine[name])} on seeds {ps}, "
        f"{_effect(theirs[name])} on seeds {rs} (Welch p = {pv:.2g})"
        for pv, name, alike in _differing(p, r, alpha)
        if alike
    ]
    return "; ".join(lines) or None


def costs_apart(j: Judgement, key: str, alpha: float = ALPHA) -> bool:
    """Whether a part on which a claim's two seed sets differ (it reverses, or its estimates
    differ beyond chance: :func:`_differing`) measures a cost (its quantity is policy's
    "cost"): a time is the machine's, so the report names the machines each set ran on."""
    p, r = j.primary.get(key), j.replication.get(key)
    if p is None or r is None:
        return False
    apart = set(reversed_parts(p, r)) | {name for _, name, _ in _differing(p, r, alpha)}
    return any(q.quantity == "cost" for q in p.parts if q.name in apart)


def stored_counts(
    runs: pd.DataFrame, profile: str | None, seeds=None, keep=None, *, supplementary=False
) -> dict[int, tuple]:
    """``{claim: (stored, declared)}``: how many of the runs each claim's experiments declare
    at ``profile`` (on ``seeds`` instead of its own; only the cells ``keep(config)`` accepts
    where given) are in ``runs``; {} for an unknown profile. The cells of a claim's further
    readings (``Experiment.supplementary``) are counted apart: ``supplementary=True`` counts
    them alone (a claim without any is left out), the default every other cell."""
    if profile not in PROFILES:
        return {}
    from ..core import studies

    done = set(runs["config_hash"]) if len(runs) and "config_hash" in runs else set()
    judged = {s.claim for s in claim_studies()}
    declared: dict[int, set] = {}
    for study in studies():  # a claim's experiments may be declared by several studies
        if study.claim in judged:
            hashes = declared.setdefault(study.claim, set())
            for e in study.experiments:
                if supplementary and e.supplementary is None:
                    continue
                hashes.update(
                    c.config_hash
                    for c in expand(e, profile, seeds=seeds)
                    if is_supplementary(e, c) == supplementary and (keep is None or keep(c))
                )
    if supplementary:
        declared = {n: h for n, h in declared.items() if h}
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
    claims=None,
    keep=None,
) -> Judgement:
    """Judge every claim on the primary seeds, the replication seeds (where stored), both
    pooled (where they agree) and without each seed of the final reading (``loso``;
    ``loso=False`` skips that check and its demotion). Runs of other seeds are ignored; a
    folder whose profile is unknown is judged on all its seeds, without replication.
    ``restricted``: each claim's rows of ``runs`` already restricted (:func:`restrict_all`), for
    callers that need them too. ``claims``: only these claims; ``keep``: only the declared cells
    it accepts count as the replication's (a reading of some cells, e.g. one number of links)."""
    declared, rep_seeds = seed_sets(profile)
    stored = sorted(int(s) for s in runs["seed"].unique()) if len(runs) and "seed" in runs else []
    if len(declared) >= required_seeds():
        primary_seeds = declared
    else:
        primary_seeds = tuple(s for s in stored if s not in rep_seeds)
    cache = restrict_all(runs, profile, claims, keep) if restricted is None else restricted

    def evaluate(seeds):
        return evaluate_claims(runs, curves, profile, claims=claims, seeds=seeds, restricted=cache)

    prim = evaluate(primary_seeds)
    primary = {v.key: v for v in prim}
    replication, rep_pending, pooled, pooled_any = {}, {}, {}, {}
    if rep_seeds and len(_on(runs, rep_seeds)):
        replication = {v.key: v for v in evaluate(rep_seeds)}
        counts = stored_counts(_on(runs, rep_seeds), profile, rep_seeds, keep)
        for key, r in list(replication.items()):
            n, m = counts.get(r.claim, (0, 0))
            if 0 < n < m:
                rep_pending[key] = (n, m)
            if 0 < n < m or r.n_seeds == 0:
                del replication[key]
        if replication:
            both = tuple(sorted({*primary_seeds, *rep_seeds}))
            every = {v.key: v for v in evaluate(both)}
            pooled_any = {k: every[k] for k in replication if k in every}
            # the seed sets add up unless they disagree: a part reverses, or its estimates
            # differ beyond chance (:func:`disagreement`)
            pooled = {
                k: v for k, v in pooled_any.items() if not disagreement(primary[k], replication[k])
            }
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
        if r is not None and v.key not in pooled and v.key in pooled_any:
            readings = (
                f"seeds {seed_span(primary_seeds)}: {v.verdict}; seeds {seed_span(rep_seeds)}: "
                + (r.verdict)
            )
            v = dataclasses.replace(
                v,
                verdict=DOES_NOT_REPLICATE,
                detail=f"{readings}; {'; '.join(disagreement(v, r))}. {v.detail}",
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
    from ._text import fmt

    ci = f" [{fmt(q.lo)}, {fmt(q.hi)}]" if q.lo == q.lo and q.hi == q.hi else ""
    return f"{fmt(q.point)}{ci}"


def why_not_replicated(j: Judgement, key: str) -> str | None:
    """Why a claim's seed sets read different verdicts, from its parts: those whose status
    differs, each with its effect and 90% interval on both sets; whether any reverses (holds
    <-> contradicts: the sets disagree) or none does (one set leaves undecided or untested
    what the other signs); and the pooled reading, which decides nothing here. None where the
    claim replicates or is not judged."""
    p, r = j.primary.get(key), j.replication.get(key)
    if p is None or r is None or r.n_seeds == 0 or j.replicates(key) is not False:
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
        else "no part reverses (holds <-> contradicts), but " + "; ".join(disagreement(p, r))
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
    """Where the seed sets add up and their pooled reading (the final one) differs from what
    either set read alone: the parts whose pooled status differs from a set's, with the pooled
    effect and interval and each set's status (ten seeds resolve what five left undecided).
    None elsewhere."""
    p, r, pooled = j.primary.get(key), j.replication.get(key), j.pooled.get(key)
    if pooled is None or p is None or r is None:
        return None
    if pooled.verdict == p.verdict and pooled.verdict == r.verdict:
        return None
    first, second = ({q.name: q.status for q in v.parts} for v in (p, r))
    both = seed_span({*j.primary_seeds, *j.replication_seeds})
    ps, rs = seed_span(j.primary_seeds), seed_span(j.replication_seeds)
    moved = [
        f"{q.name}: {q.status} on {both} ({_effect(q)}); {first.get(q.name, '-')} on {ps}, "
        f"{second.get(q.name, '-')} on {rs}"
        for q in pooled.parts
        if q.status != first.get(q.name) or q.status != second.get(q.name)
    ]
    text = "; ".join(moved) or pooled.detail[:160]
    return (
        f"seeds {ps} read {p.verdict}, seeds {rs} {r.verdict}; they add up, pooled "
        f"{pooled.verdict}: {text}"
    )


def settled(verdict: str) -> bool:
    """Whether a final verdict is a finding (not inconclusive of either kind)."""
    return verdict not in (INCONCLUSIVE, DOES_NOT_REPLICATE, CHANGES_WITHOUT_A_SEED)
