"""``python -m bench stability``: run the stability cases into ``<results>/stability.csv``."""

from __future__ import annotations

from pathlib import Path

from ...core import PROFILES, Command, check_choice, int_arg, register_command, usable_results


def _arguments(p):
    p.add_argument("--profile", default="quick", help=f"one of {', '.join(PROFILES)}")
    p.add_argument("--case", action="append", default=None, help="run only these cases")
    p.add_argument(
        "--workers",
        type=int_arg("workers"),
        default=1,
        help="processes (default 1: in-process; 0: one per core)",
    )


def _run(args) -> int:
    from ...core import cpu_count
    from ._run import CASES, run_stability

    check_choice("profile", args.profile, list(PROFILES))
    if args.case:
        for c in args.case:
            check_choice("stability case", c, list(CASES))
    usable_results(args)
    workers = getattr(args, "workers", 1)
    if workers < 0:
        raise ValueError(f"workers must be an integer >= 0; got {workers}")
    workers = cpu_count() if workers == 0 else workers
    df = run_stability(Path(args.results), args.profile, args.case, workers=workers)
    counts = df["outcome"].value_counts().to_dict() if len(df) else {}
    print(f"stability: {len(df)} rows {counts} -> {Path(args.results) / 'stability.csv'}")
    return 0


COMMAND = register_command(
    Command("stability", "numerical stability cases (results/stability.csv)", _run, _arguments)
)
