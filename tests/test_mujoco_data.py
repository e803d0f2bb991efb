"""The MuJoCo tasks as data sources: raw [q, v] states, deterministic float64 transitions, the
by-episode split and its content hash. A uniform random policy stands in for the trained SAC
policy here only: it is not the paper's data (App. C explains why)."""

import dataclasses
import functools
import warnings

import mujoco
import numpy as np
import pytest

from systems import _mujoco as mj

warnings.filterwarnings("ignore", message=".*settotalmass.*")


def random_policy(nu):
    return lambda z, rng: rng.uniform(-1.0, 1.0, nu)


@functools.cache
def episodes(name, n_steps=400, seed=0):
    return mj.collect_episodes(name, random_policy(mj.task(name).nu), seed=seed, n_steps=n_steps)


@pytest.mark.parametrize("name", list(mj.TASKS))
def test_observation_is_qpos_qvel_with_table_dims(name):
    t = mj.task(name)
    env = mj.make_env(name)
    env.reset(seed=3)
    for _ in range(5):
        env.step(env.action_space.sample())
    d = env.unwrapped.data
    z = mj.raw_state(env)
    assert z.dtype == np.float64 and z.shape == (t.nq + t.nv,)
    np.testing.assert_array_equal(z, np.concatenate([d.qpos, d.qvel]))
    assert (t.nq, t.nv, t.nu) == (d.qpos.size, d.qvel.size, d.ctrl.size)
    assert env.unwrapped.dt == pytest.approx(t.dt, abs=1e-12)
    # the full observation keeps the x position the standard one drops
    obs = env.unwrapped._get_obs()
    np.testing.assert_array_equal(obs[: t.nq], d.qpos)
    ep = episodes(name)
    assert ep.z.shape[1:] == (t.nq + t.nv,) and ep.u.shape[1:] == (t.nu,)


def test_fig7_tasks_and_timesteps_of_the_reference():
    fig7 = {t.name: t.dt for t in mj.TASKS.values() if t.in_fig7}
    assert fig7 == {"HopperFull-v0": 0.008, "SwimmerFull-v0": 0.04, "HalfCheetahFull-v0": 0.05}
    with pytest.raises(ValueError, match="unknown MuJoCo task"):
        mj.task("Hopper-v2")


@pytest.mark.parametrize("name", ["HopperFull-v0", "SwimmerFull-v0", "HalfCheetahFull-v0"])
def test_recorded_control_from_recorded_state_reproduces_next_state(name):
    ep = episodes(name)
    env = mj.make_env(name)
    env.reset(seed=123)  # a different history: only (z, u) may matter
    rows = np.flatnonzero(ep.episode[1:] == ep.episode[:-1])[::5]
    assert len(rows) > 20
    for i in rows:
        z1 = mj.step_from(env, ep.z[i], ep.u[i])
        # Not bit-exact where constraints act: the solver starts from the previous step's
        # acceleration (warm start), which a state [q, v] does not carry, and stops at its
        # tolerance; measured differences are below 1e-12, far under any model error.
        np.testing.assert_allclose(z1, ep.z[i + 1], rtol=0, atol=1e-10)


def test_collection_is_deterministic_given_the_seed():
    a = mj.collect_episodes("SwimmerFull-v0", random_policy(2), seed=5, n_steps=50)
    b = mj.collect_episodes("SwimmerFull-v0", random_policy(2), seed=5, n_steps=50)
    c = mj.collect_episodes("SwimmerFull-v0", random_policy(2), seed=6, n_steps=50)
    assert mj.content_hash(a.arrays()) == mj.content_hash(b.arrays())
    assert mj.content_hash(a.arrays()) != mj.content_hash(c.arrays())


@pytest.fixture(scope="module")
def hopper_split():
    # the random hopper falls within ~20-40 steps: many short episodes
    ep = episodes("HopperFull-v0", n_steps=1500)
    split = mj.split_episodes(ep, seed=0, n_train=200, n_test=5, test_len=10, test_fraction=0.2)
    return ep, split


