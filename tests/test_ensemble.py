"""Ensembles (bench.core._ensemble): members equal single runs, divergence stays with its member,
grouping, and the rows of an ensemble sweep."""

import dataclasses
import json

import jax
import numpy as np
import pytest

import bench.core._runner as runner
import models
from bench.core import (
    RunConfig,
    TrainConfig,
    _params,
    _store,
    ensemble_enabled,
    group_key,
    plan_groups,
    train,
    train_ensemble,
)

STEPS = 20


class _Chunks:
    """A chain-2 training set: random angles and velocities, 5 points 0.03 apart."""

    def __init__(self, seed, n=16, chunk=5):
        rng = np.random.default_rng(seed)
        q = rng.uniform(-np.pi, np.pi, (n, 1, 2)) + 0.05 * rng.standard_normal((n, chunk, 2))
        self.ts_train = np.arange(chunk) * 0.03
        self.z_train = np.concatenate([q, rng.standard_normal((n, chunk, 2))], axis=-1)
        self.args_train = np.zeros((n, 0))


def _model(seed):
    scene = models.Scene(dof=2, angular=(True, True))
    return models.make("node", scene, key=jax.random.PRNGKey(seed), width=16, depth=2)


def _config(seed, lr=5e-3):
    # euler keeps the compiles cheap; the step is the one every integrator shares
    euler = models.Integrator("euler")
    return TrainConfig(steps=STEPS, batch=8, lr=lr, seed=seed, steps_per_call=8, integrator=euler)


LRS = (5e-3, 1e30, 5e-3)  # member 1 diverges at once


@pytest.fixture(scope="module")
def trained():
    cfgs = [_config(s, lr) for s, lr in enumerate(LRS)]
    data = [_Chunks(s) for s in range(3)]
    singles = [train(_model(s), d, c) for s, (d, c) in enumerate(zip(data, cfgs, strict=True))]
    members = train_ensemble([_model(s) for s in range(3)], data, cfgs)
    return singles, members


def _max_rel(a, b):
    return max(
        float(np.max(np.abs(x - y) / (np.abs(y) + 1e-6)))
        for x, y in zip(jax.tree.leaves(a), jax.tree.leaves(b), strict=True)
        if hasattr(x, "shape")
    )


def test_member_equals_single_run_over_20_steps(trained):
    singles, members = trained
    for i in (0, 2):
        s, m = singles[i], members[i]
        assert s.status == m.status == "ok" and m.steps_done == STEPS == len(m.losses)
        # same seed, same batches, same lr: equal up to float32 round-off
        np.testing.assert_allclose(m.losses, s.losses, rtol=2e-5)
        assert _max_rel(m.model, s.model) < 1e-4
    # and the training did something: the loss fell
    assert members[0].losses[-1] < members[0].losses[0]
    # a member's share of the program's FLOPs is a single run's step, give or take the mapping
    assert members[0].flops_per_step == pytest.approx(singles[0].flops_per_step, rel=0.02)


def test_diverged_member_recorded_and_isolated(trained):
    singles, members = trained
    bad, alone = members[1], singles[1]
    assert bad.status == alone.status == "diverged"
    assert bad.diverged_step == alone.diverged_step is not None
    assert bad.steps_done == bad.diverged_step == len(bad.losses)
    # the model kept is the last one with a finite loss
    assert all(np.all(np.isfinite(x)) for x in jax.tree.leaves(bad.model) if hasattr(x, "shape"))
    # the others are as if trained alone (checked above) and finished every step
    assert members[0].steps_done == members[2].steps_done == STEPS


def test_ensemble_rejects_members_that_differ_in_shape_or_settings():
    data = [_Chunks(0), _Chunks(1)]
    with pytest.raises(ValueError, match="differ only in seed and lr"):
        train_ensemble(
            [_model(0), _model(1)], data, [_config(0), dataclasses.replace(_config(1), batch=4)]
        )
    with pytest.raises(ValueError, match="training data differ in shape"):
        train_ensemble(
            [_model(0), _model(1)], [data[0], _Chunks(1, n=12)], [_config(0), _config(1)]
        )


def _run(**kw):
    base = dict(system="chain_pendulum", k=2, model="node", steps=4, n_generated=8, n_train=6)
    base.update(n_test=2, test_chunks=2, width=8, batch=4)
    base.update(train_integrator="euler", eval_integrator="euler")
    return RunConfig(**{**base, **kw})


def test_grouping_puts_exactly_the_shape_compatible_runs_together(tmp_path):
    same = [_run(seed=0), _run(seed=1), _run(seed=2, lr=1e-3), _run(seed=0, noise=0.1)]
    other = [_run(width=16), _run(model="hnn"), _run(loss="l1"), _run(batch=2)]
    again = _run(seed=1, eval_substeps=2)  # same training as same[1]
    cached = _run(seed=7)
    pdir = tmp_path / "params" / cached.train_hash
    pdir.mkdir(parents=True)
    (pdir / "model.eqx").write_bytes(b"x")
    meta = {"sha256": _params.sha256_file(pdir / "model.eqx"), "code": _params.code_fingerprint()}
    (pdir / "train.json").write_text(json.dumps(meta))
    groups = plan_groups(same + other + [again, cached], tmp_path, max_size=20)
    as_sets = [{c.config_hash for c in g} for g in groups]
    assert {c.config_hash for c in same} in as_sets
    for c in other + [again, cached]:
        assert {c.config_hash} in as_sets
    assert sum(len(g) for g in groups) == 10 and len(groups) == 7
    # an eval-only variant goes after the run whose training it reuses
    assert groups.index([again]) > as_sets.index({c.config_hash for c in same})
    sizes = [len(g) for g in plan_groups([_run(seed=s) for s in range(7)], None, max_size=3)]
    assert sizes == [3, 3, 1]
    assert group_key(_run(seed=3, lr=0.1, eval_rtol=1e-3)) == group_key(_run())
    with pytest.raises(ValueError, match="ensemble size"):
        plan_groups(same, None, max_size=0)


