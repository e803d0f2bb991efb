"""``python -m bench diagnose-hnn``: the plain HNN's first training steps on the spring,
replayed and probed, into ``<results>/hnn_diagnosis.csv``."""

from __future__ import annotations

from ....core import Command, int_arg, register_command, usable_results


def _arguments(p):
    p.add_argument("--profile", default="paper-core", help="smoke, quick, paper or paper-core")
    p.add_argument(
        "--steps", type=int_arg("steps"), default=None, help="probe steps (default: by profile)"
    )


def _run(args) -> int:
    from ....core import read_rows, rows_frame
    from ._diagnosis import FILE, diagnose, summary

    results = usable_results(args)
    df = diagnose(args.profile, results, steps=args.steps)
    print(summary(df, rows_frame(read_rows(results))))
    print(f"wrote {results / FILE} ({len(df)} rows)")
    return 0


_HELP = (
    "the first training steps of the plain HNN on the spring, replayed and probed "
    "(claims 1 and 3): <results>/hnn_diagnosis.csv"
)
COMMAND = register_command(Command("diagnose-hnn", _HELP, _run, _arguments, _HELP))
