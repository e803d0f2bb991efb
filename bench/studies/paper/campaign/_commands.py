"""The campaign's verbs of ``python -m bench``: ``estimate`` (runs and hours per claim of a
profile's campaign) and ``campaign`` (its sweep, claim by claim). The studies' diagnoses
register their own verbs, in their folders."""

from __future__ import annotations

from pathlib import Path

from ....core import (
    PROFILES,
    Command,
    check_choice,
    check_sweep_args,
    int_arg,
    register_command,
    sweep_from_args,
    sweep_options,
    usable_results,
)


def _estimate_arguments(p):
    p.add_argument("--profile", default="paper-core", help=f"one of {', '.join(PROFILES)}")
    p.add_argument("--workers", type=int_arg("workers"), default=2, help="for the wall hours")
    p.add_argument(
        "--claims",
        default=None,
        metavar="4,3,1,2",
        help="the plan of a campaign that runs these claims in this order, each on the "
        "profile's seeds then its replication seeds (make paper-k's)",
    )


def _estimate(args) -> int:
    from ....core import SELECTIONS, replication_seeds
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
    print(f"results: {args.results}")
    seeds = replication_seeds(args.profile)
    if args.claims is not None:
        return _estimate_in_order(args, _claim_order(args.claims), seeds)
    first = cheapest_first(CAMPAIGN_CLAIMS, args.results, args.profile)
    own = plan(args.profile, args.results, workers=args.workers, order=first)
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
    _waiting(args)
    return 0


def _waiting(args) -> None:
    """The further readings not yet stored whole on a seed set (each joins its claim's verdict
    there only then), by name where the experiment names them."""
    import pandas as pd

    from ....kit import supplements_waiting
    from ._campaign import _stored_rows

    if not Path(args.results).exists():
        return
    rows = pd.DataFrame({"config_hash": [r["config_hash"] for r in _stored_rows(args.results)]})
    waiting = supplements_waiting(rows, args.profile)
    if waiting:
        print("\nfurther readings still waiting (each joins its claim once stored on a seed set):")
        print("\n".join(f"  claim {c}: {said}" for c, said in sorted(waiting.items())))


def _estimate_in_order(args, order: tuple, seeds) -> int:
    """The plan of ``make paper-k``: the claims of ``order`` one at a time, each on the
    profile's seeds and then on its replication seeds."""
    from ....kit import seed_span
    from ._campaign import format_plan, plan

    then = f", then on its replication seeds {seed_span(seeds)}" if seeds else ""
    print(f"order: claims {_claims_in(order)}, one at a time, each on the profile's seeds{then}")
    claims = frozenset(order)
    own = plan(args.profile, args.results, workers=args.workers, order=order, claims=claims)
    print(format_plan(own, args.profile, args.workers, order="the order above"))
    if seeds:
        rep = _rep(args, seeds, own, order, claims)
        print()
        print(format_plan(rep, args.profile, args.workers, seeds=seeds, order="the order above"))
    return 0


def _claim_order(text: str) -> tuple:
    """The claims of ``--claims`` in the order given, each once."""
    _claim_list(text)
    return tuple(dict.fromkeys(int(part) for part in _parts(text)))


def _parts(text: str) -> list[str]:
    """The parts of a list of claims, separated by commas or spaces."""
    return [p.strip() for p in str(text).replace(" ", ",").split(",") if p.strip()]


def _claims(claims) -> str:
    return _claims_in(sorted(claims))


def _claims_in(claims) -> str:
    return ", ".join(map(str, claims)) or "none"


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
    p.add_argument(
        "--by-reading",
        action="store_true",
        help="both seed sets, reading by reading: the claims' own cells on the profile's seeds "
        "and then its replication seeds, then their further readings cheapest run first, "
        "each cost on both sets before a costlier one (make paper-core's CAMPAIGN_FIRST)",
    )


def _claim_list(text: str) -> frozenset:
    """The claims of ``--claims`` (numbers of the campaign's claims, separated by commas)."""
    from ._campaign import CAMPAIGN_CLAIMS

    out, allowed = set(), [str(c) for c in sorted(CAMPAIGN_CLAIMS)]
    for part in _parts(text) or [""]:
        check_choice("claim", part, allowed)
        out.add(int(part))
    return frozenset(out)


