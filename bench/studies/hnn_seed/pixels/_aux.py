"""Claim 11 (c): the HNN seed's "We found that the auxiliary loss did not degrade the
autoencoder's performance" (Greydanus et al. 2019, Task 5: the pixel pendulum).

The auxiliary loss is the latent term cc = mean (dw_i - (w_{i+1} - w_i))^2 of the seed's
three-term pixel loss (``bench.core._pixels.seed_loss``, weight ``RunConfig.aux_weight``, the
seed's 1); the autoencoder's performance is its reconstruction error on the test observations,
``recon_mse`` (the decoder of the encoder of every test observation, the dynamics left out). The
part compares, per seed, the latent HNN trained with the auxiliary loss (the protocol's run) and
the same run trained without it (``aux_weight`` 0, the further reading
``pixel_pendulum_hnn_seed_no_aux``): *at most* on ``log(recon MSE with / without)`` at the loss
margin (a mean of squares: 1.5625x), "did not degrade" holding where a degradation of the margin
is ruled out.

The statement is about the autoencoder, so its gate is the autoencoder's, by role: the
protocol's HNN reconstructs the test observations better than the mean training observation
(``frame_mse_mean``, the trivial autoencoder) by the learning margin squared. The mean
observation is a property of the seed's data, the same for every run of the protocol on that
seed: it is read from whichever of the seed's rows records it (rows stored before the metric
existed have none). Whether the HNN learned the *motion* is (a)'s gate, not this part's.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from ....kit import Gate, Part, at_most, gated, learned, policy, undecided

NAME = "(c) the auxiliary loss does not degrade the autoencoder: log(recon MSE HNN with / without)"
WHERE = "the further reading pixel_pendulum_hnn_seed_no_aux (make paper-core runs it)"


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


def autoencoder_learned(r: pd.DataFrame) -> Gate:
    """The protocol's HNN autoencoder learned the frames (module docstring): per seed its
    ``recon_mse`` against the seed's ``frame_mse_mean``, at the learning margin squared."""
    label = "HNN (autoencoder)"
    hnn = protocol_rows(r[r["model"] == "hnn"]) if "model" in r else r.iloc[0:0]
    if not len(hnn) or "recon_mse" not in hnn:
        return Gate(label, None, f"{label} has no runs")
    mean = pd.to_numeric(r.get("frame_mse_mean", pd.Series(np.nan, index=r.index)), errors="coerce")
    mean = mean[np.isfinite(mean) & (mean > 0)]
    if not len(mean):
        return Gate(label, None, f"{label}: no row records the mean frame's MSE")
    trivial = np.log(mean).groupby(r.loc[mean.index, "seed"]).mean()
    return learned(label, _per_seed(hnn), trivial, squared=True)


def aux_part(r: pd.DataFrame, gate: Gate | None = None) -> Part:
    """Claim 11 (c) on the rows ``r`` (module docstring): per seed ``log(recon MSE of the HNN
    with the auxiliary loss / without)``, *at most* at the loss margin; *not tested* where
    ``r`` has no HNN run trained without it; ``gate``: default :func:`autoencoder_learned`."""
    has = {"recon_mse", "model", "seed"} <= set(r.columns)
    hnn = r[r["model"] == "hnn"] if has else r.iloc[0:0]
    without = hnn[_no_aux(hnn)]
    if not len(without):
        part = undecided(NAME, "")
        why = f"no HNN run trained without the auxiliary loss in these rows: {WHERE}"
        return gated(part, Gate("recon MSE without the auxiliary loss", False, why))
    d = (_per_seed(hnn[~_no_aux(hnn)]) - _per_seed(without)).dropna()
    part = at_most(NAME, d.to_numpy(), policy.margin("loss"))
    if len(d):
        part.note = f"recon MSE with / without {math.exp(float(d.mean())):.3g}x over {len(d)} seeds"
    return gated(part, autoencoder_learned(r) if gate is None else gate)
