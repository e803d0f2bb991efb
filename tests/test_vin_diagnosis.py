"""The VIN diagnosis of claim 12 (``python -m bench diagnose-vin``): the identity that makes the
HNN seed's auxiliary latent loss contradict a Verlet step, the auxiliary weight reaching the
loss, and the diagnosis end to end at smoke size, reading the protocol's stored runs."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pandas as pd
import pytest

import models
from bench.core import _pixels
from bench.core._experiments import expand
from bench.studies.paper import _vin_diagnosis as D


def _latent_vin(dtype="float64"):
    return models.LatentModel(
        "vin",
        (2, 8, 8),
        key=jax.random.PRNGKey(3),
        latent_dof=1,
        width=16,
        ae_width=8,
        dtype=dtype,
    )


def test_a_verlet_step_moves_by_its_velocity_plus_half_its_force():
    """Along the latent VIN's own rollout (unit steps) w_{i+1} - w_i = dw_i - 1/2 M^-1 grad U(w_i):
    the auxiliary loss's dw_i = w_{i+1} - w_i holds only where the learned force vanishes."""
    m = _latent_vin()
    vin = m.dynamics
    zs = np.asarray(m.rollout(jnp.array([0.4, -0.3]), jnp.arange(8.0), models.Integrator("rk4")))
    w, dw = zs[:, :1], zs[:, 1:]
    grad_u = np.stack([np.asarray(jax.grad(lambda q: vin.potential_energy(q, None))(x)) for x in w])
    m_inv = np.linalg.inv(np.asarray(vin.mass.matrix(w[0], None)))  # constant M
    half_force = -0.5 * grad_u[:-1] @ m_inv.T
    np.testing.assert_allclose(w[1:] - w[:-1], dw[:-1] + half_force, rtol=1e-9, atol=1e-12)
    # the auxiliary residual is that half force, not zero: the loss asks for a force-free VIN
    assert np.abs(half_force).max() > 1e-4


def test_the_auxiliary_weight_reaches_the_loss():
    m = _latent_vin("float32")
    frames = jax.random.uniform(jax.random.PRNGKey(0), (2, 3, 8, 8))
    integ = models.Integrator("rk4")
    one, (ae, cc, dyn) = _pixels.seed_loss(m, frames, integ)
    zero, parts = _pixels.seed_loss(m, frames, integ, aux_weight=0.0)
    assert float(cc) > 0
    np.testing.assert_allclose(float(one), float(ae + cc + 0.1 * dyn), rtol=1e-6)
    np.testing.assert_allclose(float(zero), float(ae + 0.1 * dyn), rtol=1e-6)
    np.testing.assert_allclose([float(x) for x in parts], [float(ae), float(cc), float(dyn)])


@pytest.mark.slow  # a smoke sweep and a training
def test_diagnosis_reads_stored_protocol_runs_and_trains_the_ablation(tmp_path):
    from bench.core import _runner

    res = tmp_path / "res"
    configs = expand(D.EXPERIMENT, "smoke")
    rows = _runner.sweep(configs, res, progress=False, cache_root=tmp_path / "c", workers=1)
    assert all(r["status"] == "ok" for r in rows)
    df = D.diagnose("smoke", res, progress=False)
    got = {(r.model, r.aux_weight): r.source for r in df.itertuples()}
    assert got == {
        ("vin", 1.0): "stored run",
        ("vin", 0.0): "trained here",
        ("resnet", 1.0): "stored run",
    }
    stored = {r["model"]: r["pixel_mse"] for r in rows}
    vin = df.set_index(["model", "aux_weight"])["pixel_mse"]
    assert vin["vin", 1.0] == pytest.approx(stored["vin"]) and np.isfinite(vin["vin", 0.0])
    assert vin["vin", 0.0] != vin["vin", 1.0]  # trained again, with another loss
    again = pd.read_csv(res / D.FILE)
    assert len(again) == 3 and set(again["source"]) == {"stored run", "trained here"}
    text = D.summary(again)
    assert "| vin | 0 | 1 | " in text and "| resnet | 1 | 1 | " in text
    with pytest.raises(ValueError, match="profile must be one of smoke, quick, paper-core"):
        D.diagnose("paper", res)
