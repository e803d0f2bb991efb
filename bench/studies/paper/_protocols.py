"""Two readings of one claim side by side: the suite's protocol and the seed's own, each with the
verdict of its runs. A claim judged on both renders one :func:`protocol_table` in its report
section; README's findings take the seeds' protocols from those tables (``bench.findings``)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from ._verdict import Verdict

HEADER = "| protocol | ours | the seed's |"
ROWS = ("data", "targets", "loss", "optimiser", "steps", "metric")


@dataclass(frozen=True)
class Protocol:
    """One reading: how its runs were trained and scored (:data:`ROWS`, one short phrase
    each), and ``verdict`` the rule's verdict on its runs alone (None: no runs)."""

    data: str
    targets: str
    loss: str
    optimiser: str
    steps: str
    metric: str
    verdict: Verdict | None = None


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
    gates = [g for g in v.parts[0].gates if not g.text.startswith("condition")]
    if not gates:
        return "-"
    mark = {True: "yes", False: "no", None: "?"}
    return ", ".join(f"{g.label} {mark[g.open]}" for g in gates)


def verdict_text(v: Verdict | None) -> str:
    """``reproduced (5 seeds)``; a headline part that was not tested says why: the models that
    did not learn (the claim is then untested, not refuted), or its unmet condition."""
    if v is None:
        return "not run"
    text = f"{v.verdict} ({v.n_seeds} seeds)"
    if v.parts and v.parts[0].status == "not tested":
        gates = [g for g in v.parts[0].gates if g.open is False]
        stuck = [g.label for g in gates if not g.text.startswith("condition")]
        if stuck:
            text += f", untested: {' and '.join(stuck)} did not learn"
        elif gates:
            text += f", untested: condition {gates[0].label} not met"
    return text


def protocol_table(ours: Protocol, seeds: Protocol, differs: str, extra: tuple = ()) -> list[str]:
    """The markdown table: a row per :data:`ROWS`, then each model's learning gate, the verdict
    of each reading and ``differs``, one line on what still separates the seed's reading from
    the seed's code (the claim's verdict is the seed's reading's where it has runs); ``extra``:
    more (row, ours, the seed's) rows before those."""
    lines = ["", HEADER, "|---|---|---|"]
    lines += [f"| {row} | {getattr(ours, row)} | {getattr(seeds, row)} |" for row in ROWS]
    lines += [f"| {row} | {a} | {b} |" for row, a, b in extra]
    lines.append(f"| learned | {learned_text(ours.verdict)} | {learned_text(seeds.verdict)} |")
    lines.append(f"| verdict | {verdict_text(ours.verdict)} | {verdict_text(seeds.verdict)} |")
    lines.append(f"| still differs from the seed's code | - | {differs} |")
    return lines
