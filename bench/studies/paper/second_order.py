"""Fig. 4 (second-order structure): the experiment, claim 3's verdict rule and the figure."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from ...core._experiments import Experiment
from ...core._query import (
    plain,
    select,
)
from ...core._studies import Study, register_study
from ._common import (
    PAPER_MODELS,
    SPRING_PAPER,
    SYSTEMS,
    _paper_cell,
    _shared,
)
from ._plot import (
    _model_bars,
)
from ._rules import (
    CLAIM_TITLES,
    _verdict,
    discrimination,
)
from ._stats import (
    DELTA,
    Verdict,
    _boot,
    _cell,
    _n_bad,
    _paired,
    _paper_spring,
    _Part,
)

SECOND_ORDER = Experiment(
    name="second_order",
    title="Fig. 4: second-order structure, NODE vs NODE+SO and HNN vs HNN+SO",
    axes={
        "system": SYSTEMS,
        "k": (2,),
        "model": (*PAPER_MODELS, "constant_velocity"),
        "system_params": ((), SPRING_PAPER),
    },
    profile_overrides=_shared(),
    include=_paper_cell,
    claim=3,
)


def claim_3(runs: pd.DataFrame, curves: pd.DataFrame | None = None) -> Verdict:
    """Claim 3 (Fig. 4): "most" of the HNN's advantage is second-order structure.

    Per system (undamped chain and spring, k = 2 where present), per seed:
    ``closed = log(err NODE / err NODE+SO)`` and ``gap = log(err NODE / err HNN+SO)``; the
    fraction of the gap that second-order structure closes is ``mean(closed) / mean(gap)``,
    with a seed bootstrap. Each system's part holds when the fraction's CI lies above 0.5
    ("most"), contradicts when below 0.5, and is undecided otherwise, or when HNN+SO has no
    meaningful advantage to explain (``mean(gap) < log 1.25``). Headline: the fraction pooled
    (per-seed means of closed and gap) over the systems that have such an advantage; a system
    where HNN+SO does not beat NODE has a near-zero denominator and would make the pooled
    fraction meaningless."""
    p = _paper_spring(select(plain(runs), loss="l2", ok=False))
    ks = p["k"].dropna().unique() if "k" in p and len(p) else []
    k = 2 if 2 in set(ks) else None
    base = {"k": k} if k is not None else {}
    parts, closed_all, gap_all, discs = [], [], [], []
    n_failed = 0
    for system in ("chain_pendulum", "spring_pendulum"):
        s = {**base, "system": system}
        closed = _paired(p, {**s, "model": "node"}, {**s, "model": "node_so"})
        gap = _paired(p, {**s, "model": "node"}, {**s, "model": "hnn_so"})
        both = pd.concat([closed, gap], axis=1, keys=["c", "g"]).dropna()
        if not len(both):
            continue
        n_failed += _n_bad(_cell(p, {**s, "model": ["node", "node_so", "hnn_so"]}))
        discs.append(discrimination(_cell(p, s), system))
        parts.append(_fraction_part(system, both["c"].to_numpy(), both["g"].to_numpy()))
        if both["g"].mean() >= DELTA:  # only a system with an advantage to explain is pooled
            closed_all.append(both["c"])
            gap_all.append(both["g"])
    if not parts:
        return _verdict(3, CLAIM_TITLES[3], [], None, 0, "fraction of the log gap closed by SO")
    if not gap_all:  # no system shows a meaningful HNN+SO advantage: the headline is undecided
        closed_all, gap_all = [pd.Series(dtype=float)], [pd.Series(dtype=float)]
    c = pd.concat(closed_all, axis=1).dropna().mean(axis=1)
    g = pd.concat(gap_all, axis=1).dropna().mean(axis=1)
    both = pd.concat([c, g], axis=1, keys=["c", "g"]).dropna()
    head = _fraction_part("pooled", both["c"].to_numpy(), both["g"].to_numpy())
    return _verdict(
        3,
        CLAIM_TITLES[3],
        parts,
        head,
        len(both),
        "fraction of log(NODE / HNN+SO) closed by second-order structure",
        discs=discs,
        n_failed=n_failed,
    )


def fig_second_order(runs, curves, outdir: Path) -> list[Path]:
    """Fig. 4: rollout error of NODE, NODE+SO, HNN, HNN+SO per system (mean +- sem)."""
    return _model_bars(runs, outdir, "fig4_second_order", "Second-order structure")


def _fraction_part(name: str, closed: np.ndarray, gap: np.ndarray) -> _Part:
    def frac(idx):
        gm = float(np.mean(gap[idx]))
        return float(np.mean(closed[idx])) / gm if gm != 0 else math.nan

    point, lo, hi = _boot(np.arange(len(gap)), frac)
    note = f"gap log(NODE/HNN+SO) = {np.mean(gap):.3g}, closed by SO = {np.mean(closed):.3g}"
    if len(gap) < 2 or not np.isfinite(lo) or np.mean(gap) < DELTA:
        status = "undecided"
        if np.mean(gap) < DELTA:
            note += "; HNN+SO has no meaningful advantage over NODE to explain"
    elif lo >= 0.5:
        status = "holds"
    elif hi < 0.5:
        status = "contradicts"
    else:
        status = "undecided"
    return _Part(f"{name}: fraction of the gap closed by SO", status, point, lo, hi, len(gap), note)


STUDY = register_study(
    Study(
        name="second_order",
        experiments=(SECOND_ORDER,),
        claim=3,
        title=CLAIM_TITLES[3],
        rule=claim_3,
        reads=("energy", "second_order", "coordinates", "loss"),
        figure=fig_second_order,
        stem="fig4_second_order",
    )
)
