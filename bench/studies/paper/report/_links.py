"""The claims at every number of links: the paper sweeps k = 1..4 in Figs. 2-5 and pools them.

paper-core judges every claim at k = 2; the ``paper-k`` selection runs the same cells at
k = 1, 3 and 4 (``make paper-k``). Both are cells of the ``paper`` profile, stored in one
folder. This reading judges the claims whose experiments sweep k (:data:`LINK_CLAIMS`) with the
same engine (:func:`bench.kit.judge`: seeds 0-4, the replication seeds 5-9, pooled where they
agree), once per k and once over every k, where the rule pools k as the paper does:

- claim 4 (Fig. 5) averages each seed's edge over the k present (the paper's plotting code
  reads Fig. 5's MSE over k = 1..4);
- claim 1 (Fig. 2) fits one line through every run of the figure, any k;
- claim 3 (Fig. 4) and claim 2 (Fig. 3) are judged per k only: claim 3's rule reads one k
  (k = 2 where present), claim 2's one grid of weights per k.

Where the judged readings of a claim disagree, the section says which parts change status
between them (:func:`disagreements`): the numbers of links are the paper's own sweep, so a
verdict that holds at one k and not at another is a finding, not noise to pool away.

A reading is *pending (n of m runs)* until every cell the campaigns declare for it on the
primary seeds is stored (the campaigns' cells: :data:`CAMPAIGN_SELECTIONS`); a pooled reading
waits for every k.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import pandas as pd

from ....core import expand, get
from ....kit import Judgement, claim_studies, judge, seed_sets, seed_span, stored_counts
from ..._claims import LINKS
from ..._claims import LINKS_PROFILE as PROFILE

# the claims judged per k, and those whose rule pools k (module docstring)
LINK_CLAIMS = (1, 2, 3, 4)
POOLED_CLAIMS = (1, 4)
# the profile whose cells these are (PROFILE), and its selections whose cells the campaigns run
CAMPAIGN_SELECTIONS = ("paper-core", "paper-k")


@dataclass
class LinkReading:
    """One reading: ``label`` ("k = 3", "k = 1-4"), its ``links``, the engine's
    ``judgement`` (None where nothing is stored) and ``counts``: ``{claim: (stored, declared)}``
    runs on the primary seeds."""

    label: str
    links: tuple[int, ...]
    judgement: Judgement | None
    counts: dict


def campaign_cells(claims=LINK_CLAIMS, seeds=None) -> frozenset:
    """The config hashes the campaigns' selections declare for ``claims`` (on ``seeds``)."""
    out = set()
    for study in claim_studies():
        if study.claim not in claims:
            continue
        for e in study.experiments:
            for sel in CAMPAIGN_SELECTIONS:
                if get(e.name).profiles is not None and sel not in get(e.name).profiles:
                    continue
                out.update(c.config_hash for c in expand(e, sel, seeds=seeds))
    return frozenset(out)


def readings(runs: pd.DataFrame, curves: pd.DataFrame | None) -> list[LinkReading]:
    """Every k with stored rows of the link claims, then every k pooled."""
    if not len(runs) or "k" not in runs:
        return []
    primary, replication = seed_sets(PROFILE)
    cells = campaign_cells(seeds=(*primary, *replication))
    own = runs[runs["config_hash"].isin(cells)]
    present = sorted(int(k) for k in own["k"].dropna().unique() if int(k) in LINKS)
    out = []
    groups = [(f"k = {k}", (k,), LINK_CLAIMS) for k in present]
    if len(present) > 1:
        groups.append((f"k = {seed_span(LINKS)}", LINKS, POOLED_CLAIMS))
    for label, ks, claims in groups:

        def keep(c, ks=ks):
            return c.k in ks and c.config_hash in cells

        rows = runs[runs["k"].isin(ks) | runs["k"].isna()].reset_index(drop=True)
        counts = stored_counts(rows, PROFILE, primary, keep)
        counts = {c: counts[c] for c in claims if c in counts and counts[c][1]}
        j = judge(rows, curves, PROFILE, loso=False, claims=claims, keep=keep) if counts else None
        out.append(LinkReading(label, ks, j, counts))
    return out


def _cell(r: LinkReading, key: str, claim: int) -> str:
    n, m = r.counts.get(claim, (0, 0))
    if not m:
        return "-"
    if n < m:
        return f"pending ({n} of {m} runs)"
    v = next((v for v in r.judgement.final if v.key == key), None) if r.judgement else None
    if v is None:
        return "-"
    eff = ""
    if math.isfinite(v.effect):
        ci = (
            f" [{v.ci_low:.3g}, {v.ci_high:.3g}]"
            if math.isfinite(v.ci_low) and math.isfinite(v.ci_high)
            else ""
        )
        eff = f" {v.effect:.3g}{ci}"
    seeds = seed_span(r.judgement.reading_seeds(key))
    return f"**{v.label()}**{eff}, seeds {seeds}"


def _part_name(name: str) -> str:
    """A part's name without its cell's k (claim 2 names each weight's cell with it)."""
    return re.sub(r"\s*\bk=\d+\b", "", name).strip()


