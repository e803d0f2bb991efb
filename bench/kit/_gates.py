"""Gates: the preconditions of a comparison ("both models learned", "at similar loss").

A part with a closed gate reads *not tested*: it never counts for or against its claim.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from . import policy
from ._stats import Part

__all__ = [
    "Gate",
    "apply_gates",
    "condition",
    "foil",
    "gated",
    "learned",
    "similar_fit",
    "waiting",
]


@dataclass(frozen=True)
class Gate:
    """A precondition of a comparison: ``open`` True (met), False (not met: the part it gates
    reads *not tested*) or None (unknown: no trivial-predictor runs; the part is judged,
    flagged). ``text`` says what was measured against what. ``binding`` False: a foil's
    status (:func:`foil`), shown beside the gates and never closing the part. ``kind``:
    "learning" (a model beat the trivial predictor), "condition" (a stated condition of the
    claim, :func:`condition`) or "waiting" (the runs a part compares are not stored yet,
    :func:`waiting`)."""

    label: str
    open: bool | None
    text: str
    binding: bool = True
    kind: str = "learning"


def foil(gate: Gate) -> Gate:
    """The learning status of a claim's foil: a model whose failure is the claim's content
    (the baseline whose energy drifts, hence whose rollout drifts), shown with the part's gates
    and never closing it."""
    return Gate(
        f"{gate.label} (the foil, not gated)", gate.open, gate.text, binding=False, kind=gate.kind
    )


def waiting(label: str, why: str) -> Gate:
    """A closed gate on the parts that compare a model whose runs are not stored yet (a
    further reading still running): those parts read *not tested*, the rest of the claim is
    judged, and nothing says the model did not learn."""
    return Gate(label, False, f"{label} waits: {why}", kind="waiting")


def learned(label: str, model_log: pd.Series, trivial_log: pd.Series, *, squared=False) -> Gate:
    """The learning gate: the model's per-seed log score beats the best trivial predictor's by
    the policy's learning margin, as a geometric mean over the paired seeds (``squared``: the
    scores are mean squares, the margin squared). Unknown without paired trivial runs."""
    mg = policy.margin("learning", squared=squared)
    if model_log is None or not len(model_log):
        return Gate(label, None, f"{label} has no runs")
    if trivial_log is None:
        return Gate(label, None, f"{label}: no paired trivial-predictor runs")
    d = (trivial_log - model_log).dropna()
    d = d[np.isfinite(d)]
    if not len(d):
        return Gate(label, None, f"{label}: no paired trivial-predictor runs")
    ratio = math.exp(float(d.mean()))
    ok = bool(float(d.mean()) >= mg.test)
    # a model worse than the trivial predictor says so, not "0.1x below" it
    where = (
        f"{ratio:.3g}x below the best trivial predictor"
        if ratio >= 1
        else f"{1 / ratio:.3g}x above the best trivial predictor"
    )
    return Gate(
        label,
        ok,
        f"{label} {'learned' if ok else 'did not learn'}: {where} (geometric mean over "
        f"{len(d)} seeds; the gate is {mg.label()})",
    )


def condition(part: Part) -> Gate:
    """A stated condition of other parts ("at similar loss"): open when ``part`` holds. The
    part becomes a *condition*: shown, never a finding of its own."""
    part.role = "condition"
    return Gate(
        part.name, part.status == "holds", f"condition {part.name}: {part.status}", kind="condition"
    )


def similar_fit(name: str, fit_edge, mg) -> tuple[Part, Gate]:
    """ "At similar loss", a stated condition that can only confound, read the same way in every
    claim that quotes one. ``fit_edge``: per seed ``log(loss of the other model / loss of the
    favoured one)``, how much better the model the claim favours fits. An *at most* part at the
    loss margin ``mg`` (a *condition*: shown, never a finding of its own), and its gate: closed
    only where the part is contradicted, i.e. the favoured model is shown to fit better by more
    than the margin, so that fit could explain its advantage. Where it fits no better, or worse,
    or the data cannot tell, fit cannot explain the advantage and the comparison is judged."""
    from ._stats import at_most

    part = at_most(name, fit_edge, mg)
    part.role = "condition"
    shut = part.status == "contradicts"
    text = f"condition {part.name}: {part.status}" + (
        " (the favoured model fits better beyond the margin)" if shut else ""
    )
    return part, Gate(part.name, not shut, text, kind="condition")


def gated(part: Part, *gates: Gate) -> Part:
    """``part`` judged only where every gate is open (:func:`apply_gates`)."""
    part.gates = (*part.gates, *gates)
    return part


def apply_gates(parts: list[Part]) -> None:
    """A part with a closed gate reads *not tested*, its reasons in the note."""
    for p in parts:
        binding = [g for g in p.gates if g.binding]
        closed = [g for g in binding if g.open is False]
        if closed:
            p.status = "not tested"
            p.note = "; ".join([*(g.text for g in closed), *([p.note] if p.note else [])])
        elif any(g.open is None for g in binding):
            unknown = "; ".join(g.text for g in binding if g.open is None)
            p.note = f"{p.note}; gate unknown: {unknown}" if p.note else f"gate unknown: {unknown}"
