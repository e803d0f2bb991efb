"""The code base's house rules, read statically from the source.

- An underscore-named definition is imported only inside its package, and a top-level
  package's private modules only inside it: across them, only what an ``__init__`` exports.
- No source file over :data:`MAX_LINES` lines (tests excepted).
- The code says what it does, not how it got there: no issue numbers, dates or commit ids.
"""

import ast
import pathlib
import re
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
PACKAGES = ("systems", "models", "collect", "bench")
MAX_LINES = 500
HISTORY = re.compile(
    r"\bissues? #?\d+|\bgh-?\d+\b|(?<![\w.])#\d{2,}\b|\b20\d\d-[01]\d-[0-3]\d\b"
    r"|\bcommit [0-9a-f]{7,40}\b"
    r"|(?<![\w.])(?=[0-9a-f]*[a-f])(?=[0-9a-f]*\d)[0-9a-f]{7,40}(?![\w.+-])",
    re.IGNORECASE,
)


def _sources(*roots):
    for root in roots:
        yield from sorted((ROOT / root).rglob("*.py"))


def _package(path):
    return path.relative_to(ROOT).parent.parts


def _crossings(path):
    """Imports in ``path`` of another package's underscore-named definitions, or of another
    top-level package's private modules (inside one top-level package, private modules are
    shared, as in equinox and diffrax)."""
    package = _package(path)
    for node, parts, names in _imports(path):
        private = [i for i, part in enumerate(parts) if _private(part)]
        if private and parts[0] != package[0]:
            yield f"{path.relative_to(ROOT)}:{node.lineno} imports {'.'.join(parts)}"
        owner = tuple(parts[: private[0]]) if private else tuple(parts)
        for name in names:
            if _private(name) and owner != package:
                yield f"{path.relative_to(ROOT)}:{node.lineno} imports {name}"


def _imports(path):
    """(node, the module's parts, the names imported from it) of every import in ``path``,
    relative ones resolved (``import a.b`` imports no names)."""
    package = _package(path)
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node, alias.name.split("."), []
        elif isinstance(node, ast.ImportFrom):
            parts = (node.module or "").split(".") if node.module else []
            if node.level:
                parts = list(package[: len(package) - node.level + 1]) + parts
            yield node, parts, [alias.name for alias in node.names]


def _private(name):
    return name.startswith("_") and not name.startswith("__")


def test_private_parts_stay_inside_their_package():
    found = [c for path in _sources(*PACKAGES) for c in _crossings(path)]
    assert found == []


def test_the_crossing_check_catches_a_private_import(tmp_path, monkeypatch):
    bad = tmp_path / "bench" / "studies" / "x.py"
    bad.parent.mkdir(parents=True)
    bad.write_text(
        "from models._mlp import MLP\nfrom ..core._x import _private\nfrom . import _own\n"
        "from bench.core._x import Public\n"
    )
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    found = list(_crossings(bad))
    assert len(found) == 2 and "models._mlp" in found[0] and "_private" in found[1]


# ----------------------------------------------------------------------------- the core's face
# Outside bench/core/, the core is reached through the names of ``bench.core.__all__``, which
# load their private module on first access. A test may take a private module whole (to patch
# or probe it: ``from bench.core import _runner``), never a name out of it.
CORE = ROOT / "bench" / "core"


def _core_privates(path):
    """Imports in ``path`` of a name out of one of ``bench.core``'s private modules, and, in the
    packages, of such a module whole."""
    whole = _package(path)[0] not in PACKAGES  # tests and examples may take a module whole
    for node, parts, names in _imports(path):
        if parts[:2] != ["bench", "core"]:
            continue
        if len(parts) > 2 and (names or not whole):
            yield f"{path.relative_to(ROOT)}:{node.lineno} imports {'.'.join(parts)}"
        elif len(parts) == 2 and not whole:
            for name in filter(_private, names):
                yield f"{path.relative_to(ROOT)}:{node.lineno} imports {name}"


def _outside_the_core():
    return [p for p in _sources(*PACKAGES, "tests", "examples") if not p.is_relative_to(CORE)]


def test_the_core_is_reached_through_its_names():
    assert [c for path in _outside_the_core() for c in _core_privates(path)] == []


def test_the_core_check_catches_a_private_module(tmp_path, monkeypatch):
    study, test = tmp_path / "bench" / "studies" / "x.py", tmp_path / "tests" / "test_x.py"
    for path in (study, test):
        path.parent.mkdir(parents=True)
    study.write_text(
        "from ..core._config import RunConfig\nfrom ..core import _store, expand\n"
        "def f():\n    import bench.core._runner\n    from ..core import sweep\n"
    )
    test.write_text(
        "from bench.core._config import RunConfig\nfrom bench.core import _store, expand\n"
        "import bench.core._runner as runner\n"
    )
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    imported = [c.split(" imports ")[1] for c in _core_privates(study)]
    assert imported == ["bench.core._config", "_store", "bench.core._runner"]
    assert [c.split(" imports ")[1] for c in _core_privates(test)] == ["bench.core._config"]


def _unresolved(core):
    """The names of ``core.__all__`` that do not resolve."""
    return [name for name in core.__all__ if not hasattr(core, name)]


def test_the_core_exports_what_it_names(monkeypatch):
    import bench.core

    assert len(set(bench.core.__all__)) == len(bench.core.__all__)
    assert _unresolved(bench.core) == []
    assert set(bench.core.__all__) <= set(dir(bench.core))
    monkeypatch.setitem(bench.core._WHERE, "no_such_name", ("_config", "no_such_name"))
    monkeypatch.setattr(bench.core, "__all__", [*bench.core.__all__, "no_such_name"])
    assert _unresolved(bench.core) == ["no_such_name"]


