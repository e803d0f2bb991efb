"""Learning-curve checkpoints: the halving grid, snapshots that are the parameters after exactly
their step's updates, final metrics unchanged by taking them, the cache and the tables."""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax
import numpy as np
import pytest

import models
from bench.core import (
    Batches,
    RunConfig,
    TrainConfig,
    _execute,
    _fit,
    _store,
    checkpoint_steps,
    loss_fn,
    prepare,
    train,
    train_ensemble,
)


def test_checkpoint_grid_halves_and_snaps_to_blocks():
    assert checkpoint_steps(8000, 4) == (1000, 2000, 4000, 8000)
    assert checkpoint_steps(1000, 4) == (100, 300, 500, 1000)
    assert checkpoint_steps(1000, 4, block=25) == (125, 250, 500, 1000)
    assert checkpoint_steps(20, 4) == (20,)  # one block: one checkpoint, the end
    assert checkpoint_steps(1000, 0) == ()
    with pytest.raises(ValueError, match="integer >= 0"):
        checkpoint_steps(1000, -1)
    with pytest.raises(ValueError, match=r"checkpoints must be a tuple of integer steps in \[1"):
        TrainConfig(steps=10, checkpoints=(11,))


class _Chunks:
    """Chain-2-like chunks: random angles and velocities, 5 points 0.03 apart."""

    def __init__(self, seed=0, n=16, chunk=5):
        rng = np.random.default_rng(seed)
        q = rng.uniform(-np.pi, np.pi, (n, 1, 2)) + 0.05 * rng.standard_normal((n, chunk, 2))
        self.ts_train = np.arange(chunk) * 0.03
        self.z_train = np.concatenate([q, rng.standard_normal((n, chunk, 2))], axis=-1)
        self.args_train = np.zeros((n, 0))


def _model(seed=0):
    scene = models.Scene(dof=2, angular=(True, True))
    return models.make("node", scene, key=jax.random.PRNGKey(seed), width=16, depth=2)


CFG = TrainConfig(
    steps=24, batch=8, lr=5e-3, steps_per_call=4, integrator=models.Integrator("euler")
)


def _leaves(m):
    return [np.asarray(x) for x in jax.tree.leaves(eqx.filter(m, eqx.is_array))]


def test_snapshots_are_the_parameters_after_their_step_and_change_nothing():
    data = _Chunks()
    plain = train(_model(), data, CFG)
    kept = train(_model(), data, dataclasses.replace(CFG, checkpoints=(4, 8, 13, 24)))
    # the final parameters and every loss are those of the run without checkpoints, bit for bit
    for a, b in zip(_leaves(plain.model), _leaves(kept.model), strict=True):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(plain.losses, kept.losses)
    # a step that is not a block end is taken at the end of the block that reaches it
    assert [s.step for s in kept.snapshots] == [4, 8, 16, 24]
    assert [s.train_seconds for s in kept.snapshots] == sorted(
        s.train_seconds for s in kept.snapshots
    )
    # independent check: the loss of snapshot s on the batch of step s is the loss the trainer
    # recorded at step s (computed before step s's update, i.e. after exactly s updates)
    z, args, ts = prepare(_model(), data, CFG)
    batches = Batches(len(z), CFG.batch, CFG.seed).take(CFG.steps)
    for snap in kept.snapshots[:-1]:
        ix = batches[snap.step]
        got = float(loss_fn(snap.model, z[ix], args[ix], ts, CFG))
        assert got == pytest.approx(float(kept.losses[snap.step]), rel=1e-5)
    for a, b in zip(_leaves(kept.snapshots[-1].model), _leaves(kept.model), strict=True):
        np.testing.assert_array_equal(a, b)  # the last snapshot is the final model


