"""The packages' layers point one way: systems <- models <- bench, and systems <- collect <-
bench (docs/design.md).

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
ALLOWED = {
    "systems": {"systems"},
    "models": {"models", "systems"},
    "collect": {"collect", "systems"},
    "bench": None,
}
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


@pytest.mark.parametrize("package", ["systems", "models", "collect"])
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


# ----------------------------------------------------------------------------- inside bench
# Layers inside bench: core <- kit <- studies <- the CLI, the report and the package's entry
# points. A module may import its own layer or a lower one, and no import cycle may join bench's
# modules (lazy imports inside functions count: they are cycles all the same).
LAYERS = ("bench.core", "bench.kit", "bench.studies")


def _layer(module: str) -> int:
    for i, layer in enumerate(LAYERS):
        if module == layer or module.startswith(layer + "."):
            return i
    return len(LAYERS)


def _module_name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _module_graph(root: Path = ROOT, package: str = "bench") -> dict[str, set[str]]:
    """Module -> the modules of ``package`` it imports (``from pkg import sub`` names ``sub``
    when it is a module; a parent package that Python imports on the way is not counted)."""
    mods = {_module_name(p, root): p for p in (root / package).rglob("*.py")}
    graph = {}
    for name, path in mods.items():
        pkg = name if path.name == "__init__.py" else name.rpartition(".")[0]
        out = set()
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = pkg.split(".")[: len(pkg.split(".")) - (node.level - 1)]
                    mod = ".".join(base + ([node.module] if node.module else []))
                else:
                    mod = node.module or ""
                subs = [f"{mod}.{a.name}" for a in node.names]
                targets = [s for s in subs if s in mods] or [mod]
            else:
                continue
            out |= {t for t in targets if t in mods and t != name}
        graph[name] = out
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def _upward(graph: dict[str, set[str]]) -> list[str]:
    return [
        f"{a} imports {b}" for a in sorted(graph) for b in sorted(graph[a]) if _layer(b) > _layer(a)
    ]


@pytest.mark.parametrize("package", ["systems", "models", "collect", "bench"])
def test_no_package_has_an_import_cycle(package):
    cycles = _cycles(_module_graph(package=package))
    assert not cycles, cycles


def test_bench_layers_point_one_way():
    graph = _module_graph()
    assert "bench.core._runner" in graph and "bench.studies.decon.energy" in graph
    assert "bench.kit._verdict" in graph
    assert not _upward(graph), "upward imports: " + "; ".join(_upward(graph))


def _top_reaching_studies(graph: dict[str, set[str]]) -> list[str]:
    """The imports of a study by a module above the studies (the CLI, the tables, the report,
    the side-by-side scripts): they reach the studies through the core's registry only."""
    return [
        f"{a} imports {b}"
        for a in sorted(graph)
        if _layer(a) == len(LAYERS)
        for b in sorted(graph[a])
        if _layer(b) == LAYERS.index("bench.studies")
    ]


def test_no_module_above_the_studies_imports_a_study():
    graph = _module_graph()
    assert "bench._cli" in graph and "bench._tables" in graph and "bench._report" in graph
    assert _top_reaching_studies(graph) == []
    graph["bench._cli"] = graph["bench._cli"] | {"bench.studies.decon.energy"}
    assert _top_reaching_studies(graph) == ["bench._cli imports bench.studies.decon.energy"]


def test_graph_checks_can_fail(tmp_path):
    # A synthetic package: core imports a study lazily and the study imports core back.
    (tmp_path / "bench" / "core").mkdir(parents=True)
    (tmp_path / "bench" / "studies").mkdir()
    for d in ("bench", "bench/core", "bench/studies"):
        (tmp_path / d / "__init__.py").write_text("")
    (tmp_path / "bench/core/_a.py").write_text("def f():\n    from ..studies import b\n")
    (tmp_path / "bench/studies/b.py").write_text("from ..core import _a\n")
    graph = _module_graph(tmp_path)
    assert graph["bench.core._a"] == {"bench.studies.b"}
    assert _cycles(graph) == [["bench.core._a", "bench.studies.b"]]
    assert _upward(graph) == ["bench.core._a imports bench.studies.b"]
    assert _cycles({"x": {"y"}, "y": {"z"}, "z": set()}) == []


def _from_imports(path: Path, root: Path = ROOT) -> list[tuple[str, str, int]]:
    """(module, name, line) of every ``from X import name`` of our packages in ``path``, lazy
    ones included, with relative imports resolved."""
    parts = list(path.relative_to(root).with_suffix("").parts)
    pkg = ".".join(parts[:-1])
    out = []
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if not isinstance(node, ast.ImportFrom):
            continue
        if node.level:
            base = pkg.split(".")[: len(pkg.split(".")) - (node.level - 1)]
            mod = ".".join(base + ([node.module] if node.module else []))
        else:
            mod = node.module or ""
        if mod.split(".")[0] in OURS:
            out += [(mod, a.name, node.lineno) for a in node.names]
    return out


