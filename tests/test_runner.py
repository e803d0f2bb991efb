"""Experiments, the store and the sweep runner: expansion, hashing, atomic rows.

Faults from outside a run (a sweep killed and resumed, damaged rows, a full disk) are in
tests/test_faults.py.
"""

import dataclasses
import json
import os
import re
import signal
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import bench.core._runner as runner
import models
from bench.core import Experiment, RunConfig, _store, cpu_count, expand, register

ROOT = Path(__file__).resolve().parents[1]

TWO = register(
    Experiment(
        name="test_two",
        title="test: two models",
        axes={"model": ["node", "node_so"]},
        fixed={"system": "chain_pendulum", "k": 1, "steps": 10},
    ),
    replace=True,
)

ALL = register(
    Experiment(
        name="test_all_smoke",
        title="test: every model on every system",
        axes={
            "system": ["chain_pendulum", "spring_pendulum", "relativistic_particle"],
            "k": [2, None],
            "friction": [0.0, 0.4],
            "model": models.available(),
            "coordinates": ["velocity", "momentum"],
        },
        # chain and spring, damped and not, and the relativistic particle: five scenes; each
        # model once, in velocity coordinates unless it takes momentum coordinates only
        include=lambda c: (
            (c.system == "relativistic_particle") == (c.k is None)
            and not (c.system == "relativistic_particle" and c.friction > 0)
            and (c.coordinates == "velocity") == ("velocity" in models.coordinates(c.model))
        ),
    ),
    replace=True,
)


# ------------------------------------------------------------------------- experiments
def test_expand_product_seeds_overrides_and_filters():
    exp = Experiment(
        name="t",
        title="t",
        axes={"model": ["node", "node_so"], "eval_integrator": ["rk4_38", "leapfrog"]},
        fixed={"system": "chain_pendulum", "k": 2},
        profile_overrides={"smoke": {"seeds": [0, 1], "steps": 7}},
    )
    runs = expand(exp, "smoke")
    # leapfrog needs a second-order model: node x leapfrog is dropped.
    combos = {(r.model, r.eval_integrator) for r in runs}
    assert combos == {("node", "rk4_38"), ("node_so", "rk4_38"), ("node_so", "leapfrog")}
    assert len(runs) == 3 * 2
    assert {r.seed for r in runs} == {0, 1}
    assert all(r.steps == 7 and r.width == 16 and r.k == 2 for r in runs)
    assert len({r.config_hash for r in runs}) == len(runs)
    # Eval-only variants share the training.
    a = [r for r in runs if r.model == "node_so" and r.seed == 0]
    assert a[0].train_hash == a[1].train_hash and a[0].config_hash != a[1].config_hash
    only = Experiment(
        name="t2",
        title="t",
        axes={"model": ["node", "node_so"]},
        fixed={"system": "chain_pendulum", "k": 1},
        include=lambda c: c.model == "node",
    )
    assert [r.model for r in expand(only, "smoke")] == ["node"]
    # The paper profile is the reference budget.
    p = expand(only, "paper")
    assert len(p) == 5 and p[0].steps == 8000 and p[0].n_train == 800 and p[0].width == 256


def test_hash_canonical_and_names_excluded():
    a = RunConfig(system="chain_pendulum", k=2, model_options={"weight": 1.0, "a": 2})
    b = RunConfig(system="chain_pendulum", k=2.0, model_options=(("a", 2), ("weight", 1.0)))
    assert a.config_hash == b.config_hash
    assert a.config_hash != RunConfig(system="chain_pendulum", k=3).config_hash
    assert RunConfig.from_dict(json.loads(json.dumps(a.to_dict()))) == a
    e1 = Experiment(name="x1", title="", axes={"model": ["node"]}, fixed={"system": "pendulum"})
    e2 = Experiment(name="x2", title="", axes={"model": ["node"]}, fixed={"system": "pendulum"})
    assert [r.config_hash for r in expand(e1, "smoke")] == [
        r.config_hash for r in expand(e2, "smoke")
    ]


def test_unknown_fields_rejected_at_registration():
    with pytest.raises(ValueError, match="did you mean 'width'"):
        Experiment(name="bad", title="", axes={"widht": [1]})
    with pytest.raises(ValueError, match="RunConfig field"):
        Experiment(name="bad", title="", fixed={"nope": 1})
    with pytest.raises(ValueError, match="profile"):
        Experiment(name="bad", title="", profile_overrides={"quik": {}})
    with pytest.raises(ValueError, match="steps"):
        Experiment(name="bad", title="", profile_overrides={"smoke": {"stepz": 3}})
    with pytest.raises(ValueError, match="k must be an integer >= 1"):
        RunConfig(system="chain_pendulum", k=0)
    with pytest.raises(ValueError, match="seed"):
        RunConfig(system="chain_pendulum", seed=-1)


