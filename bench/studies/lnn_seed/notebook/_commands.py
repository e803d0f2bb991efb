"""``python -m bench diagnose-lnn``: the learned d2L/dqdot2 of the double pendulum's LNNs
(:mod:`._diagnosis`) into ``<results>/lnn_diagnosis.csv``."""

from __future__ import annotations

from ....core import Command, register_command, usable_results


def _arguments(p):
    p.add_argument("--profile", default="quick", help="smoke, quick, paper or paper-core")


def _run(args) -> int:
    from ._diagnosis import FILE, diagnose, summary

    results = usable_results(args)
    df = diagnose(args.profile, results)
    print(summary(df))
    print(f"wrote {results / FILE} ({len(df)} rows)")
    return 0


_HELP = (
    "the learned d2L/dqdot2 of the double pendulum's LNNs at init and along rollouts "
    ": <results>/lnn_diagnosis.csv"
)
COMMAND = register_command(Command("diagnose-lnn", _HELP, _run, _arguments, _HELP))
