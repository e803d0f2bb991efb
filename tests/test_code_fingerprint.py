"""Caches keyed by a configuration's hash (datasets, trained parameters, floors) record the
fingerprint of the code that computed them and are recomputed when that code changed: the
hashes cover the configuration, not the code (a fixed bug in a system or a model must not be
hidden by an entry computed before the fix)."""

import json
import sys

import numpy as np
import pytest

import systems._dataset as _dataset
from bench import execute_run
from bench.core import RunConfig, _params, plan_groups, profile_defaults
from systems._dataset import DatasetConfig, make_dataset, source_fingerprint


def _package(root, files: dict) -> None:
    pkg = root / "fp_probe_pkg"
    pkg.mkdir(exist_ok=True)
    for name, text in files.items():
        (pkg / name).write_text(text)


def test_fingerprint_follows_every_source_file(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(tmp_path))
    _package(tmp_path, {"__init__.py": "", "a.py": "X = 1\n"})

    def fp():
        source_fingerprint.cache_clear()
        sys.modules.pop("fp_probe_pkg", None)
        return source_fingerprint("fp_probe_pkg")

    first = fp()
    assert fp() == first  # deterministic
    _package(tmp_path, {"a.py": "X = 2\n"})
    edited = fp()
    _package(tmp_path, {"a.py": "X = 1\n", "b.py": ""})
    added = fp()
    (tmp_path / "fp_probe_pkg" / "b.py").unlink()
    assert len({first, edited, added}) == 3 and fp() == first
    with pytest.raises(ValueError, match="no importable package 'no_such_pkg_x'"):
        source_fingerprint("no_such_pkg_x")
    source_fingerprint.cache_clear()


def test_a_dataset_generated_by_other_physics_code_is_rebuilt(tmp_path, monkeypatch):
    calls = []
    real = _dataset._simulate

    def counting(*a):
        calls.append(1)
        return real(*a)

    monkeypatch.setattr(_dataset, "_simulate", counting)
    c = DatasetConfig(
        "chain_pendulum", (("k", 1),), n_generated=4, n_train=3, n_test=2, test_chunks=2
    )
    first = make_dataset(c, cache_dir=tmp_path)
    make_dataset(c, cache_dir=tmp_path)
    assert len(calls) == 1  # the same code: loaded
    monkeypatch.setattr(_dataset, "source_fingerprint", lambda *p: "edited systems")
    again = make_dataset(c, cache_dir=tmp_path)
    assert len(calls) == 2  # other code: generated again
    np.testing.assert_array_equal(first.z_test, again.z_test)
    make_dataset(c, cache_dir=tmp_path)
    assert len(calls) == 2  # and cached under the new fingerprint


def test_parameters_and_floor_trained_by_other_code_are_recomputed(tmp_path, monkeypatch):
    base, _ = profile_defaults("smoke")
    config = RunConfig(**dict(base, system="chain_pendulum", k=1, model="node", seed=0))
    a = execute_run(config, cache_root=tmp_path)
    b = execute_run(config, cache_root=tmp_path)
    assert a["status"] == b["status"] == "ok", (a["error"], b["error"])
    assert not a["train_cached"] and b["train_cached"]
    monkeypatch.setattr(_params, "source_fingerprint", lambda *p: "edited models")
    c = execute_run(config, cache_root=tmp_path)
    assert c["status"] == "ok" and not c["train_cached"]
    assert c["rollout_error"] == a["rollout_error"]  # the same code really: the same numbers
    meta = json.loads((tmp_path / "params" / config.train_hash / "train.json").read_text())
    (floor,) = (tmp_path / "floors").iterdir()
    assert meta["code"] == json.loads(floor.read_text())["code"] == "edited models"


def test_ensemble_planning_groups_a_run_whose_cached_training_is_stale(tmp_path, monkeypatch):
    base, _ = profile_defaults("smoke")

    def run(seed):
        return RunConfig(**dict(base, system="chain_pendulum", k=1, model="node", seed=seed))

    def cache(c, code):
        pdir = tmp_path / "params" / c.train_hash
        pdir.mkdir(parents=True)
        (pdir / "model.eqx").write_bytes(b"params")
        meta = {"sha256": _params.sha256_file(pdir / "model.eqx"), "code": code}
        (pdir / "train.json").write_text(json.dumps(meta))

    fresh, stale, new = run(1), run(2), run(3)
    cache(fresh, _params.code_fingerprint())
    cache(stale, "older code")
    groups = [{c.seed for c in g} for g in plan_groups([fresh, stale, new], tmp_path, 8)]
    assert sorted(groups, key=len) == [{1}, {2, 3}]  # the fresh cache loads alone