def _campaign(args) -> int:
    from ....core import replication_seeds
    from ._campaign import (
        CAMPAIGN_CLAIMS,
        campaign_experiments,
        cheapest_first,
        priority,
        replicable,
        replication_order,
        signed_claims,
    )

    check_sweep_args(args)
    if not campaign_experiments(args.profile):
        raise ValueError(f"profile {args.profile!r} has no claim experiments to run")
    if args.by_reading:
        if args.replication:
            raise ValueError("--by-reading runs both seed sets: drop --replication")
        return _by_reading(args)
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
    # claim by claim; within a claim its own cells longest first, then its further readings
    key = priority(args.profile, seeds, order, claims)
    # a replication follows its cell's own seeds (a cell declared since runs them first)
    where = replicable(args.results, args.profile, names) if seeds else None
    res = sweep_from_args(args, names, order=key, seeds=seeds, where=where)
    for name, rows in res.items():
        print(f"{name}: {len(rows)} new runs", flush=True)
    return 0


def _by_reading(args) -> int:
    """``campaign --by-reading``: a further reading joins a verdict on a seed set once all its
    runs there are stored, so a cheap reading should not wait on both sets behind a costly
    one's first set. The claims' own cells run on the profile's seeds, then on its replication
    seeds; then the further cells in tiers of their estimated run cost, cheapest first, each
    tier on the profile's seeds and then on the replication seeds (a replication run still
    follows its cell's own seeds: :func:`replicable`)."""
    from ....core import expand, get, is_supplementary, replication_seeds
    from ._budget import run_seconds
    from ._campaign import (
        CAMPAIGN_CLAIMS,
        campaign_experiments,
        cheapest_first,
        priority,
        replicable,
    )

    if args.signed:
        raise ValueError("--by-reading runs both seed sets: drop --signed")
    usable_results(args)
    claims = _claim_list(args.claims) if args.claims is not None else None
    order = cheapest_first(CAMPAIGN_CLAIMS, args.results, args.profile)
    names = campaign_experiments(args.profile, order, claims)
    rep = replication_seeds(args.profile) or None
    cost: dict[str, float] = {}  # the further runs (either seed set), by hash: their cost
    placed: set[str] = set()
    for seeds in (None, rep):
        for n in names:
            for c in expand(n, args.profile, seeds=seeds):
                if c.config_hash not in placed:  # the first experiment that has it places it
                    placed.add(c.config_hash)
                    if is_supplementary(get(n), c):
                        cost[c.config_hash] = round(run_seconds(c))
    steps = [("own cells", lambda c: c.config_hash not in cost)]
    steps += [
        (f"further readings up to {t} s a run", lambda c, t=t: cost.get(c.config_hash, t + 1) <= t)
        for t in sorted(set(cost.values()))
    ]
    for what, keep in steps:
        for seeds in (None, rep) if rep else (None,):
            where = keep
            if seeds:  # read after the own seeds' sweep: what it stored is ready
                ready = replicable(args.results, args.profile, names)
                where = lambda c, keep=keep, ready=ready: keep(c) and ready(c)  # noqa: E731
            which = f"seeds {', '.join(map(str, seeds))}" if seeds else "own seeds"
            print(f"campaign {args.profile} by reading, {what}, {which}", flush=True)
            key = priority(args.profile, seeds, order, claims)
            res = sweep_from_args(args, names, order=key, seeds=seeds, where=where)
            print(f"  {sum(len(r) for r in res.values())} new runs", flush=True)
    return 0


COMMANDS = tuple(
    register_command(c)
    for c in (
        Command(
            "estimate",
            "runs and hours per claim of a profile's campaign (stored, left)",
            _estimate,
            _estimate_arguments,
        ),
        Command(
            "campaign",
            "sweep a profile's claim experiments claim by claim (make paper-core runs it niced "
            "in the background)",
            _campaign,
            _campaign_arguments,
        ),
    )
)