def test_ensemble_modes():
    assert ensemble_enabled("on") and not ensemble_enabled("off")
    assert ensemble_enabled("auto") == (jax.default_backend() != "cpu")
    with pytest.raises(ValueError, match="allowed: auto, on, off"):
        ensemble_enabled("yes")


def _sweep(configs, root, mode, executor="local", cache=None):
    return runner.sweep(
        configs,
        root / "res",
        experiment="test_ensemble",
        profile="smoke",
        executor=executor,
        progress=False,
        cache_root=cache or root / "cache",
        ensemble=mode,
    )


@pytest.mark.slow  # keeps make test under 10 min on a CPU
def test_ensemble_sweep_rows_match_single_runs(tmp_path, capsys):
    # one seed, two learning rates (one dataset to generate); the second diverges
    configs = [_run(seed=0), _run(seed=0, lr=1e30)]
    cache = tmp_path / "cache"
    ens = _sweep(configs, tmp_path / "ens", "on", cache=cache)
    assert "fell back" not in capsys.readouterr().err  # trained and rolled out as one
    ens_params = {
        c.train_hash: (cache / "params" / c.train_hash).rename(tmp_path / c.train_hash)
        for c in configs
    }
    one = _sweep(configs, tmp_path / "one", "off", cache=cache)  # the datasets are cached
    a = _store.load_runs(tmp_path / "ens" / "res").set_index("config_hash").sort_index()
    b = _store.load_runs(tmp_path / "one" / "res").set_index("config_hash").sort_index()
    assert set(a.columns) == set(b.columns) and list(a.index) == sorted(
        c.config_hash for c in configs
    )
    assert list(a.index) == list(b.index) and list(a["train_hash"]) == list(b["train_hash"])
    assert sorted(r["ensemble_size"] for r in ens) == [2, 2]
    # CPU time: every row, an ensemble member's with its share of the shared training
    assert (a["cpu_seconds"] > 0).all() and (b["cpu_seconds"] > 0).all()
    assert sorted(r["ensemble_size"] for r in one) == [1, 1]
    for h in a.index:
        assert a.loc[h, "status"] == b.loc[h, "status"]
        assert a.loc[h, "diverged_step"] == b.loc[h, "diverged_step"] or (
            np.isnan(a.loc[h, "diverged_step"]) and np.isnan(b.loc[h, "diverged_step"])
        )
    ok = configs[0].config_hash
    assert a.loc[ok, "status"] == "ok" and a.loc[configs[1].config_hash, "status"] == "diverged"
    for m in ("final_loss", "rollout_error", "mse", "energy_violation", "nfe", "n_params"):
        assert a.loc[ok, m] == pytest.approx(b.loc[ok, m], rel=1e-3)
    assert not any(r["train_cached"] for r in ens + one)
    # the member's parameters are cached like a single run's: a rerun trains nothing
    (cache / "params" / configs[0].train_hash).rename(tmp_path / "single")
    ens_params[configs[0].train_hash].rename(cache / "params" / configs[0].train_hash)
    row = runner.execute_run(configs[0], cache_root=cache)
    assert row["train_cached"] is True


@pytest.mark.ray
@pytest.mark.slow
def test_ray_sweep_one_ensemble_per_task(tmp_path):
    pytest.importorskip("ray")
    configs = [_run(seed=s) for s in range(3)] + [_run(width=16)]
    rows = _sweep(configs, tmp_path, "on", executor="ray")
    assert len(rows) == 4 and all(r["status"] == "ok" for r in rows), [r["error"] for r in rows]
    assert sorted(r["ensemble_size"] for r in rows) == [1, 3, 3, 3]
    df = _store.load_runs(tmp_path / "res")
    assert set(df["config_hash"]) == {c.config_hash for c in configs}


@pytest.mark.slow
def test_pool_sweep_runs_ensembles_in_workers(tmp_path):
    configs = [_run(seed=s) for s in range(2)] + [_run(seed=0, width=16)]
    rows = runner.sweep(
        configs,
        tmp_path / "res",
        experiment="test_ensemble",
        profile="smoke",
        workers=2,
        progress=False,
        cache_root=tmp_path / "cache",
        ensemble="on",
    )
    assert all(r["status"] == "ok" for r in rows), [r["error"] for r in rows]
    assert sorted(r["ensemble_size"] for r in rows) == [1, 2, 2]
    assert set(_store.load_runs(tmp_path / "res")["config_hash"]) == {
        c.config_hash for c in configs
    }


def test_cli_ensemble_flags(capsys, tmp_path):
    from bench._cli import _parser, main

    code = main(["--results", str(tmp_path), "sweep", "--all", "--ensemble", "of"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "did you mean 'off'" in err[0], err
    assert not (tmp_path / ".rows").exists()
    assert _parser().parse_args(["perf", "--ensemble"]).ensemble is True
    assert _parser().parse_args(["bench", "--ensemble", "off"]).ensemble == "off"
    assert _parser().parse_args(["sweep", "--all"]).ensemble == "auto"
