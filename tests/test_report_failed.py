"""The report's list of failed and diverged runs (``bench._tables._failed_lines``): each run
named by the cells its experiment's table tells apart, with what happened and how the verdicts
count it."""

import math

import pandas as pd

from bench._tables import _failed_lines

TRIVIAL = {"constant_velocity"}


def _rows(**changes):
    base = {
        "system": "rotor",
        "model": "hnn_so",
        "model_options": "",
        "coordinates": "velocity",
        "seed": 0,
        "lr": 0.005,
        "status": "ok",
        "error": math.nan,
        "diverged_step": math.nan,
        "system_params": "",
    }
    return {**base, **changes}


def _table(*rows):
    return pd.DataFrame([_rows(**r) for r in rows])


def test_diverged_runs_name_their_steps_and_the_rate_that_tells_their_cells_apart():
    rows = _table(
        {"status": "diverged", "diverged_step": 1872.0},
        {"status": "diverged", "diverged_step": 3.0, "seed": 2},
        {"status": "diverged", "diverged_step": 90.0, "seed": 1},
        {"lr": 0.001, "status": "diverged", "diverged_step": 7.0},
        {"lr": 0.001, "seed": 1},
        {"model": "node"},
    )
    got = _failed_lines(rows, TRIVIAL)
    assert got == [
        "- hnn_so on rotor (lr=0.005), seeds 0-2 (3 runs): diverged at steps 3-1872; "
        "scored as error 1",
        "- hnn_so on rotor (lr=0.001), seed 0: diverged at step 7; scored as error 1",
        "",
    ]
    assert not any("nan" in line for line in got)


def test_failed_runs_show_their_errors_and_a_trivial_predictor_is_not_counted():
    rows = _table(
        {"status": "failed", "error": "boom | at step 3"},
        {"status": "failed", "error": "boom | at step 3", "seed": 4},
        {"status": "failed", "error": "out of memory", "seed": 1},
        {"model": "constant_velocity", "status": "failed", "error": "no data", "seed": 2},
        {"model": "node", "coordinates": "momentum", "status": "diverged", "diverged_step": 5},
        {"model": "node", "coordinates": "momentum", "status": "diverged", "seed": 3},
    )
    got = _failed_lines(rows, TRIVIAL)
    assert got[0] == "- hnn_so on rotor, seeds 0, 4 (2 runs): boom \\| at step 3; scored as error 1"
    assert got[1] == "- hnn_so on rotor, seed 1: out of memory; scored as error 1"
    trivial = "- constant_velocity on rotor, seed 2: no data; not counted (a trivial predictor)"
    assert got[2] == trivial
    assert (
        got[3]
        == "- node (q, p) on rotor, seeds 0, 3 (2 runs): diverged at step 5; scored as error 1"
    )
    assert got[4:] == [""]


def test_no_line_where_every_run_finished():
    assert _failed_lines(_table({}, {"seed": 1}), TRIVIAL) == []
    assert _failed_lines(_table({}).drop(columns="status"), TRIVIAL) == []
