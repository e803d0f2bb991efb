"""README's findings table says what the committed reports say, and the README stays short."""

import re
import shutil

import pytest
from _markdown import cells, table_rows

from bench import findings

README_LIMIT = 12 * 1024


def test_readme_findings_match_the_reports():
    assert findings.current() == findings.findings(), "run python -m bench.findings"


def test_readme_is_short_with_the_findings_on_its_first_screen():
    text = findings.README.read_text()
    assert len(text.encode()) <= README_LIMIT
    assert text.index(findings.BEGIN) < text.index("## The two commands")
    assert text[: text.index(findings.BEGIN)].count("\n") < 40


def _copy(tmp_path):
    for d in findings.BUDGETS.values():
        (tmp_path / d).mkdir(parents=True)
        shutil.copy(findings.ROOT / d / "REPORT.md", tmp_path / d / "REPORT.md")
    readme = tmp_path / "README.md"
    shutil.copy(findings.README, readme)
    return readme


def test_a_changed_verdict_changes_the_table_and_the_check(tmp_path):
    readme = _copy(tmp_path)
    report = tmp_path / findings.BUDGETS["paper-core"] / "REPORT.md"
    table = findings.claims_table(report.read_text())
    row = table["5"]
    line = next(x for x in report.read_text().splitlines() if x.startswith("| 5 |"))
    report.write_text(report.read_text().replace(line, line.replace(row["verdict"], "**no way**")))
    new = findings.findings(tmp_path)
    cell = findings._replicated({**row, "verdict": "**no way**"})  # with its seeds 5-9 state
    assert cell.startswith("**no way**")
    rows = {r["claim"]: r for r in table_rows(new, "| claim | the paper says")}
    assert rows["5"]["paper-core (seeds 0-4, then 5-9)"] == cell
    assert findings.current(readme) != new
    assert findings.write(readme, tmp_path) and findings.current(readme) == new
    assert not findings.write(readme, tmp_path)


@pytest.mark.parametrize(
    ("primary", "replication", "replicates", "cell"),
    [
        (
            "partly reproduced (5)",
            "partly reproduced (5)",
            "yes",
            "**partly reproduced**, replicates",
        ),
        (
            "partly reproduced (5)",
            "not reproduced (5)",
            "**no**",
            "**inconclusive (does not replicate)**: 0-4 partly reproduced, 5-9 not reproduced",
        ),
        (
            "reproduced (5)",
            "-",
            "pending (3 of 50 runs)",
            "**reproduced**; 5-9 pending (3 of 50 runs)",
        ),
        ("reproduced (5)", "-", "not run", "**reproduced**; 5-9 not run"),
        (
            "not reproduced (5)",
            "not reproduced (5)",
            "yes",
            "**partly reproduced**, replicates (pooled; 0-4 and 5-9: not reproduced each)",
        ),
    ],
)
def test_the_paper_core_cell_states_each_seed_sets_reading(primary, replication, replicates, cell):
    verdict = "**inconclusive (does not replicate)**" if replicates == "**no**" else None
    if cell.startswith("**partly reproduced**, replicates (pooled"):
        verdict = "**partly reproduced**"  # the pooled reading, unlike each set's
    row = {
        "verdict": verdict or "**" + primary.removesuffix(" (5)") + "**",
        "seeds 0-4": primary,
        "seeds 5-9": replication,
        "replicates": replicates,
    }
    assert findings._replicated(row) == cell
    assert findings._replicated(None) == "not run"
    # a report without replication columns (an older one) gives the verdict alone
    assert findings._replicated({"verdict": "**reproduced**"}) == "**reproduced**"


def test_claims_table_reads_every_column_and_refuses_a_report_without_one():
    text = (findings.ROOT / findings.BUDGETS["quick"] / "REPORT.md").read_text()
    table = findings.claims_table(text)
    assert "1" in table and "2" not in table  # claim 2 does not run at quick
    assert {"statement", "verdict", "effect", "90% CI", "discriminating"} <= set(table["1"])
    with pytest.raises(ValueError, match="no claims table"):
        findings.claims_table("# a report\n\nno table here\n")


