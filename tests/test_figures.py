"""Figures and the report from synthetic stored runs (no training): files exist, the report
holds one verdict row per claim (claim 4: per metric and spring initial state), every
experiment's table has its trivial-predictor row and a discriminating mark, the verdicts of a
second results folder stand beside these, and an experiment without runs is skipped with a note."""

import re

import pytest
from _synthetic import synthetic_tables

from bench._report import figure_stem, make_figures, write_report
from bench.studies.paper import FIGURES


def _store(d, runs, curves):
    d.mkdir(parents=True, exist_ok=True)
    runs.to_parquet(d / "runs.parquet", index=False)
    curves.to_parquet(d / "curves.parquet", index=False)


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    d = tmp_path_factory.mktemp("results")
    runs, curves = synthetic_tables("smoke", seeds=(0, 1, 2, 3, 4), noise=0.05)
    _store(d, runs[runs["system"] != "relativistic_particle"], curves)  # one without runs
    # a second folder, "paper" runs of another profile's budget, built to contradict
    other, other_curves = synthetic_tables("smoke", seeds=(0, 1, 2, 3, 4), scenario="contradict")
    _store(d / "paper", other.assign(profile="paper"), other_curves)
    written = make_figures(d)
    # only the folder built here beside it: the committed reference folders would add columns
    report = write_report(d, compare=[d / "paper"])
    return d, written, report.read_text()


def test_every_experiment_with_runs_has_png_and_pdf(results):
    d, written, _ = results
    for name in FIGURES:
        for ext in ("png", "pdf"):
            path = d / "figures" / f"{figure_stem(name)}.{ext}"
            if name.startswith("relativistic"):  # both claim-7 experiments
                assert not path.exists()
            else:
                assert path in written and path.stat().st_size > 1000, path


VERDICT = r"\*\*(reproduced|partly reproduced|not reproduced|inconclusive)\*\*"


def test_report_has_a_verdict_row_per_claim(results):
    _, _, text = results
    claims = text.split("## Claims")[1].split("## Verdicts at both budgets")[0]
    rows = re.findall(rf"^\| (\d)( \([^|]*\))? \| .*?{VERDICT}", claims, re.M)
    assert sorted({int(c) for c, _, _ in rows}) == list(range(1, 10))  # one-digit claims
    assert sum(c == "4" for c, _, _ in rows) == 4  # 2 metrics x 2 spring initial states
    verdicts = {c: v for c, _, v in rows}
    # The synthetic table satisfies claims 1-6 and 8 by construction; claim 7 has no runs.
    assert verdicts["3"] == "reproduced" and verdicts["7"] == "inconclusive"


def test_report_sets_both_budgets_side_by_side(results):
    _, _, text = results
    section = text.split("## Verdicts at both budgets")[1].split("\n## ")[0]
    assert "| claim | smoke (here) | paper (`paper/`) | agree |" in section
    row3 = next(line for line in section.splitlines() if line.startswith("| 3 |"))
    assert "**reproduced**" in row3 and "**not reproduced**" in row3 and "budget" in row3


def test_a_claim_judged_in_one_folder_only_names_no_cause(results):
    """Claim 7 has no runs here (no relativistic rows) and a verdict in the other folder: the
    cell says *no runs*, nothing disagrees, and the cause column stays empty (it used to repeat
    "no runs or missing cells ... not comparable")."""
    _, _, text = results
    section = text.split("## Verdicts at both budgets")[1].split("\n## ")[0]
    row7 = next(line for line in section.splitlines() if line.startswith("| 7 |"))
    cells = [c.strip() for c in row7.strip("|").split("|")]
    assert cells[1] == "no runs" and re.search(VERDICT, cells[2]), row7
    assert cells[3] == "-" and cells[4] == "-", row7


def test_every_experiment_table_has_trivial_row_and_discriminating_mark(results):
    _, _, text = results
    for name in FIGURES:
        if name.startswith("relativistic"):
            continue
        section = text.split(f"## {name}")[1].split("\n## ")[0]
        assert "(trivial) |" in section, name
        assert "- discriminating: yes" in section, name


def test_report_links_figures_and_notes_missing_experiment(results):
    _, _, text = results
    assert "](figures/fig4_second_order.png)" in text
    assert "No runs of this experiment are stored" in text
    assert "No runs for 4 declared cells" in text  # relativistic, listed
    assert "profile: smoke" in text
    assert "reference_compatible" in text


def test_report_table_shows_mean_and_sem(results):
    _, _, text = results
    section = text.split("## second_order")[1].split("## ")[0]
    assert re.search(
        r"\| chain_pendulum \| - \| hnn_so \| velocity \| 5 \| [0-9.e-]+ ± [0-9.e-]+", section
    )


