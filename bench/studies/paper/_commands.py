"""The paper's verbs of ``python -m bench``: the campaign's estimate and sweep, and the
diagnoses of the plain HNN, the double pendulum's LNNs and the pixel VIN."""

from __future__ import annotations

from ...core._config import check_choice
from ...core._experiments import PROFILES
from ...core._studies import Command, register_command
from .._options import (
    check_sweep_args,
    int_arg,
    run_experiments,
    seed_list,
    sweep_options,
    usable_results,
)


def _estimate_arguments(p):
    p.add_argument("--profile", default="paper-core", help=f"one of {', '.join(PROFILES)}")
    p.add_argument("--workers", type=int_arg("workers"), default=2, help="for the wall hours")


def _estimate(args) -> int:
    from ...core._experiments import SELECTIONS, replication_seeds
    from ._campaign import CAMPAIGN_CLAIMS, cheapest_first, format_plan, plan, replication_order

    check_choice("profile", args.profile, list(PROFILES))
    if args.workers < 1:
        raise ValueError(f"workers must be an integer >= 1; got {args.workers}")
    first = cheapest_first(CAMPAIGN_CLAIMS, args.results, args.profile)
    df = plan(args.profile, args.results, workers=args.workers, order=first)
    print(f"results: {args.results}")
    print(format_plan(df, args.profile, args.workers))
    seeds = replication_seeds(args.profile)
    if args.profile in SELECTIONS and seeds:  # a campaign's second phase (make paper-core)
        order = replication_order(args.results, args.profile)
        rep = plan(
            args.profile, args.results, workers=args.workers, seeds=seeds, prior=df, order=order
        )
        print()
        print(format_plan(rep, args.profile, args.workers, seeds=seeds))
    return 0


def _lnn_arguments(p):
    p.add_argument("--profile", default="quick", help="smoke, quick or paper")


def _diagnose_lnn(args) -> int:
    from ._lnn_diagnosis import FILE, diagnose, summary

    results = usable_results(args)
    df = diagnose(args.profile, results)
    print(summary(df))
    print(f"wrote {results / FILE} ({len(df)} rows)")
    return 0


def _hnn_arguments(p):
    p.add_argument("--profile", default="paper-core", help="smoke, quick, paper or paper-core")
    p.add_argument(
        "--steps", type=int_arg("steps"), default=None, help="probe steps (default: by profile)"
    )


def _diagnose_hnn(args) -> int:
    from ...core._store import read_rows, rows_frame
    from ._hnn_diagnosis import FILE, diagnose, summary

    results = usable_results(args)
    df = diagnose(args.profile, results, steps=args.steps)
    print(summary(df, rows_frame(read_rows(results))))
    print(f"wrote {results / FILE} ({len(df)} rows)")
    return 0


def _vin_arguments(p):
    p.add_argument("--profile", default="paper-core", help="smoke, quick or paper-core")
    p.add_argument("--seeds", default=None, metavar="0,1", help="only these seeds")


def _diagnose_vin(args) -> int:
    from ._vin_diagnosis import FILE, diagnose, summary

    results = usable_results(args)
    df = diagnose(args.profile, results, seeds=seed_list(args.seeds))
    print(summary(df))
    print(f"wrote {results / FILE} ({len(df)} rows)")
    return 0


def _campaign_arguments(p):
    sweep_options(p, default_profile="paper-core")
    p.add_argument(
        "--replication",
        action="store_true",
        help="on the profile's replication seeds instead of its own "
        "(quick, paper, paper-core: 5-9)",
    )


def _campaign(args) -> int:
    from ...core._experiments import replication_seeds
    from ._campaign import (
        CAMPAIGN_CLAIMS,
        campaign_experiments,
        cheapest_first,
        priority,
        replication_order,
    )

    check_sweep_args(args)
    if not campaign_experiments(args.profile):
        raise ValueError(f"profile {args.profile!r} has no claim experiments to run")
    seeds, order = None, CAMPAIGN_CLAIMS
    if args.replication:
        seeds = replication_seeds(args.profile) or None
        if seeds is None:
            allowed = [p for p in PROFILES if replication_seeds(p)]
            check_choice("profile with replication seeds", args.profile, allowed)
    usable_results(args)
    if seeds:  # the claims with a signed verdict first (an inconclusive one cannot change)
        order = replication_order(args.results, args.profile)
    else:  # the cheapest claims first: the most verdicts per hour
        order = cheapest_first(CAMPAIGN_CLAIMS, args.results, args.profile)
    names = campaign_experiments(args.profile, order)
    which = f" seeds {', '.join(map(str, seeds))}" if seeds else ""
    print(f"campaign {args.profile}{which} -> {args.results}: {', '.join(names)}", flush=True)
    # claim by claim, longest runs first within a claim
    res = run_experiments(args, names, order=priority(args.profile, seeds, order), seeds=seeds)
    for name, rows in res.items():
        print(f"{name}: {len(rows)} new runs", flush=True)
    return 0


_LNN_HELP = (
    "the learned d2L/dqdot2 of the double pendulum's LNNs at init and along rollouts "
    ": <results>/lnn_diagnosis.csv"
)
_HNN_HELP = (
    "the first training steps of the plain HNN on the spring, replayed and probed "
    "(claims 1 and 3): <results>/hnn_diagnosis.csv"
)
_VIN_HELP = (
    "the latent VIN of the pixel pendulum trained again without the auxiliary latent loss, "
    "beside the protocol's VIN and ResNet (claim 12): <results>/vin_diagnosis.csv"
)

COMMANDS = tuple(
    register_command(c)
    for c in (
        Command(
            "estimate",
            "runs and hours per claim of a profile's campaign (stored, left)",
            _estimate,
            _estimate_arguments,
        ),
        Command("diagnose-lnn", _LNN_HELP, _diagnose_lnn, _lnn_arguments, _LNN_HELP),
        Command("diagnose-hnn", _HNN_HELP, _diagnose_hnn, _hnn_arguments, _HNN_HELP),
        Command("diagnose-vin", _VIN_HELP, _diagnose_vin, _vin_arguments, _VIN_HELP),
        Command(
            "campaign",
            "sweep a profile's claim experiments claim by claim (make paper-core runs it niced "
            "in the background)",
            _campaign,
            _campaign_arguments,
        ),
    )
)
