"""Verdicts that replicate (bench.kit._replication.judge) on synthetic stored runs.

The quick profile's claims are judged on its primary seeds (0-4), again on the replication
seeds (5-9), and without each primary seed. The tables hold only the runs of the second_order
experiment (claim 3's cells, which claims 1, 4 and 6 read too): judge() evaluates every claim
up to seven times, and a small table keeps each test to a few seconds.
"""

import re

import pandas as pd
import pytest
from _synthetic import synthetic_tables

from bench import kit as R
from bench.core import PROFILES, REPLICATION_SEEDS, expand
from bench.kit import evaluate_claims
from bench.kit._replication import (
    CHANGES_WITHOUT_A_SEED,
    DOES_NOT_REPLICATE,
    disagreement,
    estimates_differ,
    judge,
    pooled_moves,
    reversed_parts,
    seed_sets,
    seed_span,
    settled,
    why_not_replicated,
)
from bench.kit._text import fmt

PROFILE = "quick"
PRIMARY = (0, 1, 2, 3, 4)
REPLICATION = (5, 6, 7, 8, 9)


def _tables(seeds, scenario="reproduce", rng=0):
    return synthetic_tables(
        PROFILE, seeds=seeds, scenario=scenario, rng=rng, experiments=("second_order",)
    )


def _join(*tables):
    return (
        pd.concat([t[0] for t in tables], ignore_index=True),
        pd.concat([t[1] for t in tables], ignore_index=True),
    )


def _final(j):
    return {v.key: v for v in j.final}


def test_seed_sets_of_the_profiles():
    assert PROFILES[PROFILE]["seeds"] == PRIMARY and REPLICATION_SEEDS[PROFILE] == REPLICATION
    assert seed_sets(PROFILE) == (PRIMARY, REPLICATION)
    assert seed_sets("paper") == (PRIMARY, REPLICATION)
    assert seed_sets("paper-core") == (PRIMARY, REPLICATION)  # a selection: its base's seeds
    assert seed_sets("smoke") == ((0,), ())
    assert seed_sets(None) == ((), ())
    assert seed_sets("no-such-profile") == ((), ())
    assert seed_span(REPLICATION) == "5-9" and seed_span((0, 2)) == "0, 2"
    assert settled(R.REPRODUCED) and settled(R.NOT_REPRODUCED) and settled(R.PARTLY)
    assert not settled(R.INCONCLUSIVE) and not settled(DOES_NOT_REPLICATE)
    assert not settled(CHANGES_WITHOUT_A_SEED)


@pytest.fixture(scope="module")
def reproduce_primary():
    return _tables(PRIMARY)


@pytest.fixture(scope="module")
def reproduce_replication():
    return _tables(REPLICATION, rng=1)


@pytest.fixture(scope="module")
def contradict_replication():
    return _tables(REPLICATION, scenario="contradict", rng=1)


def test_both_seed_sets_reproduce(reproduce_primary, reproduce_replication):
    # runs of seeds outside both sets (10, 11) are ignored
    extra = _tables((10, 11), scenario="contradict", rng=2)
    runs, curves = _join(reproduce_primary, reproduce_replication, extra)
    j = judge(runs, curves, PROFILE, loso=False)
    assert j.primary_seeds == PRIMARY and j.replication_seeds == REPLICATION
    final = _final(j)
    for key in ("1", "3"):
        assert final[key].verdict == R.REPRODUCED, final[key].detail
        assert j.replicates(key) is True
        assert j.primary[key].n_seeds == 5 and j.replication[key].n_seeds == 5
        assert final[key].profile == PROFILE
    assert j.loso == {}
    # two disjoint seed sets that agree: the final reading is the ten seeds pooled
    for key in ("1", "3"):
        assert j.pooled[key].n_seeds == 10 and j.reading(key) is j.pooled[key]
        assert j.reading_seeds(key) == (*PRIMARY, *REPLICATION)
        assert final[key] is j.pooled[key]
    # claims without runs here: inconclusive on both sets, which "replicates" nothing
    assert final["5"].verdict == R.INCONCLUSIVE and j.replicates("5") is None
    assert DOES_NOT_REPLICATE not in {v.verdict for v in j.final}