def test_a_registered_study_is_drawn_and_reported(tmp_path, monkeypatch):
    # A study is a plug-in: registering it is all it takes for its figure and its section.
    import bench._report as report
    from bench.core import _studies

    drawn = []

    def figure(results_dir):
        drawn.append(results_dir)
        return [results_dir / "figures" / "toy.png"]

    toy = _studies.Study(name="toy", results_figure=figure, section=lambda d: "## Toy\n\nhi")
    broken = _studies.Study(name="broken", section=lambda d: 1 / 0, section_title="Broken")
    monkeypatch.setitem(_studies._STUDIES, "toy", toy)
    monkeypatch.setitem(_studies._STUDIES, "broken", broken)
    assert [s.name for s in _studies.studies()][-2:] == ["toy", "broken"]
    assert tmp_path / "figures" / "toy.png" in make_figures(tmp_path) and drawn == [tmp_path]
    text = "\n".join(report._extra_sections(tmp_path))
    assert "## Toy\n\nhi" in text
    assert "## Broken\n\n(section failed: division by zero)" in text


def test_a_campaign_folder_states_verdicts_only_for_claims_whose_runs_are_all_stored(tmp_path):
    """A paper-core folder under way: claim 6 (every run of the loss experiment stored) has its
    verdict; claims that read other experiments say pending (n of m runs), in the folder's own
    claims table; one run fewer makes claim 6 pending too."""
    from bench.core._experiments import expand

    runs, curves = synthetic_tables("paper-core", experiments=("loss",))
    assert set(runs["profile"]) == {"paper-core"}
    want = {c.config_hash for c in expand("loss", "paper-core")}
    assert set(runs["config_hash"]) == want

    def claims(text):
        return text.split("## Claims")[1].split("## Verdicts at both budgets")[0]

    _store(tmp_path / "a", runs, curves)
    text = claims(write_report(tmp_path / "a", compare=[]).read_text())
    row6 = re.search(r"^\| 6 \|.*$", text, re.M).group(0)
    assert "pending" not in row6 and re.search(VERDICT, row6)
    row1 = re.search(r"^\| 1 \|.*$", text, re.M).group(0)
    assert re.search(r"\*\*pending \(\d+ of 50 runs\)\*\*", row1), row1
    _store(tmp_path / "b", runs.iloc[1:], curves)
    text = claims(write_report(tmp_path / "b", compare=[]).read_text())
    assert "**pending (44 of 45 runs)**" in re.search(r"^\| 6 \|.*$", text, re.M).group(0)


def test_a_pending_campaign_beside_two_disagreeing_folders_names_both_causes(results, tmp_path):
    """Here pending (a campaign with only claim 6's runs), the two other folders disagreeing on
    claim 3: the row says it disagrees, why the other two differ (the budget), and that here
    is pending, each once."""
    d, _, _ = results
    runs, curves = synthetic_tables("paper-core", experiments=("loss",))
    _store(tmp_path / "camp", runs, curves)
    text = write_report(tmp_path / "camp", compare=[d, d / "paper"]).read_text()
    section = text.split("## Verdicts at both budgets")[1].split("\n## ")[0]
    row3 = next(line for line in section.splitlines() if line.startswith("| 3 |"))
    cells = [c.strip() for c in row3.strip("|").split("|")]
    assert cells[1].startswith("pending (") and cells[4] == "**no**", row3
    assert "budget" in cells[5] and "not comparable yet" in cells[5], row3
    parts = cells[5].split("; ")
    assert len(parts) == len(set(parts)), row3


def test_symplectic_figure_draws_from_weight_zero_runs_only(tmp_path):
    """A campaign under way may hold only the unregularised runs of the symplectic sweep; its
    figure is drawn (it failed on the empty log axis of the weight panel before)."""
    from bench.studies.paper.symplectic import fig_symplectic

    runs, curves = synthetic_tables("smoke", seeds=(0, 1, 2, 3, 4), experiments=("symplectic",))
    from bench.core._query import option

    zero = runs[option(runs, "weight").astype(float) == 0]
    assert len(zero) and len(zero) < len(runs)
    written = fig_symplectic(zero, curves, tmp_path)
    assert written and all(p.stat().st_size > 1000 for p in written)


def test_a_figure_saved_twice_has_the_same_bytes(tmp_path):
    """Regenerating an unchanged figure must not change its files (the PDF used to carry its
    creation date, so every report rebuild dirtied git)."""
    import time

    import matplotlib.pyplot as plt

    from bench.studies._figure import save_figure

    def draw(d):
        fig, ax = plt.subplots()
        ax.plot([1, 2, 3], [3, 1, 2])
        return [p.read_bytes() for p in save_figure(fig, tmp_path / d, "f")]

    first = draw("a")
    time.sleep(1.1)  # the PDF's date has a resolution of one second
    assert draw("b") == first


