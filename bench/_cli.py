"""Command line: ``python -m bench <verb>`` (placeholder until the runner lands)."""

from __future__ import annotations

import argparse


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench", description=__doc__)
    sub = parser.add_subparsers(dest="verb", required=True)
    b = sub.add_parser("bench", help="run every experiment, then figures and report")
    b.add_argument("--profile", default="quick")
    args = parser.parse_args(argv)
    if args.verb == "bench":
        print("no experiments yet")
    return 0