def test_ensemble_members_keep_snapshots_and_a_diverged_member_stops_them():
    cfgs = [dataclasses.replace(CFG, seed=s, lr=lr) for s, lr in ((0, 5e-3), (1, 1e30))]
    with_cp = [dataclasses.replace(c, checkpoints=(8, 24)) for c in cfgs]
    data = [_Chunks(0), _Chunks(1)]
    plain = train_ensemble([_model(0), _model(1)], data, cfgs)
    kept = train_ensemble([_model(0), _model(1)], data, with_cp)
    for a, b in zip(_leaves(plain[0].model), _leaves(kept[0].model), strict=True):
        np.testing.assert_array_equal(a, b)
    assert [s.step for s in kept[0].snapshots] == [8, 24]
    assert kept[1].status == "diverged" and kept[1].snapshots == ()


def _run(**kw):
    base = dict(system="chain_pendulum", k=2, model="node", steps=8, n_generated=10, n_train=8)
    base.update(n_test=3, test_chunks=2, width=8, batch=4)
    base.update(train_integrator="euler", eval_integrator="rk4")
    return RunConfig(**{**base, **kw})


STEADY = ("rollout_error", "energy_violation", "mse", "valid_time", "symplectic_error")


@pytest.mark.slow  # keeps make test under 10 min on a CPU
def test_run_with_checkpoints_has_the_final_metrics_of_the_run_without(tmp_path, monkeypatch):
    # 2-step blocks, so that an 8-step run has checkpoints (2, 4, 8) inside it
    monkeypatch.setattr(_fit, "TRAIN_BLOCK", 2)
    plain = _execute.execute_run(_run(), cache_root=tmp_path / "a")
    cfg = _run(eval_checkpoints=3)
    assert cfg.config_hash != _run().config_hash and cfg.train_hash == _run().train_hash
    row = _execute.execute_run(cfg, cache_root=tmp_path / "b")
    assert plain["status"] == row["status"] == "ok", (plain["error"], row["error"])
    for key in STEADY:
        assert row[key] == plain[key], key
    cp = row["checkpoints"]
    assert cp["step"] == [2, 4, 8] and cp["status"] == ["ok"] * 3
    assert cp["fraction"] == [0.25, 0.5, 1.0]
    # the last checkpoint is the final model; the earlier ones are other models
    assert cp["rollout_error"][-1] == row["rollout_error"]
    assert cp["rel_error_t"][-1] == row["curves"]["rel_error"]
    assert len({round(e, 12) for e in cp["rollout_error"]}) == 3
    # a second run of the same config loads the training and its snapshots from the cache
    again = _execute.execute_run(cfg, cache_root=tmp_path / "b")
    assert again["train_cached"] and again["checkpoints"]["rollout_error"] == cp["rollout_error"]
    # a cache entry trained without these checkpoints is retrained, not reused without a curve
    other = _execute.execute_run(cfg, cache_root=tmp_path / "a")
    assert not other["train_cached"] and other["checkpoints"]["step"] == [2, 4, 8]
    # tables: one row per checkpoint, per-time curves per checkpoint
    frame = _store.checkpoints_frame([row, plain])
    assert list(frame["step"]) == [2, 4, 8] and set(frame["config_hash"]) == {cfg.config_hash}
    curves = _store.checkpoint_curves_frame([row])
    assert len(curves) == 3 * len(row["curves"]["t"])
    assert "checkpoints" not in _store.rows_frame([row]).columns


@pytest.mark.slow  # a training driven to divergence (~15 s)
def test_a_diverged_run_records_diverged_checkpoints_after_its_divergence(tmp_path, monkeypatch):
    monkeypatch.setattr(_fit, "TRAIN_BLOCK", 2)
    row = _execute.execute_run(_run(eval_checkpoints=3, lr=1e30), cache_root=tmp_path)
    assert row["status"] == "diverged"
    cp = row["checkpoints"]
    assert cp["status"][-1] == "diverged"
    done = [s for s, st in zip(cp["step"], cp["status"], strict=True) if st == "ok"]
    assert all(s <= row["diverged_step"] for s in done)