def test_agreement_compares_verdicts_not_the_reason_of_an_inconclusive_one():
    """*inconclusive* here and *inconclusive (does not replicate)* there agree (neither signs
    the claim, no cause to name); *partly reproduced* against either does not."""
    from bench.studies.paper._comparison import comparison_section
    from bench.studies.paper.kit import Verdict

    def v(verdict, claim=3):
        return Verdict(claim, "t", verdict, 0.1, 0.0, 0.2, 5, "d", profile="p")

    others = [("a", "quick", [v("inconclusive (does not replicate)"), v("inconclusive", 1)])]
    rows = comparison_section([v("inconclusive"), v("partly reproduced", 1)], "paper", others)
    row3 = next(r for r in rows if r.startswith("| 3 |"))
    row1 = next(r for r in rows if r.startswith("| 1 |"))
    assert row3.endswith("| yes | - |"), row3
    assert "| **no** |" in row1 and "budget" in row1, row1


def test_a_cause_shared_by_two_compared_folders_is_named_once():
    """Here against two folders that disagree with it for the same reason: the budget cause
    appears once, a failed-run count only where it differs."""
    from bench.studies.paper._comparison import comparison_section
    from bench.studies.paper.kit import Verdict

    def v(verdict, n_failed=0):
        return Verdict(3, "t", verdict, 0.1, 0.0, 0.2, 5, "d", profile="p", n_failed=n_failed)

    others = [("a", "paper", [v("partly reproduced", 1)]), ("b", "paper", [v("partly reproduced")])]
    rows = comparison_section([v("inconclusive")], "quick", others)
    row3 = next(r for r in rows if r.startswith("| 3 |"))
    cause = row3.rstrip(" |").rsplit(" | ", 1)[1]
    assert cause.count("budget (") == 1, row3
    assert cause.count("failed runs (0 vs 1)") == 1, row3


def test_a_demoted_reading_that_agrees_in_direction_is_named_as_stability_not_budget():
    """Quick's seeds 0-4 read *not reproduced*, as the paper budget does, but its verdict
    changes without a seed: the cause is the reading's stability, and the budget is not named.
    Where the demoted reading's own seeds differ from the other folder, both are named."""
    from bench.studies.paper._comparison import comparison_section
    from bench.studies.paper._replication import CHANGES_WITHOUT_A_SEED, DOES_NOT_REPLICATE
    from bench.studies.paper.kit import Verdict

    def v(verdict, claim, primary=None, readings=""):
        return Verdict(
            claim,
            "t",
            verdict,
            0.1,
            0.0,
            0.2,
            5,
            "d",
            profile="p",
            primary=primary,
            readings=readings,
        )

    quick = [
        v(
            CHANGES_WITHOUT_A_SEED,
            9,
            "not reproduced",
            "seeds 0-4: not reproduced; without seed 1: inconclusive",
        ),
        v(
            DOES_NOT_REPLICATE,
            3,
            "inconclusive",
            "seeds 0-4: inconclusive; seeds 5-9: partly reproduced",
        ),
    ]
    rows = comparison_section(
        [v("not reproduced", 9), v("partly reproduced", 3)],
        "paper-core",
        [("a", "quick", quick)],
    )
    row9 = next(r for r in rows if r.startswith("| 9 |"))
    row3 = next(r for r in rows if r.startswith("| 3 |"))
    assert "| **no** |" in row9 and "reads not reproduced on its own seeds" in row9, row9
    assert "changes without a seed (seeds 0-4: not reproduced; without seed 1" in row9, row9
    assert "budget" not in row9, row9
    assert "the verdict does not replicate (seeds 0-4: inconclusive; seeds 5-9" in row3, row3
    assert "budget" in row3, row3


def test_report_names_no_folder_by_its_absolute_path(tmp_path):
    """The report is committed: a compared folder whose provenance differs is named as the
    verdict table names it (relative to ``results/``, or by its name), never by this
    machine's absolute path."""
    runs, curves = synthetic_tables("smoke", seeds=(0, 1), noise=0.05)
    _store(tmp_path / "a", runs.assign(jax_version="0.10.2"), curves)
    _store(tmp_path / "a" / "gpu", runs.assign(jax_version="0.11.2"), curves)
    text = write_report(tmp_path / "a", compare=[tmp_path / "a" / "gpu"]).read_text()
    assert "Differences from `gpu`:" in text
    assert "jax_version differs: 0.10.2 (a) vs 0.11.2 (gpu)" in text
    assert str(tmp_path) not in text


def test_report_prints_the_margin_policy_the_margin_ranges_and_the_dependent_claims(results):
    from bench.studies.paper import policy

    _, _, text = results
    section = text.split("## Margin policy")[1].split("## Margin-dependent claims")[0]
    for q in policy.POLICY.values():
        assert f"| {q.label} |" in section
    assert "several orders of magnitude" in section  # a margin a seed states, with its source
    parts = text.split("### Every part")[1].split("## Margin policy")[0]
    assert "| margin range |" in parts.splitlines()[2]
    assert re.search(r"holds below [\d.]+x; undecided [\d.]+x-[\d.]+x; contradicts from", parts)
    dependent = text.split("## Margin-dependent claims")[1].split("## Verdicts at both budgets")[0]
    assert (
        "No verdict changes inside any band." in dependent or "Margin-dependent: claim" in dependent
    )