def test_the_seeds_protocols_come_from_each_claims_section():
    from bench.kit._protocols import HEADER, ROWS, Protocol, protocol_table

    F = findings
    assert F.PROTOCOL_HEADER == HEADER
    rows = dict.fromkeys(ROWS, "-")
    ours = Protocol({**rows, "data": "a", "loss": "squared error", "steps": "100"})
    seeds = Protocol({**rows, "data": "b", "loss": "L1", "steps": "600000"})
    report = "\n".join(
        [
            "## Claims",
            "",
            "## Something (claim 9)",
            *protocol_table(ours, seeds, "the steps"),
            "",
            "## Other (claim 10)",
            "no table here",
        ]
    )
    got = F.protocols(report)
    assert list(got) == [9]
    assert got[9]["loss"] == ("squared error", "L1")
    assert got[9]["verdict"] == ("not run", "not run")
    lines = F._protocol_lines({"quick": report, "paper-core": "## Claims"})
    assert cells(lines[-1]) == ["9", "- / -", *["not run / not run"] * 3]
    # each budget's learning gates from its own report
    gates = report.replace("| learned | - | - |", "| learned | HNN yes | HNN no |")
    lines = F._protocol_lines({"quick": report, "paper-core": gates})
    assert cells(lines[-1])[3] == "HNN yes / HNN no"


def test_compute_is_summed_per_device_and_reaches_the_readme_sentence(tmp_path):
    import numpy as np
    import pandas as pd

    from bench._report import compute_lines

    runs = pd.DataFrame(
        {
            "device": ["cpu A", "cpu A", "cpu A", "gpu B"],
            "wall_seconds": [3600.0, 1800.0, 1800.0, 90.0],
            "cpu_seconds": [3000.0, np.nan, 2400.0, np.nan],
        }
    )
    lines = compute_lines(runs)
    assert lines == [
        "- compute on cpu A: 3 runs, 2.0 h run wall time, 1.5 h CPU time (measured by 2)",
        "- compute on gpu B: 1 run, 1.5 min run wall time",
    ]
    for folder, text in ((findings.BUDGETS["paper-core"], lines[0]), (findings.GPU, lines[1])):
        (tmp_path / folder).mkdir(parents=True)
        (tmp_path / folder / "REPORT.md").write_text(f"# report\n\n{text}\n- other: 1\n")
    sentence = findings.compute_sentence(tmp_path)
    said = re.findall(r"(\S+) on ([^:;]+): (\d+) runs?,", sentence)
    assert said == [("paper-core", "cpu A", "3"), ("paper_gpu", "gpu B", "1")], sentence


def test_an_ensemble_member_without_its_share_of_wall_time_is_counted_and_named():
    import pandas as pd

    from bench._report import compute_lines

    runs = pd.DataFrame(
        {
            "device": ["gpu"] * 4,
            "ensemble_size": [10, 10, 10, 1],
            # first member: stored before the share; second: with it; fourth: trained alone
            "wall_seconds": [0.5, 61.0, 0.5, 30.0],
            "train_seconds": [50.0, 50.0, 50.0, 20.0],
            "compile_seconds": [10.0, 10.0, 10.0, 5.0],
        }
    )
    runs.loc[2, "ensemble_size"] = 1  # alone and fast: its wall is what it is
    assert compute_lines(runs) == [
        "- compute on gpu: 4 runs, 2.5 min run wall time"
        " (with 1.0 min of ensemble training that 1 row's stored wall time lacks)"
    ]
    assert compute_lines(runs.assign(ensemble_size=1)) == [
        "- compute on gpu: 4 runs, 1.5 min run wall time"
    ]