def test_no_episode_in_both_train_and_test(hopper_split):
    ep, split = hopper_split
    assert len(np.unique(ep.episode)) >= 20
    assert not set(split.train_episode) & set(split.test_episode)
    assert split.train_z.shape == (200, 3, 12) and split.train_u.shape == (200, 3, 3)
    assert split.test_z.shape == (5, 10, 12) and split.test_u.shape == (5, 10, 3)


def test_windows_are_consecutive_steps_of_one_episode(hopper_split):
    ep, split = hopper_split
    for part in ("train", "test"):
        zs, us = getattr(split, f"{part}_z"), getattr(split, f"{part}_u")
        eps, starts = getattr(split, f"{part}_episode"), getattr(split, f"{part}_start")
        for z, u, e, s in zip(zs, us, eps, starts, strict=True):
            rows = np.flatnonzero(ep.episode == e)[s : s + len(z)]
            assert len(rows) == len(z)
            np.testing.assert_array_equal(ep.step[rows], s + np.arange(len(z)))
            np.testing.assert_array_equal(ep.z[rows], z)
            np.testing.assert_array_equal(ep.u[rows], u)


def test_split_asks_no_more_windows_than_exist(hopper_split):
    ep, _ = hopper_split
    with pytest.raises(ValueError, match="test: .* available"):
        mj.split_episodes(ep, seed=0, n_train=10, n_test=5, test_len=500)


@pytest.mark.parametrize("name", ["HopperFull-v0", "SwimmerFull-v0"])
def test_q_advances_with_the_mean_velocity_over_a_transition(name):
    # RK4 tasks: over one transition of dt, (q1 - q0) / dt is the mean of v over the step; the
    # trapezoid (v0 + v1) / 2 approximates it with an error of order dt^2 |dv/dt| variations
    # (the reference's mujoco.py prints the same check as a least-squares fit). Measured
    # relative residual: 0.02 (Hopper, dt 0.008) to 0.04 (Swimmer, dt 0.04) under random
    # controls; 0.1 is the bound, while a velocity off by one step (one-sided rule) gives
    # 0.25-0.30, so a mislabelled or shifted v fails.
    t = mj.task(name)
    ep = episodes(name)
    q, v = ep.z[:, : t.nq], ep.z[:, t.nq :]
    same = ep.episode[1:] == ep.episode[:-1]
    fd = ((q[1:] - q[:-1]) / t.dt)[same]

    def rel(vel):
        return np.linalg.norm(fd - vel[same]) / np.linalg.norm(fd)

    assert rel((v[1:] + v[:-1]) / 2) < 0.1
    assert rel(v[:-1]) > 0.15 and rel(v[1:]) > 0.15


def test_euler_task_advances_q_with_the_new_velocity_each_substep():
    # HalfCheetah's XML uses MuJoCo's semi-implicit Euler: v' = v + h a, then q' = q + h v'
    # exactly for its slide and hinge joints; the residual is round-off (|q| h / eps ~ 1e-16).
    t = mj.task("HalfCheetahFull-v0")
    assert t.integrator == "Euler"
    ep = episodes(t.name)
    env = mj.make_env(t.name)
    m, d = env.unwrapped.model, env.unwrapped.data
    assert m.opt.integrator == mujoco.mjtIntegrator.mjINT_EULER
    h = m.opt.timestep
    for i in range(0, len(ep.z), 25):
        mj.set_state(env, ep.z[i])
        d.ctrl[:] = ep.u[i]
        q0, v0 = d.qpos.copy(), d.qvel.copy()
        mujoco.mj_step(m, d)
        np.testing.assert_allclose(d.qpos - q0, h * d.qvel, rtol=0, atol=1e-12)
        if np.abs(d.qvel - v0).max() > 1e-3:
            assert np.abs(d.qpos - q0 - h * v0).max() > 1e-9  # the explicit rule would fail


