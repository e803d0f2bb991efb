"""The pixel protocols' diagnoses (``python -m bench diagnose-vin``, ``diagnose-hnn-seed-pixels``):
the identity that makes the HNN seed's auxiliary latent loss contradict a Verlet step, the
auxiliary weight reaching the loss, the variants' configurations, and a diagnosis end to end at
smoke size, reading stored runs from the results folder and from another folder."""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pandas as pd
import pytest
from _markdown import table_rows

import models
from bench.core import _pixels, expand
from bench.studies.hnn_seed.pixels import _ablation as D


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


def test_a_variant_changes_one_field_of_the_protocol_and_screens_where_declared():
    configs = expand(D.HNN_SEED.experiment, "paper-core")
    by = {v.name: v for v in D.HNN_SEED.variants}
    assert D.HNN_SEED.variants[0].name == D.PROTOCOL and not D.HNN_SEED.variants[0].changes
    no_l2 = by["no L2 (weight decay 0)"]
    assert all(no_l2.applies(c) for c in configs)  # every seed, both models
    for c in configs:
        v = no_l2.config(c)
        assert v.weight_decay == 0.0 and c.weight_decay > 0
        assert v.config_hash != c.config_hash
        assert dataclasses.replace(v, weight_decay=c.weight_decay).config_hash == c.config_hash
    screened = [c for c in configs if by["cosine lr"].applies(c)]
    assert sorted((c.model, c.seed) for c in screened) == [("hnn", 0), ("node", 0)]
    # the screen's other elements are ours: the pixel experiment under our protocol's values
    ours = expand("pixel_pendulum_hnn", "paper-core")[0]
    base = next(c for c in screened if c.model == "hnn")
    assert by["our initialisation"].config(base).model_options == ours.model_options
    assert by["RK4 training step"].config(base).train_integrator == ours.train_integrator
    both = by["no L2 and RK4 training step"].config(base)
    assert (both.weight_decay, both.train_integrator) == (0.0, ours.train_integrator)
    assert by["AdamW, clipped"].config(base).optimizer == ours.optimizer
    assert by["cosine lr"].config(base).lr_schedule == ours.lr_schedule


def test_the_summary_counts_the_seeds_under_the_learning_gate():
    """A synthetic diagnosis: one variant 10x below holding the first frame on both seeds, the
    protocol 10x on one and 1.5x on the other: learned 2 of 2 and 1 of 2."""
    rows = []
    for variant, gains in ((D.PROTOCOL, (10.0, 1.5)), ("no L2 (weight decay 0)", (10.0, 10.0))):
        for seed, g in enumerate(gains):
            rows.append(
                {
                    "model": "hnn",
                    "seed": seed,
                    "variant": variant,
                    "aux_weight": 1.0,
                    "source": "stored run",
                    "pixel_mse_static": 0.02,
                    "pixel_mse": 0.02 / g,
                    "pixel_mse_late": 0.02 / g,
                    "recon_mse": 1e-5,
                }
            )
    got = _summary_rows(D.summary(D.HNN_SEED, pd.DataFrame(rows)))
    assert {k: (r["aux weight"], r["seeds"], r["learned"]) for k, r in got.items()} == {
        ("hnn", D.PROTOCOL): ("1", "2", "1 of 2"),
        ("hnn", "no L2 (weight decay 0)"): ("1", "2", "2 of 2"),
    }
    assert got["hnn", D.PROTOCOL]["static / pixel MSE per seed"] == "0: 10, 1: 1.5"


def _summary_rows(text):
    """The diagnosis table's rows, per (model, variant)."""
    return {(r["model"], r["variant"]): r for r in table_rows(text, "| model | variant")}


@pytest.mark.slow  # a smoke sweep and a training
def test_diagnosis_reads_stored_protocol_runs_and_trains_the_ablation(tmp_path):
    from bench.core import _runner

    res = tmp_path / "res"
    configs = expand(D.VIN.experiment, "smoke")
    rows = _runner.sweep(configs, res, progress=False, cache_root=tmp_path / "c", workers=1)
    assert all(r["status"] == "ok" for r in rows)
    df = D.diagnose(D.VIN, "smoke", res, progress=False)
    got = {(r.model, r.variant, r.aux_weight): r.source for r in df.itertuples()}
    assert got == {
        ("vin", D.PROTOCOL, 1.0): "stored run",
        ("vin", "no auxiliary loss", 0.0): "trained here",
        ("resnet", D.PROTOCOL, 1.0): "stored run",
    }
    stored = {r["model"]: r["pixel_mse"] for r in rows}
    vin = df.set_index(["model", "aux_weight"])["pixel_mse"]
    assert vin["vin", 1.0] == pytest.approx(stored["vin"]) and np.isfinite(vin["vin", 0.0])
    assert vin["vin", 0.0] != vin["vin", 1.0]  # trained again, with another loss
    again = pd.read_csv(res / D.VIN.file)
    assert len(again) == 3 and set(again["source"]) == {"stored run", "trained here"}
    got = _summary_rows(D.summary(D.VIN, again))
    assert {k: (r["aux weight"], r["seeds"]) for k, r in got.items()} == {
        ("vin", D.PROTOCOL): ("1", "1"),
        ("vin", "no auxiliary loss"): ("0", "1"),
        ("resnet", D.PROTOCOL): ("1", "1"),
    }
    with pytest.raises(ValueError, match="profile must be one of smoke, quick, paper-core"):
        D.diagnose(D.VIN, "paper", res)
    with pytest.raises(ValueError, match="--runs-from .* is not a folder"):
        D.diagnose(D.VIN, "smoke", res, runs_from=[tmp_path / "nowhere"])


