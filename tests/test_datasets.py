"""Datasets: shapes, the sampling protocol, independence of train and test, caching."""

from __future__ import annotations

import dataclasses
import os

import jax
import numpy as np
import pytest

import systems
from systems import _dataset
from systems._dataset import DatasetConfig, make_dataset

# Small sizes and one batch size (n_train + n_test) and trajectory length, so that each system's
# ground-truth solver compiles once in this file.
SMALL = dict(n_generated=6, n_train=4, n_test=4, chunk=3, dt=0.1, duration=2.0, test_chunks=3)


def _config(system="chain_pendulum", params=(("k", 1),), **kw):
    return DatasetConfig(system=system, system_params=params, **{**SMALL, **kw})


def _fake_simulate(calls):
    """Trajectories whose state records (time index, id of the initial state)."""

    def fake(system, z0s, ts, args):
        calls.append(len(z0s))
        z0s = np.asarray(z0s)
        out = np.zeros((len(z0s), len(ts), z0s.shape[1]))
        out[:, :, 0] = np.arange(len(ts))[None]
        out[:, :, 1] = z0s[:, :1]
        return out

    return fake


@pytest.fixture
def fake(monkeypatch):
    calls = []
    monkeypatch.setattr(_dataset, "_simulate", _fake_simulate(calls))
    return calls


@pytest.fixture(scope="module")
def chain_data(tmp_path_factory):
    return make_dataset(_config(), cache_dir=tmp_path_factory.mktemp("chain"))


# ------------------------------------------------------------------------------- config
def test_default_config_matches_paper():
    c = DatasetConfig("chain_pendulum", (("k", 2),))
    assert (c.n_generated, c.n_train, c.chunk, c.n_test, c.test_chunks) == (1000, 800, 5, 200, 20)
    assert c.n_points == 334


def test_hash_is_canonical():
    a = DatasetConfig("chain_pendulum", (("k", 2), ("friction", 0.4)))
    b = DatasetConfig("chain_pendulum", (("friction", 0.4), ("k", 2)))
    assert a == b and a.hash() == b.hash() and len(a.hash()) == 64
    assert a.system_params == (("friction", 0.4), ("k", 2))
    for change in [dict(seed=1), dict(noise=0.1), dict(chunk=4), dict(system_params=(("k", 3),))]:
        assert dataclasses.replace(a, **change).hash() != a.hash()


@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(system="chain_pendulm"), "did you mean 'chain_pendulum'"),
        (dict(params=(("k", 0),)), "k must be an integer >= 1"),
        (dict(params=(("q", 1),)), "unknown parameter"),
        (dict(params=5), "system_params must be"),
        (dict(n_train=7), r"n_train \(7\) must be <= n_generated \(6\)"),
        (dict(n_train=0), "n_train must be an integer >= 1"),
        (dict(chunk=1), "chunk must be in"),
        (dict(test_chunks=8), "exceeds the 21 points"),
        (dict(noise=-0.1), "noise must be"),
        (dict(noise=float("nan")), "noise must be"),
        (dict(dt=0.0), "dt must be"),
        (dict(duration=float("inf")), "duration must be"),
        (dict(coordinates="cartesian"), "coordinates must be one of"),
        (dict(random_args=1), "random_args must be"),
        (dict(seed=-1), "seed must be"),
        (dict(seed=1.5), "seed must be"),
    ],
)
def test_bad_config(kw, match):
    with pytest.raises(ValueError, match=match):
        _config(**kw)


def test_make_dataset_rejects_non_config(tmp_path):
    with pytest.raises(ValueError, match="DatasetConfig"):
        make_dataset({"system": "chain_pendulum"}, cache_dir=tmp_path)


# -------------------------------------------------------------------- sampling protocol
def test_windows_are_consecutive_random_and_in_range(fake, tmp_path):
    c = _config(n_generated=40, n_train=30, n_test=30, test_chunks=4)
    d = make_dataset(c, cache_dir=tmp_path)
    assert fake == [60]  # the kept training and the test trajectories, in one batch
    t_train = d.z_train[:, :, 0]
    t_test = d.z_test[:, :, 0]
    for t, length in [(t_train, 3), (t_test, 12)]:
        np.testing.assert_array_equal(np.diff(t, axis=1), 1.0)  # consecutive points
        assert t.min() >= 0 and t.max() <= c.n_points - 1
        assert len(np.unique(t[:, 0])) > 5  # random starts...
        assert np.any(t[:, 0] > 0)  # ...not only at t = 0
        assert t.shape[1] == length
    np.testing.assert_allclose(d.ts_train, [0.0, 0.1, 0.2])
    np.testing.assert_allclose(d.ts_test, np.arange(12) * 0.1)


