"""Controlled runs (the MuJoCo experiment's pipeline): a smoke sweep of every model on the
random-control stand-in, the training loss reading each window's own controls, the split by
episode, a task file read and checked against its card, and the one-line refusals."""

from __future__ import annotations

import json

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import models
from bench.core import RunConfig, check_runnable, execute_run, expand, load_runs, sweep
from bench.core import _controlled as C
from bench.studies.decon import mujoco as X
from bench.studies.decon.mujoco import _rule as R
from systems import mujoco_data as D

TASK = "HopperFull-v0"
SMOKE = dict(
    system=TASK,
    dt=0.008,
    observation="controlled",
    system_params=X.STAND_IN,
    n_generated=300,
    n_train=16,
    chunk=3,
    n_test=2,
    test_chunks=4,
    width=16,
    batch=8,
    steps=2,
    train_integrator="euler",
    eval_integrator="euler",
    train_substeps=8,
    eval_substeps=8,
)


@pytest.fixture(scope="module")
def built():
    return C.build(RunConfig(**SMOKE, model="node"))


def test_a_smoke_sweep_stores_every_model_with_the_stand_ins_source_and_sha256(tmp_path):
    configs = expand("mujoco", "smoke")
    # every cell at App. C's lr (smoke's): all but the paper's HNN, which runs at the code's
    app_c = [cell for cell in X.CELLS if cell[0] != R.PAPER_HNN]
    assert sorted((c.model, c.train_integrator) for c in configs) == sorted(app_c)
    sweep(configs, tmp_path / "res", progress=False, cache_root=tmp_path / "cache")
    runs = load_runs(tmp_path / "res")
    _, card = D.stand_in(TASK, configs[0].n_generated, seed=C.STAND_IN_SEED)
    assert sorted(runs["model"]) == sorted(m for m, _ in app_c)
    assert (runs["status"] == "ok").all(), runs[["model", "error"]]
    assert runs["data_source"].str.startswith("stand-in:").all()
    assert (runs["data_sha256"] == card["episodes_sha256"]).all()
    assert np.isfinite(runs[["train_mse", "test_mse", "rollout_error"]].to_numpy(float)).all()
    trained = runs[runs["model"] != C.TRIVIAL]
    assert np.isfinite(trained["final_loss"].to_numpy(float)).all()


def test_the_loss_reads_each_windows_own_controls(built):
    c = RunConfig(**SMOKE, model="node")
    model = built.model
    tc = C.train_config(c)
    data = C.CONTROLLED.data(model, built.windows, tc)
    ix = jnp.arange(8)
    loss = float(C.CONTROLLED.loss(model, data, ix, tc))
    # the same loss by hand: each window rolled out under its u_0, u_1, divided by the std
    w = built.windows
    pred = models.rollout_batch(
        model,
        jnp.asarray(w.z_train[:8, 0], jnp.float32),
        jnp.asarray(w.ts_train, jnp.float32),
        None,
        tc.integrator,
        controls=jnp.asarray(w.u_train[:8, :-1], jnp.float32),
    )
    by_hand = np.mean(((np.asarray(pred) - w.z_train[:8]) / w.scale) ** 2)
    np.testing.assert_allclose(loss, by_hand, rtol=1e-4)
    shuffled = (*data[:3], data[3][::-1], data[4])  # the windows' controls swapped around
    assert abs(float(C.CONTROLLED.loss(model, shuffled, ix, tc)) - loss) > 1e-6 * loss
    np.testing.assert_allclose(w.scale, w.z_train.reshape(-1, 12).std(0), rtol=1e-12)
    assert tc.lr_floor * tc.lr == pytest.approx(C.LR_END)


def test_train_and_test_episodes_are_disjoint_and_windows_are_their_rows(built):
    s = built.split
    assert not set(s.train_episode) & set(s.test_episode)
    ep, _, sha = C.load_episodes(RunConfig(**SMOKE, model="node"))
    assert sha == built.sha256
    for z, e, start in ((s.train_z, s.train_episode, s.train_start),
                        (s.test_z, s.test_episode, s.test_start)):  # fmt: skip
        for i in range(len(z)):
            row = np.flatnonzero((ep.episode == e[i]) & (ep.step == start[i]))[0]
            np.testing.assert_array_equal(z[i], ep.z[row : row + z.shape[1]])