@pytest.mark.parametrize("contradicting", ["replication", "primary"])
def test_disagreeing_seed_sets_do_not_replicate(
    reproduce_primary, contradict_replication, contradicting
):
    if contradicting == "replication":
        runs, curves = _join(reproduce_primary, contradict_replication)
        primary, replication = R.REPRODUCED, R.NOT_REPRODUCED
    else:
        contradict_primary = _tables(PRIMARY, scenario="contradict", rng=3)
        runs, curves = _join(contradict_primary, _tables(REPLICATION, rng=1))
        primary, replication = R.NOT_REPRODUCED, R.REPRODUCED
    j = judge(runs, curves, PROFILE, loso=False)
    final = _final(j)
    assert j.primary["3"].verdict == primary and j.replication["3"].verdict == replication
    assert final["3"].verdict == DOES_NOT_REPLICATE and not settled(final["3"].verdict)
    assert j.replicates("3") is False
    flipped = reversed_parts(j.primary["3"], j.replication["3"])
    assert flipped  # a part holds on one set and is contradicted on the other
    # the detail: the readings, why they cannot be pooled, then the primary seeds' detail
    why = "; ".join(disagreement(j.primary["3"], j.replication["3"]))
    assert final["3"].detail == f"{final['3'].readings}; {why}. {j.primary['3'].detail}"
    # the demoted reading and the readings behind it, for the report's causes
    assert final["3"].primary == primary
    assert final["3"].readings == f"seeds 0-4: {primary}; seeds 5-9: {replication}"
    assert final["5"].primary is None and final["5"].readings == ""
    # the rest of the verdict is the primary seeds' reading
    assert final["3"].effect == j.primary["3"].effect
    assert final["3"].n_seeds == 5
    # claims that agree (inconclusive for want of runs on both sets) are left alone
    assert final["5"].verdict == R.INCONCLUSIVE and j.replicates("5") is None
    # why: the parts the sets read in reverse, each with its effect on both; the pooled
    # reading shown for information, never the verdict
    why = why_not_replicated(j, "3")
    assert re.match(r"\*\*(\d+) parts? reverses?\*\*", why).group(1) == str(len(flipped)), why
    moved = _moved(why)  # each part whose status differs, with its estimate on both sets
    first = j.primary["3"].parts[0]
    assert moved[first.name][:2] == (first.status, fmt(first.point)), why
    assert why.endswith(f", for information: {j.pooled_any['3'].verdict}"), why  # pooled
    assert "3" not in j.pooled and j.pooled_any["3"].n_seeds == 10
    assert why_not_replicated(j, "5") is None


def test_partly_stored_replication_is_pending_not_a_failure_to_replicate(
    reproduce_primary, contradict_replication
):
    """A campaign under way has stored some replication runs of a claim: its replication is
    pending (n of m runs) and the primary verdict stands, even where the partial reading
    disagrees; once every run is stored it is judged (and here does not replicate)."""
    runs, curves = _join(reproduce_primary, contradict_replication)
    full = judge(runs, curves, PROFILE, loso=False)
    assert _final(full)["3"].verdict == DOES_NOT_REPLICATE and "3" not in full.replication_pending
    rep = runs["seed"].isin(REPLICATION)
    dropped = runs[rep].iloc[0]["config_hash"]
    part = judge(runs[runs["config_hash"] != dropped], curves, PROFILE, loso=False)
    m = int(rep.sum())
    assert part.replication_pending["3"] == (m - 1, m)
    assert "3" not in part.replication and part.replicates("3") is None
    assert _final(part)["3"].verdict == R.REPRODUCED


def test_without_replication_runs_the_primary_verdicts_stand(reproduce_primary):
    runs, curves = reproduce_primary
    j = judge(runs, curves, PROFILE, loso=False)
    assert j.replication == {}
    assert [(v.key, v.verdict, v.detail) for v in j.final] == [
        (v.key, v.verdict, v.detail) for v in evaluate_claims(runs, curves, PROFILE)
    ]
    assert all(j.final[i] == j.primary[v.key] for i, v in enumerate(j.final))
    assert j.replicates("3") is None
    assert _final(j)["3"].verdict == R.REPRODUCED


