"""``python -m bench power``: the verdict engine's power on a results folder's claims, each
part's chance to sign at 5 and 10 seeds, into ``<results>/power.csv`` (the claims section of
the report reads it there)."""

from __future__ import annotations

from ....core import Command, int_arg, register_command


def _arguments(p):
    p.add_argument(
        "--simulations",
        type=int_arg("simulations"),
        default=2000,
        help="draws per part and number of seeds (default 2000)",
    )


def _run(args) -> int:
    from pathlib import Path

    from ....core import load_tables
    from ....kit import judge, power_lines, power_table

    results = Path(args.results)
    runs, curves, profile = load_tables(results)
    if not len(runs):
        raise ValueError(f"{results} holds no runs: nothing to simulate")
    j = judge(runs, curves, profile, loso=False)
    table = power_table(j.final, sims=args.simulations)
    out = results / "power.csv"
    table.to_csv(out, index=False)
    print("\n".join(power_lines(table)) or "no undecided part")
    print(f"wrote {out} ({len(table)} parts)")
    return 0


_HELP = (
    "the verdict engine's power: each part's chance to sign at 5 and 10 seeds at its observed "
    "effect and spread, and the seeds that would decide the undecided ones: <results>/power.csv"
)
COMMAND = register_command(Command("power", _HELP, _run, _arguments, _HELP))
