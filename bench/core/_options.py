"""Command-line options and checks shared by the CLI's verbs and the verbs the studies register.

Here, in the core beside the registry of verbs (:mod:`._studies`), so that a study's verb parses
``--workers`` or ``--seeds`` and runs a sweep the way ``python -m bench sweep`` does without
importing the CLI, and the CLI parses them without importing a study.
"""

from __future__ import annotations

import argparse
import math
import re
from pathlib import Path

from ._experiments import PROFILES
from ._vocab import check_choice

__all__ = [
    "SEEDS_FORMS",
    "check_sweep_args",
    "float_arg",
    "int_arg",
    "model_list",
    "seed_list",
    "sweep_from_args",
    "sweep_options",
    "usable_results",
]


def int_arg(name):
    """An argparse ``type``: an integer, or ``<name> must be an integer`` in one line."""

    def parse(s):
        try:
            return int(s)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be an integer; got {s!r}") from None

    return parse


def float_arg(name):
    """An argparse ``type``: a finite number, or one line saying what ``name`` must be."""

    def parse(s):
        try:
            v = float(s)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be a number; got {s!r}") from None
        if not math.isfinite(v):
            raise argparse.ArgumentTypeError(f"{name} must be finite; got {s!r}")
        return v

    return parse


def sweep_options(p, default_profile):
    """The options of every verb that sweeps (sweep, bench, campaign)."""
    p.add_argument("--profile", default=default_profile, help=f"one of {', '.join(PROFILES)}")
    p.add_argument(
        "--models",
        default=None,
        metavar="A,B",
        help="replace the experiments' trained models with these (built-in or plug-in names); "
        "their trivial predictors stay",
    )
    p.add_argument("--executor", default="local", help="local (default) or ray")
    p.add_argument("--address", default=None, help="Ray cluster address (ray executor)")
    p.add_argument(
        "--workers",
        type=int_arg("workers"),
        default=1,
        help="local processes (default 1: in-process; 0: one per core)",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument(
        "--ensemble",
        default="auto",
        help="auto (default: on when jax's backend is an accelerator), on or off: train runs "
        "that differ only in seed, lr or noise as one vmapped program",
    )


def check_sweep_args(args):
    """ValueError (one line) for a bad value of the :func:`sweep_options`."""
    check_choice("profile", args.profile, list(PROFILES))
    check_choice("executor", args.executor, ["local", "ray"])
    check_choice("ensemble", args.ensemble, ["auto", "on", "off"])
    if args.workers < 0:
        raise ValueError(f"workers must be an integer >= 0; got {args.workers}")


def usable_results(args) -> Path:
    """The results folder, created and writable, or a one-line ValueError (exit code 2)."""
    from ._store import check_results_dir

    return check_results_dir(args.results, create=True)


_SEED_ITEM = re.compile(r"\s*(\d+)\s*(?:-\s*(\d+)\s*)?", re.ASCII)  # 7 or 0-4
SEEDS_FORMS = "integers >= 0 or ranges a-b (a <= b), comma-separated: 5,6,7 or 0-4 or 0-4,7"


def seed_list(given: str | None) -> tuple[int, ...] | None:
    """``--seeds`` as a tuple of distinct integers >= 0, in the order given: ``5,6,7``, a range
    ``0-4`` (both ends included, as the docs write seeds) or a mix ``0-4,7``. ValueError in
    one line naming the allowed forms (:data:`SEEDS_FORMS`) otherwise."""
    if given is None:
        return None
    seeds: list[int] = []
    for item in str(given).split(","):
        match = _SEED_ITEM.fullmatch(item)
        first, last = (int(match[1]), int(match[2] or match[1])) if match else (0, -1)
        if first > last:  # not an integer or a range, or a range that runs backwards
            raise ValueError(f"--seeds must be {SEEDS_FORMS}; got {given!r}")
        seeds.extend(range(first, last + 1))
    return tuple(dict.fromkeys(seeds))


def model_list(args) -> list[str] | None:
    """``--models a,b`` as a list of registered names (ValueError naming the allowed ones)."""
    import models

    given = getattr(args, "models", None)
    if given is None:
        return None
    names = [m.strip() for m in given.split(",") if m.strip()]
    if not names:
        raise ValueError("--models needs at least one model name")
    for m in names:
        check_choice("model", m, models.available())
    return names


def sweep_from_args(args, names, *, order=None, seeds=None, where=None) -> dict:
    """One sweep of ``names`` with the :func:`sweep_options` of ``args`` (``where``: a
    predicate on the runs to keep), the longest runs first by ``order`` (default: the registered
    cost model, :func:`bench.core.run_cost`)."""
    from ._runner import run_experiments as run
    from ._studies import run_cost

    return run(
        names,
        args.profile,
        args.results,
        seeds=seeds,
        models=model_list(args),
        where=where,
        order=run_cost if order is None else order,
        executor=args.executor,
        workers=None if args.workers == 0 else args.workers,
        address=args.address,
        progress=not args.no_progress,
        ensemble=args.ensemble,
    )
