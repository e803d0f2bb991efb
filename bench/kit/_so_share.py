"""The share reading of "second-order structure explains the HNN's advantage" (claims 3, 13)."""

from __future__ import annotations

from collections.abc import Mapping

import pandas as pd

from . import policy
from ._gates import Gate, condition, gated
from ._models import MODEL_LABELS
from ._seeds import paired
from ._stats import Part, greater, share

__all__ = ["so_share"]


def so_share(
    runs: pd.DataFrame,
    cell: Mapping,
    hnn: str,
    advantage_name: str,
    share_name: str,
    gates: Mapping[str, Gate],
    *,
    either_way: bool = False,
) -> tuple[Part | None, Part | None, int]:
    """NODE+SO's share of the NODE -> HNN gap in ``cell``, as (condition, part, seeds).

    Per seed ``closed = log(err NODE / err NODE+SO)`` and ``gap = log(err NODE / err hnn)``;
    the part holds when ``closed - s * gap > 0`` at the policy's share ``s`` (:func:`share`),
    judged where the HNN has an advantage to explain (the condition: ``gap`` a *greater* part
    at the error margin) and where ``gates`` (``node``, ``node_so``, ``hnn``: learning gates)
    are open. (None, None, 0) without paired seeds.

    ``either_way``: "SO accounts for the difference" whichever model leads: where the mean gap
    is negative (the NODE ahead of the HNN) both ``closed`` and ``gap`` change sign, so the part
    asks whether NODE+SO lands at least ``s`` of the way from the NODE to the HNN, and the
    condition whether the NODE's lead exceeds the error margin.
    """
    closed = paired(runs, {**cell, "model": "node"}, {**cell, "model": "node_so"})
    gap = paired(runs, {**cell, "model": "node"}, {**cell, "model": hnn})
    both = pd.concat([closed, gap], axis=1, keys=["c", "g"]).dropna()
    if not len(both):
        return None, None, 0
    if either_way and both["g"].mean() < 0:
        both = -both
        advantage_name += " reversed: the NODE leads"
    part = share(
        share_name,
        both["c"].to_numpy(),
        both["g"].to_numpy(),
        policy.margin("share"),
        note=f"gap log(NODE/{MODEL_LABELS.get(hnn, hnn)}) = {both['g'].mean():.3g}, closed by SO = "
        f"{both['c'].mean():.3g}",
    )
    advantage = greater(advantage_name, both["g"], policy.margin("error"))
    judged = gated(part, condition(advantage), *(gates[m] for m in ("node", "node_so", hnn)))
    return advantage, judged, len(both)