def test_a_task_file_is_read_and_checked_against_its_card(monkeypatch, tmp_path):
    monkeypatch.setenv(D.ENV, str(tmp_path))
    monkeypatch.setenv("DECON_CACHE", str(tmp_path / "cache"))
    ep, card = D.stand_in(TASK, 300)
    assert not [c for c in expand("mujoco", "paper")]  # no file: no runs
    path = D.save_data(ep, {"policy": "test", "policy_budget": "none"})
    # the four models at 2e-4; NODE, NODE+SO, the HNN and the paper's HNN at 5e-3; the
    # paper's three models at 5e-3 under its update rule
    assert [c.system for c in expand("mujoco", "paper")] == [TASK] * (4 + 4 + 3) * 5
    assert not expand("mujoco", "quick")  # quick runs HalfCheetahFull-v0 only
    c = RunConfig(**{**SMOKE, "system_params": X.FILE, "n_generated": 250}, model="node")
    got, source, sha = C.load_episodes(c)
    assert source.startswith("file Hopper") and sha == card["episodes_sha256"]
    assert len(got.episode) == 250  # the first n_generated transitions
    np.testing.assert_array_equal(got.z, ep.z[:250])
    bad = json.loads(path.with_suffix(".json").read_text())
    bad["file_sha256"] = "0" * 64
    path.with_suffix(".json").write_text(json.dumps(bad))
    with pytest.raises(ValueError, match="differs from the card's") as e:
        C.load_episodes(c)
    assert "\n" not in str(e.value)


def test_a_bad_task_is_one_line_naming_the_tasks():
    with pytest.raises(ValueError) as e:
        RunConfig(**{**SMOKE, "system": "Hopper-v2"}, model="node")
    msg = str(e.value)
    assert "\n" not in msg and all(t in msg for t in X.TASKS)
    with pytest.raises(ValueError, match="dt of HopperFull-v0 is the task's, 0.008"):
        RunConfig(**{**SMOKE, "dt": 0.03}, model="node")
    with pytest.raises(ValueError, match="controlled runs need system_params"):
        RunConfig(**{**SMOKE, "system_params": ()}, model="node")


@pytest.mark.parametrize("model", ["hnn", "lnn"])
def test_a_model_that_reads_no_control_is_one_line(model):
    with pytest.raises(ValueError) as e:
        check_runnable(RunConfig(**SMOKE, model=model))
    assert "reads a control input" in str(e.value) and "\n" not in str(e.value)


def test_a_first_order_model_cannot_take_the_second_order_rule():
    c = RunConfig(**{**SMOKE, "train_integrator": "euler_so"}, model="node")
    with pytest.raises(ValueError, match="train_integrator 'euler_so' cannot run 'node'"):
        check_runnable(c)


@pytest.mark.parametrize("task", X.TASKS)
def test_every_task_runs_on_its_stand_in(task, tmp_path):
    t = X.systems.MUJOCO_TASKS[task]
    c = RunConfig(**{**SMOKE, "system": task, "dt": t.dt}, model=C.TRIVIAL)
    row = execute_run(check_runnable(c), cache_root=tmp_path)
    assert row["status"] == "ok", row["error"]
    assert len(row["curves"]["z_true"][0]) == t.nq + t.nv and row["data_points"] == 300


def test_the_scene_is_the_raw_state_with_the_tasks_controls():
    s = C.scene("HalfCheetahFull-v0")
    assert (s.dof, s.n_controls, any(s.angular)) == (9, 6, False)
    m = models.make("node_so", s, key=jax.random.PRNGKey(0), width=4, depth=1)
    assert models.spec("node_so").controls and m.scene.n_controls == 6


