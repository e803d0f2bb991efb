"""The trainer: loss definition, one trace per configuration, determinism, divergence, dtypes;
and the learned-H conservation of a separable HNN along its own rollouts."""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import bench.core._train as train_mod
import models
import systems
from bench.core import TrainConfig, Training, train, train_ensemble
from models import Integrator, rollout, rollout_batch
from models._base import AbstractContinuousModel

SMALL = TrainConfig(steps=60, batch=32, lr=1e-2, steps_per_call=20, log_every=20)


class Oscillators:
    """A Dataset-like training set from the closed-form oscillator q'' = -w^2 q (no compile)."""

    def __init__(self, n=32, chunk=5, dt=0.1, w=2.0, seed=0):
        rng = np.random.default_rng(seed)
        q0, v0 = rng.uniform(-1, 1, (2, n, 1))
        t = rng.uniform(0, 10, (n, 1)) + np.arange(chunk) * dt
        q = q0 * np.cos(w * t) + v0 / w * np.sin(w * t)
        v = -q0 * w * np.sin(w * t) + v0 * np.cos(w * t)
        self.ts_train = np.arange(chunk) * dt
        self.z_train = np.stack([q, v], axis=-1)
        self.args_train = np.zeros((n, 0))
        self.angular = (False,)


@pytest.fixture(scope="module")
def oscillators():
    return Oscillators()


@pytest.fixture(scope="module")
def pendulum(tmp_path_factory):
    config = systems.DatasetConfig(
        "chain_pendulum",
        (("k", 1),),
        n_generated=64,
        n_train=64,
        n_test=4,
        test_chunks=2,
        duration=3.0,
    )
    return systems.make_dataset(config, cache_dir=tmp_path_factory.mktemp("data"))


def scene_of(dataset):
    return models.Scene(
        dof=len(dataset.angular), angular=dataset.angular, n_args=dataset.args_train.shape[1]
    )


def make(name, dataset, dtype="float32", width=16, seed=0):
    return models.make(name, scene_of(dataset), key=jax.random.key(seed), width=width, dtype=dtype)


@pytest.fixture(scope="module")
def node_run(oscillators):
    before = train_mod._TRACES[0]
    result = train(make("node", oscillators), oscillators, SMALL)
    return result, train_mod._TRACES[0] - before


def direct_loss(model, dataset, config, n):
    """The loss on the first n chunks, computed outside the trainer."""
    dtype = jnp.dtype(config.dtype)
    z = jnp.asarray(dataset.z_train[:n], dtype)
    args = jnp.asarray(dataset.args_train[:n], dtype)
    ts = jnp.asarray(dataset.ts_train, dtype)
    pred = rollout_batch(model, z[:, 0], ts, args, config.integrator)
    err = np.asarray(pred - z, np.float64)
    return np.mean(err**2) if config.loss == "l2" else np.mean(np.abs(err))


def test_loss_decreases_and_traced_once(node_run):
    result, traces = node_run
    assert result.status == "ok" and result.diverged_step is None
    assert result.steps_done == SMALL.steps and result.losses.shape == (SMALL.steps,)
    assert result.losses[-10:].mean() < 0.5 * result.losses[:3].mean()
    assert traces == 1  # three blocks of 20 steps, one trace
    assert result.compile_seconds > 0 and result.train_seconds > 0


def test_same_seed_same_losses_and_no_recompile(oscillators, node_run):
    first, _ = node_run
    before = train_mod._TRACES[0]
    again = train(make("node", oscillators), oscillators, SMALL)
    np.testing.assert_array_equal(again.losses, first.losses)
    assert train_mod._TRACES[0] == before and again.compile_seconds == 0.0
    other = train(make("node", oscillators), oscillators, dataclasses.replace(SMALL, seed=1))
    assert not np.array_equal(other.losses, first.losses)