@pytest.mark.slow  # a smoke sweep
def test_a_variant_run_stored_in_another_folder_is_read_not_trained(tmp_path):
    """The HNN seed's no-L2 variant run by a sweep into another folder: the diagnosis reads it
    there by config hash (and the protocol's from the results folder), training nothing."""
    from bench.core import _runner

    res, other = tmp_path / "res", tmp_path / "other"
    base = [c for c in expand(D.HNN_SEED.experiment, "smoke") if c.model == "node"]
    no_l2 = D.HNN_SEED.variants[1]
    _runner.sweep(base, res, progress=False, cache_root=tmp_path / "c", workers=1)
    _runner.sweep(
        [no_l2.config(c) for c in base],
        other,
        progress=False,
        cache_root=tmp_path / "c",
        workers=1,
    )
    df = D.diagnose(D.HNN_SEED, "smoke", res, runs_from=[other], progress=False)
    node = df[df["model"] == "node"].set_index("variant")["source"]
    assert node[D.PROTOCOL] == "stored run" and node[no_l2.name] == "stored run (other)"


def _rk4(f, z, h=1.0):
    k1 = f(z)
    k2 = f(z + h / 2 * k1)
    k3 = f(z + h / 2 * k2)
    k4 = f(z + h * k3)
    return z + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)


def test_an_euler_fitted_field_spirals_in_under_rk4_and_its_hamiltonian_part_does_not():
    """The diagnosis's account of the seed's Euler training step: for a latent turning by a per
    frame, z + f(z) = R_a z asks for f = (R_a - I) z, whose flow contracts by exp(cos a - 1) per
    frame (its eigenvalues cos a - 1 +- i sin a); a linear Hamiltonian field J S z is traceless,
    and the traceless part of R_a - I, a rotation at rate sin a, keeps |z| (to RK4's error)."""
    a = 2 * np.pi / 32  # the suite's pendulum, about 32 frames per swing
    rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    euler_field = rot - np.eye(2)
    assert np.allclose(np.eye(2) + euler_field, rot)  # the Euler step reproduces the frames
    z = np.array([1.0, 0.0])
    for _ in range(100):
        z = _rk4(lambda x: euler_field @ x, z)
    np.testing.assert_allclose(np.linalg.norm(z), np.exp(100 * (np.cos(a) - 1)), rtol=1e-4)
    assert np.linalg.norm(z) < 0.9  # after 100 frames, visibly fallen in
    hamiltonian = euler_field - np.trace(euler_field) / 2 * np.eye(2)
    j = np.array([[0.0, 1.0], [-1.0, 0.0]])
    s = -j @ hamiltonian  # J S = hamiltonian with S symmetric: a quadratic H = z S z / 2
    np.testing.assert_allclose(s, s.T, atol=1e-15)
    z = np.array([1.0, 0.0])
    for _ in range(100):
        z = _rk4(lambda x: hamiltonian @ x, z)
    assert abs(np.linalg.norm(z) - 1) < 1e-4  # RK4: (sin a)^6 / 144 per frame


def test_a_diagnosis_keeps_its_earlier_rows_and_trains_only_what_its_file_lacks(
    tmp_path, monkeypatch
):
    """Called again, the diagnosis trains nothing it wrote before; called on one seed, it keeps
    the other seeds' rows; a new variant's runs are the only ones trained."""
    trained = []

    def fake_run(c):
        trained.append((c.model, c.seed, c.aux_weight))
        return {k: 0.5 for k in D.COLUMNS}

    monkeypatch.setattr(D, "_run", fake_run)
    first = D.diagnose(D.VIN, "quick", tmp_path, seeds=[0, 1], progress=False)
    n = len(trained)
    assert n == len(first) == 6 and set(first["source"]) == {"trained here"}
    again = D.diagnose(D.VIN, "quick", tmp_path, seeds=[1], progress=False)
    assert len(trained) == n and len(again) == 6  # seed 0's rows kept
    assert sorted(again["seed"].tolist()) == sorted(first["seed"].tolist())
    more = dataclasses.replace(
        D.VIN,
        variants=(
            *D.VIN.variants,
            D.Variant("half aux", changes=(("aux_weight", 0.5),), models=("vin",)),
        ),
    )
    D.diagnose(more, "quick", tmp_path, seeds=[0, 1], progress=False)
    assert trained[n:] == [("vin", 0, 0.5), ("vin", 1, 0.5)]
