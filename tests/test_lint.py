"""The code is linted and formatted as `make lint` checks, so that CI (which runs `make test`)
fails on a lint error."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("systems", "models", "collect", "bench", "tests", "examples")


@pytest.mark.skipif(importlib.util.find_spec("ruff") is None, reason="ruff is not installed")
@pytest.mark.parametrize("command", [("check",), ("format", "--check")], ids=["check", "format"])
def test_ruff(command):
    out = subprocess.run(
        [sys.executable, "-m", "ruff", *command, *PACKAGES],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-1000:]


def _reimports(tree) -> list[tuple[int, str]]:
    """(line, name) of each import inside a function of a name the module imports at its top."""
    import ast

    top = set()
    for n in tree.body:
        if isinstance(n, ast.ImportFrom):
            top |= {("." * n.level + (n.module or ""), a.name, a.asname) for a in n.names}
        elif isinstance(n, ast.Import):
            top |= {(a.name, None, a.asname) for a in n.names}
    out = []
    for f in ast.walk(tree):
        if not isinstance(f, ast.FunctionDef | ast.AsyncFunctionDef):
            continue
        for n in ast.walk(f):
            if isinstance(n, ast.ImportFrom):
                mod = "." * n.level + (n.module or "")
                out += [(n.lineno, a.name) for a in n.names if (mod, a.name, a.asname) in top]
            elif isinstance(n, ast.Import):
                out += [(n.lineno, a.name) for a in n.names if (a.name, None, a.asname) in top]
    return out


def test_no_function_imports_again_what_its_module_imported():
    import ast

    bad = []
    for folder in ("systems", "models", "collect", "bench", "tests", "examples"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            tree = ast.parse(path.read_text(), filename=str(path))
            bad += [f"{path.relative_to(ROOT)}:{line} {name}" for line, name in _reimports(tree)]
    assert bad == []


def test_the_reimport_check_sees_one():
    import ast

    src = "import json\nfrom a import b\n\ndef f():\n    import json\n    from a import b, c\n"
    assert _reimports(ast.parse(src)) == [(5, "json"), (6, "b")]
