"""Every registered study, verb and report section goes through the same checks, so that a new
one is tested by registering it.

A study declares what it measures (experiments, or tables of its own that it writes and
reports), how it is read (a verdict rule, or a report section that shows its data), a figure,
and a report section (its own, or the report's table-and-figure section of its experiment). A
verb has a help line and answers ``--help`` in-process.
"""

import pytest

from bench._cli import main
from bench.core import Command, ReportSection, _studies, commands, report_sections, studies

# Studies that lean on a sibling today: what each lacks, and why. The test below fails when a
# gap closes (remove it here) or a new one opens.
KNOWN_GAPS = {
    "pixel_pendulum_vin": {
        "figure": "claim 12 is drawn in the pixel figure of pixel_pendulum_hnn",
        "report section": "claim 12 is reported in the pixel section of pixel_pendulum_hnn",
    },
    "hnn_diagnosis": {"figure": "a diagnosis table (hnn_diagnosis.csv), reported without one"},
}


def _gaps(study) -> set[str]:
    experiment_section = study.figure is not None  # the report's table and figure of its runs
    own_tables = study.results_figure is not None or study.section is not None
    declared = {
        "experiments": bool(study.experiments) or own_tables,
        "rule or section": study.rule is not None or study.section is not None
        or experiment_section,
        "figure": study.figure is not None or study.results_figure is not None,
        "report section": study.section is not None or experiment_section,
    }  # fmt: skip
    return {what for what, ok in declared.items() if not ok}


@pytest.mark.parametrize("study", studies(), ids=lambda s: s.name)
def test_every_study_declares_experiments_rule_figure_and_section(study):
    assert _gaps(study) == set(KNOWN_GAPS.get(study.name, {})), study
    if study.rule is not None:
        assert study.claim is not None and study.title, study.name
    if study.figure is not None:
        assert study.stem, f"{study.name} draws a figure without a file stem"
    if study.section is not None:
        assert study.section_title, f"{study.name}: a failed section needs its title"


def test_known_gaps_name_registered_studies():
    assert set(KNOWN_GAPS) <= {s.name for s in studies()}


@pytest.mark.parametrize("command", commands(), ids=lambda c: c.name)
def test_every_command_has_help_and_answers_help(command, capsys):
    assert isinstance(command, Command) and command.help.strip()
    with pytest.raises(SystemExit) as e:
        main([command.name, "--help"])
    assert e.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith(f"usage: python -m bench {command.name}"), out


def test_the_studies_own_their_verbs():
    assert {"estimate", "campaign", "stability", "perf"} <= {c.name for c in commands()}
    assert {"diagnose-lnn", "diagnose-hnn", "diagnose-vin"} <= {c.name for c in commands()}


def test_a_registered_command_is_a_verb(monkeypatch, capsys):
    def add(p):
        p.add_argument("--times", type=int, default=1)

    def run(args):
        print("toy " * args.times)
        return 3

    toy = Command("toy-verb", "a verb of a plug-in", run, add)
    monkeypatch.setitem(_studies._COMMANDS, toy.name, toy)
    assert main(["toy-verb", "--times", "2"]) == 3
    assert capsys.readouterr().out == "toy toy \n"
    assert main(["toy-verb", "--times", "x"]) == 2  # a bad option: one line, exit code 2
    with pytest.raises(ValueError, match="expects a Command"):
        _studies.register_command("toy-verb")


def test_every_report_section_is_named():
    sections = report_sections()
    assert [s.name for s in sections][:2] == ["claims", "margin policy"]
    for s in sections:
        assert isinstance(s, ReportSection) and s.name and callable(s.render)
    with pytest.raises(ValueError, match="expects a ReportSection"):
        _studies.register_section(lambda ctx: [])
