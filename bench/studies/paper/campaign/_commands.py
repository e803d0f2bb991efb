"""The paper's verbs of ``python -m bench``: the campaign's estimate and sweep, and the
diagnoses of the plain HNN, the double pendulum's LNNs and the pixel protocols (the VIN's
auxiliary loss, the HNN seed's optimiser and training step)."""

from __future__ import annotations

from ....core._config import check_choice
from ....core._experiments import PROFILES
from ....core._studies import Command, register_command
from ..._options import (
    check_sweep_args,
    int_arg,
    run_experiments,
    seed_list,
    sweep_options,
    usable_results,
)
from ..pixels._ablation import ABLATIONS


def _estimate_arguments(p):
    p.add_argument("--profile", default="paper-core", help=f"one of {', '.join(PROFILES)}")
    p.add_argument("--workers", type=int_arg("workers"), default=2, help="for the wall hours")


def _estimate(args) -> int:
    from ....core._experiments import SELECTIONS, replication_seeds
    from ._campaign import (
        CAMPAIGN_CLAIMS,
        cheapest_first,
        format_plan,
        plan,
        replication_order,
        saved_trainings,
        signed_claims,
    )

    check_choice("profile", args.profile, list(PROFILES))
    if args.workers < 1:
        raise ValueError(f"workers must be an integer >= 1; got {args.workers}")
    first = cheapest_first(CAMPAIGN_CLAIMS, args.results, args.profile)
    own = plan(args.profile, args.results, workers=args.workers, order=first)
    print(f"results: {args.results}")
    seeds = replication_seeds(args.profile)
    if not (args.profile in SELECTIONS and seeds):
        print(format_plan(own, args.profile, args.workers))
        return 0
    # make paper-core's three phases: the replication seeds of the signed verdicts, the
    # profile's own seeds, the replication seeds of the rest
    signed = signed_claims(args.results, args.profile)
    order = replication_order(args.results, args.profile, signed)
    rest = frozenset(CAMPAIGN_CLAIMS) - signed
    for i, (title, df) in enumerate(
        (
            (f"signed verdicts ({_claims(signed)})", _rep(args, seeds, own, order, signed)),
            (None, own),
            (f"the other claims ({_claims(rest)})", _rep(args, seeds, own, order, rest)),
        )
    ):
        print(f"{chr(10) if i else ''}phase {i + 1} of 3")
        print(
            format_plan(df, args.profile, args.workers, seeds=seeds if title else None, which=title)
        )
    saved = saved_trainings(args.profile, args.results)
    if saved:
        print("\ntrainings saved mid-way (the next start resumes them):")
        print("\n".join(f"  {line}" for line in saved))
    return 0


def _claims(claims) -> str:
    return ", ".join(map(str, sorted(claims))) or "none"


def _rep(args, seeds, prior, order, claims):
    from ._campaign import plan

    return plan(
        args.profile,
        args.results,
        workers=args.workers,
        seeds=seeds,
        prior=prior,
        order=order,
        claims=claims,
    )


def _lnn_arguments(p):
    p.add_argument("--profile", default="quick", help="smoke, quick, paper or paper-core")


def _diagnose_lnn(args) -> int:
    from ..lnn_seed._diagnosis import FILE, diagnose, summary

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
    from ....core._store import read_rows, rows_frame
    from ..hnn_diagnosis import FILE, diagnose, summary

    results = usable_results(args)
    df = diagnose(args.profile, results, steps=args.steps)
    print(summary(df, rows_frame(read_rows(results))))
    print(f"wrote {results / FILE} ({len(df)} rows)")
    return 0


def _ablation_arguments(p):
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


def _ablation_command(ablation) -> Command:
    def run(args) -> int:
        from ..pixels._ablation import diagnose, summary

        results = usable_results(args)
        df = diagnose(
            ablation, args.profile, results, seeds=seed_list(args.seeds), runs_from=args.runs_from
        )
        print(summary(ablation, df))
        print(f"wrote {results / ablation.file} ({len(df)} rows)")
        return 0

    return Command(ablation.command, ablation.help, run, _ablation_arguments, ablation.help)