def test_controlled_runs_train_as_an_ensemble_whose_members_are_the_single_runs(tmp_path, capsys):
    from bench.core import group_key, plan_groups

    # two seeds at one rate form one ensemble; the paper's rate sets another cosine floor
    # (LR_END / lr), so its run trains alone; the trivial predictor too
    seeds = [RunConfig(**{**SMOKE, "steps": 4, "seed": s}, model="node") for s in (0, 1)]
    other_rate = RunConfig(**{**SMOKE, "steps": 4, "lr": X.LR}, model="node")
    trivial = RunConfig(**SMOKE, model=C.TRIVIAL)
    assert group_key(seeds[0]) == group_key(seeds[1]) != group_key(other_rate)
    groups = plan_groups([*seeds, other_rate, trivial])
    assert [[c.config_hash for c in g] for g in groups] == [
        [c.config_hash for c in seeds],
        [other_rate.config_hash],
        [trivial.config_hash],
    ]

    def run(mode):
        return sweep(
            seeds,
            tmp_path / mode,
            progress=False,
            cache_root=tmp_path / "cache",
            ensemble=mode,
        )

    together, alone = run("on"), run("off")
    assert "fell back" not in capsys.readouterr().err  # trained as one program
    assert sorted(r["ensemble_size"] for r in together) == [2, 2]
    # a member's wall time holds its share of the ensemble's training, as the schema says
    for r in together:
        assert r["wall_seconds"] >= r["train_seconds"] + r["compile_seconds"] > 0
    a = load_runs(tmp_path / "on").set_index("config_hash").sort_index()
    b = load_runs(tmp_path / "off").set_index("config_hash").sort_index()
    assert list(a.index) == list(b.index) and (a["status"] == "ok").all()
    for m in ("final_loss", "rollout_error", "test_mse", "train_mse", "n_params"):
        np.testing.assert_allclose(a[m].to_numpy(float), b[m].to_numpy(float), rtol=1e-4)
    # the seeds differ: a member is not its neighbour's copy
    assert a["final_loss"].nunique() == 2
    assert not any(r["train_cached"] for r in together + alone)


class _Killed(Exception):
    """Stands for a kill: raised right after a training's second save."""


def test_a_killed_controlled_training_resumes_for_the_same_data_only(tmp_path, monkeypatch):
    import dataclasses
    import shutil

    from bench.core import RECORD, _params

    c = RunConfig(**{**SMOKE, "steps": 23}, model="node")
    real_config, real_point = C.train_config, _params.resume_point
    monkeypatch.setattr(
        C, "train_config", lambda c: dataclasses.replace(real_config(c), steps_per_call=5)
    )
    built = C.build(c)
    whole, whole_meta = C.train(c, built, tmp_path / "whole", False)
    assert whole_meta["resumed_step"] == 0

    def killing(config, cache_root, data=""):
        point = real_point(config, cache_root, data)
        point.every, save, saves = 0.0, point.save, []

        def save_then_die(*state):
            save(*state)
            saves.append(state[0])
            if len(saves) == 2:
                raise _Killed

        point.save = save_then_die
        return point

    monkeypatch.setattr(_params, "resume_point", killing)
    with pytest.raises(_Killed):
        C.train(c, built, tmp_path / "cache", False)
    monkeypatch.setattr(_params, "resume_point", real_point)
    folder = _params.params_dir(tmp_path / "cache", c.train_hash) / _params.RESUME
    assert json.loads((folder / RECORD).read_text())["done"] == 10
    # the same configuration on other data (another file's sha256) starts afresh
    shutil.copytree(tmp_path / "cache", tmp_path / "other")
    _, meta = C.train(c, dataclasses.replace(built, sha256="other"), tmp_path / "other", False)
    assert meta["resumed_step"] == 0
    again, meta = C.train(c, built, tmp_path / "cache", False)
    assert meta["resumed_step"] == 10 and not folder.exists()
    for x, y in zip(
        jax.tree.leaves(eqx_params(again)), jax.tree.leaves(eqx_params(whole)), strict=True
    ):
        np.testing.assert_array_equal(np.asarray(x), np.asarray(y))


def eqx_params(model):
    import equinox as eqx

    return eqx.filter(model, eqx.is_inexact_array)
