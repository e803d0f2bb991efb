"""``python -m bench compare A B``: claims, cells and runs of two results folders.

The folders hold synthetic tables (tests/_synthetic.py: no training), written as a results
folder without row files (runs.parquet, curves.parquet, bench_meta.json)."""

import json
import re

import numpy as np
import pandas as pd
import pytest
from _markdown import section, table_rows
from _synthetic import synthetic_tables

from bench._cli import main
from bench._compare import _same_text, compare
from bench.core import SCHEMA_VERSION


def _folder(path, runs, curves, schema=SCHEMA_VERSION):
    path.mkdir(parents=True)
    runs.to_parquet(path / "runs.parquet", index=False)
    curves.to_parquet(path / "curves.parquet", index=False)
    if schema is not None:
        (path / "bench_meta.json").write_text(json.dumps({"schema_version": schema}))
    return path


@pytest.fixture(scope="module")
def tables():
    return synthetic_tables("quick", experiments=["second_order"])


def test_identical_folders_agree_everywhere(tmp_path, tables):
    runs, curves = tables
    a = _folder(tmp_path / "a", runs, curves)
    b = _folder(tmp_path / "b", runs, curves)
    c = compare(a, b)
    assert len(c.claims) >= 3 and c.claims["same"].all() and c.claims_differ == []
    assert (c.claims["moved"] == "").all()
    n_cells = len(runs.drop_duplicates([col for col in runs if col not in ("seed",)]))
    assert 0 < len(c.cells) <= n_cells and not c.cells["flagged"].any()
    assert np.allclose(c.cells["ratio"], 1.0)
    assert len(c.runs) == len(runs) and (c.runs["rel_diff"] == 0).all()
    assert "\n" not in c.summary  # one line


def test_moved_cells_are_flagged_and_changed_verdicts_named(tmp_path, tables):
    runs, curves = tables
    other, other_curves = synthetic_tables(
        "quick", experiments=["second_order"], scenario="contradict"
    )
    assert set(other["config_hash"]) == set(runs["config_hash"])  # the same runs, other errors
    c = compare(_folder(tmp_path / "a", runs, curves), _folder(tmp_path / "b", other, other_curves))
    assert "3" in c.claims_differ
    row = c.claims.set_index("claim").loc["3"]
    assert row["verdict_a"] != row["verdict_b"] and "->" in row["moved"]
    assert c.cells["flagged"].any() and (c.runs["rel_diff"] > 0).any()
    shown = _claims_table(c)["3"]  # its row
    assert (shown["verdict A"], shown["verdict B"]) == (row["verdict_a"], row["verdict_b"])
    assert shown["same"] == _same_text(False)


def _claims_table(c):
    """The comparison's claims table as rendered, per claim."""
    rows = table_rows(section(c.markdown(), "Claims"), "| claim | verdict A")
    return {r["claim"]: r for r in rows}


@pytest.mark.slow  # three folders judged (~15 s); the flagging itself is tested above
def test_a_change_inside_the_seed_spread_is_not_flagged(tmp_path, tables):
    runs, curves = tables
    b = runs.copy()
    pick = (b["model"] == "node_so") & (b["system"] == "chain_pendulum")
    b.loc[pick, "rollout_error"] *= 1.0001  # round-off, far inside the seeds' spread
    c = compare(_folder(tmp_path / "a", runs, curves), _folder(tmp_path / "b", b, curves))
    assert not c.cells["flagged"].any()
    assert (c.runs.loc[c.runs["rel_diff"] > 0, "model"] == "node_so").all()
    assert int((c.runs["rel_diff"] > 0).sum()) == int(pick.sum())
    # ... and a cell moved far outside its spread is
    b.loc[pick, "rollout_error"] *= 3
    c = compare(_folder(tmp_path / "a2", runs, curves), _folder(tmp_path / "b2", b, curves))
    flagged = c.cells[c.cells["flagged"]]
    assert len(flagged) >= 1 and flagged["cell"].str.startswith("node_so chain_pendulum").all()
    assert np.allclose(flagged["ratio"], 3.0003, rtol=1e-3)


def test_schema_versions_are_checked(tmp_path, tables):
    runs, curves = tables
    a = _folder(tmp_path / "a", runs, curves)
    with pytest.raises(ValueError, match="schema") as e:
        compare(a, _folder(tmp_path / "b", runs, curves, schema=SCHEMA_VERSION + 1))
    assert "\n" not in str(e.value)
    c = compare(a, _folder(tmp_path / "c", runs, curves, schema=None))
    assert any("no schema version" in w for w in c.warnings)