def test_every_import_of_ours_resolves():
    # A lazy import of a module that moved fails only when its function runs: find it here.
    import importlib.util

    def is_module(name: str) -> bool:
        try:
            return importlib.util.find_spec(name) is not None
        except ImportError:  # the parent is a module, not a package
            return False

    bad = []
    for package in sorted(OURS):
        for path in sorted((ROOT / package).rglob("*.py")):
            for mod, name, line in _from_imports(path):
                try:
                    m = importlib.import_module(mod)
                except ImportError as e:
                    bad.append(f"{path.relative_to(ROOT)}:{line}: {e}")
                    continue
                if not hasattr(m, name) and not is_module(f"{mod}.{name}"):
                    bad.append(f"{path.relative_to(ROOT)}:{line}: {mod} has no {name}")
    assert not bad, "; ".join(bad)


@pytest.mark.parametrize("package", ["models", "systems"])
def test_the_lower_packages_have_no_import_cycle(package):
    graph = _module_graph(ROOT, package)
    assert f"{package}._registry" in graph or f"{package}._base" in graph, sorted(graph)[:5]
    assert not _cycles(graph), _cycles(graph)


# ----------------------------------------------------------------------------- the studies' house
# The claims kit (bench.kit) is reached through its face: outside it, a module imports the names
# of ``bench.kit.__all__``, never one of its private modules. A study of a claim is a folder
# (bench/studies/<paper>/<study>/) holding its experiments, rule, figure and report section; a
# paper's folder holds its studies' folders alone, and what spans every claim (the campaign, the
# report's sections) stands in bench/studies/paper/.
STUDIES = ROOT / "bench" / "studies"
PAPERS = ("decon", "hnn_seed", "lnn_seed", "vin_seed")


def _folder(module: str) -> str:
    """The folder a module stands in as a room of the house: bench.kit, a study's folder under a
    paper's (or the campaign's or the report's under bench.studies.paper), or the module's own
    package elsewhere."""
    parts = module.split(".")
    if parts[:2] == ["bench", "kit"]:
        return "bench.kit"
    if parts[:2] == ["bench", "studies"] and len(parts) > 3 and parts[2] in (*PAPERS, "paper"):
        return ".".join(parts[:4])
    return module


def _folder_graph(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    out: dict[str, set[str]] = {}
    for a, targets in graph.items():
        out.setdefault(_folder(a), set()).update(
            _folder(b) for b in targets if _folder(b) != _folder(a)
        )
    return out


def test_no_cycle_joins_the_kit_the_studies_and_their_folders():
    folders = _folder_graph(_module_graph())
    assert "bench.kit" in folders and "bench.studies.hnn_seed.pixels" in folders
    assert not _cycles(folders), _cycles(folders)


def test_the_folder_check_sees_a_cycle_between_two_studies():
    graph = {
        "bench.studies.decon.a": {"bench.studies.vin_seed.b._rule"},
        "bench.studies.vin_seed.b._rule": {"bench.studies.decon.a._figure"},
        "bench.studies.decon.a._figure": set(),
    }
    assert _cycles(_folder_graph(graph)) == [["bench.studies.decon.a", "bench.studies.vin_seed.b"]]


def _kit_imports(path: Path, root: Path = ROOT) -> list[tuple[str, str, int]]:
    """The ``from bench.kit... import name`` of ``path``: (module, name, line)."""
    return [
        (mod, name, line)
        for mod, name, line in _from_imports(path, root)
        if mod == "bench.kit" or mod.startswith("bench.kit.")
    ]


def test_the_studies_reach_the_kit_through_its_public_names():
    import bench.kit

    public = set(bench.kit.__all__)
    bad = []
    for path in sorted((ROOT / "bench").rglob("*.py")):
        if path.is_relative_to(ROOT / "bench" / "kit"):
            continue
        for mod, name, line in _kit_imports(path):
            if mod != "bench.kit" or name not in public:
                bad.append(f"{path.relative_to(ROOT)}:{line} imports {name} from {mod}")
    assert not bad, "; ".join(bad)


def test_the_kit_exports_what_it_names():
    import bench.kit

    assert len(set(bench.kit.__all__)) == len(bench.kit.__all__)
    assert [n for n in bench.kit.__all__ if not hasattr(bench.kit, n)] == []
    for name in ("verdict", "evaluate_claims", "judge", "policy", "save_figure", "fmt"):
        assert name in bench.kit.__all__


def test_the_kit_check_sees_a_private_module(tmp_path):
    bad = tmp_path / "bench" / "studies" / "x.py"
    bad.parent.mkdir(parents=True)
    bad.write_text("from ..kit._stats import greater\nfrom ..kit import verdict\n")
    got = _kit_imports(bad, tmp_path)
    assert got == [("bench.kit._stats", "greater", 1), ("bench.kit", "verdict", 2)]


def test_each_study_of_a_claim_is_a_folder():
    from bench.core import _studies

    for paper in PAPERS:
        flat = sorted(p.name for p in (STUDIES / paper).glob("*.py") if p.name != "__init__.py")
        assert flat == [], f"modules beside the study folders of {paper}: {flat}"
    for study in _studies.studies():
        parts = [
            f.__module__
            for f in (study.rule, study.figure, study.results_figure, study.section)
            if f is not None
        ]
        mine = {m for m in parts if m.startswith("bench.studies.") and m.split(".")[2] in PAPERS}
        if not mine:
            continue
        folders = {_folder(m) for m in mine}
        assert len(folders) == 1, (study.name, sorted(mine))
        (folder,) = folders
        assert (ROOT / Path(*folder.split(".")) / "__init__.py").exists(), (study.name, folder)
