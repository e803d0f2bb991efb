"""Plug-in models: a model from outside the repository becomes a first-class name.

The throwaway plug-in is installed the way pip leaves a package: its module and a
``.dist-info`` folder with ``entry_points.txt`` in a directory on the path (written by hand
here, so the test needs no build backend and no network); the sweep runs in a subprocess that
sees it only through that entry point."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

import models

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "decon_bench_example_model" / "decon_bench_example_model"


def _install(site: Path, module: str, name: str, entry_point: bool = True) -> Path:
    """The example model as package ``module`` registering ``name``, installed in ``site``."""
    src = (EXAMPLE / "__init__.py").read_text().replace('"drag_so"', f'"{name}"')
    (site / module).mkdir(parents=True)
    (site / module / "__init__.py").write_text(src)
    if entry_point:
        info = site / f"{module}-0.1.dist-info"
        info.mkdir()
        (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {module}\nVersion: 0.1\n")
        (info / "entry_points.txt").write_text(f"[decon_bench.models]\n{name} = {module}\n")
    return site


def _bench(args, site: Path, tmp_path: Path, timeout=300):
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(site), str(ROOT)])
    env["DECON_CACHE"] = str(tmp_path / "cache")
    env.pop("DECON_MODEL_MODULES", None)
    return subprocess.run(
        [sys.executable, "-m", "bench", *args],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


@pytest.mark.slow  # a training sweep and a report in subprocesses
def test_an_installed_plugin_trains_beside_the_builtins_and_is_reported(tmp_path):
    site = _install(tmp_path / "site", "throwaway_plugin", "throwaway_so")
    res = tmp_path / "res"
    p = _bench(
        [
            "--results",
            str(res),
            "sweep",
            "second_order",
            "--profile",
            "smoke",
            "--models",
            "throwaway_so",
            "--no-progress",
        ],
        site,
        tmp_path,
    )
    assert p.returncode == 0, p.stderr[-2000:]
    runs = pd.read_parquet(res / "runs.parquet")
    mine = runs[runs["model"] == "throwaway_so"]
    assert len(mine) >= 2 and (mine["status"] == "ok").all()
    # beside the built-ins: the experiment's trivial predictor stays, scored on the same data
    assert set(runs["model"]) == {"throwaway_so", "constant_velocity"}
    p = _bench(["--results", str(res), "report"], site, tmp_path)
    assert p.returncode == 0, p.stderr[-2000:]
    assert "throwaway_so" in (res / "REPORT.md").read_text()


@pytest.mark.slow  # three subprocesses of the CLI
def test_model_module_option_loads_a_module_without_an_entry_point(tmp_path):
    site = _install(tmp_path / "site", "loose_plugin", "loose_so", entry_point=False)
    assert "loose_so" not in _bench(["list"], site, tmp_path).stdout
    p = _bench(["--model-module", "loose_plugin", "list"], site, tmp_path)
    assert p.returncode == 0 and "loose_so" in p.stdout, p.stderr
    p = _bench(["--model-module", "no_such_plugin", "list"], site, tmp_path)
    assert p.returncode == 2
    err = p.stderr.strip()
    assert err.startswith("error: model plug-in 'no_such_plugin'") and "\n" not in err


def _example_class():
    import importlib.util

    spec = importlib.util.spec_from_file_location("_example_plugin", EXAMPLE / "__init__.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # dataclasses (equinox) look the module up while defining
    spec.loader.exec_module(mod)  # registers drag_so
    return mod.DragSecondOrderODE


def test_a_registered_plugin_is_read_like_a_builtin(clean_registry):
    cls = _example_class()
    s = models.spec("drag_so")
    assert s.continuous and s.second_order and s.structure is None and not s.trivial
    assert s.coordinates == ("velocity",)
    scene = models.Scene(dof=2, angular=(True, True))
    m = models.make("drag_so", scene, key=__import__("jax").random.PRNGKey(0), width=8)
    assert isinstance(m, cls) and m.vector_field(0.0, __import__("numpy").zeros(4), None).shape == (
        4,
    )


@pytest.mark.parametrize(
    ("make_cls", "kw", "message"),
    [
        (lambda c: object, {}, "must subclass models.AbstractContinuousModel"),
        (
            lambda c: type("NoField", (models.AbstractContinuousModel,), {"__annotations__": {}}),
            {},
            "does not implement vector_field",
        ),
        (lambda c: type("Odd", (c,), {"structure": "symplectic"}), {}, "structure must be"),
        (lambda c: c, {"coordinates": "polar"}, "coordinates must be"),
        (lambda c: c, {"build": lambda scene: None}, "must accept (scene, width"),
        (lambda c: c, {"options": {"weight": 1.0}}, "validator callables"),
    ],
)
def test_a_plugin_breaking_the_contract_gets_one_line(clean_registry, make_cls, kw, message):
    cls = _example_class()
    with pytest.raises(ValueError, match="model plug-in 'broken'") as e:
        models.register("broken", make_cls(cls), **kw)
    assert message in str(e.value) and "\n" not in str(e.value)
    assert "broken" not in models.available()


def test_builtin_names_cannot_be_taken(clean_registry):
    cls = _example_class()
    with pytest.raises(ValueError, match="built-in model"):
        models.register("node_so", cls)


def test_a_registered_plugin_is_swept_beside_the_trivial_predictor(
    clean_registry, tmp_path, monkeypatch
):
    """In-process, through the CLI, the runs faked: the plug-in's name replaces the trained
    models and the experiment's trivial predictor stays."""
    import bench.core._runner as runner
    from bench._cli import main
    from bench.core import base_row

    _example_class()
    monkeypatch.setattr(runner, "execute_run", lambda c, **kw: {**base_row(c), "status": "ok"})
    argv = ["sweep", "second_order", "--profile", "smoke", "--models", "drag_so", "--no-progress"]
    assert main(["--results", str(tmp_path), *argv]) == 0
    runs = pd.read_parquet(tmp_path / "runs.parquet")
    assert set(runs["model"]) == {"drag_so", "constant_velocity"}


