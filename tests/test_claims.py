"""Verdict rules of bench.studies.paper on synthetic run tables (no training).

The tables come from ``tests/_synthetic.py``: every paper experiment expanded in the smoke
profile, the store's own row format, errors built so that each claim passes ("reproduce"), fails
("contradict") or cannot be decided (one seed, huge noise, trivial predictors that win), with
per-run log-normal noise. Each rule is pinned by a table built to pass, one built to fail and
one built to be undecided.
"""

import math

import numpy as np
import pandas as pd
import pytest
from _synthetic import synthetic_tables

from bench.core._query import option
from bench.studies import paper as C
from bench.studies.paper import _stats as R


def _by_key(runs, curves):
    return {v.key: v for v in C.evaluate_claims(runs, curves)}


@pytest.fixture(scope="module")
def tables():
    return synthetic_tables("smoke", seeds=(0, 1, 2), noise=0.05)


@pytest.fixture(scope="module")
def reproducing(tables):
    return _by_key(*tables)


@pytest.fixture(scope="module")
def contradicting():
    return _by_key(*synthetic_tables("smoke", seeds=(0, 1, 2), noise=0.05, scenario="contradict"))


KEYS = [
    "1",
    "2",
    "3",
    "4 (geometric-mean error, spring from paper)",
    "4 (geometric-mean error, spring from equilibrium)",
    "4 (MSE, spring from paper)",
    "4 (MSE, spring from equilibrium)",
    "5",
    "6",
    "7",
    "8",
]


def test_every_claim_has_its_verdicts(reproducing):
    assert sorted(reproducing) == sorted(KEYS)
    assert all(v.verdict in C.VERDICTS for v in reproducing.values())


@pytest.mark.parametrize("key", KEYS)
def test_reproducing_table_gives_reproduced(reproducing, key):
    v = reproducing[key]
    assert v.verdict == R.REPRODUCED, v.detail
    assert v.n_seeds == 3 and v.n_failed == 0
    assert v.discriminating is True
    assert np.isfinite(v.effect)


@pytest.mark.parametrize("key", KEYS)
def test_contradicting_table_gives_not_reproduced(contradicting, key):
    v = contradicting[key]
    # Claim 4's contradicting table keeps the chain edge and breaks the spring one: "partly".
    expected = R.PARTLY if key.startswith("4") else R.NOT_REPRODUCED
    assert v.verdict == expected, v.detail
    assert "contradicts" in v.detail


def test_single_seed_gives_inconclusive():
    for v in C.evaluate_claims(*synthetic_tables("smoke", seeds=(0,), noise=0.05)):
        assert v.verdict == R.INCONCLUSIVE, (v.key, v.detail)
        assert v.n_seeds <= 1


def test_trivial_predictor_that_wins_makes_every_claim_inconclusive():
    for v in C.evaluate_claims(*synthetic_tables("smoke", scenario="trivial_wins")):
        assert v.verdict == R.INCONCLUSIVE, (v.key, v.detail)
        assert v.discriminating is False
        assert "NOT DISCRIMINATING" in v.detail


def test_without_trivial_runs_discrimination_is_unknown(tables):
    runs, curves = tables
    runs = runs[~runs["model"].isin(C.TRIVIAL_MODELS)]
    for v in C.evaluate_claims(runs, curves):
        assert v.discriminating is None, v.key
        assert v.verdict == R.REPRODUCED, (v.key, v.detail)
        assert "discriminating unknown" in v.detail


@pytest.mark.parametrize("claim", [3, 7, 8])
def test_huge_noise_gives_inconclusive(claim):
    # Per-run log-normal noise of sd 4 swamps effects of 0.5-2.5 in log: with 8 seeds the
    # bootstrap interval spans both 0 and the smallest ratio that matters.
    runs, curves = synthetic_tables("smoke", seeds=range(8), noise=4.0, rng=1)
    v = C.CLAIMS[claim](runs, curves)
    assert v.verdict == R.INCONCLUSIVE, v.detail


def test_missing_runs_are_inconclusive():
    empty = pd.DataFrame(columns=["system", "model", "seed", "rollout_error", "status"])
    for v in C.evaluate_claims(empty, None):
        assert v.verdict == R.INCONCLUSIVE


def _fail(runs, mask):
    runs = runs.copy()
    runs.loc[mask, "status"] = "diverged"
    runs.loc[mask, ["rollout_error", "rollout_error_velocity", "mse"]] = np.nan
    return runs


def test_failed_runs_count_as_error_one_not_dropped(tables):
    runs, curves = tables
    # Every NODE+SO run of claim 3 diverges: it scores error 1, so second-order structure
    # "closes" a negative fraction of the gap; dropping them would leave the claim undecided.
    bad = _fail(runs, runs["model"] == "node_so")
    v = C.CLAIMS[3](bad, curves)
    assert v.verdict == R.NOT_REPRODUCED, v.detail
    assert v.n_failed == 6 and "failed/diverged" in v.detail
    # The (q, p) HNN of claim 7 fails: the naive HNN is now better than it.
    bad = _fail(runs, (runs["model"] == "hnn") & (runs["coordinates"] == "momentum"))
    v = C.CLAIMS[7](bad, curves)
    assert v.verdict in (R.NOT_REPRODUCED, R.PARTLY), v.detail
    assert v.n_failed == 3


def test_scored_sets_failures_to_the_worst_error():
    df = pd.DataFrame(
        {
            "status": ["ok", "diverged", "ok"],
            "rollout_error": [0.1, 0.2, np.nan],
            "mse": [4.0, np.nan, 1.0],
        }
    )
    assert C.scored(df).tolist() == [0.1, 1.0, 1.0]
    assert C.scored(df, "mse").tolist() == [4.0, 4.0, 1.0]