def test_one_program_for_every_rate_and_for_a_one_member_ensemble(oscillators, node_run):
    # the learning rate is an input of the compiled block, not part of it
    first, _ = node_run
    before = train_mod._TRACES[0]
    faster = train(make("node", oscillators), oscillators, dataclasses.replace(SMALL, lr=2e-2))
    assert train_mod._TRACES[0] == before and faster.compile_seconds == 0.0
    assert not np.array_equal(faster.losses, first.losses)
    # bench.train is the one-member training: the ensemble of one is the same run, bit for bit
    (alone,) = train_ensemble([make("node", oscillators)], [oscillators], [SMALL])
    assert train_mod._TRACES[0] == before and alone.compile_seconds == 0.0
    np.testing.assert_array_equal(alone.losses, first.losses)
    for a, b in zip(jax.tree.leaves(alone.model), jax.tree.leaves(first.model), strict=True):
        np.testing.assert_array_equal(a, b)
    assert alone.flops_per_step == first.flops_per_step > 0


def test_the_block_is_the_trainings_program(oscillators, node_run):
    # Training (what perf times) runs the block that bench.train runs: same losses, no compile
    first, _ = node_run
    training = Training([make("node", oscillators)], [oscillators], [SMALL])
    assert training.compile_seconds == 0.0 and training.flops == first.flops_per_step
    losses, failed = training.advance()
    assert losses.shape == failed.shape == (SMALL.steps_per_call, 1) and not failed.any()
    np.testing.assert_array_equal(losses[:, 0], first.losses[: SMALL.steps_per_call])
    assert training.done == SMALL.steps_per_call and training.train_seconds > 0
    pair = [make("node", oscillators, seed=s) for s in (0, 1)]
    with pytest.raises(ValueError, match="one member"):  # resuming is a single run's
        train_mod.drive(pair, [oscillators] * 2, [SMALL] * 2, resume=object())


def test_first_loss_is_the_defined_l2_loss(oscillators, node_run):
    # batch = N: step 0 sees every chunk, so its loss is the full-data loss of the initial model
    n = oscillators.z_train.shape[0]
    assert SMALL.batch == n
    expected = direct_loss(make("node", oscillators), oscillators, SMALL, n)
    np.testing.assert_allclose(node_run[0].losses[0], expected, rtol=1e-5)


def test_l1_float64_keeps_dtype(oscillators):
    n = oscillators.z_train.shape[0]
    config = dataclasses.replace(SMALL, steps=20, dtype="float64", loss="l1")
    model = make("node", oscillators, dtype="float64")
    result = train(model, oscillators, config, progress=True)
    leaves = jax.tree.leaves(eqx.filter(result.model, eqx.is_inexact_array))
    assert all(x.dtype == jnp.float64 for x in leaves)
    assert result.losses.dtype == np.float64 and result.status == "ok"
    np.testing.assert_allclose(
        result.losses[0], direct_loss(model, oscillators, config, n), rtol=1e-12
    )
    assert result.losses[-5:].mean() < result.losses[:3].mean()
    with pytest.raises(ValueError, match="dtype"):
        train(make("node", oscillators), oscillators, config)  # float32 model, float64 config


class SqrtRate(AbstractContinuousModel):
    """dz/dt = 30 sqrt(a) z: the loss pulls a down, through 0 into NaN."""

    a: jax.Array
    scene: models.Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)

    def __init__(self, a):
        self.a = jnp.asarray(a, jnp.float32)
        self.scene, self.dtype = models.Scene(1, (True,)), "float32"

    def vector_field(self, t, z, args):
        return 30.0 * jnp.sqrt(self.a) * z


def test_divergence_is_reported_not_raised(oscillators):
    # Adam's first steps move a by about lr each: a = 1 -> ~0.4 -> ~-0.2 (sqrt -> NaN at step 2)
    config = TrainConfig(steps=10, batch=16, lr=0.6, weight_decay=0.0, steps_per_call=4)
    result = train(SqrtRate(1.0), oscillators, config)
    assert result.status == "diverged" and result.diverged_step == 2
    assert result.steps_done == 2 and len(result.losses) == 2
    assert np.all(np.isfinite(result.losses))
    assert 0 < float(result.model.a) < 1  # the last model with a finite loss


