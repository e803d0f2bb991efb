"""Derivative-target training (the HNN and LNN seeds' protocol): the true
targets against a second derivation, the loss against its definition, a fit, and a run."""

from __future__ import annotations

import dataclasses

import jax.numpy as jnp
import numpy as np
import pytest

import models
import systems
from bench.core import RunConfig, TrainConfig, _config, check_runnable, loss_fn, prepare, train

DERIV = TrainConfig(
    steps=300, batch=32, lr=1e-2, steps_per_call=50, log_every=50, target="derivative"
)


@pytest.mark.parametrize(
    ("name", "kw", "canonical"),
    [
        ("chain_pendulum", {"k": 2}, False),
        ("chain_pendulum", {"k": 2}, True),
        ("spring_pendulum", {"k": 2}, True),
        ("chain_pendulum", {"k": 2, "friction": 0.4}, True),  # friction enters dp/dt too
    ],
)
def test_true_derivatives_match_central_differences_of_the_truth(name, kw, canonical):
    """dz/dt from systems.derivatives against (z(t + h) - z(t - h)) / 2h of float64 ground
    truth, converted to (q, p) where canonical: a second derivation of the same field."""
    s = systems.make(name, **kw)
    z0 = np.asarray(s.sample_initial(__import__("jax").random.PRNGKey(3), 3))
    h = 1e-4
    ts = np.array([0.5 - h, 0.5, 0.5 + h])
    traj = np.stack([np.asarray(s.simulate(z, ts)) for z in z0])  # (3, 3, 2d)
    if canonical:
        traj = systems.to_momentum(s, traj)
    fd = (traj[:, 2] - traj[:, 0]) / (2 * h)
    got = systems.derivatives(s, traj[:, 1], canonical=canonical)
    np.testing.assert_allclose(got, fd, rtol=1e-5, atol=1e-6)
    assert got.shape == traj[:, 1].shape and got.dtype == np.float64


class _Pendulum:
    """Chain-1 states sampled at random with their true derivatives (no trajectories)."""

    def __init__(self, n=256, seed=0):
        s = systems.make("chain_pendulum", k=1)
        rng = np.random.default_rng(seed)
        z = np.stack([rng.uniform(-np.pi, np.pi, n), rng.uniform(-2, 2, n)], -1)[:, None]
        self.z_train = z  # (n, 1, 2): chunks of one state
        self.ts_train = np.zeros(1)
        self.args_train = np.zeros((n, 0))
        self.dz_train = systems.derivatives(s, z)
        self.angular = (True,)


def _model(name="node_so", seed=0):
    scene = models.Scene(dof=1, angular=(True,), n_args=0)
    return models.make(name, scene, key=__import__("jax").random.PRNGKey(seed), width=32)


def test_loss_is_the_mean_squared_field_error():
    data = _Pendulum(n=8)
    model = _model()
    z, args, ts, dz = prepare(model, data, DERIV)
    want = np.mean(
        [
            (np.asarray(model.vector_field(0.0, zz, a)) - d) ** 2
            for zz, a, d in zip(
                np.asarray(z)[:, 0], np.asarray(args), data.dz_train[:, 0], strict=True
            )
        ]
    )
    got = float(loss_fn(model, z, args, ts, DERIV, dz))
    assert got == pytest.approx(want, rel=1e-5)
    l1 = float(loss_fn(model, z, args, ts, dataclasses.replace(DERIV, loss="l1"), dz))
    assert l1 != pytest.approx(got)


def test_training_on_derivatives_fits_the_field_on_held_out_states():
    data, held = _Pendulum(seed=0), _Pendulum(n=128, seed=1)
    model = _model()

    def err(m):
        pred = np.stack(
            [np.asarray(m.vector_field(0.0, z, jnp.zeros(0))) for z in held.z_train[:, 0]]
        )
        return float(np.mean((pred - held.dz_train[:, 0]) ** 2))

    res = train(model, data, DERIV)
    assert res.status == "ok" and np.all(np.isfinite(res.losses))
    assert err(res.model) < err(model) / 10
    assert res.losses[-1] < res.losses[0] / 10


def test_derivative_targets_need_targets_and_a_vector_field():
    data = _Pendulum(n=8)
    del data.dz_train
    with pytest.raises(ValueError, match="dz_train"):
        prepare(_model(), data, DERIV)
    with pytest.raises(ValueError, match="target"):
        TrainConfig(target="pixels")
    cfg = RunConfig(system="chain_pendulum", k=1, model="vin", train_target="derivative")
    with pytest.raises(ValueError, match="discrete map; allowed:") as e:
        check_runnable(cfg)
    assert "\n" not in str(e.value)
    with pytest.raises(ValueError, match="train_target"):
        RunConfig(system="chain_pendulum", k=1, train_target="both")


def test_the_new_field_leaves_existing_hashes_alone():
    c = RunConfig(system="chain_pendulum", k=2, model="node_so")
    new = (
        "train_target",
        "eval_checkpoints",
        "duration",
        "observation",
        "optimizer",
        "lr_schedule",
        "weight_decay",
        "train_box",
        "standardise",
        "aux_weight",
    )
    old = _config._hash({a: b for a, b in c.to_dict().items() if a not in new})
    assert c.config_hash == old
    d = dataclasses.replace(c, train_target="derivative")
    assert d.config_hash != c.config_hash and d.train_hash != c.train_hash


def test_a_derivative_run_trains_and_is_evaluated_on_rollouts(tmp_path):
    from bench.core import execute_run

    cfg = RunConfig(
        system="chain_pendulum",
        k=1,
        model="node_so",
        train_target="derivative",
        n_generated=20,
        n_train=16,
        n_test=4,
        test_chunks=4,
        width=16,
        steps=40,
        batch=8,
    )
    row = execute_run(check_runnable(cfg), cache_root=tmp_path)
    assert row["status"] == "ok" and np.isfinite(row["rollout_error"])
    assert row["train_target"] == "derivative" and row["steps_done"] == 40
    # the seeds' losses: the field error at training and test states (recorded, positive)
    assert all(0 < row[f"derivative_mse_{s}"] < np.inf for s in ("train", "test"))


def test_noisy_inputs_get_the_true_field_at_the_clean_states(tmp_path):
    """The HNN seed's protocol: noise on the observed states, targets the true dz/dt where
    the system was (its data.py adds the noise after computing dz/dt)."""
    from bench.core import build_run

    cfg = RunConfig(
        system="mass_spring",
        model="node",
        coordinates="momentum",
        train_target="derivative",
        noise=0.1,
        n_generated=6,
        n_train=6,
        n_test=2,
        test_chunks=2,
        chunk=5,
    )
    system, data, _, _ = build_run(cfg, tmp_path)
    clean = systems.make_dataset(dataclasses.replace(cfg.dataset_config(), noise=0.0), tmp_path)
    assert np.std(data.z_train - clean.z_train) == pytest.approx(0.1, rel=0.3)  # noisy inputs
    np.testing.assert_array_equal(data.z_train_clean, clean.z_train)
    expected = systems.derivatives(system, clean.z_train, None, canonical=True)
    np.testing.assert_array_equal(data.dz_train, expected)
    # H = q^2 + p^2: dq/dt = 2p, dp/dt = -2q at the clean states (not the noisy ones)
    np.testing.assert_allclose(
        data.dz_train,
        np.stack([2 * clean.z_train[..., 1], -2 * clean.z_train[..., 0]], -1),
        rtol=1e-12,
        atol=1e-12,
    )
