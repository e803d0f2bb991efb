"""The one registry of studies (name -> experiments, verdict rule, figure, report section), of
the command-line verbs they own, of the report sections they add before the experiments', and of
the suite's cost model (an estimate of a run's seconds, by which sweeps order their runs).

A study is a module under ``bench.studies`` (or a third-party module) that declares its
experiments and calls :func:`register_study` at import. The first read of a registry imports
the built-in studies (``bench.studies``), then the third-party ones. Third-party
studies are modules named by the Python entry-point group ``decon_bench.studies``; the tests add
modules with ``DECON_EXTRA_EXPERIMENTS`` (comma-separated module names). Both are imported once,
here, the first time the registry is read.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ._experiments import ENTRY_POINT_GROUP, Experiment, load_plugins, register

__all__ = [
    "ENTRY_POINT_GROUP",
    "Command",
    "ReportContext",
    "ReportSection",
    "Study",
    "commands",
    "register_command",
    "register_section",
    "register_cost_model",
    "register_study",
    "report_sections",
    "run_cost",
    "studies",
]


@dataclass(frozen=True)
class Study:
    """One study: its experiments, its verdict rule, its figure and its report section.

    ``rule(runs, curves) -> Verdict | list[Verdict]`` judges claim ``claim`` on the rows of the
    study's experiments (plus the stored rows tagged with an experiment in ``reads``);
    ``figure(rows, curves, outdir) -> list[Path]`` draws the finished rows of the study's first
    experiment into ``outdir/<stem>.{png,pdf}``. Studies with their own tables instead give
    ``results_figure(results_dir) -> list[Path]`` and ``section(results_dir) -> str`` (a
    Markdown section of the report, its figure ``figures/<stem>.png``). A study with both a
    ``figure`` and a ``section`` has its section closing its experiment's section of the report
    (claim 7's comparison of its two protocols)."""

    name: str
    experiments: tuple[Experiment, ...] = ()
    claim: int | None = None
    title: str = ""
    rule: Callable | None = None
    reads: tuple[str, ...] = ()
    figure: Callable | None = None
    stem: str | None = None
    results_figure: Callable[[Path], list[Path]] | None = None
    section: Callable[[Path], str] | None = None
    section_title: str = ""


_STUDIES: dict[str, Study] = {}


def register_study(study: Study) -> Study:
    """Add ``study`` and its experiments to the registries (re-registering replaces)."""
    if not isinstance(study, Study):
        raise ValueError(f"register_study expects a Study; got {type(study).__name__}")
    for exp in study.experiments:
        if study.claim is not None and exp.claim not in (None, study.claim):
            raise ValueError(
                f"study {study.name!r} judges claim {study.claim}; its experiment {exp.name!r} "
                f"says claim {exp.claim}"
            )
    for exp in study.experiments:
        register(exp, replace=True)
    _STUDIES[study.name] = study
    return study


def studies() -> list[Study]:
    """The registered studies, in registration order (the report's order)."""
    load_plugins()
    return list(_STUDIES.values())


def _no_arguments(parser: argparse.ArgumentParser) -> None:
    """A verb without options of its own."""


@dataclass(frozen=True)
class Command:
    """A verb of ``python -m bench`` that a study owns.

    ``add_arguments(parser)`` declares its options on its subparser; ``run(args) -> int`` runs
    it and returns the exit code (a ValueError is a bad input: one line, exit code 2).
    ``description`` is the text of ``<verb> --help`` where it differs from none."""

    name: str
    help: str
    run: Callable[[argparse.Namespace], int]
    add_arguments: Callable[[argparse.ArgumentParser], None] = _no_arguments
    description: str | None = None


@dataclass(frozen=True)
class ReportContext:
    """What a report section reads: the results folder, its stored tables and profile, the
    other folders to set beside it (``None``: the report's default), and ``memo``, where the
    sections of one study share what they computed once."""

    results_dir: Path
    runs: Any
    curves: Any
    profile: str | None
    compare: tuple[Path, ...] | None = None
    memo: dict = field(default_factory=dict)


@dataclass(frozen=True)
class ReportSection:
    """A part of REPORT.md placed after its header and before the experiments' sections:
    ``render(context) -> list[str]`` returns its Markdown lines."""

    name: str
    render: Callable[[ReportContext], list[str]]


_COMMANDS: dict[str, Command] = {}
_SECTIONS: dict[str, ReportSection] = {}


def register_command(command: Command) -> Command:
    """Add a verb to the command line (re-registering a name replaces it)."""
    if not isinstance(command, Command):
        raise ValueError(f"register_command expects a Command; got {type(command).__name__}")
    _COMMANDS[command.name] = command
    return command


def commands() -> list[Command]:
    """The registered verbs, in registration order (their order in ``--help``)."""
    load_plugins()
    return list(_COMMANDS.values())


def register_section(section: ReportSection) -> ReportSection:
    """Add a section to the report (re-registering a name replaces it)."""
    if not isinstance(section, ReportSection):
        raise ValueError(f"register_section expects a ReportSection; got {type(section).__name__}")
    _SECTIONS[section.name] = section
    return section


def report_sections() -> list[ReportSection]:
    """The registered report sections, in registration order (the report's order)."""
    load_plugins()
    return list(_SECTIONS.values())


_COST_MODEL: list[Callable] = []


def register_cost_model(seconds: Callable) -> Callable:
    """Make ``seconds(config) -> float``, an estimate of one run's seconds, the suite's cost
    model: sweeps run the longest runs first by it (:func:`run_cost`). The last one registered
    counts."""
    if not callable(seconds):
        raise ValueError(f"register_cost_model expects a callable; got {type(seconds).__name__}")
    _COST_MODEL[:] = [seconds]
    return seconds


def run_cost(config) -> float:
    """The registered cost model's estimate of ``config``'s seconds; without one, a proxy
    proportional to its training work (steps x batch x width)."""
    load_plugins()
    if _COST_MODEL:
        return float(_COST_MODEL[0](config))
    return float(config.steps * config.batch * config.width)