@pytest.mark.parametrize(
    "kwargs",
    [
        {"steps": 0},
        {"batch": -1},
        {"lr": 0.0},
        {"lr": float("nan")},
        {"weight_decay": -1.0},
        {"clip": 0.0},
        {"lr_floor": 1.5},
        {"loss": "huber"},
        {"dtype": "float16"},
        {"integrator": "rk4"},
        {"seed": -1},
        {"steps_per_call": 0},
    ],
)
def test_bad_config(kwargs):
    with pytest.raises(ValueError, match="TrainConfig"):
        TrainConfig(**kwargs)


def test_bad_dataset():
    class Bad:
        ts_train = np.zeros(3)
        z_train = np.zeros((4, 5, 2))
        args_train = np.zeros((4, 0))

    scene = models.Scene(1, (True,))
    model = models.make("node", scene, key=jax.random.key(0), width=8)
    with pytest.raises(ValueError, match="shapes"):
        train(model, Bad(), SMALL)


FIT = TrainConfig(steps=120, batch=32, lr=1e-2, steps_per_call=60)


def _fits(name, dataset):
    result = train(make(name, dataset, width=32), dataset, FIT)
    assert result.status == "ok", (name, result.diverged_step)
    first, last = result.losses[:3].mean(), result.losses[-10:].mean()
    assert last < 0.3 * first, (name, first, last)


@pytest.mark.parametrize("name", ["node_so", "resnet"])
def test_models_fit_oscillators_fast(oscillators, name):
    _fits(name, oscillators)


@pytest.mark.slow
@pytest.mark.parametrize(
    "name",
    [n for n in models.available() if n not in models.trivial_models() and n != "node_so_symreg"],
)
def test_every_model_fits_pendulum(pendulum, name):
    # node_so_symreg needs momentum data (its fit is checked with the runner's smoke sweeps)
    _fits(name, pendulum)


# --- the learned Hamiltonian of a separable HNN along its own rollouts -----------------------


@pytest.fixture(scope="module")
def hnn64():
    # angular q: the learned potential is periodic, so the rollout stays on a bounded H level
    scene = models.Scene(1, (True,))
    return models.make("hnn_so", scene, key=jax.random.key(3), width=16, dtype="float64")


Z0_H = jnp.array([0.5, 0.3])
NO_ARGS = jnp.zeros((0,))


def _energies(model, zs, args):
    return np.asarray(jax.vmap(lambda z: model.hamiltonian(z, args))(zs))


@pytest.mark.slow  # keeps make test under 10 min on a 2-core CPU
def test_learned_h_conserved_adaptive(hnn64):
    ts = jnp.linspace(0.0, 10.0, 101)
    zs = rollout(hnn64, Z0_H, ts, NO_ARGS, Integrator("adaptive", rtol=1e-10, atol=1e-12))
    h = _energies(hnn64, zs, NO_ARGS)
    assert np.max(np.abs(h - h[0])) < 1e-8 * abs(h[0])
    assert np.ptp(np.asarray(zs[:, 0])) > 1.0  # it actually moved


@pytest.mark.parametrize("method", ["leapfrog_explicit", "leapfrog"])
def test_learned_h_leapfrog_drift(hnn64, method):
    ts = jnp.arange(10_001) * 0.03
    zs = rollout(hnn64, Z0_H, ts, NO_ARGS, Integrator(method))
    dh = _energies(hnn64, zs, NO_ARGS)
    dh = dh - dh[0]
    spread = np.max(np.abs(dh))
    blocks = dh[:10_000].reshape(10, 1000).mean(axis=1)
    drift = abs(blocks[-1] - blocks[0])
    if method == "leapfrog":
        # learned M(q) makes H non-separable in the Stormer-Verlet sense; the generalised
        # (implicit) Stormer-Verlet in (q, p) is symplectic: bounded error, no drift
        assert spread < 1e-4 * abs(_energies(hnn64, Z0_H[None], NO_ARGS)[0])
        assert drift < 0.2 * spread
    else:
        # the explicit variant (documented) is not reversible here: the error grows steadily
        assert drift > 0.5 * spread


@pytest.mark.slow
def test_perf_smoke(tmp_path):
    from bench.studies.perf import main

    out = tmp_path / "perf.csv"
    assert main(["--models", "resnet", "--quick", "--block", "2", "--out", str(out)]) == 0
    import pandas as pd

    row = pd.read_csv(out).iloc[0]
    assert row["model"] == "resnet" and row["ms_per_step_median"] > 0
    assert row["step_gflop"] > 0 and row["threads"] >= 1


