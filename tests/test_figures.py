"""Figures and the report from synthetic stored runs (no training): files exist, the report
holds one verdict row per claim (claim 4: per metric and spring initial state), every
experiment's table has its trivial-predictor row and discriminates, the verdicts of a second
results folder stand beside these, and an experiment without runs is skipped.

Verdicts, agreement and causes are asserted on the structured values the report is written
from (:func:`load_other`'s verdicts, :func:`comparison_rows`), the report itself on its
sections and rows."""

import dataclasses
import difflib
import os
import re
from pathlib import Path

import pytest
from _markdown import section, table_rows
from _synthetic import synthetic_tables

from bench._report import figure_stem, make_figures, write_report
from bench._tables import discrimination_groups
from bench.core import compare_provenance, experiment_rows, load_runs, load_tables, studies
from bench.kit import (
    INCONCLUSIVE,
    NOT_REPRODUCED,
    PARTLY,
    REPRODUCED,
    VERDICTS,
    Verdict,
    folder_label,
)
from bench.studies.paper import PAPER_EXPERIMENTS
from bench.studies.paper.report._comparison import comparison_rows, comparison_section, load_other

# experiment name -> figure function of the studies whose runs the synthetic tables hold
FIGURES = {
    s.name: s.figure
    for s in studies()
    if s.figure is not None
    and {e.name for e in s.experiments} <= {e.name for e in PAPER_EXPERIMENTS}
}


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


# The report written from the synthetic folders, as committed: any change to what the report
# says of the same runs shows as a diff of this file. ``make golden`` rewrites it.
GOLDEN = Path(__file__).with_name("golden") / "report_smoke.md"
UPDATE_GOLDEN = "DECON_UPDATE_GOLDEN"


def _normalised(text: str, folder: Path) -> str:
    """``text`` without what differs between two writes of the same runs: the machine, date and
    commit lines, and the temporary folder's path and name."""
    text = text.replace(str(folder), "<results>").replace(folder.name, "<results>")
    volatile = ("- machine:", "- date:", "- commit:")
    keep = [line for line in text.splitlines() if not line.startswith(volatile)]
    return "\n".join(keep) + "\n"


def test_the_report_is_its_golden_file(results):
    d, _, text = results
    got = _normalised(text, d)
    if os.environ.get(UPDATE_GOLDEN) == "1":
        GOLDEN.parent.mkdir(exist_ok=True)
        GOLDEN.write_text(got)
    want = GOLDEN.read_text()
    diff = "".join(
        difflib.unified_diff(want.splitlines(True), got.splitlines(True), "golden", "written", n=1)
    )
    assert got == want, f"the report changed (accept it with `make golden`):\n{diff[:4000]}"


@pytest.fixture(scope="module")
def loaded(results):
    """Both folders judged once, as the report reads them (:func:`load_other`)."""
    d, _, _ = results
    return load_other(d), load_other(d / "paper")


@pytest.fixture(scope="module")
def judged(loaded):
    """What the report is written from: this folder's final verdicts (pending where a
    campaign's runs are missing) and, per claim key, its comparison with the paper folder."""
    (_, profile, verdicts), paper = loaded
    rows = comparison_rows(verdicts, profile, [paper])
    return verdicts, {r.key: r for r in rows}


def _claims(text):
    """The report's claims table, per claim key."""
    return {r["claim"]: r for r in table_rows(section(text, "Claims"), "| claim | statement")}


def test_every_experiment_with_runs_has_png_and_pdf(results):
    d, written, _ = results
    for name in FIGURES:
        for ext in ("png", "pdf"):
            path = d / "figures" / f"{figure_stem(name)}.{ext}"
            if name.startswith("relativistic"):  # both claim-7 experiments
                assert not path.exists()
            else:
                assert path in written and path.stat().st_size > 1000, path


def test_report_has_a_verdict_row_per_claim(results, judged):
    _, _, text = results
    verdicts, _ = judged
    assert {v.claim for v in verdicts} >= set(range(1, 10))  # the paper's claims, and more
    assert sum(v.claim == 4 for v in verdicts) == 4  # 2 metrics x 2 spring initial states
    final = {v.key: v.verdict for v in verdicts}
    # The synthetic table satisfies claims 1-6 and 8 by construction; claim 7 has no runs.
    assert final["3"] == REPRODUCED and final["7"] == INCONCLUSIVE
    claims = _claims(text)
    assert set(claims) == {v.key for v in verdicts}  # one row per verdict, showing it
    for v in verdicts:
        assert claims[v.key]["verdict"] == f"**{v.label()}**", v.key