def test_content_hash_changes_when_data_change(hopper_split):
    ep, split = hopper_split
    h = split.sha256()
    assert h == mj.content_hash(split.arrays()) and len(h) == 64
    z = split.train_z.copy()
    z[3, 1, 4] = np.nextafter(z[3, 1, 4], np.inf)
    assert dataclasses.replace(split, train_z=z).sha256() != h
    assert dataclasses.replace(split, test_start=split.test_start + 1).sha256() != h
    other = mj.split_episodes(ep, seed=1, n_train=200, n_test=5, test_len=10, test_fraction=0.2)
    assert other.sha256() != h


def test_data_card(hopper_split):
    ep, split = hopper_split
    card = mj.data_card(
        split, ep, policy="uniform random (test stand-in)", policy_budget="none", policy_return=None
    )
    assert card["task"] == "HopperFull-v0" and card["sha256"] == split.sha256()
    assert card["sizes"]["train"] == [200, 3, 12] and card["sizes"]["test"] == [5, 10, 12]
    assert "Hopper-v5" in card["source"] and card["collection"]["transitions"] == 1500


# --- the task files: controls and first states, replayed bit for bit ----------------------


@pytest.fixture
def data_folder(monkeypatch, tmp_path):
    from systems import mujoco_data as D

    monkeypatch.setenv(D.ENV, str(tmp_path / "data"))
    monkeypatch.setenv("DECON_CACHE", str(tmp_path / "cache"))
    return tmp_path


@pytest.mark.parametrize("name", [n for n, t in mj.TASKS.items() if t.in_fig7])
def test_a_task_file_replays_to_its_episodes_bit_for_bit(name, data_folder):
    from systems import mujoco_data as D

    ep = episodes(name, 300)
    path = D.save_data(ep, {"policy": "uniform random (test)"})
    with np.load(path) as f:
        assert set(f.files) == set(D.FILE_FIELDS) and "z" not in f.files  # states not stored
    got, card = D.load_data(name)
    for k, a in ep.arrays().items():
        np.testing.assert_array_equal(getattr(got, k), a, err_msg=k)
        assert getattr(got, k).dtype == a.dtype
    assert card["episodes_sha256"] == mj.content_hash(ep.arrays()) and got.seed == ep.seed
    assert card["replay_mujoco"] == mujoco.__version__


def test_a_second_load_reads_the_cached_replay(data_folder, monkeypatch):
    from systems import mujoco_data as D

    ep = episodes("HalfCheetahFull-v0", 300)
    D.save_data(ep, {})
    D.load_data("HalfCheetahFull-v0")

    def no_replay(*a, **k):
        raise AssertionError("replayed again")

    monkeypatch.setattr(D, "replay", no_replay)
    got, _ = D.load_data("HalfCheetahFull-v0")
    np.testing.assert_array_equal(got.z, ep.z)


def test_states_the_controls_do_not_give_are_not_saved(data_folder):
    from systems import mujoco_data as D

    ep = episodes("HopperFull-v0", 300)
    z = ep.z.copy()
    z[40, 7] += 1e-12  # one velocity, one ulp-sized change, mid-episode
    with pytest.raises(ValueError, match="replay of the controls does not give the episodes"):
        D.save_data(dataclasses.replace(ep, z=z), {})
    assert not D.data_path("HopperFull-v0").exists()


def test_episodes_not_numbered_from_step_0_are_refused():
    from systems import mujoco_data as D

    ep = episodes("HopperFull-v0", 300)
    later = {k: v[5:] for k, v in ep.arrays().items()}  # the first episode's start cut off
    with pytest.raises(ValueError, match="numbered 0, 1, ... from step 0"):
        D.compact(dataclasses.replace(ep, **later))


@pytest.mark.parametrize("field", ["file_sha256", "episodes_sha256"])
def test_a_file_or_replay_unlike_its_card_is_one_line(field, data_folder):
    import json

    from systems import mujoco_data as D

    path = D.save_data(episodes("SwimmerFull-v0", 300), {})
    card = json.loads(path.with_suffix(".json").read_text())
    card[field] = "0" * 64
    path.with_suffix(".json").write_text(json.dumps(card))
    with pytest.raises(ValueError, match="sha256") as e:
        D.load_data("SwimmerFull-v0")
    assert "\n" not in str(e.value)
    with pytest.raises(ValueError, match="no data for HopperFull-v0"):
        D.load_data("HopperFull-v0")


