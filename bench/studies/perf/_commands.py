"""``python -m bench perf``: the performance measurements, written to the results folder."""

from __future__ import annotations

from ...core import Command, register_command, usable_results


def _arguments(p):
    p.add_argument(
        "--ensemble",
        action="store_true",
        help="runs per minute, ensembles vs one at a time (perf_ensemble.csv in --results)",
    )


def _run(args) -> int:
    from ._main import main  # pins the threads: imported only to measure

    # its own defaults (`python -m bench.studies.perf --help`); written to --results
    results = usable_results(args)
    ens = getattr(args, "ensemble", False)
    name = "perf_ensemble.csv" if ens else "perf.csv"
    out = main([*(["--ensemble"] if ens else []), "--out", str(results / name)])
    return int(out or 0)


COMMAND = register_command(
    Command("perf", "performance measurements (bench.studies.perf)", _run, _arguments)
)
