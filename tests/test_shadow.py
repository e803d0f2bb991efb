"""A ``models.py`` or ``systems.py`` in the folder ``python -m bench`` starts in hides the
suite's package of that name: the entry point says so in one line (what shadows what, what to
do) instead of failing on a bare ImportError, and the console script it recommends works there."""

from __future__ import annotations

import os
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from bench import _shadow

ROOT = Path(__file__).resolve().parents[1]


def _env() -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT)  # the suite importable however it is installed
    return env


@pytest.mark.parametrize("name", ["models", "systems"])
def test_python_m_bench_names_the_file_that_shadows_a_package(tmp_path, name):
    (tmp_path / f"{name}.py").write_text("# a researcher's own module\n")
    p = subprocess.run(
        [sys.executable, "-m", "bench", "list"],
        cwd=tmp_path,
        env=_env(),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert p.returncode == 2 and p.stdout == "", p.stderr
    err = p.stderr
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert err.startswith(f"error: {tmp_path.resolve() / f'{name}.py'} shadows the suite's")
    assert f"package {name!r} ({ROOT / name})" in err
    assert "run from another folder" in err and "decon-bench" in err


def test_shadowing_is_found_without_importing_and_not_for_the_suite(tmp_path, monkeypatch):
    assert _shadow.shadowing() is None  # the suite's own packages
    (tmp_path / "systems.py").write_text("")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "systems")  # as in a fresh process (restored after)
    message = _shadow.shadowing()
    assert message is not None and "systems.py shadows the suite's package 'systems'" in message
    assert "systems" not in sys.modules  # found, not imported
    monkeypatch.setattr(sys, "argv", ["python"])
    with pytest.raises(ImportError, match="shadows the suite's package 'systems'"):
        _shadow.check()  # a plain import of the suite: the same line as an ImportError


def test_the_console_script_runs_where_python_m_bench_is_shadowed(tmp_path):
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    assert scripts[_shadow.CONSOLE_SCRIPT] == "bench._cli:main"
    work, bin_dir = tmp_path / "work", tmp_path / "bin"
    work.mkdir()
    bin_dir.mkdir()
    (work / "models.py").write_text("")
    script = bin_dir / _shadow.CONSOLE_SCRIPT  # what pip writes for [project.scripts]
    script.write_text("import sys\nfrom bench._cli import main\nsys.exit(main())\n")
    p = subprocess.run(
        [sys.executable, str(script), "list"],
        cwd=work,
        env=_env(),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert p.returncode == 0, p.stderr[-2000:]
    assert "models:" in p.stdout and "node_so" in p.stdout