def test_unknown_profile_is_judged_on_every_seed_without_replication(
    reproduce_primary, reproduce_replication
):
    runs, curves = _join(reproduce_primary, reproduce_replication)
    j = judge(runs, curves, None, loso=False)
    assert j.primary_seeds == tuple(range(10)) and j.replication == {}
    assert _final(j)["3"].n_seeds == 10 and _final(j)["3"].verdict == R.REPRODUCED


def _chain(runs, model):
    return (
        (runs["system"] == "chain_pendulum")
        & (runs["model"] == model)
        & (runs["k"] == 2)
        & (runs["loss"] == "l2")
    )


def _so_gain(runs, factors):
    """NODE+SO on the chain set to NODE's error divided by ``factors[seed]``: the per-seed
    ``log(err NODE / err NODE+SO)`` of claim 3 (a) is then ``log(factors)``."""
    runs = runs.copy()
    node = runs.loc[_chain(runs, "node")].set_index("seed")["rollout_error"]
    so = _chain(runs, "node_so")
    assert so.sum() == len(node) == 5
    seeds = runs.loc[so, "seed"]
    runs.loc[so, "rollout_error"] = (seeds.map(node) / seeds.map(dict(enumerate(factors)))).values
    return runs


@pytest.mark.parametrize(
    ("factors", "all_seeds", "without_3"),
    [
        # SO gains 3.3x on every seed but seed 3, where NODE+SO is 3x worse than NODE: with seed
        # 3 the gain is undecided (inconclusive); without it the claim is reproduced
        ((3.3, 3.3, 3.3, 1 / 3, 3.3), R.INCONCLUSIVE, R.REPRODUCED),
        # SO gains 1.1x (a tie: contradicted) on every seed but seed 3, where it gains 30x:
        # seed 3 alone leaves the chain's parts undecided; without it they are contradicted
        ((1.1, 1.1, 1.1, 30.0, 1.1), R.INCONCLUSIVE, R.PARTLY),
    ],
)
def test_leave_one_seed_out_names_the_seed_a_verdict_rests_on(
    reproduce_primary, factors, all_seeds, without_3
):
    runs, curves = reproduce_primary
    runs = _so_gain(runs, factors)
    j = judge(runs, curves, PROFILE)
    assert R.required_seeds() == R.MIN_SEEDS  # the leave-one-out's 4 seeds are not left behind
    v = j.primary["3"]
    assert v.verdict == all_seeds, v.detail
    assert [p.status for p in v.parts if p.name.startswith("chain_pendulum: (a) log(NODE")] == [
        "undecided"
    ]
    # judged five times, once without each seed, with one seed fewer required
    assert [s for s, _ in j.loso["3"]] == list(PRIMARY)
    assert all(w.n_seeds == 4 for _, w in j.loso["3"])
    changes = j.loso_changes("3")
    assert [s for s, _ in changes] == [3], [(s, w.verdict) for s, w in j.loso["3"]]
    assert changes[0][1].verdict == without_3
    # an inconclusive verdict stays what it is, whatever the seeds' subsets say
    assert _final(j)["3"].verdict == all_seeds
    # every claim is judged without each seed; one inconclusive for want of runs stays so
    assert set(j.loso) == set(j.primary)
    assert all(len(got) == 5 for got in j.loso.values())
    assert j.loso_changes("5") == []


@pytest.mark.parametrize(
    "factors",
    [
        (3.3, 3.3, 3.3, 3.3, 3.3),  # a clear gain on every seed
        # seed 3's 2x gain is close to the margin: without another seed the four left may not
        # clear the test, which costs power and is no evidence against the claim
        (5.0, 3.3, 3.3, 2.0, 3.3),
    ],
)
def test_losing_significance_without_a_seed_does_not_demote(reproduce_primary, factors):
    runs, curves = reproduce_primary
    runs = _so_gain(runs, factors)
    j = judge(runs, curves, PROFILE)
    assert j.primary["3"].verdict == R.REPRODUCED
    assert j.loso_reversals("3") == []
    v = _final(j)["3"]
    assert v.verdict == R.REPRODUCED and v.primary is None and v.readings == ""