def test_report_sets_both_budgets_side_by_side(results, judged):
    _, _, text = results
    _, rows = judged
    row3 = rows["3"]
    assert row3.labels == ("smoke (here)", "paper (`paper/`)")
    assert [v.verdict for v in row3.verdicts] == [REPRODUCED, NOT_REPRODUCED]
    assert row3.agree is False and "budget" in {c.kind for c in row3.causes}
    # where the two readings part: the parts whose status moved, with both sides' effects
    (moved,) = [c.text for c in row3.causes if c.kind == "parts"]
    here, there = (v for v in row3.verdicts)
    theirs = {q.name: q.status for q in there.parts}
    names = [q.name for q in here.parts if q.role == "part" and theirs.get(q.name) != q.status]
    assert names and moved.startswith(f"parts that read otherwise: {names[0]}: holds (")
    assert ") at smoke (here), contradicts (" in moved and moved.count("; ") <= 3
    shown = {r["claim"] for r in table_rows(section(text, "Verdicts at both budgets"), "claim")}
    for key, row in rows.items():  # one row per claim key that some folder has runs for
        ran = any(v is not None and (v.n_seeds or v.pending) for v in row.verdicts)
        assert ran == (key in shown), key


def test_a_claim_judged_in_one_folder_only_names_no_cause(judged):
    """Claim 7 has no runs here (no relativistic rows) and a verdict in the other folder: here
    has *no runs*, nothing disagrees, and no cause is named (not even "not comparable")."""
    _, rows = judged
    row7 = rows["7"]
    assert row7.states == ("no runs", "judged")
    assert row7.agree is None and row7.causes == ()


def test_every_experiment_table_has_trivial_row_and_discriminates(results):
    d, _, text = results
    runs, _, profile = load_tables(d)
    for name in FIGURES:
        if name.startswith("relativistic"):
            continue
        rows = experiment_rows(runs, name, profile)
        assert {"constant_velocity", "at_rest"} & set(rows["model"]), name
        groups = discrimination_groups(rows)
        assert groups and all(g.status == "yes" for g in groups), (name, groups)
        table = table_rows(section(text, name), "|")  # its row in the table
        assert any(r["variant"].endswith("(trivial)") for r in table), name


def test_report_links_figures_and_skips_an_experiment_without_runs(results):
    d, _, text = results
    assert _figure_links(section(text, "second_order")) == ["figures/fig4_second_order.png"]
    skipped = section(text, "relativistic")
    with pytest.raises(LookupError):  # no table
        table_rows(skipped, "|")
    assert _figure_links(skipped) == []
    assert re.search(r"^- profile: (\S+)$", text, re.M).group(1) == "smoke"
    assert section(text, "What the suite does not copy from the reference") is not None


def _figure_links(md):
    return re.findall(r"!\[[^\]]*\]\(([^)]+)\)", md)


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
    assert section(text, "Toy").strip() == "hi"
    assert "division by zero" in section(text, "Broken")  # the failure, in its own section


def test_a_campaign_folder_states_verdicts_only_for_claims_whose_runs_are_all_stored(tmp_path):
    """A paper-core folder under way: claim 6 (every run of the loss experiment stored) has its
    verdict; claims that read other experiments say pending (n of m runs), in the folder's own
    claims table; one run fewer makes claim 6 pending too."""
    from bench.core import expand

    runs, curves = synthetic_tables("paper-core", experiments=("loss",))
    assert set(runs["profile"]) == {"paper-core"}
    want = {c.config_hash for c in expand("loss", "paper-core")}
    assert set(runs["config_hash"]) == want

    _store(tmp_path / "a", runs, curves)
    final = {v.key: v for v in load_other(tmp_path / "a")[2]}
    assert final["6"].pending is None and final["6"].verdict in VERDICTS
    stored, declared = final["1"].pending
    assert declared == 50 and stored < declared
    claims = _claims(write_report(tmp_path / "a", compare=[]).read_text())
    for key in ("1", "6"):  # the folder's own claims table shows them
        assert claims[key]["verdict"] == f"**{final[key].label()}**"
    _store(tmp_path / "b", runs.iloc[1:], curves)
    final = {v.key: v for v in load_other(tmp_path / "b")[2]}
    assert final["6"].pending == (44, 45)


def test_a_pending_campaign_beside_two_disagreeing_folders_names_both_causes(loaded, tmp_path):
    """Here pending (a campaign with only claim 6's runs), the two other folders disagreeing on
    claim 3: the row says it disagrees, why the other two differ (the budget), and that here
    is pending, each once."""
    runs, curves = synthetic_tables("paper-core", experiments=("loss",))
    _store(tmp_path / "camp", runs, curves)
    _, profile, verdicts = load_other(tmp_path / "camp")
    others = list(loaded)
    row3 = next(r for r in comparison_rows(verdicts, profile, others) if r.key == "3")
    assert row3.states == ("pending", "judged", "judged") and row3.agree is False
    kinds = [c.kind for c in row3.causes]
    assert kinds.count("budget") == 1 and kinds.count("not comparable") == 1, row3.causes
    assert next(c for c in row3.causes if c.kind == "not comparable").folder == row3.labels[0]