def test_expansions_follow_a_model_registered_again_as_first_order(clean_registry):
    """:func:`expand` builds an experiment's configurations once per process; what it reads
    from the model registry (whether a model is second order, which decides its leapfrog runs)
    is asked again at every call. (An ``include`` that asks whether a data file is there:
    tests/test_real_pendulum.py, tests/test_mujoco_study.py.)"""
    from bench.core import Experiment, expand

    cls = _example_class()  # registers drag_so, second order
    exp = Experiment(
        name="memo_probe",
        title="t",
        axes={"model": ["drag_so", "node"], "eval_integrator": ["rk4", "leapfrog"]},
        fixed={"system": "chain_pendulum", "k": 1},
    )
    first = expand(exp, "smoke")
    assert {(r.model, r.eval_integrator) for r in first} >= {("drag_so", "leapfrog")}
    again = expand(exp, "smoke")
    assert again == first and again is not first  # a fresh list: callers may change it
    again.clear()
    assert expand(exp, "smoke") == first
    models.register("drag_so", type("FirstOrder", (cls,), {"second_order": False}))
    assert not models.spec("drag_so").second_order
    combos = {(r.model, r.eval_integrator) for r in expand(exp, "smoke")}
    assert ("drag_so", "rk4") in combos and ("drag_so", "leapfrog") not in combos


@pytest.mark.slow  # starts a local Ray instance and trains one smoke run (~1 min on 2 cores)
@pytest.mark.ray
def test_a_model_module_plugin_trains_on_ray_workers(clean_registry, tmp_path, monkeypatch):
    """A plug-in that only the driver imported (``--model-module``, from a folder that only
    the driver has on its path) is built on the Ray workers, which import nothing of it."""
    pytest.importorskip("ray")
    from bench.core import _runner as runner
    from bench.core import _store, expand

    site = _install(tmp_path / "site", "ray_only_plugin", "ray_only_so", entry_point=False)
    monkeypatch.syspath_prepend(str(site))  # this process only: not in $PYTHONPATH
    monkeypatch.delenv(models.MODULES_ENV, raising=False)
    models.load_plugins("ray_only_plugin")
    configs = [c for c in expand("second_order", "smoke", models=["ray_only_so"])]
    configs = [c for c in configs if c.model == "ray_only_so"][:1]
    rows = runner.sweep(
        configs,
        tmp_path / "res",
        experiment="ray_plugin",
        profile="smoke",
        executor="ray",
        progress=False,
        cache_root=tmp_path / "cache",
    )
    assert [r["status"] for r in rows] == ["ok"], [r.get("error") for r in rows]
    assert _store.load_runs(tmp_path / "res")["model"].tolist() == ["ray_only_so"]


def test_plugin_modules_name_what_a_worker_must_load(clean_registry, tmp_path, monkeypatch):
    """The modules of the plug-ins a sweep uses, with their folders, load in a process that
    has neither on its path (a Ray task's ``_load_plugins``)."""
    from bench.core import _runner as runner

    site = _install(tmp_path / "site", "worker_plugin", "worker_so", entry_point=False)
    monkeypatch.setattr(sys, "path", list(sys.path))  # _load_plugins appends the folder
    monkeypatch.delenv(models.MODULES_ENV, raising=False)
    runner._load_plugins({"worker_plugin": [str(site)]})
    assert "worker_so" in models.available() and str(site) in sys.path
    assert models.plugin_modules({"worker_so"}) == {"worker_plugin": [str(site)]}
    assert models.plugin_modules({"node"}) == {"worker_plugin": [str(site)]}  # loaded by name
    _example_class()  # a package loaded from its file: the folder holding the package
    assert models.plugin_modules({"drag_so"})["_example_plugin"] == [str(EXAMPLE.parent)]