# --- the committed task files ---------------------------------------------------------------


def _committed():
    from systems import mujoco_data as D

    return sorted(D.COMMITTED.glob("*.npz"))


@pytest.mark.parametrize("path", _committed(), ids=lambda p: p.stem)
def test_a_committed_file_matches_its_card_and_the_experiments_size(path):
    import json

    from bench.studies.decon import mujoco as X
    from systems import mujoco_data as D

    card = json.loads(path.with_suffix(".json").read_text())
    with np.load(path) as f:
        arrays = {k: f[k] for k in D.FILE_FIELDS}
    assert mj.content_hash(arrays) == card["file_sha256"]
    assert int(arrays["length"].sum()) == card["collection"]["transitions"] == X.TRANSITIONS
    assert card["task"] == path.stem and card["replay_mujoco"] == mujoco.__version__
    assert card["policy_training"]["steps"] == X.TRANSITIONS  # the whole buffer of the run


@pytest.mark.slow
@pytest.mark.parametrize("path", _committed(), ids=lambda p: p.stem)
def test_a_committed_file_replays_to_its_cards_episodes(path, monkeypatch, tmp_path):
    from systems import mujoco_data as D

    monkeypatch.setenv("DECON_CACHE", str(tmp_path))  # no cached replay: replay it here
    ep, card = D.load_data(path.stem, path.parent)
    assert mj.content_hash(ep.arrays()) == card["episodes_sha256"]


def _episodes_of_lengths(task, lengths):
    """Episodes with the committed file's episode structure and zero states: enough for the
    split, which reads only the episode ids and steps."""
    t = mj.task(task)
    n = int(lengths.sum())
    return mj.Episodes(
        t.name,
        z=np.zeros((n, t.nq + t.nv)),
        u=np.zeros((n, t.nu)),
        reward=np.zeros(n),
        episode=np.repeat(np.arange(len(lengths)), lengths),
        step=np.concatenate([np.arange(k) for k in lengths]),
        seed=0,
    )


@pytest.mark.parametrize("profile", ["quick", "paper-core", "paper"])
def test_every_declared_cell_finds_its_windows_in_the_committed_files(profile):
    """Each task's training and test windows at each profile's sizes exist in the committed
    file's episodes (a Hopper policy that falls early holds too few 201-state test windows,
    hence its shorter test trajectories, mujoco.SHORT_TEST_CHUNKS)."""
    from bench.core import _controlled as C
    from bench.core import expand
    from systems import mujoco_data as D

    cells = {
        (c.system, c.n_generated, c.n_train, c.chunk, c.n_test, c.test_chunks)
        for c in expand("mujoco", profile)
    }
    assert cells
    for task, n_generated, n_train, chunk, n_test, test_chunks in sorted(cells):
        with np.load(D.data_path(task)) as f:
            lengths = f["length"]
        ep = _episodes_of_lengths(task, lengths)
        assert len(ep.episode) >= n_generated
        split = mj.split_episodes(
            ep,
            seed=C.SPLIT_SEED,
            n_train=n_train,
            train_len=chunk,
            n_test=n_test,
            test_len=chunk * test_chunks,
        )
        assert split.test_z.shape[:2] == (n_test, chunk * test_chunks), task
    # and the check can fail: the paper's 201 states are too many for Hopper's episodes
    with np.load(D.data_path("HopperFull-v0")) as f:
        ep = _episodes_of_lengths("HopperFull-v0", f["length"])
    with pytest.raises(ValueError, match="test: 200 windows of 201 steps asked"):
        mj.split_episodes(
            ep, seed=C.SPLIT_SEED, n_train=40_000, train_len=3, n_test=200, test_len=201
        )