def test_a_protocols_verdict_cell_is_read_per_seed_set():
    from bench.findings import _short

    assert _short("not run") == "not run"
    assert _short("reproduced (seeds 0-4)") == "reproduced"
    both = "inconclusive (seeds 0-4), untested: HNN did not learn; inconclusive (seeds 5-9)"
    assert _short(both) == "inconclusive, replicates"
    assert _short("not reproduced (seeds 0-4); partly reproduced (seeds 5-9)") == (
        "not reproduced, does not replicate"
    )
    waiting = "partly reproduced (seeds 0-4); pending (0 of 20 runs, seeds 5-9)"
    assert _short(waiting) == "partly reproduced; 5-9 pending"
    assert _short("pending (3 of 20 runs, seeds 0-4); pending (0 of 20 runs, seeds 5-9)") == (
        "pending"
    )


def test_margin_dependent_readings_of_one_claim_are_counted():
    from bench.findings import _grouped

    keys = "1, 4 (geometric-mean error, spring from paper), 4 (MSE, spring from paper), 5"
    assert _grouped(keys) == "1, 4 (2 readings), 5"
    assert _grouped("7 (rollout loss), 10") == "7 (rollout loss), 10"


def test_a_pending_claim_is_not_called_margin_dependent():
    from bench.kit import Verdict
    from bench.kit._sensitivity import Dependence
    from bench.studies.paper.report._sections import _dependence_section

    def v(key, pending=None):
        return Verdict(int(key), "t", "inconclusive", 0.0, 0.0, 0.0, 5, "", pending=pending)

    deps = [Dependence(k, "error", ((1.5, "reproduced"),), "inconclusive") for k in ("1", "12")]

    def shown(final):
        text = "\n".join(_dependence_section(deps, final))
        rows = [r["claim"] for r in table_rows(text, "| claim | quantity")]
        named = re.search(r"^Margin-dependent: claim (.*)\.$", text, re.M).group(1)
        return rows, named.split(", ")

    assert shown([v("1"), v("12", pending=(27, 30))]) == (["1"], ["1"])
    assert shown([v("1"), v("12")]) == (["1", "12"], ["1", "12"])


def test_the_sentences_say_what_holds_what_is_contradicted_and_what_is_open():
    def row(verdict, disc="yes"):
        return {"verdict": f"**{verdict}**", "discriminating": disc}

    core = {
        "1": row("partly reproduced: headline contradicted"),
        "2": row("reproduced"),
        "4 (a)": row("inconclusive (does not replicate)"),
        "4 (b)": row("inconclusive (does not replicate)"),
        "13": row("inconclusive", "**no**"),
        "9": row("not reproduced"),
    }
    quick = {"3": row("partly reproduced: headline holds"), "2": row("inconclusive")}
    papers = {1: "deconstructing", 2: "deconstructing", 3: "deconstructing", 4: "deconstructing"}
    papers |= {13: "deconstructing", 9: "lnn"}
    said = _summary_facts(findings.summary(core, quick, papers))
    assert said == {
        "The Deconstructing paper": {
            "holds": [("2", "reproduced"), ("3 (quick)", "partly reproduced: headline holds")],
            "contradicted in part or whole": [("1", "partly reproduced: headline contradicted")],
            "not decided": [
                ("4", "inconclusive, does not replicate, 2 of 2 readings"),
                ("13", "inconclusive, not discriminating"),
            ],
        },
        "The LNN seed": {"contradicted in part or whole": [("9", "not reproduced")]},
    }


def _summary_facts(lines):
    """The summary's sentences read back: per paper, per group (holds, contradicted, not
    decided), the claims it names, each as (claim, its reading)."""
    out = {}
    for line in lines:
        paper, text = re.fullmatch(r"- \*\*(.+?)\.\*\* (.*)\.", line).groups()
        groups = {}
        for said in text.split("; "):
            group, claims = said.split(": claim ", 1)
            named = re.findall(
                r"(?:^|, | and )(\d+(?: \(quick\))?) \(((?:[^()]|\([^()]*\))*)\)", claims
            )
            groups[group.lower()] = named
        out[paper] = groups
    return out
