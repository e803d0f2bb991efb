"""Trivial predictors as the floor: does a model learn, and does an experiment discriminate?

A model learned when its rollout error beats the best trivial predictor (at rest, constant
velocity) by the policy's learning margin; an experiment discriminates when its best model did.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..core import parse_pairs
from . import policy
from ._gates import Gate, learned
from ._models import MODEL_LABELS, TRIVIAL_MODELS
from ._seeds import bad_rows, log_per_seed, scored, seed_span

__all__ = [
    "TRIVIAL_FACTOR",
    "Discrimination",
    "discrimination",
    "LinkGates",
    "learned_at_each_k",
    "learned_cell",
    "non_trivial",
    "per_system_discrimination",
    "succeeds",
    "trivial_log",
]


# A model succeeds when it beats the best trivial predictor by this factor (the policy's).
TRIVIAL_FACTOR = policy.POLICY["learning"].margin


def several_rates(runs: pd.DataFrame) -> bool:
    """Whether some model of ``runs`` was trained at more than one learning rate (then the
    rate tells cells apart; a protocol that gives each model its own rate does not)."""
    if not len(runs) or "lr" not in runs:
        return False
    lr = pd.to_numeric(runs["lr"], errors="coerce")
    return bool((lr.groupby(runs["model"]).nunique() > 1).any())


def _variant_key(runs: pd.DataFrame) -> pd.Series:
    """A label per row naming its model variant (model, options, dissipation, coordinates,
    loss, data size and noise where they are not the defaults, and the learning rate where a
    model of ``runs`` has more than one: :func:`several_rates`)."""
    if not len(runs):
        return pd.Series(dtype=object)
    lr_varies = several_rates(runs)

    def one(model, dissipation, options, coordinates, loss, noise, lr) -> str:
        s = str(model)
        if dissipation is True or dissipation == 1.0:
            s += "+rayleigh"
        opts = parse_pairs(options)
        if opts:
            s += "[" + ",".join(f"{a}={b}" for a, b in sorted(opts.items())) + "]"
        if coordinates == "momentum":
            s += " (q,p)"
        if loss == "l1":
            s += " L1"
        if noise:
            s += f" noise={float(noise):g}"
        if lr_varies:
            s += f" lr={float(lr):g}"
        return s

    fields = ("model", "dissipation", "model_options", "coordinates", "loss", "noise", "lr")
    columns = [runs[f].to_numpy() if f in runs else [None] * len(runs) for f in fields]
    return pd.Series([one(*row) for row in zip(*columns, strict=True)], index=runs.index)


@dataclass
class Discrimination:
    """Whether a group's best model beats the best trivial predictor by the learning margin."""

    group: str
    status: str  # "yes" | "no" | "unknown"
    best: str = ""
    margin: float = math.nan  # min over seeds of log(err trivial / err best)
    trivial: float = math.nan  # mean trivial error

    def text(self) -> str:
        if self.status == "unknown":
            return f"{self.group}: discriminating unknown (no finished trivial-predictor runs)"
        return (
            f"{self.group}: discriminating {self.status} (best {self.best} beats the best "
            f"trivial predictor by {math.exp(self.margin):.3g}x on its worst seed, needs "
            f"{policy.margin('learning').label()})"
        )


def trivial_log(rows: pd.DataFrame, metric: str = "rollout_error") -> pd.Series:
    """Per-seed log error of the best finished trivial predictor among ``rows``."""
    if not len(rows):
        return pd.Series(dtype=float)
    t = rows["model"].isin(TRIVIAL_MODELS).to_numpy() & ~bad_rows(rows, metric).to_numpy()
    if not t.any():
        return pd.Series(dtype=float)
    s = np.log(scored(rows, metric)[t])  # finished rows: their own values
    return s.groupby([rows["seed"][t], rows["model"][t]]).mean().groupby(level=0).min()


def succeeds(model_log: pd.Series, trivial_log: pd.Series) -> tuple[bool | None, float]:
    """(success, worst-seed log margin): a model succeeds when ``log(trivial / model)`` reaches
    the policy's learning margin on every seed both have; None without paired seeds."""
    m = (trivial_log - model_log).dropna()
    if not len(m):
        return None, math.nan
    worst = float(m.min())
    return bool(worst >= policy.margin("learning").test), worst


def learned_cell(
    rows: pd.DataFrame,
    cell: Mapping,
    label: str | None = None,
    metric: str = "rollout_error",
    trivial: pd.DataFrame | None = None,
    *,
    squared: bool = False,
) -> Gate:
    """The learning gate of one cell of ``rows`` against the best finished trivial predictor
    among ``trivial`` (default: the trivial rows of ``rows``: the same test set); ``squared``
    when ``metric`` is a mean of squares."""
    t = trivial_log(rows if trivial is None else trivial, metric)
    name = label or MODEL_LABELS.get(str(cell.get("model")), str(cell.get("model")))
    return learned(name, log_per_seed(rows, cell, metric), t if len(t) else None, squared=squared)


