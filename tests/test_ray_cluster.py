"""A sweep on a multi-node Ray cluster loses and repeats nothing when a worker node dies.

The cluster is Ray's own test cluster (``ray.cluster_utils.Cluster``): a head with no CPUs,
so every task runs on one of two worker nodes, each its own raylet and processes on this
machine. A plug-in model that only the driver imported trains there; one worker node is killed
(not drained) while the sweep runs; Ray resubmits the tasks that were running on it to the
other node. The rows must be those of an uninterrupted in-process sweep, run for run."""

from __future__ import annotations

import threading
import time

import pytest

import models
from bench.core import _runner as runner
from bench.core import _store, expand
from tests.test_plugins import _install

# a row's numbers that depend on where and when it ran, not on what it computed
_CIRCUMSTANCE = ("seconds", "host", "time", "date", "pid", "device", "cpu", "machine", "node")


def _computed(df):
    """The columns of the runs' results: everything but timing and provenance."""
    keep = [c for c in df.columns if not any(w in c.lower() for w in _CIRCUMSTANCE)]
    return df[keep].set_index("config_hash").sort_index()


@pytest.mark.slow  # starts a three-node Ray cluster and trains 6 smoke runs twice (~3 min)
@pytest.mark.ray
# the test cluster's raylets are started from this process, which has JAX loaded; the suite's
# own local instance is started from a spawned helper instead (bench.core._ray_head)
@pytest.mark.filterwarnings("ignore:os.fork:RuntimeWarning")
def test_a_worker_node_killed_mid_sweep_loses_and_repeats_no_run(
    clean_registry, tmp_path, monkeypatch
):
    ray = pytest.importorskip("ray")
    from ray.cluster_utils import Cluster

    site = _install(tmp_path / "site", "cluster_plugin", "cluster_so", entry_point=False)
    monkeypatch.syspath_prepend(str(site))  # the driver's path only
    monkeypatch.delenv(models.MODULES_ENV, raising=False)
    models.load_plugins("cluster_plugin")
    configs = [c for c in expand("second_order", "smoke", seeds=[0, 1, 2], models=["cluster_so"])]
    configs = [c for c in configs if c.model == "cluster_so"]
    configs = sorted(configs, key=lambda c: c.config_hash)[:6]
    assert len(configs) == 6 and len({c.config_hash for c in configs}) == 6

    common = dict(profile="smoke", progress=False, ensemble="off", experiment="cluster")
    reference = runner.sweep(
        configs, tmp_path / "ref", workers=1, cache_root=tmp_path / "ref_cache", **common
    )
    assert [r["status"] for r in reference] == ["ok"] * 6, [r.get("error") for r in reference]

    cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 0})
    workers = [cluster.add_node(num_cpus=1) for _ in range(2)]
    cluster.wait_for_nodes()
    out: list = []

    def run():
        try:
            out.append(
                runner.sweep(
                    configs,
                    tmp_path / "res",
                    executor="ray",
                    address=cluster.address,
                    cache_root=tmp_path / "cache",
                    **common,
                )
            )
        except BaseException as e:  # pragma: no cover - shown by the assert below
            out.append(e)

    sweep = threading.Thread(target=run, daemon=True)
    try:
        sweep.start()
        rows_dir = tmp_path / "res" / _store.ROWS
        deadline = time.monotonic() + 600
        # the first finished run: both nodes are busy (4 or more runs still wait), so the
        # node killed now is running one
        while not list(rows_dir.glob("*.json")) and time.monotonic() < deadline:
            assert sweep.is_alive() or out, "the sweep ended before any row was written"
            time.sleep(0.2)
        assert list(rows_dir.glob("*.json")), "no run finished in 600 s"
        done_before_kill = len(list(rows_dir.glob("*.json")))
        cluster.remove_node(workers[0], allow_graceful=False)
        sweep.join(timeout=900)
        assert not sweep.is_alive(), "the sweep did not finish after the node died"
    finally:
        if ray.is_initialized():
            ray.shutdown()
        cluster.shutdown()

    assert out and not isinstance(out[0], BaseException), out
    rows = out[0]
    assert done_before_kill < 6, "every run finished before the node was killed"
    hashes = [r["config_hash"] for r in rows]
    assert sorted(hashes) == sorted(c.config_hash for c in configs)  # none lost, none twice
    assert [r["status"] for r in rows] == ["ok"] * 6, [r.get("error") for r in rows]
    stored = _store.load_runs(tmp_path / "res")
    assert len(stored) == 6 and stored["config_hash"].is_unique
    got, want = _computed(stored), _computed(_store.load_runs(tmp_path / "ref"))
    assert list(got.columns) == list(want.columns)
    numeric = got.select_dtypes("number").columns
    assert len(numeric) > 5
    assert got[numeric].equals(want[numeric]), (got[numeric] - want[numeric]).abs().max()