def _campaign_arguments(p):
    sweep_options(p, default_profile="paper-core")
    p.add_argument(
        "--replication",
        action="store_true",
        help="on the profile's replication seeds instead of its own "
        "(quick, paper, paper-core: 5-9)",
    )
    p.add_argument(
        "--signed",
        action="store_true",
        help="only the claims whose verdict on the profile's own seeds is stored and signed "
        "(make paper-core replicates them first)",
    )
    p.add_argument(
        "--claims",
        default=None,
        metavar="9,12",
        help="only these claims' cells (with --signed: those of them that are signed); "
        "make paper-core CAMPAIGN_FIRST=9 runs them before its phases",
    )


def _claim_list(text: str) -> frozenset:
    """The claims of ``--claims`` (comma-separated numbers of the campaign's claims)."""
    from ._campaign import CAMPAIGN_CLAIMS

    out, allowed = set(), [str(c) for c in sorted(CAMPAIGN_CLAIMS)]
    for part in str(text).split(","):
        check_choice("claim", part.strip(), allowed)
        out.add(int(part))
    return frozenset(out)


def _campaign(args) -> int:
    from ....core._experiments import replication_seeds
    from ._campaign import (
        CAMPAIGN_CLAIMS,
        campaign_experiments,
        cheapest_first,
        priority,
        replication_order,
        signed_claims,
    )

    check_sweep_args(args)
    if not campaign_experiments(args.profile):
        raise ValueError(f"profile {args.profile!r} has no claim experiments to run")
    seeds, order, claims = None, CAMPAIGN_CLAIMS, None
    if args.replication:
        seeds = replication_seeds(args.profile) or None
        if seeds is None:
            allowed = [p for p in PROFILES if replication_seeds(p)]
            check_choice("profile with replication seeds", args.profile, allowed)
    usable_results(args)
    if args.signed:
        claims = signed_claims(args.results, args.profile)
    if args.claims is not None:
        wanted = _claim_list(args.claims)
        claims = wanted if claims is None else claims & wanted
    if seeds:  # the claims with a signed verdict first (an inconclusive one cannot change)
        order = replication_order(args.results, args.profile, claims)
    else:  # the cheapest claims first: the most verdicts per hour
        order = cheapest_first(CAMPAIGN_CLAIMS, args.results, args.profile)
    names = campaign_experiments(args.profile, order, claims)
    if not names:
        print(f"campaign {args.profile}: no claim with a signed verdict to run yet")
        return 0
    which = f" seeds {', '.join(map(str, seeds))}" if seeds else ""
    kind = "signed verdicts: claims" if args.signed else "claims"
    only = f" ({kind} {_claims(claims)})" if claims is not None else ""
    print(f"campaign {args.profile}{which}{only} -> {args.results}: {', '.join(names)}", flush=True)
    # claim by claim, longest runs first within a claim
    key = priority(args.profile, seeds, order, claims)
    res = run_experiments(args, names, order=key, seeds=seeds)
    for name, rows in res.items():
        print(f"{name}: {len(rows)} new runs", flush=True)
    return 0


def _power_arguments(p):
    p.add_argument(
        "--simulations",
        type=int_arg("simulations"),
        default=2000,
        help="draws per part and number of seeds (default 2000)",
    )


def _power(args) -> int:
    from pathlib import Path

    from ....core._query import load_tables
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


_POWER_HELP = (
    "the verdict engine's power: each part's chance to sign at 5 and 10 seeds at its observed "
    "effect and spread, and the seeds that would decide the undecided ones: <results>/power.csv"
)
_LNN_HELP = (
    "the learned d2L/dqdot2 of the double pendulum's LNNs at init and along rollouts "
    ": <results>/lnn_diagnosis.csv"
)
_HNN_HELP = (
    "the first training steps of the plain HNN on the spring, replayed and probed "
    "(claims 1 and 3): <results>/hnn_diagnosis.csv"
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
        Command("power", _POWER_HELP, _power, _power_arguments, _POWER_HELP),
        Command("diagnose-lnn", _LNN_HELP, _diagnose_lnn, _lnn_arguments, _LNN_HELP),
        Command("diagnose-hnn", _HNN_HELP, _diagnose_hnn, _hnn_arguments, _HNN_HELP),
        *(_ablation_command(a) for a in ABLATIONS),
        Command(
            "campaign",
            "sweep a profile's claim experiments claim by claim (make paper-core runs it niced "
            "in the background)",
            _campaign,
            _campaign_arguments,
        ),
    )
)
