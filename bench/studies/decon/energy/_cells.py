"""The cells and the fit that claim 1 and Fig. 2 share: the Fig. 2 runs scored as the verdicts
score them, and the Theil-Sen line of log energy violation on log rollout error."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy import stats

from ....core import plain, select
from ....kit import TRIVIAL_MODELS, non_trivial, paper_spring, scored, t_bounds_jackknife
from ..._claims import PAPER_MODELS, suite_form


def energy_cells(runs: pd.DataFrame) -> pd.DataFrame:
    """Fig. 2 cells: the four paper models (in the suite's form) and the trivial predictors on
    undamped chain/spring (the paper's spring initial state where present), any k, L2 loss;
    failed rows kept."""
    p = paper_spring(plain(suite_form(runs)))
    return select(
        p,
        ok=False,
        system=["chain_pendulum", "spring_pendulum"],
        model=[*PAPER_MODELS, *TRIVIAL_MODELS],
        loss="l2",
    )


def scored_cells(runs: pd.DataFrame) -> pd.DataFrame:
    """The model runs of the Fig. 2 cells (:func:`energy_cells`, trivial predictors left out)
    with ``_err`` and ``_ev``: rollout error and energy violation as claim 1 and Fig. 2 score
    them (failed and diverged runs at the worst, ``kit.scored`` over these runs)."""
    cells = non_trivial(energy_cells(runs))
    return cells.assign(_err=scored(cells, "rollout_error"), _ev=scored(cells, "energy_violation"))


# Claim 1 is judged on the models of the paper's Fig. 2 (its plotting notebook: the separable
# HNN, NODE and NODE+SO); the non-separable HNN is reported beside it, not judged.
FIG2_HNNS = ("hnn_so",)
FIG2_NODES = ("node", "node_so")
FIG2_FAMILIES = {"NODEs": FIG2_NODES, "HNNs": FIG2_HNNS}


def _theil_sen(x: np.ndarray, y: np.ndarray) -> float:
    """The Theil-Sen slope of ``y`` on ``x`` (the median of the pairwise slopes); NaN with fewer
    than two distinct ``x``."""
    if len(x) < 2 or np.ptp(x) == 0:
        return math.nan
    return float(stats.theilslopes(y, x).slope)


def proportionality(models: pd.DataFrame) -> tuple[float, float, float, int]:
    """(slope, lo, hi, n seeds): the Theil-Sen slope of ``log EV`` on ``log rollout_error``
    (columns ``_ev``, ``_err``) over every run of ``models``, one line through models, systems
    and seeds pooled (as the paper's notebook fits one line through Fig. 2's scatter), with
    one-sided (1 - alpha) t bounds from the leave-one-seed-out jackknife
    (:func:`t_bounds_jackknife`)."""
    seeds = np.sort(models["seed"].unique())
    by_seed = [
        (np.log(g["_err"].to_numpy(float)), np.log(g["_ev"].to_numpy(float)))
        for g in (models[models["seed"] == s] for s in seeds)
    ]

    def stat(idx) -> float:
        return _theil_sen(
            np.concatenate([by_seed[i][0] for i in idx]),
            np.concatenate([by_seed[i][1] for i in idx]),
        )

    return (*t_bounds_jackknife(stat, len(seeds)), len(seeds))
