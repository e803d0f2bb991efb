"""Two readings of one claim side by side: the suite's protocol and the seed's own, each with the
verdict of its runs on each seed set. Every claim judged on two protocols renders its table with
:func:`protocol_table`; README's findings take the seeds' protocols from those tables
(``bench.findings``)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field

import pandas as pd

from ..core import SELECTIONS, expand, get
from ._seeds import required_seeds, seed_sets, seed_span
from ._verdict import Verdict

HEADER = "| protocol | ours | the seed's |"
ROWS = ("data", "targets", "loss", "optimiser", "steps", "metric")


@dataclass(frozen=True)
class SeedSet:
    """One seed set's reading: ``verdict`` the rule's on its runs (None: none stored), and where
    the profile is a campaign's selection, ``stored`` of the ``declared`` runs of the reading's
    experiment on these seeds (``declared`` 0: not a selection, nothing is pending)."""

    seeds: tuple[int, ...]
    verdict: Verdict | None
    stored: int = 0
    declared: int = 0

    @property
    def pending(self) -> bool:
        return bool(self.declared) and self.stored < self.declared


@dataclass(frozen=True)
class Protocol:
    """One reading: how its runs were trained and scored (``cells``, row -> one short phrase:
    :data:`ROWS` and any the claim adds, in table order) and its verdict on each seed set
    (:func:`by_seed_set`; empty: no runs)."""

    cells: dict[str, str]
    seed_sets: tuple[SeedSet, ...] = field(default=())

    @property
    def verdict(self) -> Verdict | None:
        """The verdict on the first seed set (the profile's own seeds), None while pending."""
        first = self.seed_sets[0] if self.seed_sets else None
        return None if first is None or first.pending else first.verdict


def by_seed_set(
    rows: pd.DataFrame,
    profile: str | None,
    read: Callable[[pd.DataFrame], Verdict],
    experiment: str | None = None,
    runs: pd.DataFrame | None = None,
) -> tuple[SeedSet, ...]:
    """``read`` (the reading's rule: its rows -> a Verdict) on each seed set of ``profile``: its
    own seeds, then the replication seeds where any run is stored or declared there. Where
    ``profile`` is a campaign's selection (``paper-core``), a set on which fewer of
    ``experiment``'s declared runs are stored (in ``runs``, the folder's rows; default ``rows``)
    than it declares is pending and not judged. The own seeds of a profile that declares fewer
    than a verdict needs are the stored seeds outside the replication set (as the claims table
    reads them); without a profile, every stored seed."""
    stored = set(rows["seed"].astype(int)) if len(rows) and "seed" in rows else set()
    declared, rep = seed_sets(profile)
    if len(declared) < required_seeds():
        declared = tuple(sorted(s for s in stored if s not in rep))
    sets = [s for s in (declared, rep) if s] or [tuple(sorted(stored))]
    runs = rows if runs is None else runs
    done = set(runs["config_hash"]) if len(runs) and "config_hash" in runs else set()
    out = []
    for i, seeds in enumerate(sets):
        want = set()
        if experiment is not None and profile in SELECTIONS:
            want = {c.config_hash for c in expand(get(experiment), profile, seeds=list(seeds))}
        mine = rows[rows["seed"].isin(seeds)].reset_index(drop=True) if stored else rows
        if i and not len(mine) and not want:
            continue  # no replication runs stored or declared
        n = len(want & done)
        v = read(mine) if len(mine) and n == len(want) else None  # pending: not judged
        out.append(SeedSet(tuple(seeds), v, n, len(want)))
    return tuple(out)


def decided_by(v: Verdict, what: str, name: str, other: Verdict) -> Verdict:
    """``v``, the reading that decides the claim (``what``: its protocol, in words), with the
    verdict of the ``other`` reading (``name``) in its ``other_readings`` and its detail."""
    return dataclasses.replace(
        v,
        detail=f"{v.detail}; {what} ({name}: {other.verdict})",
        other_readings=(*v.other_readings, (name, other.verdict)),
    )


def learned_text(v: Verdict | None) -> str:
    """Each model's learning gate on the headline part: ``HNN yes, MLP no`` (``?`` unknown)."""
    if v is None or not v.parts:
        return "-"
    gates = [g for g in v.parts[0].gates if g.kind == "learning"]
    if not gates:
        return "-"
    mark = {True: "yes", False: "no", None: "?"}
    return ", ".join(f"{g.label} {mark[g.open]}" for g in gates)


def seed_set_text(s: SeedSet) -> str:
    """``reproduced (seeds 0-4)``, or ``pending (3 of 20 runs, seeds 0-4)``; an inconclusive
    verdict whose headline part was not tested says why: the models that did not learn (the
    claim is then untested, not refuted), or its unmet condition; a reading without a trivial
    predictor it beats says it does not discriminate."""
    where = f"seeds {seed_span(s.seeds)}"
    if s.pending:
        return f"pending ({s.stored} of {s.declared} runs, {where})"
    v = s.verdict
    if v is None or not v.n_seeds:
        return f"not run ({where})"
    text = f"{v.verdict} ({where})"
    if v.verdict.startswith("inconclusive") and v.parts and v.parts[0].status == "not tested":
        gates = [g for g in v.parts[0].gates if g.open is False and g.binding]
        stuck = [g.label for g in gates if g.kind == "learning"]
        if stuck:
            text += f", untested: {' and '.join(stuck)} did not learn"
        elif gates:  # "condition (b) ...: undecided" (or contradicts)
            text += f", untested: {gates[0].text}"
    if v.discriminating is False:
        text += ", not discriminating"
    return text


def verdict_text(p: Protocol) -> str:
    """The verdict cell of a reading: each seed set's :func:`seed_set_text`, or ``not run``."""
    return "; ".join(map(seed_set_text, p.seed_sets)) or "not run"


def protocol_table(ours: Protocol, seeds: Protocol, differs: str) -> list[str]:
    """The markdown table: a row per cell (ours' rows first, then any only the seed's has; each
    of :data:`ROWS` at least), each model's learning gate (on the profile's own seeds; ``-``
    while pending), the verdict of each reading per seed set, and ``differs``, one line on what
    still separates the seed's reading from the seed's code (the claim's verdict is the seed's
    reading's where it has runs)."""
    names = [*ours.cells, *(k for k in seeds.cells if k not in ours.cells)]
    if missing := [r for r in ROWS if r not in names]:
        raise ValueError(f"a protocol table needs the rows {ROWS}; missing {missing}")
    lines = ["", HEADER, "|---|---|---|"]
    lines += [f"| {n} | {ours.cells.get(n, '-')} | {seeds.cells.get(n, '-')} |" for n in names]
    lines.append(f"| learned | {learned_text(ours.verdict)} | {learned_text(seeds.verdict)} |")
    lines.append(f"| verdict | {verdict_text(ours)} | {verdict_text(seeds)} |")
    lines.append(f"| still differs from the seed's code | - | {differs} |")
    return lines