def test_claim_1_growth_is_judged_per_family(tables):
    runs, curves = tables
    hnn = runs.loc[runs["model"].isin(["hnn", "hnn_so"]), "config_hash"]
    flat = curves.copy()
    flat.loc[flat["config_hash"].isin(hnn), "energy_violation"] = 0.01  # HNNs level off
    v = C.CLAIMS[1](runs, flat)
    assert v.verdict == R.PARTLY, v.detail
    assert "(b) HNNs" in v.detail and "(b) NODEs" in v.detail
    assert "x better at equal error" in v.detail


def test_claim_3_is_a_fraction_of_the_gap(reproducing):
    v = reproducing["3"]
    # pooled over chain (log(0.1/0.03) / log(0.1/0.02)) and spring (log(0.04/0.0105) /
    # log(0.04/0.01)) in the construction
    closed = (math.log(0.1 / 0.03) + math.log(0.04 / 0.0105)) / 2
    gap = (math.log(0.1 / 0.02) + math.log(0.04 / 0.01)) / 2
    assert v.effect == pytest.approx(closed / gap, abs=0.1)
    assert v.ci_low >= 0.5


def test_claim_5_is_judged_against_the_mixture_hnn(tables):
    runs, curves = tables
    runs = runs.copy()
    damped = runs["friction"] > 0
    # the paper's damped HNN becomes 10x better than NODE+SO; the Rayleigh extra is unchanged
    mix = damped & (runs["model"] == "mixture_hnn")
    runs.loc[mix, "rollout_error"] = runs.loc[mix, "rollout_error"] / 10
    v = C.CLAIMS[5](runs, curves)
    assert v.verdict == R.PARTLY, v.detail
    assert "(b) log(NODE+SO / mixture HNN)" in v.detail and "Rayleigh" in v.detail


def test_claim_5_cost_can_come_out_against_node_so(tables):
    runs, curves = tables
    runs = runs.copy()
    so = (runs["friction"] > 0) & (runs["model"] == "node_so")
    runs.loc[so, "train_seconds"] = 500.0
    v = C.CLAIMS[5](runs, curves)
    assert v.verdict == R.PARTLY, v.detail
    assert "(c) cost" in v.detail


def test_claim_6_needs_half_the_pairs_resolved_under_both(tables):
    runs, curves = tables
    runs = runs.copy()
    l1 = runs["loss"] == "l1"
    runs.loc[l1, "rollout_error"] = 0.05  # L1 ties every model: no pair resolved under L1
    v = C.CLAIMS[6](runs, curves)
    assert v.verdict == R.INCONCLUSIVE, v.detail
    assert "0/6 pairs resolved under both" in v.detail


def test_claim_7_scores_every_model_on_velocities(reproducing, tables):
    # the weaker of log(0.3 / 0.02) and log(0.3 / 0.03) in the construction; the (q, p) HNN's
    # own rollout_error is 4x smaller and must not be used
    assert reproducing["7"].effect == pytest.approx(math.log(0.3 / 0.03), abs=0.2)
    runs, curves = tables
    old = runs.drop(columns=["rollout_error_velocity"])
    assert "scored in (q, p)" in C.CLAIMS[7](old, curves).detail


def test_claim_2_ignores_velocity_space_regularisation(tables):
    runs, curves = tables
    runs = runs.copy()
    runs["coordinates"] = "velocity"
    v = C.CLAIMS[2](runs, curves)
    assert v.verdict == R.INCONCLUSIVE and v.detail == "no runs"


@pytest.mark.parametrize(
    "value",
    ['[["weight", 0.1]]', (("weight", 0.1),), [["weight", 0.1]], "(('weight', 0.1),)"],
)
def test_option_parses_every_serialisation(value):
    df = pd.DataFrame({"model_options": [value]})
    assert option(df, "weight").iloc[0] == pytest.approx(0.1)


def test_positive_null_and_threshold_rules():
    assert R._positive("x", [0.5, 0.6, 0.7]).status == "holds"
    assert R._positive("x", [-0.5, -0.6, -0.7]).status == "contradicts"
    assert R._positive("x", [-3.0, 0.1, 3.0]).status == "undecided"
    assert R._null("x", [0.01, -0.02, 0.0]).status == "holds"
    assert R._null("x", [1.0, 1.1, 1.2]).status == "contradicts"
    assert R._null("x", [-3.0, 0.1, 3.0]).status == "undecided"
    assert R._threshold("x", [0.9, 1.0, 1.1], 0.5).status == "holds"
    assert R._threshold("x", [0.0, 0.1, -0.1], 0.5).status == "contradicts"
    assert R._threshold("x", [0.0, 1.0, 0.5], 0.5).status == "undecided"


def test_success_needs_the_factor_on_every_seed():
    triv = pd.Series(np.log([1.0, 1.0, 1.0]), index=[0, 1, 2])
    assert C.succeeds(pd.Series(np.log([0.1, 0.1, 0.1]), index=[0, 1, 2]), triv)[0] is True
    # 10x better on two seeds, 1.5x on the third: not a success
    assert C.succeeds(pd.Series(np.log([0.1, 0.1, 0.67]), index=[0, 1, 2]), triv)[0] is False
    assert C.succeeds(pd.Series(dtype=float), triv)[0] is None


def test_failed_trivial_predictors_leave_discrimination_unknown(tables):
    runs, curves = tables
    bad = _fail(runs, runs["model"].isin(C.TRIVIAL_MODELS))
    v = C.CLAIMS[3](bad, curves)
    assert v.discriminating is None and v.verdict == R.REPRODUCED, v.detail
    assert v.n_failed == 0  # trivial failures are not model failures
