"""A plug-in model's source is part of what its trained parameters and stored rows depend on:
the parameter cache keys a plug-in's training by the fingerprint of its source, a row records
it, and a sweep reruns (and replaces) the row of a run whose plug-in was edited since. The
built-in models' hashes and cache keys stay what the committed rows were stored under."""

from __future__ import annotations

import importlib
import json
import sys
from pathlib import Path

import pytest

import models
from bench.core import (
    RunConfig,
    base_row,
    cache_key,
    params_dir,
    profile_defaults,
    read_rows,
    sweep,
)
from models import _registry as registry

ROOT = Path(__file__).resolve().parents[1]
MODULE = "tiny_source_plugin"  # the plug-in written by the tests, registering NAME
NAME = "tiny_free"

PLUGIN = '''"""A free first-order field dz/dt = MLP(z) whose activation is {activation}."""

import equinox as eqx
import jax
import jax.numpy as jnp

import models


class TinyFree(models.AbstractContinuousModel):
    scene: models.Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    net: eqx.nn.MLP

    def __init__(self, scene, width, depth, activation, dtype, *, key):
        self.scene, self.dtype = scene, dtype
        n = 2 * scene.dof
        self.net = eqx.nn.MLP(
            n, n, width, depth, activation={activation}, key=key, dtype=jnp.dtype(dtype)
        )

    def vector_field(self, t, z, args):
        return self.net(jnp.asarray(z, self.dtype))


models.register("{name}", TinyFree)
'''


@pytest.fixture
def plugin(tmp_path, monkeypatch):
    """``write(activation)``: (re)write the plug-in's file and import it again, as a new
    process would; the registry is restored afterwards."""
    site = tmp_path / "site"
    site.mkdir()
    monkeypatch.syspath_prepend(str(site))
    before, sources = dict(registry._REGISTRY), dict(registry._SOURCES)

    def write(activation: str) -> str:
        (site / f"{MODULE}.py").write_text(PLUGIN.format(activation=activation, name=NAME))
        importlib.invalidate_caches()
        sys.modules.pop(MODULE, None)
        importlib.import_module(MODULE)
        return models.plugin_fingerprint(NAME)

    yield write
    sys.modules.pop(MODULE, None)
    registry._REGISTRY.clear()
    registry._REGISTRY.update(before)
    registry._SOURCES.clear()
    registry._SOURCES.update(sources)
    models.spec.cache_clear()


def _config(model: str) -> RunConfig:
    base, _ = profile_defaults("smoke")
    return RunConfig(**dict(base, system="chain_pendulum", k=1, model=model, seed=0))


def test_builtin_runs_keep_their_stored_hashes_and_cache_keys():
    """One committed row of each built-in model: its configuration hashes as it was stored,
    its parameters are cached under its train_hash and its row gains no plug-in column."""
    rows = {}
    for path in sorted((ROOT / "results" / "reference" / "quick" / ".rows").glob("*.json")):
        row = json.loads(path.read_text())
        rows.setdefault(row["model"], row)
    assert len(rows) >= 5, "the committed quick rows are missing"
    fields = {f for f in RunConfig.__dataclass_fields__}
    for model, row in rows.items():
        config = RunConfig.from_dict({a: b for a, b in row.items() if a in fields})
        assert config.config_hash == row["config_hash"], model
        assert cache_key(config) == config.train_hash == row["train_hash"], model
        assert models.plugin_fingerprint(model) is None
        assert "plugin_source" not in base_row(config)


def test_a_plugins_fingerprint_follows_its_source(plugin):
    silu = plugin("jax.nn.silu")
    assert plugin("jax.nn.silu") == silu  # the same source: the same fingerprint
    tanh = plugin("jnp.tanh")
    assert len({silu, tanh}) == 2 and None not in (silu, tanh)
    config = _config(NAME)
    assert cache_key(config) == f"{config.train_hash}-{tanh}"
    assert base_row(config)["plugin_source"] == tanh
    plugin("jax.nn.silu")
    assert cache_key(config) == f"{config.train_hash}-{silu}"


def test_an_edited_plugin_trains_again_and_replaces_its_row(plugin, tmp_path, capsys):
    cache, results = tmp_path / "cache", tmp_path / "results"
    config = _config(NAME)

    def run(folder) -> list[dict]:
        return sweep([config], folder, progress=False, cache_root=cache, ensemble="off")

    silu = plugin("jax.nn.silu")
    (first,) = run(results)
    assert first["status"] == "ok" and not first["train_cached"], first["error"]
    assert first["plugin_source"] == silu
    assert run(results) == []  # unchanged source: the stored row stands
    (elsewhere,) = run(tmp_path / "elsewhere")
    assert elsewhere["train_cached"]  # and its parameters are reused
    assert elsewhere["rollout_error"] == first["rollout_error"]
    assert "plug-in" not in capsys.readouterr().err

    tanh = plugin("jnp.tanh")
    (second,) = run(results)  # the same results folder, the edited plug-in
    assert not second["train_cached"] and second["plugin_source"] == tanh
    assert second["rollout_error"] != first["rollout_error"]
    assert f"plug-in model(s) {NAME}" in capsys.readouterr().err
    (stored,) = read_rows(results)  # replaced, not added
    assert stored["plugin_source"] == tanh
    assert stored["rollout_error"] == second["rollout_error"]
    for source in (silu, tanh):  # each source's parameters under their own key
        assert (params_dir(cache, f"{config.train_hash}-{source}") / "model.eqx").is_file()
