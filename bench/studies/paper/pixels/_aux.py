"""Claim 11 (c): the HNN seed's "We found that the auxiliary loss did not degrade the
autoencoder's performance" (Greydanus et al. 2019, Task 5: the pixel pendulum).

The auxiliary loss is the latent term cc = mean (dw_i - (w_{i+1} - w_i))^2 of the seed's
three-term pixel loss (``bench.core._pixels.seed_loss``, weight 1); the autoencoder's
performance is its reconstruction error on the test observations, ``recon_mse`` (the decoder of
the encoder of every test observation, the dynamics left out). The part compares, per seed, the
latent HNN trained with the auxiliary loss (the protocol's run) and the same run trained
without it (auxiliary weight 0): *at most* on ``log(recon MSE with / without)`` at the loss
margin (a mean of squares: 1.5625x), "did not degrade" holding where a degradation of the
margin is ruled out.

Where the data are: a run's configuration has no auxiliary weight, so no stored run is trained
without it; the HNN seed's pixel diagnosis (``python -m bench diagnose-hnn-seed-pixels``,
``_ablation.HNN_SEED``, variant ``no auxiliary loss``) trains them and writes their
``recon_mse`` beside the protocol's to ``hnn_seed_pixel_diagnosis.csv`` (rows with an
``aux_weight`` column). A runs table has no such rows: there the part is *not tested*, with the
reason; the report's pixel section judges it on the diagnosis's rows (:func:`diagnosis_line`).
Stored diagnoses written before the variant existed hold none either (the VIN's diagnosis has the
VIN trained without it, another model and claim 12's protocol: not read here). Judged where the
protocol's HNN learned the motion (the model the seed reports).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from ....kit import Gate, Part, at_most, gated, policy, undecided

NAME = "(c) the auxiliary loss does not degrade the autoencoder: log(recon MSE HNN with / without)"
NO_AUX = "no auxiliary loss"  # the diagnosis's variant (``_ablation.HNN_SEED``)
WHERE = (
    "`python -m bench diagnose-hnn-seed-pixels` trains them (variant "
    f"'{NO_AUX}', hnn_seed_pixel_diagnosis.csv; the report's pixel section reads it there)"
)


def _no_aux(r: pd.DataFrame) -> pd.Series:
    """Which rows were trained without the auxiliary loss (an ``aux_weight`` of 0)."""
    if "aux_weight" not in r:
        return pd.Series(False, index=r.index)
    return pd.to_numeric(r["aux_weight"], errors="coerce") == 0.0


def protocol_rows(r: pd.DataFrame) -> pd.DataFrame:
    """The rows trained with the protocol's auxiliary loss: the claim's other parts read these
    (a run without it is (c)'s comparison, not the protocol)."""
    return r[~_no_aux(r)]


def _per_seed(rows: pd.DataFrame) -> pd.Series:
    """Per-seed mean log ``recon_mse`` of ``rows``; a failed run (non-finite) at the worst
    finite value (at least 1)."""
    x = pd.to_numeric(rows["recon_mse"], errors="coerce")
    good = np.isfinite(x) & (x > 0)
    worst = max(1.0, float(x[good].max())) if good.any() else 1.0
    return np.log(x.where(good, worst)).groupby(rows["seed"]).mean()


def aux_part(r: pd.DataFrame, learned: Gate | None = None) -> Part:
    """Claim 11 (c) on the rows ``r`` (module docstring): per seed ``log(recon MSE of the HNN
    with the auxiliary loss / without)``, *at most* at the loss margin; *not tested* where
    ``r`` has no HNN run trained without it; ``learned``: the protocol's HNN learning gate."""
    has = {"recon_mse", "model", "seed"} <= set(r.columns)
    hnn = r[r["model"] == "hnn"] if has else r.iloc[0:0]
    without = hnn[_no_aux(hnn)]
    if not len(without):
        part = undecided(NAME, "")
        why = f"no HNN run trained without the auxiliary loss in these rows: {WHERE}"
        return gated(part, Gate("recon MSE without the auxiliary loss", False, why))
    with_ = hnn[~_no_aux(hnn)]
    if "variant" in with_:
        with_ = with_[with_["variant"] == "protocol"]
    d = (_per_seed(with_) - _per_seed(without)).dropna()
    part = at_most(NAME, d.to_numpy(), policy.margin("loss"))
    if len(d):
        part.note = f"recon MSE with / without {math.exp(float(d.mean())):.3g}x over {len(d)} seeds"
    return gated(part, learned) if learned is not None else part


def diagnosis_line(diag: pd.DataFrame | None, learned_gate=None) -> list[str]:
    """Claim 11 (c) judged on the HNN seed's pixel diagnosis (``diag``, its CSV's rows), or
    what is missing: one report line. ``learned_gate(rows, model)``: the pixel models'
    learning gate (the pixel rule's; none: the part is not gated)."""
    if diag is None or not len(diag):
        return []
    from ....kit import verdict

    d = diag.assign(observation="pixels")
    d["status"] = np.where(np.isfinite(pd.to_numeric(d["pixel_mse"])), "ok", "failed")
    proto = d[d["variant"] == "protocol"]
    gate = learned_gate(proto, "hnn") if learned_gate is not None and len(proto) else None
    p = aux_part(d, gate)
    verdict(11, "auxiliary loss", [p], p, p.n, "log recon MSE ratio")  # settles the part
    return ["", f"- Claim 11 {p.text()} (the HNN seed's pixel diagnosis; not in the verdict)."]