def test_run_config_is_checked_once_where_it_is_built():
    """Construction checks the values, the system with its parameters and the dataset's shape
    (a RunConfig that exists is valid: from_dict and dataclasses.replace build one too);
    expand checks only the combinations its experiment keeps."""
    for bad, message in (
        ({"system": "chain_pendulm", "k": 1}, "unknown system 'chain_pendulm'"),
        ({"system": "chain_pendulum"}, "needs parameter(s) k"),
        ({"system": "relativistic_particle", "k": 2}, "unknown parameter(s) k"),
        ({"system": "chain_pendulum", "k": 1, "chunk": 1}, "chunk must be in [2, 334]"),
        ({"system": "chain_pendulum", "k": 1, "loss": "l3"}, "allowed: l1, l2"),
    ):
        with pytest.raises(ValueError, match=re.escape(message)):
            RunConfig(**bad)
    good = RunConfig(system="chain_pendulum", k=1)
    with pytest.raises(ValueError, match="test_chunks"):
        dataclasses.replace(good, test_chunks=100)
    with pytest.raises(ValueError, match="unknown system"):
        RunConfig.from_dict({**good.to_dict(), "system": "nope"})
    # a row read back from JSON (lists for tuples) is the same, hashable configuration
    params = RunConfig(system="chain_pendulum", k=2, system_params={"masses": (1.0, 2.0)})
    back = RunConfig.from_dict(json.loads(json.dumps(params.to_dict())))
    assert back == params and hash(back) == hash(params)
    assert back.config_hash == params.config_hash
    # the product holds a spring's initial state on the chain; include drops it, so it is
    # never built, but a kept combination that cannot be built names its experiment
    spring = (("initial", "paper"),)
    exp = Experiment(
        name="t3",
        title="t",
        axes={"system": ["chain_pendulum", "spring_pendulum"], "system_params": [(), spring]},
        fixed={"k": 1},
        include=lambda c: (c.system == "spring_pendulum") == (c.system_params == spring),
    )
    assert [r.system for r in expand(exp, "smoke")] == ["chain_pendulum", "spring_pendulum"]
    everything = dataclasses.replace(exp, name="t4", include=None)
    with pytest.raises(ValueError, match="experiment 't4' at smoke: unknown parameter"):
        expand(everything, "smoke")


# ------------------------------------------------------------------------------- store
def test_store_one_row_per_hash_and_tables(tmp_path):
    c = RunConfig(system="chain_pendulum", k=1)
    row = runner.base_row(c)
    row.update(status="ok", rollout_error=float("nan"), experiment="e", profile="smoke")
    row["curves"] = {
        "t": [0, 1],
        "rel_error": [0, 0.5],
        "energy_violation": [0, 0.1],
        "z_true": [[1, 2], [3, 4]],
        "z_pred": [[1, 2], [3, 5]],
    }
    _store.write_row(tmp_path, row)
    _store.write_row(tmp_path, row)  # rewriting the same run cannot duplicate it
    df = _store.rebuild_tables(tmp_path)
    assert len(df) == 1 and np.isnan(df.loc[0, "rollout_error"])
    assert len(pd.read_parquet(tmp_path / "runs.parquet")) == 1
    assert len(pd.read_csv(tmp_path / "runs.csv")) == 1
    cur = pd.read_parquet(tmp_path / "curves.parquet")
    assert list(cur["rel_error"]) == [0, 0.5] and list(cur["z_pred_1"]) == [2, 5]
    assert not list(tmp_path.glob(".tmp*")) and not list((tmp_path / ".rows").glob(".tmp*"))
    assert _store.done_hashes(tmp_path) == {c.config_hash}


# -------------------------------------------------------------------------- real runs
@pytest.fixture(scope="module")
def smoke(tmp_path_factory):
    """A real smoke sweep: two models plus a deliberately diverging learning rate."""
    res = tmp_path_factory.mktemp("results")
    cache = tmp_path_factory.mktemp("cache")
    configs = expand(TWO, "smoke")
    bad = RunConfig(**{**configs[0].to_dict(), "lr": 1e30})
    t0 = time.perf_counter()
    rows = runner.sweep(
        [*configs, bad],
        res,
        experiment="test_two",
        profile="smoke",
        progress=False,
        cache_root=cache,
    )
    return {
        "res": res,
        "cache": cache,
        "rows": rows,
        "configs": configs,
        "bad": bad,
        "seconds": time.perf_counter() - t0,
    }