def test_symplectic_figure_draws_from_weight_zero_runs_only(tmp_path):
    """A campaign under way may hold only the unregularised runs of the symplectic sweep; its
    figure is drawn (it failed on the empty log axis of the weight panel before)."""
    from bench.studies.decon.symplectic import fig_symplectic

    runs, curves = synthetic_tables("smoke", seeds=(0, 1, 2, 3, 4), experiments=("symplectic",))
    from bench.core import option

    zero = runs[option(runs, "weight").astype(float) == 0]
    assert len(zero) and len(zero) < len(runs)
    written = fig_symplectic(zero, curves, tmp_path)
    assert written and all(p.stat().st_size > 1000 for p in written)


def test_a_figure_saved_twice_has_the_same_bytes(tmp_path):
    """Regenerating an unchanged figure must not change its files (the PDF used to carry its
    creation date, so every report rebuild dirtied git)."""
    import time

    import matplotlib.pyplot as plt

    from bench.kit._figure import save_figure

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

    def v(verdict, claim=3):
        return Verdict(claim, "t", verdict, 0.1, 0.0, 0.2, 5, "d", profile="p")

    others = [("a", "quick", [v(f"{INCONCLUSIVE} (does not replicate)"), v(INCONCLUSIVE, 1)])]
    rows = comparison_rows([v(INCONCLUSIVE), v(PARTLY, 1)], "paper", others)
    row3, row1 = (next(r for r in rows if r.claim == c) for c in (3, 1))
    assert row3.agree is True and row3.causes == (), row3
    assert row1.agree is False and [c.kind for c in row1.causes] == ["budget"], row1


def test_a_key_no_folder_ran_is_left_out_of_the_comparison_table():
    """A verdict key without runs in any folder (a variant no folder ran, e.g. claim 15's
    *not run* once every folder has the measured data) gives no row; a pending one stays."""

    def v(claim, n_seeds, variant="", verdict=INCONCLUSIVE):
        return Verdict(claim, "t", verdict, 0.1, 0.0, 0.2, n_seeds, "d", variant=variant)

    here = [v(15, 10), v(15, 0, "not run"), v(13, 0, verdict="pending (0 of 60 runs)")]
    here[2] = dataclasses.replace(here[2], pending=(0, 60))
    others = [("a", "quick", [v(15, 10), v(15, 0, "not run"), v(13, 5)])]
    table = "\n".join(comparison_section(here, "paper-core", others))
    assert sorted(r["claim"] for r in table_rows(table, "| claim")) == ["13", "15"], table


def test_a_cause_shared_by_two_compared_folders_is_named_once():
    """Here against two folders that disagree with it for the same reason: the budget cause
    appears once, a failed-run count only where it differs."""

    def v(verdict, n_failed=0):
        return Verdict(3, "t", verdict, 0.1, 0.0, 0.2, 5, "d", profile="p", n_failed=n_failed)

    others = [("a", "paper", [v(PARTLY, 1)]), ("b", "paper", [v(PARTLY)])]
    (row3,) = comparison_rows([v(INCONCLUSIVE)], "quick", others)
    assert row3.agree is False
    assert sorted(c.kind for c in row3.causes) == ["budget", "failed runs"], row3.causes


def test_a_demoted_reading_that_agrees_in_direction_is_named_as_stability_not_budget():
    """Quick's seeds 0-4 read *not reproduced*, as the paper budget does, but its verdict
    changes without a seed: the cause is the reading's stability, and the budget is not named.
    Where the demoted reading's own seeds differ from the other folder, both are named."""
    from bench.kit._replication import CHANGES_WITHOUT_A_SEED, DOES_NOT_REPLICATE

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
    rows = comparison_rows(
        [v(NOT_REPRODUCED, 9), v(PARTLY, 3)], "paper-core", [("a", "quick", quick)]
    )
    row9, row3 = (next(r for r in rows if r.claim == c) for c in (9, 3))
    quick_label = row9.labels[1]
    assert row9.agree is False
    # quick's own seeds read as paper-core does: its stability is the only cause
    assert [(c.kind, c.folder) for c in row9.causes] == [("stability", quick_label)], row9
    # quick's own seeds read otherwise: its stability, and the budget
    assert [(c.kind, c.folder) for c in row3.causes] == [
        ("stability", quick_label),
        ("budget", ""),
    ], row3


