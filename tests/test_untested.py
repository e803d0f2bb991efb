"""What more training would decide: a claim with a closed learning gate gets the longer
profile's steps and cost; open gates, conditions and foils do not count; a claim whose longer
profile trains no longer says so; the cost is rescaled by the measured CPU time here."""

import math

import numpy as np
import pandas as pd
import pytest

from bench.core import expand
from bench.kit import Gate, Part, Verdict, foil, learned, waiting
from bench.studies.paper.campaign._budget import run_seconds
from bench.studies.paper.campaign._untested import (
    closed_learning_gates,
    training_gap,
    training_gap_lines,
)


def _verdict(claim: int, *gates: Gate) -> Verdict:
    part = Part("(a) a comparison", "not tested", 0.0, -1.0, 1.0, 10, gates=gates)
    return Verdict(claim, "t", "inconclusive", 0.0, -1.0, 1.0, 10, "", parts=(part,))


STUCK = Gate(
    "pure LNN",
    False,
    "pure LNN did not learn: 1.09x below the best trivial predictor (geometric mean over 10 "
    "seeds; the gate is 2x)",
)


def test_only_closed_binding_learning_gates_count():
    cond = Gate("(b) fit edge", False, "condition (b) fit edge: contradicts", kind="condition")
    wait = waiting("HNN", "no runs at lr 0.005 here yet")
    v = _verdict(9, Gate("baseline", True, "baseline learned"), cond, wait, foil(STUCK), STUCK)
    assert [g.label for g in closed_learning_gates(v)] == ["pure LNN"]
    alone = [_verdict(9, cond, wait, foil(STUCK))]
    assert training_gap(alone, pd.DataFrame(), "paper-core").empty


def test_a_claim_the_longer_profile_trains_longer_is_costed():
    t = training_gap([_verdict(9, STUCK)], pd.DataFrame(), "paper-core")
    (r,) = t.to_dict("records")
    assert r["longer"] and r["steps_here"][1] < r["steps_longer"][1] == 600_000
    assert r["runs_longer"] > 0 and r["cpu_hours_longer"] > 0
    assert math.isnan(r["calibration"])  # nothing stored here: the estimate alone
    (row,) = [x for x in training_gap_lines(t, "paper-core") if x.startswith("| 9 |")]
    assert "600,000" in row and "estimated; no run here records CPU time" in row
    assert "| pure LNN (1.09x below the trivial predictor; gate 2x) |" in row


def test_a_claim_trained_at_its_papers_budget_says_more_training_is_not_the_gap():
    gate = Gate("HNN", False, "HNN did not learn")
    t = training_gap([_verdict(11, gate)], pd.DataFrame(), "paper-core")
    assert not t.iloc[0]["longer"]
    assert "paper trains no longer" in training_gap_lines(t, "paper-core")[-2]


def test_the_cost_is_rescaled_by_the_measured_cpu_time_here():
    cells = [c for c in expand("lnn_seed_notebook", "paper-core") if c.model == "lnn"][:2]
    runs = pd.DataFrame(
        {
            "config_hash": [c.config_hash for c in cells],
            "cpu_seconds": [3.0 * run_seconds(c) for c in cells],
            "backend": ["cpu", "cpu"],
        }
    )
    (r,) = training_gap([_verdict(9, STUCK)], runs, "paper-core").to_dict("records")
    assert r["calibration"] == pytest.approx(3.0)
    assert r["cpu_hours_calibrated"] == pytest.approx(3.0 * r["cpu_hours_longer"])
    # a GPU's rows do not measure this machine
    gpu = runs.assign(backend="gpu")
    (g,) = training_gap([_verdict(9, STUCK)], gpu, "paper-core").to_dict("records")
    assert math.isnan(g["calibration"])


def test_no_closed_gate_no_section():
    assert training_gap_lines(training_gap([], pd.DataFrame(), "paper-core"), "paper-core") == []


def test_a_model_worse_than_the_trivial_predictor_reads_above_it():
    seeds = pd.Series([0, 1, 2])
    model = pd.Series(np.log([8.0, 8.0, 8.0]), index=seeds)
    trivial = pd.Series(np.log([1.0, 1.0, 1.0]), index=seeds)
    g = learned("NODE", model, trivial)
    assert g.open is False and "8x above the best trivial predictor" in g.text
    assert "8x below" in learned("NODE", trivial - math.log(8.0), trivial).text


def test_an_inconclusive_claim_whose_headline_went_untested_says_so():
    v = _verdict(9, STUCK)
    untested = Verdict(**{**v.__dict__, "headline_status": "not tested"})
    assert untested.label() == "inconclusive: headline untested"
    assert Verdict(**{**v.__dict__, "headline_status": "undecided"}).label() == "inconclusive"
