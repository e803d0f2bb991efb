"""Provenance: every row and bench_meta.json record the versions, device and commit.

The values are checked against independent routes (the modules' own ``__version__``, JAX's
backend, ``git``); old rows without provenance still load; the report table and the
comparison of two results folders say what they cannot know instead of guessing.
"""

import json
import platform
import re
import subprocess
from pathlib import Path

import jax
import jaxlib
import numpy as np
import pandas as pd
import pytest
from _markdown import table_rows

from bench.core import _provenance as P
from bench.core import _store

ROOT = Path(__file__).resolve().parents[1]


def test_provenance_matches_the_running_environment():
    import diffrax
    import equinox
    import optax
    import optimistix

    prov = P.provenance()
    assert tuple(prov) == P.PROVENANCE_COLUMNS
    assert prov["python_version"] == platform.python_version()
    for module in (jax, equinox, diffrax, optax, optimistix, np):
        assert prov[f"{module.__name__}_version"] == module.__version__
    assert prov["jaxlib_version"] == jaxlib.__version__
    assert prov["backend"] == jax.default_backend()
    assert prov["device"] and prov["device"] != P.UNKNOWN
    assert P.provenance() is prov  # computed once per process
    # the cores of this process's affinity mask (an independent route: os, not _env)
    import os

    assert prov["cpu_cores"] == str(len(os.sched_getaffinity(0)))


