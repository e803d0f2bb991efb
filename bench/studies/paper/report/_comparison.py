"""*Verdicts at both budgets*: each claim's verdict here and in the other results folders
(the paper-profile runs beside quick's), with the likely cause where they disagree."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pandas as pd

from ....core import SELECTIONS, load_tables
from ....kit import fmt, folder_label, judge, md_escape, stored_counts, supplements_waiting

__all__ = [
    "Cause",
    "ComparisonRow",
    "comparison_rows",
    "comparison_section",
    "load_other",
    "pending",
    "supplements_waiting",
]

# The kinds of likely cause of two folders' verdicts of one claim disagreeing, in the order
# they are named (:class:`Cause`).
CAUSES = (
    "not comparable",
    "stability",
    "test set",
    "failed runs",
    "metric",
    "seeds",
    "parts",
    "budget",
)
# At most this many parts named in a "parts" cause (the rest counted).
PARTS_NAMED = 3


@dataclasses.dataclass(frozen=True)
class Cause:
    """A likely cause of a disagreement: its ``kind`` (one of :data:`CAUSES`), the folder it
    is about where it names one (``folder``: its label), and the sentence the report prints."""

    kind: str
    text: str
    folder: str = ""


@dataclasses.dataclass(frozen=True)
class ComparisonRow:
    """One claim (``key``) in every folder: ``verdicts`` here first, then the other folders'
    (None where a folder has none of the claim), each folder's ``state`` (one of
    :data:`STATES`); ``agree`` compares the judged ones (None when fewer than two are),
    ``causes`` each cause once."""

    key: str
    claim: int
    labels: tuple[str, ...]
    verdicts: tuple
    states: tuple[str, ...]
    agree: bool | None
    causes: tuple[Cause, ...]


# A folder's state for a claim: judged, none of its runs, its campaign under way, or some of
# the cells the claim needs missing.
STATES = ("judged", "no runs", "pending", "cells missing")


def _disc_mark(v) -> str:
    """yes, **no**, unknown or n/a; **no** names the systems where the others discriminate
    (only their parts went untested)."""
    if v.discriminating is None and not v.has_trivial:
        return "n/a"
    if v.discriminating is False and v.undiscriminating:
        return f"**no** on {', '.join(v.undiscriminating)}"
    return {True: "yes", False: "**no**", None: "unknown"}[v.discriminating]


def _no_runs(v) -> bool:
    """No comparable verdict: no runs at all, a cell the claim needs is missing, or the
    claim's runs are still being computed (``pending``)."""
    return v is None or v.n_seeds == 0 or _is_pending(v)


def _is_pending(v) -> bool:
    """The claim's campaign has not stored all its runs yet (:func:`pending`)."""
    return v is not None and v.pending is not None


def _outcome(v) -> str:
    """The verdict without the reason of an inconclusive one: *inconclusive (does not
    replicate)* and *inconclusive* agree (neither signs the claim)."""
    return v.verdict.split(" (")[0]


def _absent(v) -> bool:
    """The folder has none of the claim's runs (its cell reads *no runs*)."""
    return v is None or (v.detail == "no runs" and not _is_pending(v))


def _state(v) -> str:
    if _is_pending(v):
        return "pending"
    if _absent(v):
        return "no runs"
    return "cells missing" if v.n_seeds == 0 else "judged"


def _cell_text(v) -> str:
    state = _state(v)
    if state == "pending":
        return v.verdict
    if state == "no runs":
        return "no runs"
    if state == "cells missing":
        return f"**{v.verdict}** (cells missing)"
    if v.discriminating is False and v.undiscriminating:
        return f"**{v.verdict}** (not discriminating on {', '.join(v.undiscriminating)})"
    return f"**{v.verdict}**" + (" (not discriminating)" if v.discriminating is False else "")


