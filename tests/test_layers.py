"""The packages' layers point one way: systems <- models <- bench (ARCHITECTURE.md).

Checked two ways: statically, over every ``import`` statement of the packages' source (so a
lazy import inside a function counts too), and dynamically, by importing ``models`` in a fresh
interpreter and looking at what it loaded.
"""

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
# A package may import only the packages listed for it (besides third-party ones).
ALLOWED = {"systems": {"systems"}, "models": {"models", "systems"}, "bench": None}
OURS = set(ALLOWED)


def _imports(path: Path, package: str) -> list[tuple[str, int]]:
    """Top-level package names of our own that ``path`` imports, with line numbers."""
    tree = ast.parse(path.read_text(), filename=str(path))
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(a.name.split(".")[0], node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            name = package if node.level else (node.module or "").split(".")[0]
            out.append((name, node.lineno))
    return [(n, line) for n, line in out if n in OURS]


def _import_graph() -> dict[str, list[tuple[str, int]]]:
    graph = {}
    for package in OURS:
        for path in sorted((ROOT / package).rglob("*.py")):
            graph[str(path.relative_to(ROOT))] = _imports(path, package)
    return graph


@pytest.mark.parametrize("package", ["systems", "models"])
def test_no_upward_imports(package):
    bad = [
        f"{path}:{line} imports {name}"
        for path, names in _import_graph().items()
        if path.startswith(package + "/")
        for name, line in names
        if name not in ALLOWED[package]
    ]
    assert not bad, "upward imports: " + "; ".join(bad)


def test_checker_sees_an_upward_import(tmp_path):
    # The static check must be able to fail: a module that imports bench is caught.
    p = tmp_path / "m.py"
    p.write_text("import numpy\ndef f():\n    from bench.core._env import cpu_count\n")
    assert _imports(p, "models") == [("bench", 3)]


def test_import_models_loads_no_bench():
    code = (
        "import models, sys; "
        "bad = [m for m in sys.modules if m == 'bench' or m.startswith('bench.')]; "
        "assert not bad, bad"
    )
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)
