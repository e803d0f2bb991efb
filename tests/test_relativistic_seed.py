"""Claim 7's two protocols in the report: the comparison table of the relativistic study (what
each protocol trains on and how, and each reading's verdict) sits inside the claim's section,
and the seed's protocol has its own experiment section and figure. Synthetic stored runs, no
training. The rule's parts on both protocols: tests/test_claims.py."""

import re

import pytest
from _markdown import section, table_rows
from _synthetic import synthetic_tables

from bench._report import make_figures, write_report
from bench.studies.lnn_seed import relativistic as REL
from bench.studies.lnn_seed.relativistic._section import _one, _protocol

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
    """A row of the section's tables (the protocols', then the models' errors) as a list."""
    for header in ("| protocol | ours", "| model | ours"):
        for r in table_rows(text, header):
            if next(iter(r.values())) == name:
                return list(r.values())
    raise LookupError(name)


def test_the_comparison_table_names_both_protocols_and_their_verdicts(tmp_path):
    text = REL.comparison_section(_folder(tmp_path / "r"))
    assert section(text, REL.SECTION_TITLE) is not None
    ours_c, seed_c = _one(REL.RELATIVISTIC, "smoke"), _one(REL.RELATIVISTIC_SEED, "smoke")
    # each protocol as declared: ours rolls out an L2 loss, the seed's fits dz/dt with L1
    assert (ours_c.train_target, ours_c.loss, ours_c.lr) == ("rollout", "l2", 0.005)
    assert (seed_c.train_target, seed_c.loss, seed_c.lr) == ("derivative", "l1", 0.001)
    ours, seed = _protocol(ours_c), _protocol(seed_c)
    for row in ("data", "targets", "loss", "optimiser", "steps", "metric"):
        assert _row(text, row) == [row, ours[row], seed[row]], row  # the table shows them
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
    assert section(section(text, "relativistic"), REL.SECTION_TITLE) is not None
    seed = section(text, "relativistic_seed")
    assert any(r["variant"].endswith("(trivial)") for r in table_rows(seed, "|"))
    assert "figures/fig_relativistic_seed.png" in re.findall(r"\]\(([^)]+)\)", seed)
    # not again among the extra sections
    assert [x for x in text.splitlines() if x.lstrip("#").strip() == REL.SECTION_TITLE] == [
        f"### {REL.SECTION_TITLE}"
    ]