def test_report_names_no_folder_by_its_absolute_path(tmp_path):
    """The report is committed: a compared folder whose provenance differs is named as the
    verdict table names it (relative to ``results/``, or by its name), never by this
    machine's absolute path."""
    runs, curves = synthetic_tables("smoke", seeds=(0, 1), noise=0.05, experiments=("vin",))
    _store(tmp_path / "a", runs.assign(jax_version="0.10.2"), curves)
    _store(tmp_path / "a" / "gpu", runs.assign(jax_version="0.11.2"), curves)
    text = write_report(tmp_path / "a", compare=[tmp_path / "a" / "gpu"]).read_text()
    names = (folder_label(tmp_path / "a"), folder_label(tmp_path / "a" / "gpu"))
    assert names == ("a", "gpu")
    warnings = compare_provenance(
        load_runs(tmp_path / "a"), load_runs(tmp_path / "a" / "gpu"), names=names
    )
    assert warnings  # the jax versions differ
    provenance = section(text, "Provenance")
    assert re.findall(r"^Differences from `(.+)`:$", provenance, re.M) == ["gpu"]
    assert [x.removeprefix("- ") for x in provenance.splitlines() if x.startswith("- ")] == warnings
    assert str(tmp_path) not in text


def test_report_prints_the_margin_policy_the_margin_ranges_and_the_dependent_claims(
    results, judged
):
    from bench.kit import margin_ranges, policy

    _, _, text = results
    verdicts, _ = judged
    margins = section(text, "Margin policy")
    labels = [r["quantity"] for r in table_rows(margins, "| quantity | margin")]
    assert labels == [q.label for q in policy.POLICY.values()]
    stated = policy.stated_margins()  # margins a seed states, each with its quote and source
    assert stated and all(m.quote in margins and m.source in margins for m in stated)
    parts = table_rows(section(text, "Every part"), "| claim | part")
    shown = {(r["part"], r["margin range"]) for r in parts}
    tested = [p for v in verdicts for p in v.parts if p.status != "not tested"]
    for p in tested:
        p.ranges = margin_ranges(p)
        assert (p.name, p.range_text()) in shown, (p.name, p.range_text())
    three = [p for p in tested if [r[0] for r in p.ranges] == ["holds", "undecided", "contradicts"]]
    assert three, "no part that holds, then is undecided, then contradicted as the margin grows"
    assert section(text, "Margin-dependent claims") is not None


def test_figures_are_drawn_without_pyplot():
    """Every figure is a ``Figure`` saved by ``bench.kit``'s figure helpers: no module of the suite
    goes through pyplot's global state or switches the backend."""
    root = Path(__file__).resolve().parents[1]
    offenders = [
        f"{p.relative_to(root)}:{i}"
        for p in sorted((root / "bench").rglob("*.py"))
        for i, line in enumerate(p.read_text().splitlines(), 1)
        if re.search(
            r"import matplotlib\.pyplot|from matplotlib import pyplot|matplotlib\.use\(", line
        )
    ]
    assert not offenders, offenders


def test_every_built_in_model_has_a_colour():
    """A model drawn without one takes matplotlib's next colour, which another model of the
    same figure may have (the paper's MuJoCo HNN was drawn in NODE's blue)."""
    import models
    from bench.kit import TRIVIAL_MODELS
    from bench.kit._plot import COLORS
    from models import _registry

    built = [n for n in models.available() if n not in _registry._MODULES]
    assert [n for n in built if n not in TRIVIAL_MODELS and n not in COLORS] == []


def test_two_metrics_that_disagree_name_the_parts_where_they_part():
    """Claim 4 under geometric-mean error holds its spring edge, under MSE leaves it undecided:
    the metric cause names that part with its status, effect and interval under each metric;
    a part both metrics read alike is not named."""
    from bench.kit._stats import Part

    def v(variant, verdict, edge_status, edge):
        parts = [
            Part("chain edge", "holds", 2.0, 1.8, 2.2, 5),
            Part("spring edge", edge_status, edge, edge - 0.3, edge + 0.3, 5),
        ]
        return Verdict(4, "t", verdict, 0.1, 0.0, 0.2, 5, "d", variant=variant, parts=parts)

    gm, mse = "geometric-mean error, spring from paper", "MSE, spring from paper"
    here = [v(gm, PARTLY, "contradicts", 0.75), v(mse, INCONCLUSIVE, "undecided", 0.28)]
    others = [("a", "quick", [v(gm, REPRODUCED, "holds", 0.1), v(mse, REPRODUCED, "holds", 0.1)])]
    rows = {r.key: r for r in comparison_rows(here, "paper-core", others)}
    (note,) = [c.text for c in rows[f"4 ({gm})"].causes if c.kind == "metric"]
    assert note == (
        "metric: geometric-mean error and MSE disagree within a profile (the parts: spring "
        "edge: contradicts (0.75 [0.45, 1.05]) at geometric-mean error, undecided (0.28 "
        "[-0.02, 0.58]) at MSE)"
    )
