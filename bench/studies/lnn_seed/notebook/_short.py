"""Claim 9 (c): the LNN seed's Fig. 2(a), "the LNN and baseline model perform similarly in
modelling the dynamics of the pendulum over short time periods" (Cranmer et al. 2020).

"Short" is the window of Fig. 2(a): the seed's notebook (``notebooks/DoublePendulum.ipynb`` of
MilesCranmer/lagrangian_nns, the cell that draws the figure) plots theta_1 and its error for the
LNN, the baseline and the truth over the first 100 points of a rollout at fps 10, t in
[0, 10) s (and again at 140-150 s, across a broken axis), against Fig. 2(b)'s energy over
1000 s. The short horizon is therefore :data:`SHORT_HORIZON_S` = 10 s, and the quantity is the
rollout's state error over it: a run's ``rollout_error`` (the geometric mean over t >= 1 and the
test trajectories of ||zhat - z|| / (||zhat|| + ||z||)) where its test horizon is at most 10 s,
as in both of claim 9's protocols (100 points 0.1 s apart: 9.9 s). A run whose horizon is longer
has no stored error over the first 10 s alone: the part is not tested on it.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ....kit import Part, equivalent, gated, learned_cell, paired, policy, undecided

SHORT_HORIZON_S = 10.0  # Fig. 2(a): the first 100 points at fps 10
COLUMN = "rollout_error_short"  # scored as a rollout error: a failed run at the worst, 1
NAME = "(c) short-horizon rollout error (first 10 s, Fig. 2(a)), log(LNN / baseline)"


def horizon_s(r: pd.DataFrame) -> pd.Series:
    """Each row's test horizon in seconds: (chunk * test_chunks - 1) * dt."""
    n = pd.to_numeric(r["chunk"], errors="coerce") * pd.to_numeric(
        r["test_chunks"], errors="coerce"
    )
    return (n - 1) * pd.to_numeric(r["dt"], errors="coerce")


def short_error(r: pd.DataFrame) -> pd.Series:
    """Each row's rollout error over the short horizon: its ``rollout_error`` where its test
    horizon is at most :data:`SHORT_HORIZON_S`, else NaN."""
    err = pd.to_numeric(r["rollout_error"], errors="coerce")
    return err.where(horizon_s(r) <= SHORT_HORIZON_S + 1e-9)


def short_part(r0: pd.DataFrame, lnn: dict, baseline: dict) -> Part:
    """An *equivalent* part (TOST) at the error margin on per-seed ``log(short-horizon rollout
    error LNN / baseline)``, failed runs at the worst error; judged where both models learned
    (the claim expects both to model the short-time dynamics: a model that learned nothing
    leaves it untested, not refuted)."""
    if not len(r0) or not {"chunk", "test_chunks", "dt", "rollout_error"} <= set(r0):
        return undecided(NAME, "no rollout errors")
    long = horizon_s(r0) > SHORT_HORIZON_S + 1e-9
    if long.all():
        return undecided(NAME, f"every test horizon is longer than {SHORT_HORIZON_S:g} s")
    # a failed run keeps its NaN error: scored at the worst; a long horizon drops the row
    r = r0[~long].assign(**{COLUMN: short_error(r0[~long])})
    d = paired(r, lnn, baseline, COLUMN)
    part = equivalent(NAME, d.to_numpy(), policy.margin("error"))
    if len(d):
        part.note = f"LNN / baseline {np.exp(d.mean()):.3g}x over {len(d)} seeds"
    return gated(
        part,
        learned_cell(r0, lnn, "pure LNN"),
        learned_cell(r0, baseline, "NODE+SO (baseline)"),
    )