def _replication_gains(runs, gains):
    runs = runs.copy()
    node = runs.loc[_chain(runs, "node")].set_index("seed")["rollout_error"]
    so = _chain(runs, "node_so") & runs["seed"].isin(list(gains))
    seeds = runs.loc[so, "seed"]
    runs.loc[so, "rollout_error"] = (seeds.map(node) / seeds.map(gains)).values
    return runs


def test_a_part_left_undecided_on_the_other_set_adds_evidence(
    reproduce_primary, reproduce_replication
):
    """Seeds 5-9 leave undecided a part seeds 0-4 sign (SO gains 3.3x on four of them, loses 3x
    on one). No part reverses and the estimates do not differ beyond chance: the sets add up,
    and the final reading is the ten seeds pooled, each set's reading kept beside it."""
    runs, curves = _join(reproduce_primary, reproduce_replication)
    runs = _replication_gains(runs, {5: 3.3, 6: 3.3, 7: 1 / 3, 8: 3.3, 9: 3.3})
    j = judge(runs, curves, PROFILE, loso=False)
    assert j.primary["3"].verdict == R.REPRODUCED
    assert j.replication["3"].verdict == R.INCONCLUSIVE
    assert j.replicates("3") is True and why_not_replicated(j, "3") is None
    assert _final(j)["3"] is j.pooled["3"] and j.pooled["3"].n_seeds == 10
    said = _added_up(pooled_moves(j, "3"))
    assert said[:3] == (R.REPRODUCED, R.INCONCLUSIVE, j.pooled["3"].verdict), said


def _gains_on_both(runs, primary, replication):
    """The chain's NODE+SO gain set per seed on both seed sets."""
    runs = _replication_gains(runs, dict(zip(PRIMARY, primary, strict=True)))
    return _replication_gains(runs, dict(zip(REPLICATION, replication, strict=True)))


CHAIN_SO = "chain_pendulum: (a) log(NODE / NODE+SO)"


def _status(v, name=CHAIN_SO):
    return {q.name: q.status for q in v.parts}[name]


def test_estimates_that_differ_beyond_chance_where_both_sets_sign_alike_replicate(
    reproduce_primary, reproduce_replication
):
    """Both sets sign SO's gain on the chain, one at 30x and the other at 3x on every seed: the
    two estimates differ far beyond their spread (Welch's test), but each set reaches the same
    finding on its own. The sets add up (the pooled ten seeds are the final reading), and the
    report names the part whose size does not replicate, with both estimates."""
    runs, curves = _join(reproduce_primary, reproduce_replication)
    jitter = (1.0, 1.05, 0.95, 1.1, 0.9)
    runs = _gains_on_both(runs, [30.0 * x for x in jitter], [3.0 * x for x in jitter])
    j = judge(runs, curves, PROFILE, loso=False)
    assert [_status(v) for v in (j.primary["3"], j.replication["3"])] == ["holds", "holds"]
    assert disagreement(j.primary["3"], j.replication["3"]) == []
    assert j.replicates("3") is True and why_not_replicated(j, "3") is None
    assert _final(j)["3"] is j.pooled["3"] and _status(j.pooled["3"]) == "holds"
    said = estimates_differ(j, "3")
    assert said.startswith(f"{CHAIN_SO}: holds on both, ") and "Welch p = " in said, said
    assert said.count("Welch p") == 1  # the one part whose sizes differ
    assert estimates_differ(j, "5") is None