def _cause(a, b, label_a: str, label_b: str, same_profile_metric: str = "") -> list[Cause]:
    """The likely causes of two verdicts of one claim disagreeing."""
    if _no_runs(a) or _no_runs(b):
        # name the side that has some runs (pending or cells missing) before one with none
        sides = [(v, lab) for v, lab in ((a, label_a), (b, label_b)) if _no_runs(v)]
        v, label = next(((v, lab) for v, lab in sides if not _absent(v)), sides[0])
        if _is_pending(v):
            return [Cause("not comparable", f"{v.verdict} at {label}: not comparable yet", label)]
        what = "no runs" if _absent(v) else "cells missing"
        return [Cause("not comparable", f"{what} at {label}: not comparable", label)]
    causes = []
    # A verdict the replication checks demoted (does not replicate, changes without a seed):
    # where its own seeds read what the other folder reads, the folders agree in direction and
    # the disagreement is that reading's stability, not the budget.
    agree_but_unstable = False
    for v, lab, o, o_lab in ((a, label_a, b, label_b), (b, label_b, a, label_a)):
        if v.primary is None:
            continue
        why = v.verdict.split(" (", 1)[1].rstrip(")")
        if v.primary == _outcome(o):
            agree_but_unstable = o.primary is None
            text = (
                f"stability: {lab} reads {v.primary} on its own seeds, as {o_lab} does, but "
                f"{why} ({v.readings})"
            )
        else:
            text = f"stability: at {lab} the verdict {why} ({v.readings})"
        causes.append(Cause("stability", text, lab))
    if agree_but_unstable:
        return causes
    if a.discriminating != b.discriminating:
        text = (
            f"test set: discriminating {_disc_mark(a)} at {label_a}, {_disc_mark(b)} at {label_b}"
        )
        causes.append(Cause("test set", text))
    if a.n_failed != b.n_failed:
        causes.append(Cause("failed runs", f"failed runs ({a.n_failed} vs {b.n_failed})"))
    if same_profile_metric:
        causes.append(Cause("metric", same_profile_metric))
    if a.n_seeds != b.n_seeds and min(a.n_seeds, b.n_seeds) < 2:
        causes.append(Cause("seeds", "too few seeds on one side"))
    if moved := _parts_moved(a, b, label_a, label_b):
        causes.append(Cause("parts", moved))
    budget = (
        "budget (training steps, data, width and seeds differ between the profiles: "
        "effects that need the longer training show only at the paper profile)"
    )
    return [*causes, Cause("budget", budget)]


def _parts_moved(a, b, label_a: str, label_b: str, lead: str = "parts that read otherwise") -> str:
    """The parts of a claim whose status differs between two verdicts of it (statements only,
    not the conditions), each with its status, effect and 90% interval on both sides: where the
    verdicts part ways ("" where no part's status moved: a gate or the discrimination check
    did)."""

    def said(q) -> str:
        return f"{q.status} ({fmt(q.point)} [{fmt(q.lo)}, {fmt(q.hi)}])"

    theirs = {q.name: q for q in b.parts if q.role == "part"}
    moved = [
        f"{q.name}: {said(q)} at {label_a}, {said(theirs[q.name])} at {label_b}"
        for q in a.parts
        if q.role == "part" and q.name in theirs and theirs[q.name].status != q.status
    ]
    if not moved:
        return ""
    more = len(moved) - PARTS_NAMED
    return f"{lead}: " + "; ".join(moved[:PARTS_NAMED]) + (f"; and {more} more" if more > 0 else "")


def _labels(profile: str | None, others) -> list[str]:
    return [f"{profile or 'this folder'} (here)"] + [
        f"{p or 'unknown'} (`{folder_label(d)}/`)" for d, p, _ in others
    ]


def comparison_rows(verdicts, profile: str | None, others) -> list[ComparisonRow]:
    """Every claim's verdict here (``verdicts``) and in each other results folder (``others``:
    ``(folder, profile, verdicts)`` as :func:`load_other` gives them), with whether they agree
    and the likely causes where they do not."""
    labels = _labels(profile, others)
    maps = [{v.key: v for v in verdicts}] + [{v.key: v for v in vs} for _, _, vs in others]
    keys = list(dict.fromkeys(k for m in maps for k in m))

    def metric_note(m, key) -> str:
        if not key.startswith("4 ("):
            return ""
        other = (
            key.replace("geometric-mean error", "MSE")
            if "geometric" in key
            else key.replace("MSE", "geometric-mean error")
        )
        a, b = m.get(key), m.get(other)
        if a and b and _outcome(a) != _outcome(b) and not (_no_runs(a) or _no_runs(b)):
            labels = ("geometric-mean error", "MSE")
            labels = labels if "geometric" in key else labels[::-1]
            moved = _parts_moved(a, b, *labels, lead="the parts")
            return "metric: geometric-mean error and MSE disagree within a profile" + (
                f" ({moved})" if moved else ""
            )
        return ""

    rows = []
    for key in keys:
        vs = [m.get(key) for m in maps]
        claim = next(m[key].claim for m in maps if key in m)
        for i, m in enumerate(maps):  # a key its pending campaign has no rows for yet
            if vs[i] is None:
                vs[i] = next(
                    (v for v in m.values() if v.claim == claim and _is_pending(v)),
                    None,
                )
        real = [v for v in vs if not _no_runs(v)]
        agree = None if len(real) < 2 else len({_outcome(v) for v in real}) == 1
        # Causes against the first folder with a comparable verdict (here, unless here is
        # pending or has no runs: then the others' disagreement is still explained).
        base = next((i for i, v in enumerate(vs) if not _no_runs(v)), 0)
        causes = []
        for i in range(len(vs)):
            a, b = vs[base], vs[i]
            # a folder without the claim's runs says so in its cell: no cause to name
            if i == base or (_no_runs(a) and _no_runs(b)) or _absent(b):
                continue
            if a is None or b is None or _outcome(a) != _outcome(b) or _no_runs(a) != _no_runs(b):
                note = metric_note(maps[base], key) or metric_note(maps[i], key)
                causes += _cause(a, b, labels[base], labels[i], note)
        causes = list(dict.fromkeys(causes))  # each cause once, whichever folders share it
        states = tuple(_state(v) for v in vs)
        rows.append(
            ComparisonRow(key, claim, tuple(labels), tuple(vs), states, agree, tuple(causes))
        )
    return rows