@dataclass(frozen=True)
class LinkGates:
    """The learning gates of a part read over one or several numbers of links: ``kept``, the
    k it pools (empty where none passed); ``gates``, the gates to put on it
    (:func:`bench.kit.gated`); ``note``: the k left out and why, where any was."""

    kept: tuple
    gates: tuple
    note: str = ""


def learned_at_each_k(cells) -> LinkGates:
    """The learning gates of a part whose models must have learned (principle b), over every
    k its rows hold. ``cells``: ``(rows, cell, label)`` triples, one per gated model: the
    rows of its comparison group (trivial rows included, the same test set), its cell and
    its name (:func:`learned_cell`).

    One k (or none stored): each model's gate, as :func:`learned_cell` gives it. Several k: a
    k is a cell of its own, so each gate is judged at each k, and the part pools only the k
    at which every gate is open (or unknown): a k where a gated model did not learn says
    nothing about the comparison and is left out, named in ``note``. The one gate returned is
    closed where no k is kept."""
    cells = list(cells)
    ks = sorted({float(k) for rows, cell, _ in cells for k in _links_of(rows, cell)})
    if len(ks) <= 1:
        gates = tuple(learned_cell(rows, cell, label) for rows, cell, label in cells)
        kept = tuple(ks) if all(g.open is not False for g in gates) else ()
        return LinkGates(kept, gates)
    at = {
        k: [learned_cell(r[r["k"] == k], c, f"{name} at k = {k:g}") for r, c, name in cells]
        for k in ks
    }
    kept = tuple(k for k in ks if all(g.open is not False for g in at[k]))
    closed = "; ".join(g.text for k in ks if k not in kept for g in at[k] if g.open is False)
    span = seed_span([int(k) for k in kept])
    if not kept:
        return LinkGates((), (Gate("learned at some k", False, closed),))
    unknown = "; ".join(g.text for k in kept for g in at[k] if g.open is None)
    gate = Gate(
        "learned at each k pooled",
        None if unknown else True,
        unknown or f"every gated model learned at k = {span}",
    )
    note = f"pooled over k = {span}, where every gated model learned; left out: {closed}"
    return LinkGates(kept, (gate,), note if closed else "")


def _links_of(rows: pd.DataFrame, cell: Mapping) -> np.ndarray:
    """The k of the rows of ``cell`` (its model's, not its trivial predictors')."""
    if "k" not in rows or not len(rows):
        return np.array([])
    mask = np.ones(len(rows), dtype=bool)
    for col, value in cell.items():
        mask &= (rows[col] == value).to_numpy() if col in rows else False
    return rows["k"][mask].dropna().unique()


def discrimination(
    rows: pd.DataFrame, group: str, metric: str = "rollout_error", scores: pd.Series | None = None
) -> Discrimination:
    """Is ``rows`` (one comparison group, trivial rows included) discriminating? The best model
    is the non-trivial variant with the lowest mean log score (``scores`` overrides the metric,
    e.g. claim 7's velocity-space scores)."""
    if not len(rows):
        return Discrimination(group, "unknown")
    sc = scores.reindex(rows.index) if scores is not None else scored(rows, metric)
    trivial = rows["model"].isin(TRIVIAL_MODELS).to_numpy()
    # a trivial predictor that failed says nothing about the test set: only finished ones count
    finished = ~bad_rows(rows, metric if scores is None else "rollout_error").to_numpy()
    is_t = trivial & finished
    if not is_t.any():
        return Discrimination(group, "unknown")
    lt = np.log(sc[is_t]).groupby([rows["seed"][is_t], rows["model"][is_t]]).mean()
    triv = lt.groupby(level=0).min()
    m = rows[~trivial]
    if not len(m):
        return Discrimination(group, "unknown")
    key = _variant_key(m)
    per = np.log(sc[m.index]).groupby([key, m["seed"]]).mean()
    means = per.groupby(level=0).mean().sort_values()
    best = str(means.index[0])
    ok, margin = succeeds(per.loc[best], triv)
    status = "unknown" if ok is None else ("yes" if ok else "no")
    return Discrimination(group, status, best, margin, float(np.exp(triv).mean()))


def non_trivial(rows: pd.DataFrame) -> pd.DataFrame:
    return rows[~rows["model"].isin(TRIVIAL_MODELS)] if len(rows) else rows


def per_system_discrimination(
    rows: pd.DataFrame, metric: str = "rollout_error"
) -> list[Discrimination]:
    if not len(rows):
        return []
    return [discrimination(g, str(s), metric) for s, g in rows.groupby("system")]