def test_estimates_that_differ_beyond_chance_where_a_set_leaves_it_undecided_do_not_replicate(
    reproduce_primary, reproduce_replication
):
    """One set signs SO's gain at 30x, the other leaves it undecided around 0.9x, and the two
    estimates differ beyond chance: pooling sets that differ so would let one set decide for
    the other, so they do not replicate, with the reason named; no part reverses."""
    runs, curves = _join(reproduce_primary, reproduce_replication)
    first = (30.0, 31.5, 28.5, 33.0, 27.0)
    runs = _gains_on_both(runs, first, (0.5, 2.0, 0.7, 1.2, 0.6))
    j = judge(runs, curves, PROFILE, loso=False)
    statuses = [_status(v) for v in (j.primary["3"], j.replication["3"])]
    assert statuses == ["holds", "undecided"]
    final = _final(j)["3"]
    assert final.verdict == DOES_NOT_REPLICATE and j.replicates("3") is False
    reasons = disagreement(j.primary["3"], j.replication["3"])
    assert (
        len(reasons) == 1 and reasons[0].startswith(f"{CHAIN_SO}: ") and reasons[0] in final.detail
    )
    assert reversed_parts(j.primary["3"], j.replication["3"]) == []
    why = why_not_replicated(j, "3")
    assert not re.match(r"\*\*\d+ parts? reverse", why) and reasons[0] in why, why
    assert estimates_differ(j, "3") is None


@pytest.mark.parametrize("stronger", [1.0, 2.0, 4.0])
def test_stronger_evidence_in_one_set_never_weakens_the_verdict(
    reproduce_primary, reproduce_replication, stronger
):
    """Monotone in the evidence: the replication set's SO gain moved further in the claim's
    favour (a modest 2.5x, then 5x, then 10x, each with the same spread) never turns a signed
    verdict inconclusive; with the modest gain, which one set alone may leave undecided, the
    pooled reading already signs the part."""
    runs, curves = _join(reproduce_primary, reproduce_replication)
    jitter = (1.0, 1.2, 0.8, 1.3, 0.7)
    base = {s: 2.5 * stronger * j for s, j in zip(REPLICATION, jitter, strict=True)}
    primary_gain = {s: 2.5 * stronger * j for s, j in zip(PRIMARY, jitter[::-1], strict=True)}
    runs = _replication_gains(_replication_gains(runs, primary_gain), base)
    j = judge(runs, curves, PROFILE, loso=False)
    assert j.replicates("3") is True
    part = {q.name: q.status for q in j.pooled["3"].parts}[
        "chain_pendulum: (a) log(NODE / NODE+SO)"
    ]
    assert part == "holds"


def test_pooling_that_resolves_a_part_is_said(
    reproduce_primary, reproduce_replication, monkeypatch
):
    """Both seed sets read one verdict; the pooled ten seeds (the final reading) sign a part
    that each set left undecided, and read another verdict: the report names that part."""
    import dataclasses

    from bench.kit import _replication

    runs, curves = _join(reproduce_primary, reproduce_replication)
    real = _replication.evaluate_claims

    def fake(runs_, curves_, profile, claims=None, *, seeds=None, restricted=None):
        got = real(runs_, curves_, profile, claims, seeds=seeds, restricted=restricted)
        out = []
        for v in got:
            if v.key == "3":  # each set alone: the first part undecided (synthetic)
                parts = [dataclasses.replace(q) for q in v.parts]
                if len(seeds) == 5:
                    parts[0].status = "undecided"
                    v = dataclasses.replace(v, verdict=R.INCONCLUSIVE, parts=tuple(parts))
            out.append(v)
        return out

    monkeypatch.setattr(_replication, "evaluate_claims", fake)
    j = judge(runs, curves, PROFILE, loso=False)
    assert j.primary["3"].verdict == j.replication["3"].verdict == R.INCONCLUSIVE
    assert _final(j)["3"].verdict == R.REPRODUCED and j.replicates("3") is True
    said = _added_up(pooled_moves(j, "3"))
    name = j.pooled["3"].parts[0].name
    assert said[:3] == (R.INCONCLUSIVE, R.INCONCLUSIVE, R.REPRODUCED), said
    # the part ten seeds resolve: its pooled status, then each set's
    assert said[3][name] == ("holds", "0-9", "undecided", "undecided"), said
    assert pooled_moves(j, "5") is None and why_not_replicated(j, "3") is None