def test_train_and_test_are_independent(fake, tmp_path):
    d = make_dataset(_config(n_generated=40, n_train=30, n_test=30), cache_dir=tmp_path)
    train_ids, test_ids = d.z_train[:, 0, 1], d.z_test[:, 0, 1]
    assert len(np.unique(train_ids)) == 30 and len(np.unique(test_ids)) == 30
    assert not set(train_ids) & set(test_ids)


def test_kept_trajectories_do_not_depend_on_n_train(fake, tmp_path):
    a = make_dataset(_config(n_generated=10, n_train=4), cache_dir=tmp_path)
    b = make_dataset(_config(n_generated=10, n_train=7), cache_dir=tmp_path)
    np.testing.assert_array_equal(a.z_train[:, 0, 1], b.z_train[:4, 0, 1])


def test_noise_only_on_training_set(fake, tmp_path):
    clean = make_dataset(_config(n_generated=40, n_train=40, n_test=40), cache_dir=tmp_path)
    noisy = make_dataset(
        _config(n_generated=40, n_train=40, n_test=40, noise=0.05), cache_dir=tmp_path
    )
    np.testing.assert_array_equal(noisy.z_test, clean.z_test)
    diff = noisy.z_train - clean.z_train
    assert np.std(diff) == pytest.approx(0.05, rel=0.15) and abs(np.mean(diff)) < 0.01


def test_default_cache_dir_from_env(fake, tmp_path, monkeypatch):
    monkeypatch.setenv("DECON_CACHE", str(tmp_path / "env"))
    c = _config()
    assert not systems.dataset_path(c).exists()
    make_dataset(c)
    assert (tmp_path / "env" / "datasets" / f"{c.hash()}.npz").is_file()
    assert systems.dataset_path(c) == tmp_path / "env" / "datasets" / f"{c.hash()}.npz"
    monkeypatch.delenv("DECON_CACHE")
    monkeypatch.chdir(tmp_path)
    make_dataset(c)
    assert (tmp_path / ".cache" / "decon-bench" / "datasets" / f"{c.hash()}.npz").is_file()
    assert systems.dataset_path(c).resolve() == (
        tmp_path / ".cache" / "decon-bench" / "datasets" / f"{c.hash()}.npz"
    )


# ------------------------------------------------------------------------------- caching
def test_cache_hit_does_not_simulate(tmp_path, monkeypatch, fake):
    c = _config()
    first = make_dataset(c, cache_dir=tmp_path)
    assert fake == [8]
    second = make_dataset(c, cache_dir=tmp_path)
    assert fake == [8]  # loaded, not simulated
    for name in _dataset._ARRAYS:
        np.testing.assert_array_equal(getattr(first, name), getattr(second, name))
    assert [p.name for p in (tmp_path / "datasets").iterdir()] == [f"{c.hash()}.npz"]


def test_a_failed_ground_truth_raises_and_caches_nothing(tmp_path, monkeypatch):
    """A solve that runs out of steps is not finite from there on (``simulate_batch``)."""
    calls = []
    fake = _fake_simulate(calls)

    def failing(system, z0s, ts, args):
        out = fake(system, z0s, ts, args)
        out[2, 5:] = np.inf
        return out

    monkeypatch.setattr(_dataset, "_simulate", failing)
    with pytest.raises(RuntimeError, match=r"1 of 8 trajectories is not finite \(first \[2\]\)"):
        make_dataset(_config(), cache_dir=tmp_path)
    assert not (tmp_path / "datasets").exists() or not any((tmp_path / "datasets").iterdir())