def test_cli_prints_claims_and_summary_and_writes_the_comparison(tmp_path, tables, capsys):
    runs, curves = tables
    a = _folder(tmp_path / "a", runs, curves)
    b = _folder(tmp_path / "b", runs, curves)
    out = tmp_path / "cmp" / "COMPARE.md"
    assert main(["compare", str(a), str(b), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert section(printed, "Claims") is not None
    assert printed.strip().splitlines()[-1] == compare(a, b).summary  # the summary, last
    written = out.read_text()
    assert all(section(written, s) is not None for s in ("Claims", "Cells", "Runs"))


def test_cli_bad_folders_get_one_line(tmp_path, tables, capsys):
    runs, curves = tables
    b = _folder(tmp_path / "b", runs, curves)
    assert main(["compare", str(tmp_path / "nope"), str(b)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error:") and "does not exist" in err and "\n" not in err
    (tmp_path / "empty").mkdir()
    assert main(["compare", str(tmp_path / "empty"), str(b)]) == 2
    assert "no stored runs" in capsys.readouterr().err


def test_compare_folders_lists_references_then_subfolders_not_itself(tmp_path):
    from bench.core import compare_folders

    refs = tmp_path / "reference"
    for name in ("quick", "paper", "empty"):
        (refs / name).mkdir(parents=True)
    (refs / "quick" / "runs.parquet").write_bytes(b"")
    (refs / "paper" / ".rows").mkdir()
    own = tmp_path / "own"
    (own / "paper_gpu").mkdir(parents=True)
    (own / "paper_gpu" / "runs.csv").write_text("")
    (own / "figures").mkdir()
    assert compare_folders(own, refs) == [refs / "paper", refs / "quick", own / "paper_gpu"]
    # a reference folder is not compared with itself
    assert compare_folders(refs / "quick", refs) == [refs / "paper"]


def test_a_one_seed_cell_has_no_spread_and_is_never_flagged(tmp_path, tables):
    runs, curves = tables
    one = runs[(runs["seed"] == runs["seed"].min())]
    b = one.copy()
    b["rollout_error"] *= 1.001  # round-off on another CPU type
    c = compare(_folder(tmp_path / "a", one, curves), _folder(tmp_path / "b", b, curves))
    assert len(c.cells) and not c.cells["spread"].any() and not c.cells["flagged"].any()
    # ... while a cell with a spread is still judged against it
    b2 = runs.copy()
    b2["rollout_error"] *= 3
    c = compare(_folder(tmp_path / "a2", runs, curves), _folder(tmp_path / "b2", b2, curves))
    assert c.cells["flagged"].any()


def test_a_claim_not_run_in_one_folder_is_listed_not_counted(tmp_path, tables):
    """`make bench` runs one paper's claims; the reference holds every paper's: a claim none of
    whose experiments ran in a folder reads "no runs" there and is neither same nor differing."""
    runs, curves = tables
    vin, vin_curves = synthetic_tables("quick", experiments=["vin"], scenario="contradict")
    both = _folder(
        tmp_path / "a",
        pd.concat([runs, vin], ignore_index=True),
        pd.concat([curves, vin_curves], ignore_index=True),
    )
    c = compare(both, _folder(tmp_path / "b", runs, curves))
    row = c.claims.set_index("claim").loc["8"]
    assert row["verdict_a"] != "no runs" and row["verdict_b"] == "no runs"
    assert row["same"] is None  # neither the same nor a difference
    assert "8" not in c.claims_differ and c.n_judged == len(c.claims) - 1
    same = re.search(r"(\d+) of (\d+) claim verdicts the same", c.summary).groups()
    assert same == (str(c.n_judged), str(c.n_judged))
    assert re.search(r", (\d+) with no runs in one folder", c.summary).group(1) == "1"
    shown = _claims_table(c)
    assert shown.pop("8")["same"] == _same_text(None) != _same_text(False)
    assert shown and all(r["same"] == _same_text(True) for r in shown.values())


def test_a_verdict_that_read_none_of_its_cells_reads_no_runs(monkeypatch):
    """A folder with rows of a claim's experiments but none of the cells its parts read: the
    judge's verdict says "no runs" in its detail; compare reads it as no runs, not as an
    inconclusive verdict to count as the same as (or other than) the reference's."""
    from types import SimpleNamespace

    import bench._compare as C
    from bench import kit

    def verdict(key, text, detail):
        return SimpleNamespace(key=key, claim=int(key), verdict=text, detail=detail, parts=[])

    sides = {
        "a": {"1": verdict("1", "inconclusive", "part: undecided"), "2": verdict("2", "x", "d")},
        "b": {"1": verdict("1", "inconclusive", "no runs"), "2": verdict("2", "y", "d")},
    }
    monkeypatch.setattr(kit, "restrict_all", lambda runs, profile: {1: runs, 2: runs})
    monkeypatch.setattr(
        kit,
        "judge",
        lambda runs, curves, profile, restricted: SimpleNamespace(
            final=list(sides[profile].values()), primary=sides[profile]
        ),
    )
    one = pd.DataFrame({"config_hash": ["h"]})
    claims = C._claims(one, None, "a", one, None, "b").set_index("claim")
    assert claims.loc["1", "verdict_b"] == claims.loc["1", "final_b"] == "no runs"
    assert claims.loc["1", "same"] is None and claims.loc["2", "same"] is False
    assert C._same_text(claims.loc["1", "same"]) == "no runs"
    assert C._same_text(False) == "**no**" and C._same_text(True) == "yes"


def test_row_cell_keys_equal_the_uncached_keys_on_a_second_call(tables):
    from bench.core import RunConfig, cell_key, row_cell_keys

    runs, _ = tables
    want = [cell_key(RunConfig.from_dict(r)) for r in runs.to_dict("records")]
    assert row_cell_keys(runs) == want
    assert row_cell_keys(runs) == want  # from the memo, NaN cells included
    assert len(set(want)) < len(want)  # seeds share a cell
