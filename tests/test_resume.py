"""Interrupted training resumes from its last saved state and ends where the uninterrupted
training ends, bit for bit: parameters, losses, checkpoint snapshots; for a stream of dataset
batches and for fresh states drawn from a box. A state that other code saved, or that does not
read back, is ignored; the cache removes the state once the training is stored, and the row
counts the interrupted part's CPU time."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import equinox as eqx
import jax
import numpy as np
import pytest

import models
from bench.core import RECORD, BoxObjective, ResumePoint, RunConfig, TrainConfig, _params, train


class Killed(Exception):
    """Stands for a kill: raised right after the ``after``-th save."""


class KilledAfter(ResumePoint):
    def __init__(self, folder, after, code=""):
        super().__init__(folder, every=0, code=code)
        self.after, self.saves = after, 0

    def save(self, *state):
        super().save(*state)
        self.saves += 1
        if self.saves == self.after:
            raise Killed


class Oscillators:
    """A dataset of chunks of the oscillator q'' = -4 q (closed form, no integration)."""

    def __init__(self, n=24, chunk=4, dt=0.1):
        rng = np.random.default_rng(0)
        q0, v0 = rng.uniform(-1, 1, (2, n, 1))
        t = rng.uniform(0, 10, (n, 1)) + np.arange(chunk) * dt
        self.ts_train = np.arange(chunk) * dt
        self.z_train = np.stack(
            [
                q0 * np.cos(2 * t) + v0 / 2 * np.sin(2 * t),
                -2 * q0 * np.sin(2 * t) + v0 * np.cos(2 * t),
            ],
            axis=-1,
        )
        self.args_train = np.zeros((n, 0))


def _leaves(model):
    return [np.asarray(x) for x in jax.tree.leaves(eqx.filter(model, eqx.is_inexact_array))]


def _same(a, b):
    assert a.status == b.status and a.steps_done == b.steps_done
    np.testing.assert_array_equal(a.losses, b.losses)
    for x, y in zip(_leaves(a.model), _leaves(b.model), strict=True):
        np.testing.assert_array_equal(x, y)
    assert [s.step for s in a.snapshots] == [s.step for s in b.snapshots]
    for s, t in zip(a.snapshots, b.snapshots, strict=True):
        for x, y in zip(_leaves(s.model), _leaves(t.model), strict=True):
            np.testing.assert_array_equal(x, y)


def _node(seed=0, name="node", dof=1):
    scene = models.Scene(dof=dof, angular=(False,) * dof)
    return models.make(name, scene, key=jax.random.PRNGKey(seed), width=16, depth=2)


# 43 steps in blocks of 5 (the last one partial), with snapshots on both sides of the kill
CFG = TrainConfig(steps=43, batch=8, lr=1e-2, steps_per_call=5, checkpoints=(5, 20, 35, 43))


@pytest.mark.parametrize("killed_after", [1, 3, 8])
def test_a_killed_training_resumes_to_the_uninterrupted_result(tmp_path, killed_after):
    data = Oscillators()
    whole = train(_node(), data, CFG)
    with pytest.raises(Killed):
        train(_node(), data, CFG, resume=KilledAfter(tmp_path, killed_after))
    saved = json.loads((tmp_path / RECORD).read_text())
    assert saved["done"] == 5 * killed_after  # a save at every block boundary (every=0)
    # one state on disk, the record's: the earlier saves' files are gone
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        [RECORD, saved["state"], saved["losses"]]
    )
    again = train(_node(), data, CFG, resume=ResumePoint(tmp_path, every=1e9))
    assert again.resumed_step == 5 * killed_after and whole.resumed_step == 0
    assert again.resumed_cpu_seconds > 0
    _same(again, whole)
    # the wall time of the interrupted part is counted
    assert again.train_seconds >= saved["train_seconds"] > 0


def test_fresh_box_states_are_replayed_on_resume(tmp_path):
    """The notebook protocol's stream (new uniform states each step) resumes exactly."""
    box = (0.0, 2 * math.pi, -2.0, 2.0)
    objective = BoxObjective("chain_pendulum", (("k", 1),), box)
    cfg = TrainConfig(steps=30, batch=16, lr=1e-2, steps_per_call=5, target="derivative")

    def model():
        scene = models.Scene(dof=1, angular=(True,))
        return models.make("node_so", scene, key=jax.random.PRNGKey(0), width=16, depth=2)

    whole = train(model(), None, cfg, objective=objective)
    with pytest.raises(Killed):
        train(model(), None, cfg, objective=objective, resume=KilledAfter(tmp_path, 2))
    again = train(model(), None, cfg, objective=objective, resume=ResumePoint(tmp_path))
    assert again.resumed_step == 10
    _same(again, whole)


def test_state_from_other_code_or_damaged_is_ignored(tmp_path):
    data = Oscillators()
    whole = train(_node(), data, CFG)
    with pytest.raises(Killed):
        train(_node(), data, CFG, resume=KilledAfter(tmp_path, 2))
    # other code saved it: trained from the start (and still the same result)
    fresh = train(_node(), data, CFG, resume=ResumePoint(tmp_path, every=1e9, code="other"))
    assert fresh.resumed_step == 0
    _same(fresh, whole)
    # a state file that does not match its record (a damaged or foreign file)
    (tmp_path / json.loads((tmp_path / RECORD).read_text())["state"]).write_bytes(b"damaged")
    fresh = train(_node(), data, CFG, resume=ResumePoint(tmp_path, every=1e9))
    assert fresh.resumed_step == 0
    _same(fresh, whole)
    # blocks of another size cannot be replayed: ignored too
    with pytest.raises(Killed):
        train(_node(), data, CFG, resume=KilledAfter(tmp_path, 2))
    other = dataclasses.replace(CFG, steps_per_call=10)
    assert train(_node(), data, other, resume=ResumePoint(tmp_path)).resumed_step == 0