def test_a_part_reversed_without_a_seed_demotes_the_verdict(reproduce_primary, monkeypatch):
    import dataclasses

    from bench.kit import _replication

    runs, curves = reproduce_primary
    real = _replication.evaluate_claims

    def fake(runs_, curves_, profile, claims=None, *, seeds=None, restricted=None):
        got = real(runs_, curves_, profile, claims, seeds=seeds, restricted=restricted)
        if seeds is None or 2 in seeds:
            return got
        # without seed 2, claim 3's first part is contradicted (synthetic)
        out = []
        for v in got:
            if v.key == "3":
                parts = [dataclasses.replace(q) for q in v.parts]
                parts[0].status = "contradicts"
                v = dataclasses.replace(v, verdict=R.PARTLY, parts=tuple(parts))
            out.append(v)
        return out

    monkeypatch.setattr(_replication, "evaluate_claims", fake)
    j = judge(runs, curves, PROFILE)
    assert [s for s, _ in j.loso_reversals("3")] == [2]
    v = _final(j)["3"]
    assert v.verdict == CHANGES_WITHOUT_A_SEED and v.primary == R.REPRODUCED
    ((_, parts),) = j.loso_reversals("3")
    assert parts == ["chain_pendulum: (a) log(NODE / NODE+SO)"] and parts[0] in v.readings


def test_leave_one_seed_out_needs_more_than_one_seed(reproduce_primary):
    runs, curves = reproduce_primary
    one = runs[runs["seed"] == 0]
    j = judge(one, curves, PROFILE)
    assert j.loso == {} and _final(j)["3"].verdict == R.INCONCLUSIVE


def test_every_claim_evaluates_on_a_table_of_one_experiment(reproduce_primary):
    runs, curves = reproduce_primary
    for v in evaluate_claims(runs, curves, PROFILE):
        assert "could not evaluate" not in v.detail, (v.key, v.detail)
    shuffled = runs.sample(frac=1, random_state=0).reset_index(drop=True)
    got = {v.key: v.verdict for v in evaluate_claims(shuffled, curves, PROFILE)}
    assert got == {v.key: v.verdict for v in evaluate_claims(runs, curves, PROFILE)}


def test_a_claim_without_stored_replication_runs_has_no_replication_reading(
    reproduce_primary, contradict_replication
):
    """A campaign has stored the replication runs of some experiments only: a claim with none
    of its own has no replication reading (the report's '-'), not a verdict on zero seeds."""
    runs, curves = _join(reproduce_primary, contradict_replication)
    rep = runs["seed"].isin(REPLICATION)
    j = judge(runs[~rep | (runs["experiment"] == "second_order")], curves, PROFILE, loso=False)
    assert j.replication["3"].n_seeds == 5 and j.replicates("3") is False
    assert "5" not in j.replication and "5" not in j.replication_pending
    assert j.replicates("5") is None
    # a claim that shares some of the stored runs but has no complete seed is pending
    one = runs[rep & (runs["experiment"] == "second_order")].iloc[:1]
    k = judge(pd.concat([runs[~rep], one]), curves, PROFILE, loso=False)
    assert "3" not in k.replication and k.replication_pending["3"][0] == 1


def test_a_claims_declared_runs_count_every_study_that_declares_its_experiments():
    """Claim 7's seed protocol is declared by a study of its own: its runs count toward the
    claim's stored/declared runs (else a campaign folder reads claim 7 as complete, not pending,
    with none of the seed protocol's runs stored)."""

    from bench.kit._replication import stored_counts

    counts = stored_counts(pd.DataFrame({"config_hash": []}), "paper-core")
    ours = {c.config_hash for c in expand("relativistic", "paper-core")}
    seeds = {c.config_hash for c in expand("relativistic_seed", "paper-core")}
    assert seeds and counts[7] == (0, len(ours | seeds))


def _moved(why):
    """The parts :func:`why_not_replicated` names, read back: name -> (status on seeds 0-4, its
    estimate, status on seeds 5-9)."""
    found = re.findall(
        r"(?:: |; )([^;]+?): (\w[\w ]*?) on seeds \S+ \((\S+?)[ )][^;]*?, (\w[\w ]*?) on seeds",
        why,
    )
    return {name: (a, est, b) for name, a, est, b in found}


