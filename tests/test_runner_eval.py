"""The runner's evaluation of trivial predictors, the (q, qdot) scores of momentum runs, and the
FLOPs of a training step (smoke sizes)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import systems
from bench.core import RunConfig, execute_run, to_velocity

SMOKE = dict(
    n_generated=12, n_train=8, n_test=3, test_chunks=4, width=8, steps=5, batch=4, dtype="float64"
)
REL = dict(system="relativistic_particle", random_args=True, **SMOKE)


@pytest.fixture(scope="module")
def rows(tmp_path_factory):
    cache = tmp_path_factory.mktemp("cache")
    out = {}
    for name, coords in [
        ("node", "momentum"),
        ("constant_velocity", "momentum"),
        ("at_rest", "momentum"),
        ("constant_velocity", "velocity"),
    ]:
        out[name, coords] = execute_run(
            RunConfig(model=name, coordinates=coords, **REL), cache_root=cache
        )
    return out


def test_trivial_runs_train_nothing_and_score_like_models(rows):
    for key, row in rows.items():
        assert row["status"] == "ok", (key, row["error"])
    for name in ("constant_velocity", "at_rest"):
        row = rows[name, "momentum"]
        assert row["steps_done"] == 0 and row["train_seconds"] == 0.0 and row["n_params"] == 0
        assert math.isnan(row["symplectic_error"])
        assert np.isfinite(row["rollout_error"]) and np.isfinite(row["rollout_error_velocity"])
    hnn = rows["node", "momentum"]
    assert hnn["steps_done"] == 5 and hnn["n_params"] > 0
    # same cell, same test trajectories: the true curves stored with each row agree
    np.testing.assert_array_equal(
        hnn["curves"]["z_true"], rows["constant_velocity", "momentum"]["curves"]["z_true"]
    )
    # at rest is a worse guess than constant velocity over 0.36 s of a moving particle
    assert (
        rows["at_rest", "momentum"]["rollout_error_velocity"]
        > rows["constant_velocity", "momentum"]["rollout_error_velocity"]
    )


def test_velocity_scores_only_for_momentum_runs(rows):
    vel = rows["constant_velocity", "velocity"]
    assert math.isnan(vel["rollout_error_velocity"]) and math.isnan(vel["mse_velocity"])
    # constant velocity is the same physical prediction in either coordinates: its (q, qdot)
    # score from the momentum run equals the velocity run's own score
    mom = rows["constant_velocity", "momentum"]
    np.testing.assert_allclose(mom["rollout_error_velocity"], vel["rollout_error"], rtol=1e-6)
    np.testing.assert_allclose(mom["mse_velocity"], vel["mse"], rtol=1e-6)


def test_flops_per_step_recorded(rows):
    assert rows["node", "momentum"]["flops_per_step"] > 1e3
    assert rows["constant_velocity", "momentum"]["flops_per_step"] == 0.0


def test_to_velocity_inverts_the_momentum_map():
    particle = systems.make("relativistic_particle")
    v = np.array([[[0.1, -0.5], [0.3, 0.8]]])  # (1 trajectory, 2 times, (q, qdot))
    p = np.array([[[float(particle.momentum(np.asarray(z))[0]) for z in v[0]]]]).T.reshape(1, 2, 1)
    z = np.concatenate([v[..., :1], p], axis=-1)
    np.testing.assert_allclose(to_velocity(particle, z, np.array([[1.0]])), v, rtol=1e-12)
    bad = z.copy()
    bad[0, 1, 1] = np.nan
    assert np.isnan(to_velocity(particle, bad)[0, 1]).all()