def test_git_commit_is_this_checkout():
    head = subprocess.run(
        ["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True, text=True
    )
    prov = P.provenance()
    if head.returncode != 0:  # an exported tree, not a clone
        assert prov["git_commit"] == P.UNKNOWN and prov["git_dirty"] is None
        return
    assert prov["git_commit"] == head.stdout.strip()
    assert re.fullmatch(r"[0-9a-f]{40}", prov["git_commit"])
    assert isinstance(prov["git_dirty"], bool)


def test_dirty_means_changes_outside_results(tmp_path, monkeypatch):
    def git(*args):
        subprocess.run(["git", "-C", str(tmp_path), "-c", "user.name=t", "-c", "user.email=t@t",
                        *args], check=True, capture_output=True)  # fmt: skip

    git("init", "-q")
    (tmp_path / "code.py").write_text("x = 1\n")
    git("add", "code.py")
    git("commit", "-qm", "c")
    monkeypatch.setattr(P, "_REPO", tmp_path.resolve())
    commit, dirty = P._git_state()
    assert re.fullmatch(r"[0-9a-f]{40}", commit) and dirty is False
    (tmp_path / "results").mkdir()
    (tmp_path / "results" / "row.json").write_text("{}")  # a sweep writing its rows
    assert P._git_state() == (commit, False)
    (tmp_path / "code.py").write_text("x = 2\n")
    assert P._git_state() == (commit, True)
    # A package folder that is not the top of the work tree has no history of its own here.
    monkeypatch.setattr(P, "_REPO", (tmp_path / "results").resolve())
    assert P._git_state() == (P.UNKNOWN, None)


def _row(h, profile="quick", **prov):
    return {"config_hash": h, "experiment": "e", "system": "s", "model": "m", "seed": 0,
            "profile": profile, "status": "ok", "rollout_error": 0.1, **prov}  # fmt: skip


def test_old_and_new_rows_load_together(tmp_path):
    _store.write_row(tmp_path, _row("old"))
    _store.write_row(tmp_path, _row("new", **P.provenance()))
    _store.rebuild_tables(tmp_path)
    for df in (_store.load_runs(tmp_path), pd.read_parquet(tmp_path / "runs.parquet")):
        assert len(df) == 2
        new, old = (df[df["config_hash"] == h].iloc[0] for h in ("new", "old"))
        assert new["jax_version"] == jax.__version__
        assert pd.isna(old["jax_version"]) and pd.isna(old["git_commit"])
    table = _fields(P.provenance_markdown(_store.load_runs(tmp_path)))
    assert table["jax_version"]["profile `quick`"] == f"{jax.__version__} (1), not recorded (1)"


def _fields(md):
    """The provenance table, per field."""
    return {r["field"]: r for r in table_rows(md, "| field |")}


def test_markdown_is_one_column_per_profile():
    prov = dict(P.provenance(), jax_version="0.10.2", git_commit="a" * 40, git_dirty=False)
    df = pd.DataFrame(
        [_row("1", "quick", **prov), _row("2", "quick", **prov)]
        + [_row("3", "paper", **dict(prov, jax_version="0.11.2", backend="gpu"))]
    )
    table = _fields(P.provenance_markdown(df))
    assert list(table["runs"]) == ["field", "profile `paper`", "profile `quick`"]
    got = {f: (table[f]["profile `paper`"], table[f]["profile `quick`"]) for f in table}
    assert got["runs"] == ("1", "2")
    assert got["jax_version"] == ("0.11.2", "0.10.2")
    assert got["git_commit"] == ("aaaaaaaaaa", "aaaaaaaaaa")
    assert got["git_dirty"] == ("clean", "clean")
    assert P.provenance_markdown(pd.DataFrame()) == "No runs."


def test_compare_warns_on_versions_and_on_what_is_not_recorded():
    prov = dict(P.provenance(), git_commit="a" * 40)
    a = pd.DataFrame([_row("1", **prov)])
    assert P.compare_provenance(a, a.copy()) == []
    b = pd.DataFrame([_row("1", **dict(prov, jax_version="0.11.2", backend="gpu"))])
    warnings = P.compare_provenance(a, b, names=("cpu", "gpu"))
    assert len(warnings) == 2
    said = [_warning(w) for w in warnings]
    assert ("differs", "jax_version", jax.__version__, "cpu", "0.11.2", "gpu") in said
    old = pd.DataFrame([_row("1")])
    warnings = P.compare_provenance(a, old, names=("new", "old"))
    assert len(warnings) == len(P.PROVENANCE_COLUMNS) - 1
    said = [_warning(w) for w in warnings]
    assert ("not recorded", "jax_version", "1", "old", "new", jax.__version__) in said
    unknown = pd.DataFrame([_row("1", **dict(prov, numpy_version=P.UNKNOWN))])
    warnings = P.compare_provenance(a, unknown)
    assert [_warning(w) for w in warnings] == [
        ("not recorded", "numpy_version", "1", "b", "a", np.__version__)
    ]


def test_a_folder_filled_over_many_commits_lists_the_commonest_and_counts_the_rest():
    prov = P.provenance()
    commits = [f"{i:02d}" * 20 for i in range(P.MAX_LISTED + 4)]
    df = pd.DataFrame(
        [_row(str(i), "paper", **dict(prov, git_commit=c)) for i, c in enumerate(commits)]
        + [_row("x", "paper", **dict(prov, git_commit=commits[0]))]
    )
    cell = _fields(P.provenance_markdown(df))["git_commit"]["profile `paper`"]
    assert cell.startswith("0000000000 (2)") and cell.endswith("4 more (4)")
    one = pd.DataFrame([_row("1", **dict(prov, git_commit=commits[0]))])
    (w,) = [w for w in P.compare_provenance(df, one) if w.startswith("git_commit")]
    assert f"{len(commits)} values (0000000000, 0101010101, 0202020202, ...) (a)" in w
    assert w.endswith("vs 0000000000 (b)")


def _warning(w):
    """A provenance warning read back: ("differs", field, value, folder, value, folder) or
    ("not recorded", field, runs, folder, other folder, its value)."""
    m = re.fullmatch(r"(\w+) differs: (.+) \((.+)\) vs (.+) \((.+)\)", w)
    if m:
        return ("differs", *m.groups())
    m = re.fullmatch(r"(\w+) not recorded for (\d+) runs of (\S+) \((\S+): (.+)\)", w)
    return ("not recorded", *m.groups())


def test_backfill_records_what_is_known_and_the_rest_as_unknown(tmp_path):
    _store.write_row(tmp_path, _row("old"))
    _store.write_row(tmp_path, _row("new", **P.provenance()))
    assert P.backfill(tmp_path, {"jax_version": "0.11.2", "backend": "gpu"}) == 1
    rows = {r["config_hash"]: r for r in _store.read_rows(tmp_path)}
    assert rows["old"]["jax_version"] == "0.11.2" and rows["old"]["backend"] == "gpu"
    assert rows["old"]["jaxlib_version"] == P.UNKNOWN and rows["old"]["git_dirty"] is None
    assert rows["new"]["jax_version"] == jax.__version__  # rows with provenance untouched
    assert P.backfill(tmp_path, {"jax_version": "0.11.2"}) == 0  # idempotent
    assert len(pd.read_parquet(tmp_path / "runs.parquet")) == 2
    with pytest.raises(ValueError, match="allowed"):
        P.backfill(tmp_path, {"jax": "0.11.2"})


def test_every_row_of_execute_run_carries_provenance(tmp_path):
    from bench import execute_run
    from bench.core import RunConfig

    # A configuration that fails at once: the row is written all the same, with provenance.
    config = RunConfig(system="chain_pendulum", k=1, model="no_such_model", steps=1)
    row = execute_run(config, cache_root=tmp_path)
    assert row["status"] == "failed"
    assert {c: row[c] for c in P.PROVENANCE_COLUMNS} == P.provenance()


def test_bench_meta_json_records_provenance(tmp_path, monkeypatch):
    import bench._cli as cli
    import bench.core._runner as runner

    monkeypatch.setattr(runner, "run_experiments", lambda *a, **k: {})
    monkeypatch.setattr(cli, "_cmd_figures", lambda args: 0)
    monkeypatch.setattr(cli, "_cmd_report", lambda args: 0)
    assert cli.main(["--results", str(tmp_path), "bench", "--skip-stability", "--no-compare"]) == 0
    meta = json.loads((tmp_path / "bench_meta.json").read_text())
    assert meta["provenance"] == P.provenance()


def test_usage_error():
    assert P.main(["nonsense"]) == 2
