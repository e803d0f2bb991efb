"""The pixel protocols' diagnoses as verbs of ``python -m bench`` (``diagnose-vin``,
``diagnose-hnn-seed-pixels``): each protocol's runs beside the same runs with one element
changed (:mod:`._ablation`), into the ablation's CSV file."""

from __future__ import annotations

from ....core import Command, register_command, seed_list, usable_results
from ._ablation import ABLATIONS


def _arguments(p):
    p.add_argument("--profile", default="paper-core", help="smoke, quick or paper-core")
    p.add_argument("--seeds", default=None, metavar="0,1", help="only these seeds")
    p.add_argument(
        "--runs-from",
        action="append",
        default=[],
        metavar="DIR",
        help="a results folder holding runs of the variants' configurations (read by "
        "config_hash instead of training them again); repeatable",
    )


def _command(ablation) -> Command:
    def run(args) -> int:
        from ._ablation import diagnose, summary

        results = usable_results(args)
        df = diagnose(
            ablation, args.profile, results, seeds=seed_list(args.seeds), runs_from=args.runs_from
        )
        print(summary(ablation, df))
        print(f"wrote {results / ablation.file} ({len(df)} rows)")
        return 0

    return Command(ablation.command, ablation.help, run, _arguments, ablation.help)


COMMANDS = tuple(register_command(_command(a)) for a in ABLATIONS)