def test_smoke_sweep_end_to_end(smoke):
    df = _store.load_runs(smoke["res"])
    assert len(df) == 3 and df["config_hash"].is_unique
    by = df.set_index("config_hash")
    for c in smoke["configs"]:
        r = by.loc[c.config_hash]
        assert r["status"] == "ok", r["error"]
        assert 0 < r["rollout_error"] < 1 and 0 <= r["energy_violation"] <= 1
        assert r["n_params"] > 0 and r["rollout_seconds"] > 0 and r["nfe"] == 4 * 19
        # process CPU time: positive, and a run cannot use more than its cores' worth of it
        assert 0 < r["cpu_seconds"] <= r["wall_seconds"] * cpu_count() + 0.5
        assert r["experiment"] == "test_two" and r["profile"] == "smoke"
        assert r["floor"] < r["rollout_error"]
    # The diverging run is recorded as such, without stopping the others.
    assert by.loc[smoke["bad"].config_hash, "status"] == "diverged"
    cur = pd.read_parquet(smoke["res"] / "curves.parquet")
    assert set(cur["config_hash"]) >= {c.config_hash for c in smoke["configs"]}
    assert len(cur[cur["config_hash"] == smoke["configs"][0].config_hash]) == 20
    # Rerunning the sweep executes nothing.
    again = runner.sweep(smoke["configs"], smoke["res"], progress=False, cache_root=smoke["cache"])
    assert again == []


def test_same_config_same_metrics(smoke, tmp_path):
    c = smoke["configs"][0]
    fresh = runner.execute_run(c, cache_root=tmp_path)  # retrains from scratch
    old = _store.load_runs(smoke["res"]).set_index("config_hash").loc[c.config_hash]
    assert fresh["train_cached"] is False
    for m in ("rollout_error", "energy_violation", "mse"):
        assert fresh[m] == pytest.approx(old[m], rel=1e-6)