@pytest.mark.parametrize("damage", ["truncate", "flip", "tamper", "empty"])
def test_corrupt_cache_is_rebuilt(tmp_path, fake, damage):
    c = _config()
    good = make_dataset(c, cache_dir=tmp_path)
    path = tmp_path / "datasets" / f"{c.hash()}.npz"
    raw = path.read_bytes()
    if damage == "truncate":
        path.write_bytes(raw[: len(raw) // 2])
    elif damage == "flip":
        i = len(raw) // 2
        path.write_bytes(raw[:i] + bytes([raw[i] ^ 0xFF]) + raw[i + 1 :])
    elif damage == "empty":
        path.write_bytes(b"")
    else:  # a valid archive whose data disagree with its stored checksum
        with np.load(path) as f:
            arrays = {k: f[k] for k in f.files}
        arrays["z_train"] = arrays["z_train"] + 1.0
        with open(path, "wb") as fh:
            np.savez(fh, **arrays)
    assert fake == [8]
    rebuilt = make_dataset(c, cache_dir=tmp_path)
    assert fake == [8, 8]  # simulated again, not loaded
    np.testing.assert_array_equal(rebuilt.z_train, good.z_train)
    assert _dataset._load(path, c) is not None  # and the file was overwritten with good data


# --------------------------------------------------------------- real ground truth, small
def test_shapes_and_physics(chain_data):
    d = chain_data
    assert d.z_train.shape == (4, 3, 2) and d.z_test.shape == (4, 9, 2)
    assert d.args_train.shape == (4, 0) and d.args_test.shape == (4, 0)
    assert d.ts_train.shape == (3,) and d.ts_test.shape == (9,)
    assert d.angular == (True,)
    for z in (d.z_train, d.z_test):
        assert z.dtype == np.float64 and np.all(np.isfinite(z))
    s = systems.make("chain_pendulum", k=1)
    energy = np.asarray(jax.jit(jax.vmap(jax.vmap(s.energy)))(d.z_test))
    np.testing.assert_allclose(energy, energy[:, :1] * np.ones((1, 9)), rtol=1e-8, atol=1e-8)
    # A window of a true trajectory: the central difference matches the field.
    dq = (d.z_test[:, 2:, 0] - d.z_test[:, :-2, 0]) / 0.2
    np.testing.assert_allclose(dq, d.z_test[:, 1:-1, 1], atol=0.05 * np.abs(dq).max())


def test_deterministic_per_seed(chain_data, tmp_path):
    again = make_dataset(_config(), cache_dir=tmp_path)  # fresh cache: regenerated
    for name in _dataset._ARRAYS:
        np.testing.assert_array_equal(getattr(again, name), getattr(chain_data, name))
    other = make_dataset(_config(seed=1), cache_dir=tmp_path)
    assert not np.allclose(other.z_train, chain_data.z_train)
    assert not np.allclose(other.z_test, chain_data.z_test)
    assert not [p for p in os.listdir(tmp_path / "datasets") if p.startswith(systems.TMP_PREFIX)]


def test_relativistic_momentum_and_random_args(tmp_path):
    params = ()
    vel = make_dataset(
        _config("relativistic_particle", params, random_args=True), cache_dir=tmp_path
    )
    mom = make_dataset(
        _config("relativistic_particle", params, random_args=True, coordinates="momentum"),
        cache_dir=tmp_path,
    )
    assert vel.args_train.shape == (4, 1) and vel.args_test.shape == (4, 1)
    assert np.all((vel.args_train >= 0.5) & (vel.args_train <= 2.0))
    assert len(np.unique(vel.args_train)) == 4  # drawn per trajectory
    assert not set(vel.args_train[:, 0]) & set(vel.args_test[:, 0])
    np.testing.assert_array_equal(mom.args_train, vel.args_train)
    np.testing.assert_array_equal(mom.z_train[..., 0], vel.z_train[..., 0])
    v = vel.z_test[..., 1]
    np.testing.assert_allclose(mom.z_test[..., 1], v * (1 - v**2) ** -1.5, rtol=1e-12)
    # dp/dt = g: the momentum grows linearly at the trajectory's own g.
    slope = (mom.z_test[:, -1, 1] - mom.z_test[:, 0, 1]) / (mom.ts_test[-1] - mom.ts_test[0])
    np.testing.assert_allclose(slope, mom.args_test[:, 0], rtol=1e-7)
