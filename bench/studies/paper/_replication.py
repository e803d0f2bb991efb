"""Verdicts that replicate (issue 20): every claim judged on the profile's seeds, again on a
disjoint seed set, and without each of its seeds.

- *Primary*: the profile's own seeds (``quick`` and ``paper``: 0-4; for a profile that declares
  fewer than a verdict needs, ``smoke``, every stored seed outside the replication set).
- *Replication*: :data:`bench.core._experiments.REPLICATION_SEEDS` (``quick`` and ``paper``,
  hence ``paper-core``: 5-9), stored beside the primary runs by ``make replicate``
  (``python -m bench campaign --profile quick --replication``) or by the paper-core campaign
  after its own seeds. Where both exist and the verdicts differ, the claim's verdict is
  *inconclusive (does not replicate)*, and both readings are shown. A claim whose replication
  runs are only partly stored (a campaign under way) is not judged on them until all are:
  its replication reads *pending (n of m runs)*.
- *Leave one seed out*: the primary seeds without each one in turn, judged by the same rules
  with one seed fewer required (:func:`bench.studies.paper._stats.min_seeds`); a verdict that
  changes when one seed is dropped rests on that seed, and the report says which.

A claim counts as settled only when its verdict replicates on both checks: a verdict that
differs on the replication seeds is *inconclusive (does not replicate)*; one that changes when
any one primary seed is dropped is *inconclusive (changes without a seed)*, and the report names
the seeds and what the verdict becomes without each. Dropping a seed costs the tests power (4
seeds), so this demotes verdicts that only just clear their test: that is the point, a verdict
that one seed carries is not one the suite signs. (Until 2026-11-25 the leave-one-seed-out
reading was shown beside the verdict, not folded into it; folding it in turned quick's claim 4
(geometric-mean error) and claim 9 inconclusive.)
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import pandas as pd

from ...core._experiments import PROFILES, SELECTIONS, expand, profile_defaults, replication_seeds
from ._rules import claim_studies, evaluate_claims
from ._stats import INCONCLUSIVE, Verdict, min_seeds, required_seeds

DOES_NOT_REPLICATE = "inconclusive (does not replicate)"
CHANGES_WITHOUT_A_SEED = "inconclusive (changes without a seed)"


@dataclass
class Judgement:
    """Every claim's verdicts: ``final`` (what the report states), ``primary`` (the profile's
    seeds), ``replication`` (the replication seeds; empty when none are stored) and ``loso``
    (key -> [(dropped seed, verdict)]), with the seed sets used."""

    final: list[Verdict]
    primary: dict[str, Verdict]
    replication: dict[str, Verdict] = field(default_factory=dict)
    loso: dict[str, list[tuple[int, Verdict]]] = field(default_factory=dict)
    primary_seeds: tuple[int, ...] = ()
    replication_seeds: tuple[int, ...] = ()
    # key -> (stored, declared) replication runs of a claim whose replication is under way:
    # not judged until all are stored (a partial reading is not a replication)
    replication_pending: dict[str, tuple[int, int]] = field(default_factory=dict)

    def replicates(self, key: str) -> bool | None:
        r = self.replication.get(key)
        if r is None or r.n_seeds == 0:
            return None
        return r.verdict == self.primary[key].verdict

    def loso_changes(self, key: str) -> list[tuple[int, Verdict]]:
        base = self.primary[key].verdict
        return [(s, v) for s, v in self.loso.get(key, []) if v.verdict != base]


def seed_sets(profile: str | None) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """(primary seeds, replication seeds) of a profile (a selection: its base profile's)."""
    if profile is None:
        return (), ()
    base = SELECTIONS.get(profile, profile)
    try:
        primary = profile_defaults(base)[1]
    except ValueError:
        return (), ()
    return tuple(primary), replication_seeds(base)


def stored_counts(runs: pd.DataFrame, profile: str | None, seeds=None) -> dict[int, tuple]:
    """``{claim: (stored, declared)}``: how many of the runs each claim's experiments declare
    at ``profile`` (on ``seeds`` instead of its own) are in ``runs``; {} for an unknown
    profile."""
    if profile not in PROFILES:
        return {}
    done = set(runs["config_hash"]) if len(runs) and "config_hash" in runs else set()
    out = {}
    for study in claim_studies():
        hashes = {c.config_hash for e in study.experiments for c in expand(e, profile, seeds=seeds)}
        out[study.claim] = (len(hashes & done), len(hashes))
    return out


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
) -> Judgement:
    """Judge every claim on the primary seeds, the replication seeds (where stored) and
    without each primary seed (``loso``; ``loso=False`` skips that check and its demotion, for
    callers that need only the primary and replication readings). Runs of other seeds are
    ignored; a folder whose profile is unknown is judged on all its seeds, without
    replication."""
    declared, rep_seeds = seed_sets(profile)
    # primary: the profile's seeds; for a profile that declares fewer than a verdict needs
    # (smoke) or none, every stored seed outside the replication set
    stored = sorted(int(s) for s in runs["seed"].unique()) if len(runs) and "seed" in runs else []
    if len(declared) >= required_seeds():
        primary_seeds = declared
    else:
        primary_seeds = tuple(s for s in stored if s not in rep_seeds)
    prim = evaluate_claims(_on(runs, primary_seeds), curves, profile)
    primary = {v.key: v for v in prim}
    replication, rep_pending = {}, {}
    if rep_seeds and len(_on(runs, rep_seeds)):
        replication = {v.key: v for v in evaluate_claims(_on(runs, rep_seeds), curves, profile)}
        # a claim whose replication runs are partly stored (a campaign under way) is not
        # judged on them yet: fewer seeds would read as a verdict that does not replicate;
        # one with no complete seed (none of its runs stored) has no reading, as with no runs
        counts = stored_counts(_on(runs, rep_seeds), profile, rep_seeds)
        for key, r in list(replication.items()):
            n, m = counts.get(r.claim, (0, 0))
            if 0 < n < m:
                rep_pending[key] = (n, m)
            if 0 < n < m or r.n_seeds == 0:
                del replication[key]
    out_loso: dict[str, list[tuple[int, Verdict]]] = {}
    present = sorted(set(_on(runs, primary_seeds)["seed"])) if len(runs) else []
    if loso and len(present) > 1:
        with min_seeds(max(2, required_seeds() - 1)):
            for s in present:
                for v in evaluate_claims(
                    _on(runs, [x for x in present if x != s]), curves, profile
                ):
                    out_loso.setdefault(v.key, []).append((int(s), v))
    final = []
    for v in prim:
        r = replication.get(v.key)
        if r is not None and r.n_seeds > 0 and r.verdict != v.verdict:
            readings = f"seeds {_span(primary_seeds)}: {v.verdict}; seeds {_span(rep_seeds)}: " + (
                r.verdict
            )
            v = dataclasses.replace(
                v,
                verdict=DOES_NOT_REPLICATE,
                detail=f"{readings}. {v.detail}",
                primary=v.verdict,
                readings=readings,
            )
        elif settled(v.verdict) and (
            moved := [(s, w) for s, w in out_loso.get(v.key, []) if w.verdict != v.verdict]
        ):
            without = "; ".join(f"without seed {s}: {w.verdict}" for s, w in moved)
            readings = f"seeds {_span(primary_seeds)}: {v.verdict}; {without}"
            v = dataclasses.replace(
                v,
                verdict=CHANGES_WITHOUT_A_SEED,
                detail=f"{readings}. {v.detail}",
                primary=v.verdict,
                readings=readings,
            )
        final.append(v)
    return Judgement(final, primary, replication, out_loso, primary_seeds, rep_seeds, rep_pending)


def _span(seeds) -> str:
    seeds = sorted(seeds)
    if seeds and seeds == list(range(seeds[0], seeds[-1] + 1)) and len(seeds) > 2:
        return f"{seeds[0]}-{seeds[-1]}"
    return ", ".join(map(str, seeds))


def settled(verdict: str) -> bool:
    """Whether a final verdict is a finding (not inconclusive of either kind)."""
    return verdict not in (INCONCLUSIVE, DOES_NOT_REPLICATE, CHANGES_WITHOUT_A_SEED)
