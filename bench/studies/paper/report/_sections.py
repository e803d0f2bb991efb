"""The paper's sections of REPORT.md, before the experiments' own: the claims and their
replication, every part of every claim, the margin policy, the claims that depend on a margin,
and the verdicts at both budgets. Registered at import; they share one judgement of the runs."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ....core import ReportContext, ReportSection, register_section
from ....kit import (
    TRIVIAL_FACTOR,
    fmt,
    judge,
    margin_dependence,
    md_escape,
    power_lines,
    power_table,
    write_headlines,
)
from ..campaign._untested import training_gap, training_gap_lines
from ._comparison import _disc_mark, comparison_section, load_other, pending
from ._links import links_section


def _ci(lo, hi) -> str:
    return f"[{fmt(lo)}, {fmt(hi)}]" if np.isfinite(lo) and np.isfinite(hi) else "-"


def _loso_text(j, key: str) -> str:
    runs = j.loso.get(key, [])
    if not runs:
        return "-"
    changes = j.loso_changes(key)
    if not changes:
        return f"stable (each of {len(runs)} seeds dropped)"
    return "changes: " + "; ".join(f"without seed {s}: {v.verdict}" for s, v in changes)


def _not_run_note(profile) -> list[str]:
    """One line per claim that is not judged at ``profile`` (its experiments do not run there)."""
    from ....kit import claims_not_run

    out = []
    for study in claims_not_run(profile):
        names = ", ".join(f"`{e.name}`" for e in study.experiments)
        runs_at = sorted({p for e in study.experiments for p in (e.profiles or ())})
        out.append(
            f"Claim {study.claim} is not run at {profile} ({names} runs at "
            f"{', '.join(runs_at)}): see *Verdicts at both budgets*."
        )
    return [*out, ""] if out else []


def _claims_table(j) -> list[str]:
    """One row per claim (claim 4: per metric and spring start): the final verdict, the
    verdicts on the primary and replication seeds and pooled, whether it replicates, and what
    dropping one seed does. Effect and interval are the final reading's."""
    from ....kit import seed_span

    ps, rs = seed_span(j.primary_seeds), seed_span(j.replication_seeds)
    both = seed_span(sorted({*j.primary_seeds, *j.replication_seeds}))
    out = [
        f"| claim | statement | verdict | seeds {ps} | seeds {rs or '(none)'} | pooled {both} | "
        "replicates | leave one seed out | effect | 90% CI | discriminating | failed runs |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for v in j.final:
        p = j.reading(v.key)
        r = j.replication.get(v.key)
        pooled = j.pooled.get(v.key)
        rep = {True: "yes", False: "**no**", None: "not run"}[j.replicates(v.key)]
        if v.key in j.replication_pending:
            rep = "pending ({} of {} runs)".format(*j.replication_pending[v.key])
        effect = f"{fmt(p.effect)} ({p.effect_name})" if p.effect_name else fmt(p.effect)
        prim = j.primary[v.key]
        if pooled is None and v.key in j.pooled_any:  # shown, never the verdict
            pooled = j.pooled_any[v.key]
            pooled_text = f"({pooled.verdict} ({pooled.n_seeds}), not judged)"
        else:
            pooled_text = f"{pooled.verdict} ({pooled.n_seeds})" if pooled else "-"
        out.append(
            f"| {md_escape(v.key)} | {md_escape(v.title)} | **{v.label()}** | {prim.verdict} "
            f"({prim.n_seeds}) | {r.verdict + f' ({r.n_seeds})' if r else '-'} | "
            f"{pooled_text} | {rep} | "
            f"{md_escape(_loso_text(j, v.key))} | {md_escape(effect)} | "
            f"{_ci(p.ci_low, p.ci_high)} | {_disc_mark(p)} | {p.n_failed} |"
        )
    return out


def _machines_apart(ctx: ReportContext, j, claim: int) -> str:
    """Where the two seed sets of ``claim`` ran on different machines: each set's machines
    (``machine_key``: device and CPU family/model) with their runs, a clause to close a line
    on the sets' difference in a cost (a time is the machine's); "" elsewhere."""
    from ....core import experiment_rows, machine_key
    from ....kit import claim_studies, seed_span

    names = {e.name for s in claim_studies() if s.claim == claim for e in s.experiments}
    runs = ctx.runs
    if runs is None or not len(runs) or not names:
        return ""
    rows = [experiment_rows(runs, n, ctx.profile) for n in sorted(names)]
    rows = [r for r in rows if len(r)]
    if not rows:
        return ""
    rows = pd.concat(rows, ignore_index=True)
    key = machine_key(rows).replace("", "unrecorded")
    sets = []
    for seeds in (j.primary_seeds, j.replication_seeds):
        counts = key[rows["seed"].isin(seeds)].value_counts()
        sets.append((seed_span(seeds), counts))
    if len(sets[1][1]) == 0 or set(sets[0][1].index) == set(sets[1][1].index):
        return ""
    said = "; ".join(
        f"seeds {span}: " + ", ".join(f"{m} ({n} runs)" for m, n in counts.items())
        for span, counts in sets
    )
    return f" (the seed sets ran on different machines: {said})"


def _why_not_replicated(j, ctx: ReportContext | None = None) -> list[str]:
    """One line per claim whose seed sets read different verdicts (the parts that moved), per
    claim whose pooled reading differs from the one both sets read (the parts pooling
    resolved), and per claim whose sets sign a part alike at sizes that differ beyond chance;
    where the sets differ in a cost (:func:`~bench.kit.costs_apart`), the line names the
    machines each set ran on, if they differ."""
    from ....kit import costs_apart, estimates_differ, pooled_moves, why_not_replicated

    def machines(v) -> str:
        if ctx is None or not costs_apart(j, v.key):
            return ""
        return md_escape(_machines_apart(ctx, j, v.claim))

    lines = [
        f"- claim {md_escape(v.key)}: {md_escape(why)}{machines(v)}"
        for v in j.final
        if (why := why_not_replicated(j, v.key))
    ]
    pooled = [
        f"- claim {md_escape(v.key)}: {md_escape(why)}"
        for v in j.final
        if (why := pooled_moves(j, v.key))
    ]
    sized = [
        f"- claim {md_escape(v.key)}: {md_escape(why)}{machines(v)}"
        for v in j.final
        if (why := estimates_differ(j, v.key))
    ]
    out = []
    if lines:
        out += [
            "Why a claim does not replicate (effect [90% CI] on each seed set): a part reverses, "
            "or its two estimates differ beyond chance (Welch's test, Holm's step-down across "
            "the claim's parts) and the sets do not sign it alike:",
            "",
            *lines,
            "",
        ]
    if pooled:
        out += [
            "Where the seed sets add up and the pooled ten seeds (the final reading) read "
            "otherwise than a set alone (ten seeds resolve a part that five leave undecided):",
            "",
            *pooled,
            "",
        ]
    if sized:
        out += [
            "Where both seed sets sign a part alike but its two estimates differ beyond chance "
            "(the finding replicates, its size does not; the pooled interval understates the "
            "spread between the sets):",
            "",
            *sized,
            "",
        ]
    return out


def _parts_table(j) -> list[str]:
    """Every part of the final reading (pooled where the seed sets agree): its effect, margin,
    the margins at which it holds and is contradicted, its test and level, its status and point
    estimate on each seed set, and whether dropping one seed reverses it."""
    from ....kit import margin_ranges, seed_span

    ps, rs = seed_span(j.primary_seeds), seed_span(j.replication_seeds)
    out = [
        "| claim | part | role | kind | margin | margin range | test (level) | effect [90% CI] | "
        f"seeds {ps} | seeds {rs or '(none)'} | pooled | leave one seed out |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for v in j.final:
        reading = j.reading(v.key)
        prim = {q.name: q for q in j.primary[v.key].parts}
        rep = {q.name: q for q in j.replication[v.key].parts} if v.key in j.replication else {}
        pooled = {q.name: q for q in j.pooled[v.key].parts} if v.key in j.pooled else {}
        loso = [(s, {q.name: q for q in w.parts}) for s, w in j.loso.get(v.key, [])]
        flip = {("holds", "contradicts"), ("contradicts", "holds")}
        for part in reading.parts:
            if part.status != "not tested" and not part.ranges:
                part.ranges = margin_ranges(part)
            moved = [s for s, d in loso if d.get(part.name) and d[part.name].status != part.status]
            reversed_ = [
                s
                for s, d in loso
                if d.get(part.name) and (part.status, d[part.name].status) in flip
            ]
            if not loso:
                lo_text = "-"
            elif reversed_:
                lo_text = "**reversed** without seed " + ", ".join(map(str, reversed_))
            elif moved:
                lo_text = "changes without seed " + ", ".join(map(str, moved))
            else:
                lo_text = "stable"
            test = f"{part.test} ({part.alpha:.3g})" if part.test else "-"
            name = part.name + (
                f" (not tested: {part.note})" if part.status == "not tested" else ""
            )
            cells = [
                f"{d[part.name].status} {fmt(d[part.name].point)}" if part.name in d else "-"
                for d in (prim, rep, pooled)
            ]
            out.append(
                f"| {md_escape(v.key)} | {md_escape(name)} | {part.role} | "
                f"{part.kind or '-'} | {md_escape(part.margin) or '-'} | "
                f"{md_escape(part.range_text())} | {md_escape(test)} | {fmt(part.point)} "
                f"{_ci(part.lo, part.hi)} | {cells[0]} | {cells[1]} | {cells[2]} | {lo_text} |"
            )
    return out


def _policy_section() -> list[str]:
    """The margin policy: one margin per quantity, its plausible band, the words it covers,
    and the margins the seeds state as numbers."""
    from ....kit import policy

    out = [
        "## Margin policy",
        "",
        "One margin per compared quantity, the same for every word the papers use about it "
        "(`bench/kit/policy.py`); a ratio of mean squares (MSE, loss, energy MSE) "
        "uses the square of its quantity's margin. The band is the range of margins a "
        "reasonable reader might pick: *Margin-dependent claims* below re-judges every claim "
        "across it.",
        "",
        "| quantity | margin | plausible band | words | why |",
        "| --- | --- | --- | --- | --- |",
    ]
    for q in policy.POLICY.values():
        fmt = (lambda x: f"{x:.3g}x") if q.ratio else (lambda x: f"{x:g}")
        out.append(
            f"| {q.label} | {fmt(q.margin)} | {fmt(q.band[0])} to {fmt(q.band[1])} | "
            f"{md_escape(q.words)} | {md_escape(q.why)} |"
        )
    stated = policy.stated_margins()
    if stated:
        out += ["", "Margins the seeds state as numbers (never varied):", ""]
        for m in stated:
            out.append(f'- {m.quantity}, {m.label()}: "{m.quote}" ({m.source})')
    return [*out, ""]


def _dependence_section(deps, final) -> list[str]:
    """The claims whose final reading changes inside a band; a claim still pending in a
    campaign has no reading to depend on a margin, and is left out."""
    waiting = {v.key for v in final if v.pending}
    deps = [d for d in deps if d.key not in waiting]
    out = [
        "## Margin-dependent claims",
        "",
        "Each claim's final reading judged again at the ends and the middle of the plausible "
        "band of each quantity its parts use (one quantity at a time, the others at the policy's; "
        "learning is the learning gate). A claim whose campaign runs are not all stored is "
        "left out until they are.",
        "",
    ]
    if not deps:
        return [*out, "No verdict changes inside any band.", ""]
    out += [
        "| claim | quantity | verdict at the policy | verdicts across the band |",
        "| --- | --- | --- | --- |",
    ]
    for d in deps:
        out.append(f"| {md_escape(d.key)} | {d.quantity} | {d.at_policy} | {md_escape(d.text())} |")
    keys = sorted({d.key for d in deps}, key=lambda k: [v.key for v in final].index(k))
    return [*out, "", f"Margin-dependent: claim {', '.join(keys)}.", ""]


def _judged(ctx: ReportContext):
    """The judgement of these runs (in a campaign's folder, *pending* where a claim's runs are
    not all stored), the other folders' verdicts, and a line for each folder that could not be
    read; computed once per report."""
    if "paper" not in ctx.memo:
        j = judge(ctx.runs, ctx.curves, ctx.profile)
        j.final = pending(ctx.results_dir, ctx.runs, ctx.profile, j.final)
        others, errors = [], []
        for d in ctx.compare:
            try:
                others.append(load_other(d))
            except Exception as e:  # noqa: BLE001 - a broken folder must not lose the report
                errors.append(f"- could not read `{d}`: {md_escape(str(e))[:200]}")
        ctx.memo["paper"] = (j, others, errors)
    return ctx.memo["paper"]


# draws per part in the report's power table (python -m bench power: 2000)
POWER_SIMULATIONS = 1000


def _gap_lines(j, ctx: ReportContext) -> list[str]:
    """What more training would decide (:mod:`..campaign._untested`), where the profile is
    known."""
    if ctx.profile is None:
        return []
    return training_gap_lines(training_gap(j.final, ctx.runs, ctx.profile), ctx.profile)


def claims_section(ctx: ReportContext) -> list[str]:
    """How a claim is judged, the claims table, the claims not run here, and every part."""
    j = _judged(ctx)[0]
    n_failed = sum(v.n_failed for v in j.final)
    write_headlines(ctx.results_dir, j.final)
    return [
        "## Claims",
        "",
        "Verdict rules are in the docstrings of the studies' folders, "
        "`bench/studies/<paper>/` (conventions: `bench/kit/_stats.py`). Each claim is split "
        "into the parts its sentences "
        "state; each part is a one-sided t test on paired per-seed values (log ratios of "
        "rollout errors, energy violations, losses or training times; slopes; shares) against "
        "the margin of its quantity (*Margin policy* below). An ordering holds only beyond the "
        'margin; "no gain", "no better" and "matches" hold only when the data rule out the '
        "margin; a difference inside it is a tie. Holm's correction runs across a claim's parts, "
        "for holds and for contradicts alike (the level column). A comparison is judged only "
        "where each of its models learned (beat the best trivial predictor by the learning "
        "margin, geometric mean over seeds) and where the claim's stated condition holds "
        '("at similar loss": a *condition* part); otherwise the part reads *not tested* and '
        "cannot count against the claim. A claim is *reproduced* when every part holds, *partly "
        "reproduced* when some hold and others are contradicted, *not reproduced* when parts "
        "are contradicted and none holds, *inconclusive* otherwise, with fewer than 5 seeds, or "
        "when the experiment is not discriminating (its best model does not beat the best "
        f"trivial predictor by {TRIVIAL_FACTOR:g}x on every seed), judged per system or cell: "
        "where some discriminate and others do not, only the others' parts go untested, the "
        "verdict stands on the rest, and the discriminating column names those systems. "
        "Failed and diverged runs "
        "score the worst error, 1, and are counted. *n/a* in the discriminating column: the "
        "claim's evidence has no trivial predictor to beat (an embedding's structure), so each "
        "part is gated on its own model's learning instead.",
        "",
        "Replication adds evidence: every claim is judged on the profile's seeds, again on a "
        "disjoint set, and on both pooled, which is the final reading unless the sets disagree: "
        "a part holds on one set and is contradicted on the other, or its two estimates differ "
        "beyond chance (Welch's test, Holm's step-down across the claim's parts) and the sets "
        "do not sign it alike. Then the claim is *inconclusive (does not replicate)*. One set "
        "signing what the other leaves undecided is no disagreement, nor are two sets that sign "
        "a part alike at different sizes. *Leave one seed out* judges "
        "the final reading's seeds without each one in turn; it demotes a verdict to "
        "*inconclusive (changes without a seed)* only where dropping a seed reverses a part "
        "(holds <-> contradicts).",
        "",
        *_claims_table(j),
        "",
        *_why_not_replicated(j, ctx),
        *_not_run_note(ctx.profile),
        "### Every part: effect, margin, test, level, and its status and estimate on each seed set",
        "",
        *_parts_table(j),
        "",
        *power_lines(power_table(j.final, sims=POWER_SIMULATIONS)),
        *_gap_lines(j, ctx),
        f"Failed or diverged runs scored as error 1 in the verdicts: {n_failed}.",
        "",
    ]


def policy_section(ctx: ReportContext) -> list[str]:
    """The margin policy (the same whatever the runs)."""
    return _policy_section()


def dependence_section(ctx: ReportContext) -> list[str]:
    """The claims whose verdict changes inside the plausible band of a margin."""
    j = _judged(ctx)[0]
    return _dependence_section(margin_dependence(ctx.runs, ctx.curves, ctx.profile, j), j.final)


def budgets_section(ctx: ReportContext) -> list[str]:
    """Every claim's verdict here and in the other results folders, side by side."""
    j, others, errors = _judged(ctx)
    return [*comparison_section(j.final, ctx.profile, others), *errors]


SECTIONS = tuple(
    register_section(ReportSection(name, render))
    for name, render in (
        ("claims", claims_section),
        ("margin policy", policy_section),
        ("margin-dependent claims", dependence_section),
        ("verdicts at both budgets", budgets_section),
        ("claims at every number of links", links_section),
    )
)