def _added_up(said):
    """:func:`pooled_moves` read back: (seeds 0-4's verdict, seeds 5-9's, the pooled one,
    {part: (pooled status, pooled seeds, status on 0-4, status on 5-9)})."""
    head, _, text = said.partition(": ")
    first, second, pooled = re.fullmatch(
        r"seeds \S+ read (.+), seeds \S+ (.+); they add up, pooled (.+)", head
    ).groups()
    statuses = r"holds|contradicts|undecided|not tested|-"
    parts = re.findall(
        rf"([^;]+?): ({statuses}) on (\S+) \([^)]*\); ({statuses}) on \S+, ({statuses}) on \S+",
        text,
    )
    moved = {n.strip(): (s, both, a, b) for n, s, both, a, b in parts}
    return first, second, pooled, moved


def test_a_further_reading_joins_its_claim_whole_and_never_holds_it_pending():
    """Claim 5's Rayleigh HNN is a further reading of paper-core (``Experiment.supplementary``):
    stored on some seeds only, the claim is judged on its own cells, without that reading (not
    with the seeds that happen to be done), and the report says how many runs it waits for;
    stored whole, it is a verdict of its own."""
    from bench.core import get, is_supplementary
    from bench.studies.paper.report._comparison import pending

    runs, curves = synthetic_tables("paper-core", seeds=PRIMARY, experiments=("damped",))
    ray = runs["dissipation"].eq(True)
    assert ray.sum() == 10 and all(is_supplementary(get("damped"), c) for c in _configs(runs[ray]))
    part = runs[~ray | runs["seed"].isin((0, 1, 2))].reset_index(drop=True)
    assert R.stored_counts(part, "paper-core")[5] == (50, 50)  # the claim's own cells: all
    assert R.stored_counts(part, "paper-core", supplementary=True)[5] == (6, 10)
    j = judge(part, curves, "paper-core", loso=False, claims=[5])
    assert [v.key for v in j.final] == ["5"] and j.final[0].verdict == R.REPRODUCED
    (v,) = pending(None, part, "paper-core", j.final)
    assert v.pending is None and v.verdict == R.REPRODUCED
    assert v.detail.endswith("its further reading waits for runs: 6 of 10 on seeds 0-4")
    # its rows never reach the rule while incomplete: a Rayleigh HNN that wins would show
    assert not len(R.restrict(part, get_study(5), "paper-core").query("dissipation == True"))
    j = judge(runs, curves, "paper-core", loso=False, claims=[5])
    got = {v.key: v.verdict for v in pending(None, runs, "paper-core", j.final)}
    assert got == {"5": R.REPRODUCED, "5 (against the Rayleigh HNN)": R.REPRODUCED}
    # the claim's own cells missing: pending, as before
    short = runs[~(runs["model"].eq("node_so") & runs["seed"].eq(4))]
    j = judge(short, curves, "paper-core", loso=False, claims=[5])
    assert pending(None, short, "paper-core", j.final)[0].pending == (48, 50)  # two systems


def test_each_named_further_reading_joins_on_its_own():
    """Claim 16 names its further readings (``Experiment.supplementary`` returns the name): the
    paper's HNN, stored on both seed sets, joins while our HNN at the code's lr, stored on no
    seed, waits; the report names which reading waits for which runs."""
    from bench.core import get, reading_of
    from bench.kit import supplements_waiting

    study, exp = get_study(16), get("mujoco")
    seeds = (*PRIMARY, *REPLICATION_SEEDS["paper"])
    cells = expand(exp, "paper-core", seeds=seeds)
    by = {}
    for c in cells:
        by.setdefault(reading_of(exp, c), []).append(c.config_hash)
    assert {"the paper's HNN", "our HNN at the code's lr", None} <= set(by)
    stored = [*by[None], *by["the paper's HNN"]]
    rows = pd.DataFrame({"config_hash": stored})
    drop = R.incomplete_supplements(rows, study, "paper-core")
    assert drop >= set(by["our HNN at the code's lr"]) and not drop & set(by["the paper's HNN"])
    said = supplements_waiting(rows, "paper-core")[16]
    n = len([c for c in cells if reading_of(exp, c) == "our HNN at the code's lr" and c.seed < 5])
    assert f"our HNN at the code's lr: 0 of {n} on seeds 0-4" in said
    assert "the paper's HNN:" not in said
    # one seed of the paper's HNN missing: that reading waits too, on its seed set only
    rows = pd.DataFrame({"config_hash": stored[:-1]})
    assert set(by["the paper's HNN"]) & R.incomplete_supplements(rows, study, "paper-core")