def test_prepare_drops_parameters_the_scene_does_not_take():
    # the relativistic particle's data carry its default g even without random_args; a model
    # built for a scene with n_args = 0 must train on args of shape (0,), as it is evaluated
    data = dataclasses.make_dataclass("D", ["ts_train", "z_train", "args_train"])(
        np.arange(3) * 0.1, np.zeros((4, 3, 2)), np.ones((4, 1))
    )
    scene = models.Scene(dof=1, angular=(False,))
    model = models.make("node_symreg", scene, key=jax.random.PRNGKey(0), width=4)
    z, args, ts = train_mod.prepare(model, data, TrainConfig(steps=1, batch=2))
    assert args.shape == (4, 0) and z.shape == (4, 3, 2)
    with_g = models.make(
        "node", models.Scene(dof=1, angular=(False,), n_args=1), key=jax.random.PRNGKey(0), width=4
    )
    assert train_mod.prepare(with_g, data, TrainConfig(steps=1, batch=2))[1].shape == (4, 1)


def test_perf_cells_are_the_experiments_own_trainable_cells():
    from bench.core import expand
    from bench.studies.perf._cells import cell_configs

    configs = cell_configs("coordinates", "paper-k", k=4)
    cells = {(c.system, c.model, c.k) for c in configs}
    trainable = {
        (c.system, c.model, c.k)
        for c in expand("coordinates", "paper-k", seeds=[0])
        if c.k == 4 and c.model not in models.trivial_models()
    }
    assert cells == trainable and len(configs) == len(cells)  # one variant (start) per cell
    assert {c.seed for c in configs} == {0} and all(c.batch == 200 for c in configs)
    only = cell_configs("coordinates", "paper-k", k=4, names={"hnn_so"})
    assert {c.model for c in only} == {"hnn_so"}
    spring = cell_configs("coordinates", "paper-k", k=4, systems={"spring_pendulum"})
    assert {c.system for c in spring} == {"spring_pendulum"} and len(spring) == len(cells) // 2
    with pytest.raises(SystemExit, match="coordinates.*k = 7; it has k 1, 3, 4; models hnn_so"):
        cell_configs("coordinates", "paper-k", k=7)


def test_perf_cells_refuse_kinds_that_train_alone():
    from bench.studies.perf._cells import cell_configs

    assert {c.observation for c in cell_configs("mujoco", "smoke")} == {"controlled"}
    with pytest.raises(SystemExit, match="state and controlled runs.*has pixels runs"):
        cell_configs("pixel_pendulum_hnn", "smoke")


@pytest.mark.slow
def test_perf_cells_controlled_smoke(tmp_path):
    """A MuJoCo cell (the stand-in data at smoke) is built and fitted as its run's train step
    does: its controls reach the objective."""
    from bench.studies.perf import main

    out = tmp_path / "cells.csv"
    argv = ["--cells", "mujoco", "--profile", "smoke", "--models", "node_so", "--quick"]
    assert main([*argv, "--systems", "HopperFull-v0", "--out", str(out)]) == 0
    import pandas as pd

    rows = pd.read_csv(out)
    assert list(rows["system"]) == ["HopperFull-v0"] and (rows["ms_per_step_median"] > 0).all()


@pytest.mark.slow
def test_perf_cells_smoke(tmp_path):
    from bench.studies.perf import main

    out = tmp_path / "cells.csv"
    argv = ["--cells", "coordinates", "--profile", "smoke", "--models", "node_so", "--quick"]
    assert main([*argv, "--out", str(out)]) == 0
    import pandas as pd

    rows = pd.read_csv(out)
    assert set(rows["model"]) == {"node_so"} and (rows["ms_per_step_median"] > 0).all()
    assert (rows["step_gflop"] > 0).all() and (rows["of_peak"] > 0).all()
    with pytest.raises(SystemExit, match="unknown experiment 'coordinatez'"):
        main(["--cells", "coordinates,coordinatez"])
