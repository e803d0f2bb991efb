"""Training that blows up with a finite loss: ``loss_rise`` on built traces and on a real run,
its row column, and the report's list of the runs it flags (the ``diverged`` status sees only
non-finite losses)."""

from __future__ import annotations

import math
import re

import numpy as np
import pandas as pd
import pytest

from bench import _report
from bench.core import BLOW_UP_RISE, TrainResult, loss_rise, result_meta


def _result(losses) -> TrainResult:
    return TrainResult(None, np.asarray(losses), "ok", None, 1.0, 0.0, len(losses))


def test_loss_rise_is_one_at_the_best_and_large_after_a_finite_blow_up():
    steps = np.arange(1, 2001)
    falling = 1.0 / steps
    assert loss_rise(falling) == 1.0  # the last stretch's median is the lowest
    rng = np.random.default_rng(0)
    noisy = 0.05 * np.exp(0.3 * rng.standard_normal(2000))  # a noisy plateau of batch losses
    assert 1.0 <= loss_rise(noisy) < 1.5
    # fits to 0.06 by step 800 then blows up to 1e8, finite throughout (the MuJoCo HNN's trace)
    blown = np.concatenate([np.geomspace(1.0, 0.06, 800), np.geomspace(0.06, 1e8, 1200)])
    assert np.isfinite(blown).all() and loss_rise(blown) > 1e8
    assert loss_rise(np.r_[blown[:1000], np.nan, np.inf]) == loss_rise(blown[:1000])
    assert loss_rise([]) is None and loss_rise([0.3]) is None and loss_rise([np.nan] * 9) is None
    assert loss_rise([0.0, 0.0, 0.0]) == 1.0 and loss_rise([0.0, 0.0, 1.0]) == math.inf
    assert loss_rise([2.0, 1.0]) == 1.0 and loss_rise([1.0, 3.0]) == 3.0  # one step a stretch


def test_a_run_that_trains_is_not_flagged_and_the_meta_carries_the_rise(tmp_path):
    from bench.core import execute_run, expand

    c = next(c for c in expand("energy", "smoke") if c.model == "node")
    row = execute_run(c, cache_root=tmp_path)
    assert row["status"] == "ok" and row["loss_rise"] is not None
    assert 0.99 <= row["loss_rise"] < BLOW_UP_RISE
    blown = np.concatenate([np.geomspace(1.0, 0.06, 80), np.geomspace(0.06, 1e8, 120)])
    assert result_meta(_result(blown))["loss_rise"] > 1e8


def _rows():
    base = {"system": "HalfCheetahFull-v0", "model": "hnn_force", "model_options": "[]"}
    return pd.DataFrame(
        [
            {**base, "seed": 0, "status": "ok", "loss_rise": 3.4e9},
            {**base, "seed": 1, "status": "ok", "loss_rise": 1.3},
            {**base, "seed": 2, "status": "diverged", "loss_rise": 5e4},  # listed as diverged
            {**base, "seed": 3, "status": "ok", "loss_rise": float("nan")},  # an older row
            {**base, "seed": 4, "status": "ok", "loss_rise": BLOW_UP_RISE * 1.01},
        ]
    )


def test_the_report_names_the_finished_runs_that_blew_up():
    lines = _report._blown_up_lines(_rows())
    named = [
        re.fullmatch(r"- (\S+) on (\S+) seed (\d+): ended (\S+)x above its best", line).groups()
        for line in lines
        if line.startswith("- hnn_force on")
    ]
    assert [(seed, float(rise)) for *_, seed, rise in named] == [
        ("0", pytest.approx(3.4e9)),
        ("4", pytest.approx(BLOW_UP_RISE * 1.01, rel=1e-3)),
    ]
    recorded = re.fullmatch(r"- \((\d+) of (\d+) runs record it.*", lines[-2]).groups()
    assert recorded == ("4", "5")  # seed 3's older row does not
    calm = _rows().assign(loss_rise=1.2)
    assert _report._blown_up_lines(calm) == []
    assert _report._blown_up_lines(_rows().drop(columns="loss_rise")) == []