def test_eval_variant_reuses_training_and_corrupt_params_retrain(smoke):
    c = smoke["configs"][1]
    variant = RunConfig(**{**c.to_dict(), "eval_substeps": 2})
    row = runner.execute_run(variant, cache_root=smoke["cache"])
    assert row["status"] == "ok" and row["train_cached"] is True
    assert row["nfe"] == 2 * 4 * 19
    pfile = Path(smoke["cache"]) / "params" / c.train_hash / "model.eqx"
    data = pfile.read_bytes()
    pfile.write_bytes(data[: len(data) // 2])  # truncated: the checksum no longer holds
    variant3 = RunConfig(**{**c.to_dict(), "eval_substeps": 3})
    row = runner.execute_run(variant3, cache_root=smoke["cache"])
    assert row["status"] == "ok" and row["train_cached"] is False
    assert pfile.read_bytes() != data[: len(data) // 2]


def test_failed_run_recorded_with_traceback(tmp_path):
    c = RunConfig(
        system="chain_pendulum",
        k=1,
        model="no_such_model",
        steps=1,
        n_generated=4,
        n_train=2,
        n_test=1,
        test_chunks=1,
        width=4,
        batch=2,
    )
    row = runner.execute_run(c, cache_root=tmp_path)
    assert row["status"] == "failed" and "no_such_model" in row["error"]
    assert (
        "Traceback" in (runner.artifact_dir(c.config_hash, tmp_path) / "traceback.txt").read_text()
    )


def test_a_drained_sweep_stores_the_runs_in_flight_and_starts_no_other(tmp_path, monkeypatch):
    """``$DECON_DRAIN`` (``make paper-core-drain``): once its file exists, the run in flight is
    stored and no other starts, in process or in a pool worker; without it the sweep resumes."""
    drain = tmp_path / "drain"
    monkeypatch.setenv(runner.DRAIN_ENV, str(drain))
    configs = expand("test_two", "smoke", seeds=[0, 1])
    assert len(configs) == 4
    started = []

    def fake(c, cache_root=None, progress=False):
        started.append(c.config_hash)
        if len(started) == 1:
            drain.touch()  # drained while the first run is in flight
        return {**runner.base_row(c), "status": "ok"}

    monkeypatch.setattr(runner, "execute_run", fake)

    def sweep():
        return runner.sweep(configs, tmp_path / "res", workers=1, progress=False, ensemble="off")

    rows = sweep()
    assert len(started) == 1 and [r["config_hash"] for r in rows] == started
    assert _store.done_hashes(tmp_path / "res") == set(started)
    assert sweep() == [] and len(started) == 1  # still draining: nothing starts
    assert runner._star_execute(([configs[0].to_dict()], str(tmp_path))) == []  # a pool job
    drain.unlink()
    assert len(sweep()) == 3 and len(set(started)) == 4
    assert _store.done_hashes(tmp_path / "res") == {c.config_hash for c in configs}


# Kill and resume, damaged rows, a full disk: tests/test_faults.py


# --------------------------------------------------------------------------------- ray
@pytest.mark.slow  # keeps make test under 10 min on a 2-core CPU
@pytest.mark.ray
def test_ray_two_run_sweep(tmp_path):
    pytest.importorskip("ray")
    configs = expand(TWO, "smoke")
    t0 = time.perf_counter()
    rows = runner.sweep(
        configs,
        tmp_path / "res",
        experiment="test_two",
        profile="smoke",
        executor="ray",
        progress=False,
        cache_root=tmp_path / "cache",
    )
    assert len(rows) == 2, rows
    assert all(r["status"] == "ok" for r in rows), [r["error"] for r in rows]
    df = _store.load_runs(tmp_path / "res")
    assert set(df["config_hash"]) == {c.config_hash for c in configs}
    print(f"ray two-run sweep: {time.perf_counter() - t0:.1f} s")


@pytest.mark.slow
@pytest.mark.parametrize("executor", ["local", "ray"])
def test_smoke_every_model_and_system(executor, tmp_path):
    if executor == "ray":
        pytest.importorskip("ray")
    configs = expand(ALL, "smoke")
    assert len(configs) == 5 * len(models.available())
    t0 = time.perf_counter()
    rows = runner.sweep(
        configs,
        tmp_path,
        experiment="test_all_smoke",
        profile="smoke",
        executor=executor,
        progress=False,
        cache_root=tmp_path / "cache",
    )
    failed = [(r["system"], r["model"], r["error"]) for r in rows if r["status"] == "failed"]
    assert not failed
    assert len(_store.load_runs(tmp_path)) == len(configs)
    print(f"{executor}: {len(configs)} smoke runs in {time.perf_counter() - t0:.0f} s")


def test_schedule_starts_one_run_of_every_cell_before_the_other_seeds():
    """Seeds of one cell compile the same programs: the first of each cell goes first
    (longest first among them), then the rest longest first; a tuple key keeps its groups."""
    long = [RunConfig(system="chain_pendulum", k=2, model="hnn_so", seed=s) for s in range(3)]
    short = [RunConfig(system="chain_pendulum", k=2, model="node", seed=s) for s in range(3)]
    cost = {"hnn_so": 10.0, "node": 1.0}
    got = runner._schedule(long + short, lambda c: cost[c.model])
    assert [(c.model, c.seed) for c in got] == [
        ("hnn_so", 0),
        ("node", 0),
        ("hnn_so", 1),
        ("hnn_so", 2),
        ("node", 1),
        ("node", 2),
    ]
    # a (rank, seconds) key: node's group first, the rule inside each group
    got = runner._schedule(long + short, lambda c: (c.model == "node", cost[c.model]))
    assert [(c.model, c.seed) for c in got] == [
        ("node", 0),
        ("node", 1),
        ("node", 2),
        ("hnn_so", 0),
        ("hnn_so", 1),
        ("hnn_so", 2),
    ]


def test_compiled_programs_are_dropped_when_the_memory_maps_near_the_limit():
    """Every compiled XLA program holds memory maps until jax's caches drop it; a worker that
    runs run after run reaches vm.max_map_count and segfaults (bench.core._env). Past the
    threshold the runner's hook clears the caches and the maps fall; below it, nothing."""
    import jax
    import jax.numpy as jnp

    from bench.core import _env

    counts = _env._map_count()
    if counts is None:
        pytest.skip("no /proc maps on this OS")
    for i in range(12):  # twelve programs of different shapes, each compiled and kept
        jax.jit(lambda x: jnp.sin(x) * 2 + 1)(jnp.ones(i + 1)).block_until_ready()
    before, limit = _env._map_count()
    assert not _env.bound_compiled_programs(fraction=1.0)  # far below the kernel's limit
    assert _env._map_count()[0] >= before - 5
    assert _env.bound_compiled_programs(fraction=1 / limit)  # past any threshold
    after = _env._map_count()[0]
    assert after < before - 12, (before, after)  # at least one map per program went


def _die_on_2(job):
    """A pool task (importable by the spawned workers) whose worker is killed on job 2."""
    if job == 2:
        os.kill(os.getpid(), signal.SIGKILL)  # the OOM killer, a segfault in native code
    time.sleep(0.2)
    return job


@pytest.mark.slow  # two pools of worker processes, one killed
def test_a_pool_worker_that_dies_raises_instead_of_hanging():
    """multiprocessing.Pool replaced a dead worker and waited forever for its task (a niced
    campaign would have hung unseen); the sweep's pool raises WorkerDied, one line, and
    cancels what had not started."""
    from bench.core import WorkerDied, imap_unordered, worker_pool

    with worker_pool(2) as pool:
        assert sorted(imap_unordered(pool, _die_on_2, [0, 1, 3])) == [0, 1, 3]
    got = []
    with worker_pool(2) as pool, pytest.raises(WorkerDied, match="a worker process died"):
        for r in imap_unordered(pool, _die_on_2, range(8)):
            got.append(r)
    assert 2 not in got and len(got) < 8