def comparison_section(verdicts, profile: str | None, others) -> list[str]:
    """Every claim's verdict here and in each other results folder, side by side: the
    markdown of :func:`comparison_rows`."""
    if not others:
        return []
    head = ["claim", *_labels(profile, others), "agree", "likely cause of a disagreement"]
    out = [
        "## Verdicts at both budgets",
        "",
        "Each claim's verdict from these runs and from the other results folders (same rules; "
        "a folder without a claim's runs says *no runs*). Where they disagree, the likely cause "
        "is named: missing runs, a test set that does not discriminate, failed runs, the "
        "stability of one folder's reading (it does not replicate on seeds 5-9 or changes "
        "without one seed; where its own seeds read as the other folder does, that is the only "
        "cause named), the metric "
        "(claim 4: geometric-mean error vs MSE), the parts that read otherwise (each with its "
        "status and effect on both sides: where the two readings part), or the budget (the "
        "paper profile trains 8000 "
        "steps on 800 trajectories at width 256 with 5 seeds; quick 1000 steps on 200 at width "
        "128 with 5). *agree* compares the verdicts (reproduced, partly reproduced, not "
        "reproduced, inconclusive), not an inconclusive verdict's reason: neither "
        "*inconclusive* nor *inconclusive (does not replicate)* signs the claim.",
        "",
        "| " + " | ".join(head) + " |",
        "|" + " --- |" * len(head),
    ]
    for row in comparison_rows(verdicts, profile, others):
        if all(v is None or (v.n_seeds == 0 and not _is_pending(v)) for v in row.verdicts):
            continue  # a key no folder has runs for (e.g. a variant none of them ran)
        agree = {None: "-", True: "yes", False: "**no**"}[row.agree]
        causes = md_escape("; ".join(c.text for c in row.causes)) or "-"
        cells = [_cell_text(v) for v in row.verdicts]
        out.append("| " + " | ".join([md_escape(row.key), *cells, agree, causes]) + " |")
    return out + [""]


def pending(d: Path, runs: pd.DataFrame, profile: str | None, verdicts) -> list:
    """The verdicts of a folder of a selection's runs (``paper-core``), each replaced by
    ``pending (n of m runs)`` where fewer of its claim's runs are stored than the selection
    declares (a campaign under way); a judged claim whose further reading
    (``Experiment.supplementary``) waits for runs says so in its detail, per seed set."""
    if profile not in SELECTIONS or not len(runs):  # only a campaign's selection is pending
        return verdicts
    want = stored_counts(runs, profile)
    waiting = supplements_waiting(runs, profile)
    out = []
    for v in verdicts:
        n, m = want.get(v.claim, (0, 0))
        if m and n < m:
            v = dataclasses.replace(v, verdict=f"pending ({n} of {m} runs)", pending=(n, m))
        elif v.claim in waiting:
            v = dataclasses.replace(v, detail=f"{v.detail}; {waiting[v.claim]}")
        out.append(v)
    return out


def load_other(d: Path):
    runs, curves, profile = load_tables(d)
    verdicts = judge(runs, curves, profile).final
    return d, profile, pending(d, runs, profile, verdicts)
