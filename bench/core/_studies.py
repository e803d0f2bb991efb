"""The one registry of studies: name -> experiments, verdict rule, figure and report section.

A study is a module under ``bench.studies`` (or a third-party module) that declares its
experiments and calls :func:`register_study` at import. ``bench`` imports ``bench.studies``, so
the built-in studies are registered whenever any part of ``bench`` is loaded. Third-party
studies are modules named by the Python entry-point group ``decon_bench.studies``; the tests add
modules with ``DECON_EXTRA_EXPERIMENTS`` (comma-separated module names). Both are imported once,
here, the first time the registry is read.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ._experiments import ENTRY_POINT_GROUP, Experiment, load_plugins, register

__all__ = ["ENTRY_POINT_GROUP", "Study", "register_study", "studies"]


@dataclass(frozen=True)
class Study:
    """One study: its experiments, its verdict rule, its figure and its report section.

    ``rule(runs, curves) -> Verdict | list[Verdict]`` judges claim ``claim`` on the rows of the
    study's experiments (plus the stored rows tagged with an experiment in ``reads``);
    ``figure(rows, curves, outdir) -> list[Path]`` draws the finished rows of the study's first
    experiment into ``outdir/<stem>.{png,pdf}``. Studies with their own tables instead give
    ``results_figure(results_dir) -> list[Path]`` and ``section(results_dir) -> str`` (a
    Markdown section of the report, its figure ``figures/<stem>.png``)."""

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