def _configs(rows):
    from bench.core import RunConfig, field_names

    names = [c for c in rows.columns if c in field_names()]
    return [RunConfig.from_dict(dict(zip(names, r, strict=True))) for r in rows[names].values]


def get_study(claim):
    return next(s for s in R.claim_studies() if s.claim == claim)


def test_a_difference_between_the_seed_sets_names_their_machines_where_they_differ():
    """The report closes a line on the seed sets' difference with the machines each ran on,
    where they differ (a time or a cost is the machine's), and says nothing where they match."""
    from pathlib import Path
    from types import SimpleNamespace

    import numpy as np

    from bench.core import ReportContext
    from bench.studies.paper.report._sections import _machines_apart

    runs, curves = synthetic_tables("smoke", seeds=range(10), experiments=["damped"])
    j = SimpleNamespace(primary_seeds=(0, 1, 2, 3, 4), replication_seeds=(5, 6, 7, 8, 9))
    alike = runs.assign(device="cpu A", cpu_family_model="1/2")
    assert _machines_apart(ReportContext(Path("."), alike, curves, "smoke"), j, 5) == ""
    other = runs["seed"].ge(5) & runs["model"].ne("node_so")
    apart = runs.assign(
        device=np.where(other, "cpu B", "cpu A"), cpu_family_model=np.where(other, "3/4", "1/2")
    )
    said = _machines_apart(ReportContext(Path("."), apart, curves, "smoke"), j, 5)
    n0 = int(runs["seed"].lt(5).sum())
    assert said.startswith(" (the seed sets ran on different machines: seeds 0-4: cpu A 1/2 ")
    assert f"cpu A 1/2 ({n0} runs); seeds 5-9: cpu B 3/4 (" in said
    assert said.endswith(" runs))") and "cpu A 1/2" in said.split("seeds 5-9:")[1]


def test_costs_apart_only_where_a_cost_part_differs_between_the_seed_sets():
    """The report names the seed sets' machines only where the sets differ on a cost (a time is
    the machine's): a cost part whose estimates differ beyond chance, or that reverses; not an
    error part, nor a cost part both sets estimate alike."""
    from types import SimpleNamespace

    from bench.kit import costs_apart
    from bench.kit._stats import Part

    def part(name, quantity, point, status="holds"):
        return Part(name, status, point, point - 0.02, point + 0.02, 5, quantity=quantity)

    def j(*pairs):
        primary = SimpleNamespace(parts=[a for a, _ in pairs])
        replication = SimpleNamespace(parts=[b for _, b in pairs])
        return SimpleNamespace(primary={"5": primary}, replication={"5": replication})

    cost_apart = (part("(c) cost", "cost", 1.7), part("(c) cost", "cost", 1.85))
    cost_alike = (part("(c) cost", "cost", 1.7), part("(c) cost", "cost", 1.71))
    error_apart = (part("(a) error", "error", 0.9), part("(a) error", "error", 0.6))
    reverses = (part("(c) cost", "cost", 0.1), part("(c) cost", "cost", 0.1, "contradicts"))
    assert costs_apart(j(cost_apart, error_apart), "5")
    assert costs_apart(j(reverses), "5")
    assert not costs_apart(j(cost_alike, error_apart), "5")
    assert not costs_apart(j(cost_alike), "5") and not costs_apart(j(cost_apart), "4")
