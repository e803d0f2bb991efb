"""Claim 7's two protocols in the report: the comparison table of the relativistic study (what
each protocol trains on and how, and each reading's verdict) sits inside the claim's section,
and the seed's protocol has its own experiment section and figure. Synthetic stored runs, no
training. The rule's parts on both protocols: tests/test_claims.py."""

import pytest
from _synthetic import synthetic_tables

from bench._report import make_figures, write_report
from bench.studies.paper import relativistic as REL

EXPERIMENTS = ("relativistic", "relativistic_seed")


def _folder(d, scenario="reproduce", drop_seed=False):
    runs, curves = synthetic_tables("smoke", experiments=EXPERIMENTS, scenario=scenario)
    if drop_seed:
        runs = runs[runs["train_target"] != "derivative"]
    d.mkdir(parents=True, exist_ok=True)
    runs.to_parquet(d / "runs.parquet", index=False)
    curves.to_parquet(d / "curves.parquet", index=False)
    return d


def _row(text, name):
    line = next(x for x in text.splitlines() if x.startswith(f"| {name} |"))
    return [c.strip() for c in line.strip("|").split("|")]


def test_the_comparison_table_names_both_protocols_and_their_verdicts(tmp_path):
    text = REL.comparison_section(_folder(tmp_path / "r"))
    assert text.startswith(f"### {REL.SECTION_TITLE}")
    for row in ("data", "targets", "loss", "optimiser", "steps", "metric", "verdict"):
        assert len(_row(text, row)) == 3, row
    _, ours, seed = _row(text, "targets")
    assert "rolled out" in ours and "dz/dt" in seed
    _, ours, seed = _row(text, "loss")
    assert ours.startswith("L2") and seed.startswith("L1")
    _, ours, seed = _row(text, "optimiser")
    assert "lr 0.005" in ours and "lr 0.001" in seed and "32 states" in seed
    assert _row(text, "verdict")[1:] == ["reproduced (seeds 0-4)"] * 2
    # the errors of both protocols' models, the (q, p) HNN's decoded to velocities
    for cell in _row(text, "HNN (q, p)")[1:]:  # 0.02 by construction; 0.005 in (q, p)
        assert float(cell.split()[0]) == pytest.approx(0.02, rel=0.2), cell


def test_the_claim_reads_the_seeds_protocol_and_says_so_without_it(tmp_path):
    text = REL.comparison_section(_folder(tmp_path / "c", scenario="contradict"))
    assert _row(text, "verdict")[1:] == ["not reproduced (seeds 0-4)"] * 2
    text = REL.comparison_section(_folder(tmp_path / "o", drop_seed=True))
    assert _row(text, "verdict")[1:] == ["reproduced (seeds 0-4)", "not run (seeds 0-4)"]


def test_the_report_places_the_table_in_the_claims_section(tmp_path):
    d = _folder(tmp_path / "rep")
    written = make_figures(d)
    assert d / "figures" / "fig_relativistic_seed.png" in written
    text = write_report(d, compare=[]).read_text()
    claim7 = text.split("## relativistic (claim 7)")[1].split("\n## ")[0]
    assert f"### {REL.SECTION_TITLE}" in claim7
    seed = text.split("## relativistic_seed (claim 7)")[1].split("\n## ")[0]
    assert "(trivial) |" in seed and "fig_relativistic_seed.png" in seed
    assert text.count(f"### {REL.SECTION_TITLE}") == 1  # not again among the extra sections