def disagreements(got: list[LinkReading], keys) -> list[str]:
    """One line per claim whose judged readings (every k alone and pooled; pending ones left
    out) give different verdicts: the verdict of each, then each part whose status differs,
    with its estimate and 90% interval at each k, so the reader sees which sentence of the
    claim depends on the number of links; where no part does, the readings whose final
    verdict is not their seeds' own (a replication check demoted it). Empty where they
    agree."""
    out = []
    for key, claim in keys:
        judged = []
        for r in got:
            n, m = r.counts.get(claim, (0, 0))
            if not m or n < m or r.judgement is None:
                continue
            final = next((v for v in r.judgement.final if v.key == key), None)
            if final is None:
                continue
            judged.append((r.label, final, r.judgement.reading(key)))
        if len({f.label() for _, f, _ in judged}) < 2:
            continue
        by_part: dict[str, list[tuple[str, object]]] = {}
        for label, _, reading in judged:
            for p in reading.parts:
                if p.role == "part":
                    by_part.setdefault(_part_name(p.name), []).append((label, p))
        changes = []
        for name, seen in by_part.items():
            if len({p.status for _, p in seen}) < 2:
                continue
            each = []
            for label, p in seen:
                ci = f" [{p.lo:.3g}, {p.hi:.3g}]" if math.isfinite(p.lo) else ""
                est = f" ({p.point:.3g}{ci})" if math.isfinite(p.point) else ""
                each.append(f"{p.status} at {label}{est}")
            changes.append(f"{name}: " + ", ".join(each))
        verdicts = "; ".join(f"{label} {f.label()}" for label, f, _ in judged)
        demoted = [
            f"{label} reads {reading.label()} on its seeds, {f.label()} in the end"
            for label, f, reading in judged
            if reading.label() != f.label()
        ]
        why = "; ".join(changes or ["no part changes status", *demoted])
        out.append(f"- claim {key}: {verdicts}. {why}")
    return out


def left_out(got: list[LinkReading], keys) -> list[str]:
    """One line per part of the judged pooled readings that leaves a k out
    (:func:`bench.kit.learned_at_each_k`): why, then the readings whose part it is (one line
    for the readings that leave out the same k for the same reason)."""
    by_note: dict[tuple[str, str], list[str]] = {}
    for r in got:
        if len(r.links) < 2 or r.judgement is None:
            continue
        for key, claim in keys:
            n, m = r.counts.get(claim, (0, 0))
            if not m or n < m or not any(v.key == key for v in r.judgement.final):
                continue
            for p in r.judgement.reading(key).parts:
                i = p.note.find("pooled over k =")
                if i >= 0:
                    by_note.setdefault((p.name, p.note[i:]), []).append(f"claim {key}")
    return [f"- {name}, {'; '.join(ks)}: {note}" for (name, note), ks in by_note.items()]


def links_section(ctx) -> list[str]:
    """The claims of Figs. 2-5 per number of links and pooled over them (module docstring)."""
    got = readings(ctx.runs, ctx.curves)
    got = [r for r in got if r.counts]
    if not got or all(r.links == (2,) for r in got):
        return []
    keys: list[tuple[str, int]] = []
    for r in got:
        for v in r.judgement.final if r.judgement else ():
            if (v.key, v.claim) not in keys:
                keys.append((v.key, v.claim))
    for r in got:  # a reading still pending names its claims too
        for c in r.counts:
            if not any(c == claim for _, claim in keys):
                keys.append((str(c), c))
    keys.sort(key=lambda kc: (kc[1], kc[0]))
    out = [
        "## The claims at every number of links",
        "",
        "The paper sweeps k = 1..4 in Figs. 2-5; the verdicts above are judged at k = 2 "
        "(paper-core). Here the same engine judges each k alone (seeds 0-4, then 5-9, pooled "
        "where they agree) and, for the claims whose rule pools k as the paper does (claim 4: "
        "each seed's edge averaged over k; claim 1: one line through every run), every k "
        "together, each part over the k where every model it gates learned. Claims 2 and 3 "
        "are read per k only. Each cell: the verdict, its headline "
        "effect with the 90% interval, and the seeds it rests on; *pending* until every cell "
        "of the reading is stored on seeds 0-4 (`make paper-k` runs them).",
        "",
        "| claim | " + " | ".join(r.label for r in got) + " |",
        "|---|" + "---|" * len(got),
    ]
    for key, claim in keys:
        out.append(f"| {key} | " + " | ".join(_cell(r, key, claim) for r in got) + " |")
    left = left_out(got, keys)
    if left:
        out += [
            "",
            "The k a pooled part leaves out (a gated model did not learn there):",
            "",
            *left,
        ]
    differ = disagreements(got, keys)
    if differ:
        out += [
            "",
            "Where the numbers of links disagree (each judged reading's verdict, then the parts "
            "whose status changes with k, estimate and 90% interval):",
            "",
            *differ,
        ]
    return [*out, ""]