def test_the_cache_resumes_then_removes_the_state(tmp_path):
    data = Oscillators()
    config = RunConfig(system="chain_pendulum", k=1, steps=CFG.steps, seed=0)

    def fit(resume):
        return train(_node(), data, CFG, resume=resume)

    def killed_fit(resume):
        return train(_node(), data, CFG, resume=KilledAfter(resume.folder, 4, resume.code))

    with pytest.raises(Killed):
        _params.cached_training(config, _node(), tmp_path, killed_fit)
    folder = _params.params_dir(tmp_path, config.train_hash) / _params.RESUME
    assert (folder / RECORD).exists()
    # saved for the code that runs: the cache resumes it
    assert json.loads((folder / RECORD).read_text())["code"] == _params.code_fingerprint()
    model, meta = _params.cached_training(config, _node(), tmp_path, fit)
    assert meta["resumed_step"] == 20 and meta["resumed_cpu_seconds"] > 0
    assert not folder.exists()  # stored: the state is gone
    for x, y in zip(_leaves(model), _leaves(train(_node(), data, CFG).model), strict=True):
        np.testing.assert_array_equal(x, y)


def test_the_row_counts_the_interrupted_cpu_time_only_where_it_trained():
    from bench.core import training_columns

    meta = {
        "status": "ok",
        "train_seconds": 1.0,
        "compile_seconds": 0.0,
        "train_cached": False,
        "resumed_step": 20,
        "resumed_cpu_seconds": 7.5,
    }
    assert training_columns(meta)["resumed_cpu_seconds"] == 7.5
    assert training_columns({**meta, "train_cached": True})["resumed_cpu_seconds"] == 0.0
    assert training_columns({**meta, "resumed_step": None})["resumed_step"] == 0


def test_resume_point_validates_its_interval(tmp_path):
    with pytest.raises(ValueError, match="every must be a number of seconds >= 0"):
        ResumePoint(tmp_path, every=-1)


def test_a_kill_before_the_record_leaves_the_previous_state(tmp_path, monkeypatch):
    """The record is written last: a kill after a new state's files but before its record
    resumes from the previous state, not from scratch."""
    from bench.core import _resume

    data = Oscillators()
    whole = train(_node(), data, CFG)
    with pytest.raises(Killed):
        train(_node(), data, CFG, resume=KilledAfter(tmp_path, 3))
    real = _resume.write_json

    def killed_record(path, obj):
        if Path(path).name == RECORD:
            raise Killed
        return real(path, obj)

    monkeypatch.setattr(_resume, "write_json", killed_record)
    with pytest.raises(Killed):  # resumes at 15, trains a block, dies writing the record
        train(_node(), data, CFG, resume=ResumePoint(tmp_path, every=0))
    monkeypatch.undo()
    again = train(_node(), data, CFG, resume=ResumePoint(tmp_path, every=1e9))
    assert again.resumed_step == 15
    _same(again, whole)


_CHILD = """
import json, sys
from pathlib import Path
import dataclasses
import systems
systems.enable_x64()
import bench.core._resume as R
R.EVERY_S = 0.0
from bench.core import execute_run, expand, get
cfg = [c for c in expand(get("lnn_seed_notebook"), "smoke") if c.model == "lnn"][0]
from bench.studies.lnn_seed.notebook import notebook_lr
steps = int(sys.argv[2])
cfg = dataclasses.replace(cfg, steps=steps, lr=notebook_lr("lnn", steps))
row = execute_run(cfg, cache_root=Path(sys.argv[1]))
keys = ("status", "derivative_mse_test", "energy_pct_max_pe", "final_loss", "resumed_step")
print(json.dumps({k: row.get(k) for k in keys}))
"""


@pytest.mark.slow  # two processes and a third run: about a minute
def test_a_run_killed_with_sigkill_resumes_to_the_same_row(tmp_path):
    import os
    import signal
    import subprocess
    import sys
    import time

    root = Path(__file__).resolve().parents[1]
    steps = "6000"

    def run(cache, wait=True):
        cmd = [sys.executable, "-c", _CHILD, str(cache), steps]
        if wait:
            out = subprocess.run(cmd, cwd=root, capture_output=True, text=True, timeout=600)
            return json.loads(out.stdout.strip().splitlines()[-1])
        return subprocess.Popen(cmd, cwd=root, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

    killed = tmp_path / "killed"
    child = run(killed, wait=False)
    deadline = time.monotonic() + 300
    while not list(killed.glob("params/*/resume/resume.json")):
        assert child.poll() is None and time.monotonic() < deadline, "no state saved"
        time.sleep(0.2)
    os.kill(child.pid, signal.SIGKILL)
    child.wait()
    record = json.loads(next(killed.glob("params/*/resume/resume.json")).read_text())
    assert 0 < record["done"] < int(steps)
    resumed, whole = run(killed), run(tmp_path / "whole")
    assert resumed["resumed_step"] >= record["done"] > 0 and whole["resumed_step"] == 0
    assert resumed["status"] == whole["status"] == "ok"
    for key in ("derivative_mse_test", "energy_pct_max_pe", "final_loss"):
        assert resumed[key] == whole[key], key
    assert not list(killed.glob("params/*/resume"))
