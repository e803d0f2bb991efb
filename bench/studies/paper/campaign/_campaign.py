"""A campaign: the runs of a profile (usually the ``paper-core`` selection) swept claim by claim,
in an order that settles first what the quick profile does not, resumable at any moment.

Runs are content-addressed, so a killed campaign loses only the runs in flight; the replication
phase judges each verdict again on the profile's disjoint replication seeds (:func:`plan` counts
it apart). The selection, the order and how hours are estimated: docs/studies/campaign.md.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

import systems

from ....core import (
    available,
    expand,
    get,
    holds_runs,
    is_supplementary,
    read_rows,
    replication_seeds,
    rows_digest,
)
from ._budget import data_seconds, run_seconds, total_seconds

# The row columns summed as the campaign's training and evaluation time (the "CPU
# hours the campaign took"; wall seconds of each part: at nice 19 they include waiting).
TRAIN_EVAL_COLUMNS = (
    "train_seconds",
    "compile_seconds",
    "rollout_seconds",
    "eval_compile_seconds",
    "checkpoint_seconds",
)

# The order in which a campaign settles the claims (docs/studies/campaign.md).
CAMPAIGN_CLAIMS = (6, 4, 1, 3, 10, 2, 5, 9, 7, 8, 11, 12, 13, 14, 15, 16)

# the last rows parsed, by folder and content (_stored_rows)
_PARSED: dict[tuple[str, str], list[dict]] = {}


def _stored_rows(results_dir) -> list[dict]:
    """The rows stored in ``results_dir``, parsed once per content (:func:`rows_digest`, the
    row files' names and bytes): a status plans several phases over the same rows, and
    parsing them is its costly part. The rows are shared: read them, never change them."""
    key = (str(Path(results_dir).resolve()), rows_digest(results_dir))
    if key not in _PARSED:
        _PARSED.clear()
        _PARSED[key] = read_rows(Path(results_dir))
    return _PARSED[key]


def _done(results_dir) -> set[str]:
    """The config hashes of the rows stored in ``results_dir`` (:func:`_stored_rows`)."""
    return {r["config_hash"] for r in _stored_rows(results_dir)}


def campaign_experiments(
    profile: str = "paper-core", order=CAMPAIGN_CLAIMS, claims=None
) -> list[str]:
    """The registered experiments with a claim and runs under ``profile``, in claim order
    (``order``: :data:`CAMPAIGN_CLAIMS`, or a replication phase's :func:`replication_order`);
    only those of ``claims`` where given."""
    names = [
        n
        for n in available()
        if get(n).claim is not None
        and (claims is None or get(n).claim in claims)
        and expand(n, profile)
    ]
    order = tuple(order)

    def rank(n):
        c = get(n).claim
        return (order.index(c) if c in order else len(order), c, n)

    return sorted(names, key=rank)


def replication_order(results_dir, profile: str = "paper-core", signed=None) -> tuple[int, ...]:
    """The claims in the order a replication phase settles them: first those whose verdict on
    the profile's own seeds is signed (reproduced, partly reproduced or not reproduced), then
    the rest (inconclusive or pending), each group in :data:`CAMPAIGN_CLAIMS` order. An
    inconclusive verdict stays inconclusive whatever its replication says (a verdict that does
    not replicate is *inconclusive (does not replicate)*), so its replication runs cannot change
    a verdict and wait until the others are stored; they are still run. Runs shared between
    claims go with the first claim that reads them, as in the first phase. ``signed``: the
    claims of :func:`signed_claims`, where already known."""
    if signed is None:
        signed = signed_claims(results_dir, profile)
    first = tuple(c for c in CAMPAIGN_CLAIMS if c in signed)
    rest = tuple(c for c in CAMPAIGN_CLAIMS if c not in signed)
    seeds = replication_seeds(profile) or None
    return cheapest_first(first, results_dir, profile, seeds) + cheapest_first(
        rest, results_dir, profile, seeds
    )


def signed_claims(results_dir, profile: str = "paper-core") -> frozenset:
    """The claims whose runs on the profile's own seeds are all stored and whose verdict there
    is signed (reproduced, partly reproduced or not reproduced): the campaign replicates them
    first. A claim with runs still to store is not signed, even where one of its readings is
    (claim 7's rollout-loss reading, while the seed's protocol that decides it is pending)."""
    from ....core import load_tables
    from ....kit import NOT_REPRODUCED, PARTLY, REPRODUCED, judge, stored_counts

    if results_dir is None or not holds_runs(Path(results_dir)):
        return frozenset()
    runs, curves, _ = load_tables(Path(results_dir))
    j = judge(runs, curves, profile, loso=False)
    incomplete = {c for c, (n, m) in stored_counts(runs, profile).items() if n < m}
    return frozenset(
        v.claim
        for v in j.primary.values()
        if v.pending is None
        and v.claim not in incomplete
        and v.verdict in (REPRODUCED, PARTLY, NOT_REPRODUCED)
    )


def cheapest_first(claims, results_dir, profile: str = "paper-core", seeds=None) -> tuple:
    """``claims`` with the fewest estimated CPU hours left first, so that a campaign settles
    the most verdicts per hour (a claim of ten hours does not hold back three of one hour
    each); ties, and claims with nothing left, keep their place in ``claims``. On ``seeds``
    instead of the profile's: the replication phase."""
    claims = tuple(claims)
    if not claims:
        return claims
    df = plan(profile, results_dir, seeds=seeds, order=claims)
    left = dict(zip(df["claim"], df["cpu_hours_left"], strict=True)) if len(df) else {}
    return tuple(sorted(claims, key=lambda c: left.get(c, 0.0)))


def campaign_runs(
    profile: str = "paper-core", seeds=None, order=CAMPAIGN_CLAIMS, claims=None
) -> list[tuple[str, object]]:
    """``(experiment, RunConfig)`` of every unique run of the campaign, in the order they start:
    by claim (``order``), then as :func:`priority` orders a claim's runs; on ``seeds`` instead of
    the profile's (its replication seeds); only ``claims``' where given."""
    out, seen = [], set()
    for name in campaign_experiments(profile, order, claims):
        cfgs = [c for c in expand(name, profile, seeds=seeds) if c.config_hash not in seen]
        seen.update(c.config_hash for c in cfgs)
        further = {c.config_hash for c in cfgs if is_supplementary(get(name), c)}
        cfgs.sort(key=lambda c: _within_claim(c, c.config_hash in further), reverse=True)
        out += [(name, c) for c in cfgs]
    return out


def _within_claim(c, further: bool) -> tuple:
    """The order of a claim's runs (largest key first): fewer links first (:func:`_links`);
    the claim's own cells before its further readings; its own cells longest first (the
    workers end together), a further reading's shortest first, since a reading joins the
    verdict only when all its runs are stored (a cheap one is not held behind a costly one)."""
    seconds = run_seconds(c)
    return (-_links(c), not further, -seconds if further else seconds)


def replicable(results_dir, profile: str, names) -> object:
    """A predicate on a replication run: whether its cell (the run but for its seed) is stored
    on every one of ``profile``'s own seeds, in the experiments ``names``. A replication
    phase runs only those, so that a cell declared since the last campaign has its own seeds
    run before its replication seeds."""
    import dataclasses

    done = _done(results_dir) if holds_runs(Path(results_dir)) else set()
    stored: dict[str, bool] = {}
    for n in names:
        for c in expand(n, profile):
            key = dataclasses.replace(c, seed=0).config_hash
            stored[key] = stored.get(key, True) and c.config_hash in done
    ready = {k for k, v in stored.items() if v}
    return lambda c: dataclasses.replace(c, seed=0).config_hash in ready


def _links(c) -> int:
    """A run's number of links (0 where the system has none): within a claim the campaign
    finishes the cheaper k first, so that each k is judged as soon as it can be (paper-k
    sweeps k = 1, 3, 4; a claim of one k keeps its longest-first order)."""
    return int(c.k or 0)


def priority(profile: str = "paper-core", seeds=None, order=CAMPAIGN_CLAIMS, claims=None):
    """A sort key for ``bench.core._runner.sweep(order=...)`` (which starts the largest keys
    first): earlier claims first (``order``), then within a claim as :func:`_within_claim`
    (fewer links first; the claim's own cells longest first, then its further readings
    shortest first)."""
    rank, further = {}, set()
    for i, name in enumerate(campaign_experiments(profile, order, claims)):
        for c in expand(name, profile, seeds=seeds):
            if c.config_hash in rank:  # the first experiment that has it places it
                continue
            rank[c.config_hash] = i
            if is_supplementary(get(name), c):
                further.add(c.config_hash)

    def key(c):
        return (-rank.get(c.config_hash, len(rank)), *_within_claim(c, c.config_hash in further))

    return key


def plan(
    profile: str = "paper-core",
    results_dir=None,
    workers: int = 2,
    seeds=None,
    prior=None,
    order=CAMPAIGN_CLAIMS,
    claims=None,
) -> pd.DataFrame:
    """One row per claim of the campaign: ``claim, experiments, runs`` (every run its verdict
    reads), ``stored`` (of those), ``new_runs`` (those no earlier claim brings),
    ``cpu_hours`` (estimated, its new runs), ``cpu_hours_left`` (estimated, its new runs not
    stored), ``wall_hours_left`` (at ``workers`` processes on an idle machine) and
    ``cpu_hours_done`` (the stored runs' measured ``wall_seconds``: data, compilation,
    training, evaluation and, for a niced run, time spent waiting), ``train_eval_hours`` (of
    those, the :data:`TRAIN_EVAL_COLUMNS`: training and evaluation only),
    ``measured_cpu_hours`` and ``measured_cpu_runs`` (the process CPU time, ``cpu_seconds``, of
    the stored runs that record it, and how many do; runs stored from an accelerator count as
    done and in none of the measured columns), ``measured_estimate_hours`` (the
    estimate of those runs), ``calibration`` (measured over estimated: the claim's, or the
    campaign's where the claim has no such run) and ``cpu_hours_left_calibrated`` /
    ``wall_hours_left_calibrated`` (the hours left rescaled by it); a last row ``total``. On
    ``seeds`` instead of the profile's: the campaign's replication phase, whose claims without
    a measured run take their calibration from ``prior`` (the plan of the profile's seeds).
    Only ``claims``' experiments where given (a phase of the campaign)."""
    runs = campaign_runs(profile, seeds, order, claims)
    cfgs = {c.config_hash: c for _, c in runs}
    stored = pd.DataFrame()
    if results_dir is not None and Path(results_dir).exists():
        every = _stored_rows(results_dir)
        done = {r["config_hash"] for r in every}
        rows = [r for r in every if r["config_hash"] in cfgs]
        stored = pd.DataFrame(rows)
    else:
        done = set()
    # what the stored runs cost on this campaign's kind of machine: rows run on an accelerator
    # (backend other than cpu) are done, but their times do not measure a CPU's
    if "backend" in stored:
        stored = stored[stored["backend"].fillna("cpu") == "cpu"]
    walls = _per_run(stored, ("wall_seconds",))
    # training and evaluation: the steps, their compilation, the test rollouts and the
    # learning-curve checkpoints (wall_seconds less the data and setup)
    train_eval = _per_run(stored, TRAIN_EVAL_COLUMNS)
    # the process CPU time of the runs that record it (cpu_seconds; older rows lack it)
    cpu = _per_run(stored, ("cpu_seconds",))
    table = []
    # a dataset charged apart from its runs (the LNN seed's) is paid by the first claim whose
    # runs need it, and is left to pay until one of its runs is stored and it is in this
    # machine's cache (:func:`_cached`)
    charged = set()
    # (only those datasets: a run with its own data, the pixel tasks', need not have a
    # DatasetConfig that describes it)
    paid = {
        d
        for c in cfgs.values()
        if c.config_hash in done and data_seconds(c) and _cached(d := c.dataset_config())
    }
    for name in campaign_experiments(profile, order, claims):
        cells = expand(name, profile, seeds=seeds)  # every run the claim reads, shared too
        mine = [c for n, c in runs if n == name]  # the runs it brings first
        left = [c for c in mine if c.config_hash not in done]
        table.append(
            {
                "claim": get(name).claim,
                "experiments": name,
                "runs": len(cells),
                "stored": sum(c.config_hash in done for c in cells),
                "new_runs": len(mine),
                "cpu_hours": total_seconds(mine, charged) / 3600,
                "cpu_hours_done": sum(walls.get(c.config_hash, 0.0) for c in mine) / 3600,
                "cpu_hours_left": total_seconds(left, paid) / 3600,
                "train_eval_hours": sum(train_eval.get(c.config_hash, 0.0) for c in mine) / 3600,
                "measured_cpu_hours": sum(cpu.get(c.config_hash, 0.0) for c in mine) / 3600,
                "measured_cpu_runs": sum(c.config_hash in cpu for c in mine),
                "measured_estimate_hours": sum(
                    _measured_estimate(c, walls, train_eval) for c in mine if c.config_hash in cpu
                )
                / 3600,
            }
        )
    df = pd.DataFrame(table)
    if len(df):
        df = df.groupby("claim", sort=False, as_index=False).agg(
            {
                "experiments": ", ".join,
                "runs": "sum",
                "stored": "sum",
                "new_runs": "sum",
                "cpu_hours": "sum",
                "cpu_hours_done": "sum",
                "cpu_hours_left": "sum",
                "train_eval_hours": "sum",
                "measured_cpu_hours": "sum",
                "measured_cpu_runs": "sum",
                "measured_estimate_hours": "sum",
            }
        )
        # The estimate of the runs left, rescaled by what the stored runs really cost: the
        # claim's measured CPU time over its estimate, or the campaign's where the claim has no
        # run that records cpu_seconds (1 where none has)
        known = {}
        if prior is not None:
            known = dict(zip(prior["claim"], prior["calibration"], strict=True))
        overall = _ratio(
            df["measured_cpu_hours"].sum(),
            df["measured_estimate_hours"].sum(),
            known.get("total", 1.0),
        )
        df["calibration"] = [
            _ratio(a, b, known.get(c, overall))
            for c, a, b in zip(
                df["claim"], df["measured_cpu_hours"], df["measured_estimate_hours"], strict=True
            )
        ]
        df["cpu_hours_left_calibrated"] = df["cpu_hours_left"] * df["calibration"]
        total = df.sum(numeric_only=True).to_dict()
        total.update(
            claim="total",
            experiments="(unique runs)",
            runs=len(runs),
            stored=sum(h in done for h in cfgs),
        )
        total["calibration"] = overall
        df = pd.concat([df, pd.DataFrame([total])], ignore_index=True)
        df["wall_hours_left"] = df["cpu_hours_left"] / max(1, workers)
        df["wall_hours_left_calibrated"] = df["cpu_hours_left_calibrated"] / max(1, workers)
    return df


def _cached(d) -> bool:
    """Whether the dataset ``d`` is in this machine's cache (``systems.dataset_path``). A
    stored run says that its dataset was made somewhere, not that it is here: a checkout
    starts with an empty cache, and a dataset made on a GPU machine stays there."""
    return systems.dataset_path(d).exists()


def _measured_estimate(c, walls: dict, train_eval: dict) -> float:
    """The estimate to set against a stored run's measured CPU time: its own, plus its dataset's
    where the run generated it (a dataset charged apart, ``_budget.data_seconds``, is made by
    the first run that needs it; that run's set-up, its wall less training and evaluation, then
    exceeds half the dataset's estimate; a run that found its dataset made spends seconds)."""
    own, data = run_seconds(c), data_seconds(c)
    setup = walls.get(c.config_hash, 0.0) - train_eval.get(c.config_hash, 0.0)
    return own + data if data > 0 and setup > data / 2 else own


def _per_run(stored: pd.DataFrame, columns) -> dict[str, float]:
    """``{config_hash: sum of the row's columns}`` over the stored rows, skipping a missing
    value; a run with none of them recorded (older rows) is left out."""
    cols = [c for c in columns if c in stored]
    if not len(stored) or not cols:
        return {}
    total = stored[cols].apply(pd.to_numeric, errors="coerce").sum(axis=1, min_count=1)
    return {h: float(v) for h, v in zip(stored["config_hash"], total, strict=True) if v == v}


def _ratio(measured: float, estimated: float, default: float = 1.0) -> float:
    """``measured / estimated``, or ``default`` where nothing was measured."""
    return measured / estimated if estimated > 0 else default


def format_plan(
    df: pd.DataFrame, profile: str, workers: int, seeds=None, which=None, order=None
) -> str:
    """The plan as a fixed-width text table (``python -m bench estimate``); ``seeds``: the
    replication phase's, ``which``: the claims it holds, named in the title, and ``order``:
    the order of its claims in words (the campaign's own where None)."""
    title = f"{profile}, replication seeds {', '.join(map(str, seeds))}" if seeds else profile
    which = f"{title}, {which}" if which else title
    if not len(df):
        return f"{which}: no runs"
    if order is None:
        order = "campaign order, signed verdicts first" if seeds else "campaign order"
    lines = [
        f"{which}: runs and hours per claim, in {order} (hours: the estimator's; done: "
        "the stored runs' wall seconds, waiting included; t+e: of those, training and "
        f"evaluation; wall hours left at {workers} idle workers)",
        f"{'claim':>6} {'runs':>5} {'stored':>6} {'new':>5} {'CPU h':>6} {'done h':>6} "
        f"{'t+e h':>6} {'left h':>6} {'wall h':>6} {'cal':>5} {'cal h':>6} {'cal wh':>6}  "
        "experiments",
    ]
    for r in df.to_dict("records"):
        lines.append(
            f"{r['claim']!s:>6} {int(r['runs']):>5} {int(r['stored']):>6} {int(r['new_runs']):>5} "
            f"{r['cpu_hours']:>6.2f} "
            f"{r['cpu_hours_done']:>6.2f} {r['train_eval_hours']:>6.2f} "
            f"{r['cpu_hours_left']:>6.2f} "
            f"{r['wall_hours_left']:>6.2f} {r['calibration']:>5.2f} "
            f"{r['cpu_hours_left_calibrated']:>6.2f} {r['wall_hours_left_calibrated']:>6.2f}  "
            f"{r['experiments']}"
        )
    t = df.iloc[-1]
    lines.append(
        f"CPU time measured (cpu_seconds, no waiting) on {int(t['measured_cpu_runs'])} of "
        f"{int(t['stored'])} stored runs: {t['measured_cpu_hours']:.2f} h, "
        f"{t['calibration']:.2f}x their estimate"
    )
    lines.append(
        "cal: measured CPU time over the estimate of the claim's stored runs that record it "
        "(the campaign's where it has none); cal h, cal wh: the CPU and wall hours left "
        "rescaled by it"
    )
    return "\n".join(lines)


def saved_trainings(profile: str = "paper-core", results_dir=None, cache_root=None) -> list[str]:
    """One line per campaign run (either seed set) not stored whose training was interrupted
    with its state saved (``bench.core._resume``): where it resumes, and whether the code
    that saved it is the code that runs now (otherwise it trains from the start)."""
    import json

    from ....core import RECORD, RESUME, params_dir, saved_by_this_code

    cache_root = Path(cache_root or systems.cache_root())
    done = _done(results_dir) if results_dir and Path(results_dir).exists() else set()
    lines, seen = [], set()
    for seeds in (None, replication_seeds(profile)):
        for name, c in campaign_runs(profile, seeds):
            if c.config_hash in done or c.train_hash in seen:
                continue
            seen.add(c.train_hash)
            record = params_dir(cache_root, c.train_hash) / RESUME / RECORD
            try:
                rec = json.loads(record.read_text())
            except (OSError, ValueError):
                continue
            state = (
                "resumes"
                if saved_by_this_code(rec.get("code"))
                else "restarts: saved by other code"
            )
            lines.append(
                f"claim {get(name).claim}, {name}, {c.model} seed {c.seed}: step "
                f"{rec['done']:,} of {c.steps:,} ({rec['train_seconds'] / 3600:.2f} h trained; "
                f"{state})"
            )
    return lines
