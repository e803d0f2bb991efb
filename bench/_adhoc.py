"""``python -m bench run``: one ad-hoc run from the command line. Its RunConfig is the profile's
defaults with the given fields (``--set FIELD=VALUE`` for any other); the run is stored as
experiment ``adhoc`` and its main metrics printed.
"""

from __future__ import annotations

import argparse
import json

from .core import (
    PROFILES,
    RunConfig,
    check_choice,
    field_names,
    float_arg,
    int_arg,
    profile_defaults,
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The ``run`` verb's options."""
    p.add_argument("--system", required=True)
    p.add_argument("--k", type=int_arg("k"), default=None)
    p.add_argument("--friction", type=float_arg("friction"), default=0.0)
    p.add_argument("--model", default="node")
    p.add_argument("--seed", type=int_arg("seed"), default=0)
    p.add_argument("--profile", default="smoke", help=f"one of {', '.join(PROFILES)}")
    p.add_argument("--width", type=int_arg("width"))
    p.add_argument("--depth", type=int_arg("depth"))
    p.add_argument("--steps", type=int_arg("steps"))
    p.add_argument("--lr", type=float_arg("lr"))
    p.add_argument("--coordinates")
    p.add_argument("--integrator", help="train and eval integrator")
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="FIELD=VALUE",
        help="any other RunConfig field (JSON value), repeatable",
    )


def config_from_args(args) -> RunConfig:
    """The run of the options: the profile's defaults, the options given, then ``--set``."""
    base, _ = profile_defaults(args.profile)  # ValueError naming the profiles
    kw = dict(base)
    kw.update(system=args.system, k=args.k, friction=args.friction, model=args.model)
    kw["seed"] = args.seed
    for name in ("width", "depth", "steps", "lr", "coordinates"):
        if getattr(args, name) is not None:
            kw[name] = getattr(args, name)
    if args.integrator is not None:
        kw["train_integrator"] = kw["eval_integrator"] = args.integrator
    names = field_names()
    for item in args.set:
        if "=" not in item:
            raise ValueError(f"--set expects FIELD=VALUE; got {item!r}")
        key, value = item.split("=", 1)
        check_choice("RunConfig field", key, names)
        try:
            kw[key] = json.loads(value)
        except ValueError:
            kw[key] = value
    # ValueError for a bad value, system or dataset shape; the model for the scene and the
    # integrators it allows are checked by the sweep, before it writes anything
    return RunConfig(**kw)


# The metrics ``run`` prints, in order (error and diverged_step only where set).
_ROW_KEYS = (
    "status error diverged_step rollout_error energy_violation mse valid_time floor "
    "rollout_error_ref energy_pct_max_pe symplectic_error train_seconds compile_seconds "
    "rollout_seconds nfe n_params config_hash"
).split()


def _print_row(row: dict) -> None:
    for k in _ROW_KEYS:
        v = row.get(k)
        if v is None and k in ("error", "diverged_step"):
            continue
        if isinstance(v, float):
            v = f"{v:.4g}"
        print(f"{k:>18}: {v}")


def run(args) -> int:
    """Run (or find stored) the configuration of the options and print its row."""
    from .core import sweep

    cfg = config_from_args(args)
    row = sweep([cfg], args.results, experiment="adhoc", profile=args.profile, progress=False)
    if not row:  # already stored: show the stored row
        from .core import read_rows

        row = [r for r in read_rows(args.results) if r["config_hash"] == cfg.config_hash]
        print("(already stored; delete its row file to rerun)")
    _print_row(row[0])
    return 0 if row[0]["status"] != "failed" else 1