def test_every_name_the_core_exports_is_imported_outside_it():
    import bench.core

    imported = {
        name
        for path in _outside_the_core()
        for _, parts, names in _imports(path)
        if parts == ["bench", "core"]
        for name in names
    }
    assert sorted(set(bench.core.__all__) - imported) == []


def test_importing_bench_loads_no_study_until_the_registry_is_used():
    code = (
        "import sys; import bench; "
        "studies = lambda: [m for m in sys.modules if m.startswith('bench.studies')]; "
        "assert not studies(), studies(); "
        "names = [s.name for s in bench.registered_studies()]; "
        "assert 'bench.studies.paper' in sys.modules and 'energy' in names, names"
    )
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)


def test_importing_the_core_imports_none_of_its_modules():
    # ``import bench`` loads the core's names it re-exports, and with them jax: a bare parent
    # package leaves ``bench.core``'s own import alone.
    code = (
        "import sys, types; "
        "bench = sys.modules['bench'] = types.ModuleType('bench'); bench.__path__ = ['bench']; "
        "import bench.core; "
        "loaded = [m for m in sys.modules if m.startswith('bench.core.') or m == 'jax']; "
        "assert not loaded, loaded; "
        "bench.core.PROFILES; "
        "assert 'bench.core._experiments' in sys.modules"
    )
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)


@pytest.mark.parametrize("path", list(_sources(*PACKAGES)), ids=lambda p: str(p.relative_to(ROOT)))
def test_no_source_file_is_long(path):
    assert len(path.read_text().splitlines()) <= MAX_LINES


def test_no_history_in_the_code():
    found = [
        f"{path.relative_to(ROOT)}:{i}: {match.group(0)}"
        for path in _sources(*PACKAGES, "tests")
        for i, line in enumerate(path.read_text().splitlines(), 1)
        for match in [HISTORY.search(line)]
        if match
    ]
    assert found == []


@pytest.mark.parametrize(
    "line, history",
    [
        (" ".join(["# see", "issue", "12"]), True),  # joined: this file must not match itself
        ("# fixed in #" + "123", True),
        ("measured on " + "-".join(["2031", "01", "09"]), True),
        (" ".join(["as of", "commit", "0a1b" + "2c3"]), True),
        ("the row came from " + "9f8e7d" + "6c5", True),
        ("GYRO = (2.4137838e-3, 1.0906e02)", False),
        ("sha = 'ffff'", False),
        ("tol = 1e-13  # ten seeds", False),
    ],
)
def test_the_history_check_reads_lines_as_meant(line, history):
    assert bool(HISTORY.search(line)) is history


def test_every_data_file_of_the_packages_ships_with_them():
    # A file that a package reads at import (not a .py) must be named in pyproject.toml's
    # package-data, or a wheel and a non-editable install go without it.
    import fnmatch
    import tomllib

    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    shipped = config["tool"]["setuptools"].get("package-data", {})
    missing = []
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*")):
            if not path.is_file() or path.suffix in (".py", ".pyc") or "__pycache__" in path.parts:
                continue
            owner = ".".join(path.parent.relative_to(ROOT).parts)
            if not any(fnmatch.fnmatch(path.name, p) for p in shipped.get(owner, ())):
                missing.append(str(path.relative_to(ROOT)))
    assert missing == []


def test_each_study_of_a_claim_lives_in_its_papers_folder():
    """The claims' studies are folders by paper (``bench/studies/<paper>/<study>/``): every
    registered study of a claim is inside one, every folder there holds a study, and nothing sits
    loose beside them; ``bench/studies/paper/`` holds what spans every claim, the campaign's and
    the report's operations, and no study."""
    import inspect

    import bench  # noqa: F401 (registers the studies)
    from bench.core import studies

    root = ROOT / "bench" / "studies"
    papers = ("decon", "hnn_seed", "lnn_seed", "vin_seed")
    used = set()
    for s in studies():
        code = s.rule or s.figure or s.section
        module = inspect.getmodule(code).__name__.split(".")
        assert module[:3] != ["bench", "studies", "paper"], f"study {s.name} in studies/paper"
        if module[:2] != ["bench", "studies"] or module[2] not in papers:
            assert s.claim is None, f"claim {s.claim}'s study {s.name} outside the papers' folders"
            continue
        assert len(module) >= 4, f"study {s.name} sits loose in bench/studies/{module[2]}"
        used.add((module[2], module[3]))
    folders = {
        (paper, p.name)
        for paper in papers
        for p in (root / paper).iterdir()
        if p.is_dir() and (p / "__init__.py").exists()
    }
    assert folders == used
    assert {p.name for paper in papers for p in (root / paper).glob("*.py")} == {"__init__.py"}
    spans = {p.name for p in (root / "paper").iterdir() if p.name != "__pycache__"}
    assert spans == {"__init__.py", "campaign", "report"}


def test_the_studies_index_names_every_study_folder_and_its_pages_exist():
    """docs/studies/README.md maps each claim to its study's folder and page: every folder of
    the papers' studies is named once, every folder it names exists, every page it links too."""
    root = ROOT / "bench" / "studies"
    index = ROOT / "docs" / "studies" / "README.md"
    text = index.read_text()
    folders = {
        f"bench/studies/{paper}/{p.name}/"
        for paper in ("decon", "hnn_seed", "lnn_seed", "vin_seed")
        for p in (root / paper).iterdir()
        if (p / "__init__.py").exists()
    }
    named = re.findall(r"`(bench/studies/[a-z_]+/[a-z_]+/)`", text)
    named = [n for n in named if not n.startswith("bench/studies/paper/")]
    assert sorted(named) == sorted(folders)
    for link in re.findall(r"\]\(([^)#]+)\)", text):
        assert (index.parent / link).exists(), link
