"""Claim 12's second reading, the VIN seed's protocol: the embedding's structure on synthetic
embeddings that pass and fail, the position latent (the VIN's first step lands on the second
encoded position; the rollout is the seed's Stormer-Verlet recursion), the seed's ELBO against
an independent computation, the seed's starts, a smoke sweep through the store, and the rule
on synthetic tables that pass, fail and stay undecided."""

from __future__ import annotations

import math
import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from _markdown import table_rows

import models
import systems
from bench.core import (
    FRAME_METRICS,
    RunConfig,
    WindowDraws,
    _embedding,
    _store,
    check_runnable,
    expand,
    seed_elbo,
)
from bench.kit import policy
from bench.studies.hnn_seed import pixels as P
from bench.studies.paper.report._comparison import _disc_mark
from bench.studies.vin_seed import vin_blog as V

SEEDS = (0, 1, 2, 3, 4)
SPREAD = np.array([-0.4, 0.4, 0.0, -0.2, 0.2])  # mean 0, sd 0.32


# ------------------------------------------------------------------- the embedding's structure
def _pendulum_angles(n_traj=6, points=80, dt=0.1, seed=0) -> np.ndarray:
    """True angles (n_traj, points) of the seed's pendulum (g / l = 9.82) from its starts,
    by a fine symplectic Euler: swings far from rest, some over the top."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n_traj):
        q = rng.choice([-1.0, 1.0]) * rng.uniform(np.pi / 2, np.pi - 0.1)
        v = rng.uniform(-1.0, 1.0)
        traj = []
        for _ in range(points):
            traj.append(q)
            for _ in range(40):
                v -= dt / 40 * 9.82 * np.sin(q)
                q += dt / 40 * v
        out.append(traj)
    return np.asarray(out)


def _circle(a):
    return np.stack([np.sin(a), -np.cos(a)], axis=-1)


def test_a_circle_ordered_in_time_passes_and_a_scrambled_one_fails():
    a = _pendulum_angles()
    mg = policy.margin("embedding").value
    truth = _embedding.structure(_circle(a), a)
    assert truth == {"trust": 1.0, "jumps": 0.0, "defect": 0.0}
    # continuous and one-to-one on the circle: rotated, reflected, stretched, a little noise
    rng = np.random.default_rng(1)
    warped = a + 0.3 * np.sin(a) + 1.0
    for e in (
        np.stack([2.0 * np.cos(warped), 0.5 * np.sin(warped)], axis=-1),
        _circle(-a) + 0.05 * rng.standard_normal(a.shape + (2,)),
        np.cos(a)[..., None] * np.array([1.0, 0.0, 2.0]) + np.sin(a)[..., None] * [0, 3, 0],
    ):
        assert _embedding.structure(e, a)["defect"] < mg
    # the same points in a random order: neither trustworthy nor ordered in time
    flat = _circle(a).reshape(-1, 2)
    scrambled = flat[rng.permutation(len(flat))].reshape(a.shape + (2,))
    s = _embedding.structure(scrambled, a)
    assert s["trust"] < 0.6 and s["jumps"] > 0.5 and s["defect"] > 0.4


def test_folds_double_wraps_and_cuts_fail():
    a = _pendulum_angles()
    mg = policy.margin("embedding").value
    fold = np.stack([np.cos(a), np.zeros_like(a)], axis=-1)  # q and -q on one point
    double = np.stack([np.cos(2 * a), np.sin(2 * a)], axis=-1)  # round the circle twice
    cut = np.stack([np.mod(a, 2 * np.pi), np.zeros_like(a)], axis=-1)  # opened at the bottom
    s_fold, s_double, s_cut = (_embedding.structure(e, a) for e in (fold, double, cut))
    assert s_fold["trust"] < 0.8 and s_fold["defect"] > 3 * mg
    assert s_double["trust"] < 0.7 and s_double["defect"] > 5 * mg
    # a cut keeps the neighbours (trustworthy) but every swing through it jumps in time
    assert s_cut["trust"] > 0.99 and s_cut["jumps"] > mg and s_cut["defect"] > mg
    # the jumps are the cut's crossings: count them independently
    crossings = np.mean(np.abs(np.diff(np.mod(a, 2 * np.pi), axis=1)) > np.pi)
    assert s_cut["jumps"] == pytest.approx(crossings, abs=0.01)


def test_trustworthiness_against_its_formula_and_bad_embeddings():
    rng = np.random.default_rng(3)
    g = rng.standard_normal((30, 2))
    e = g + 0.5 * rng.standard_normal((30, 2))
    r_e, r_g = _embedding.ranks(e), _embedding.ranks(g)
    # by the definition: every intruder j of i's k nearest in e charged r_g(i, j) - k
    n, k = 30, 5
    total = 0
    for i in range(n):
        d_e = np.linalg.norm(e - e[i], axis=1)
        d_g = np.linalg.norm(g - g[i], axis=1)
        d_e[i] = d_g[i] = np.inf
        near_e, order_g = np.argsort(d_e)[:k], np.argsort(d_g)
        rank_g = {int(j): r + 1 for r, j in enumerate(order_g)}
        total += sum(rank_g[int(j)] - k for j in near_e if rank_g[int(j)] > k)
    expect = 1 - 2 / (n * k * (2 * n - 3 * k - 1)) * total
    assert _embedding.trustworthiness(r_e, r_g, k) == pytest.approx(expect)
    a = _pendulum_angles(2, 40)
    e = _circle(a).copy()
    e[0, 3] = np.nan
    assert _embedding.structure(e, a)["defect"] == 1.0
    with pytest.raises(ValueError, match="differ"):
        _embedding.structure(e[:, :10], a)


# ------------------------------------------------------------------------ the position latent
def _model(name, latent, key=0):
    return models.PositionLatentModel(
        name, (6, 6), key=jax.random.PRNGKey(key), latent=latent, width=8, ae_width=8
    )


def test_the_vin_lands_on_the_second_position_and_steps_as_stormer_verlet():
    m = _model("vin", "so2")
    h = m.step
    assert h == 0.1  # the seed's latent step on SO(2)
    vin, none = m.dynamics, jnp.zeros((0,))
    mass = float(vin.mass.matrix(jnp.array([0.0]), none)[0, 0])
    force = jax.grad(lambda q: vin.potential_energy(q, none))
    for q0, q1 in ((0.3, 0.45), (3.1, -3.1)):  # the second across the wrap
        z0 = m.initial_state(jnp.array([q0]), jnp.array([q1]))
        qs = np.asarray(m.positions(z0, 6))[:, 0]
        assert qs[0] == pytest.approx(q0, abs=1e-6)
        d = math.atan2(math.sin(q1 - q0), math.cos(q1 - q0))
        assert qs[1] == pytest.approx(q0 + d, abs=1e-5)
        # q_{n+1} = 2 q_n - q_{n-1} - h^2 M^-1 U'(q_n), with the model's own M and U
        for n in range(1, 5):
            f = float(force(jnp.array([qs[n]]))[0])
            assert qs[n + 1] == pytest.approx(2 * qs[n] - qs[n - 1] - h**2 * f / mass, abs=1e-4)


def test_models_without_dynamics_hold_the_position_and_the_others_start_from_two():
    for latent in ("so2", "r2"):
        m = _model("at_rest", latent)
        assert m.static and m.dof == (1 if latent == "so2" else 2)
        q0 = jnp.full((m.dof,), 0.2)
        qs = np.asarray(m.positions(m.initial_state(q0, q0 + 0.1), 4))
        np.testing.assert_allclose(qs, 0.2, rtol=1e-6)
    m = _model("resnet", "r2")
    z0 = m.initial_state(jnp.array([0.1, 0.2]), jnp.array([0.3, 0.1]))
    np.testing.assert_allclose(np.asarray(z0), [0.1, 0.2, 0.2, -0.1], atol=1e-6)  # v = d / 1
    assert m.embed(jnp.array([0.1, 0.2])).shape == (2,)
    assert np.asarray(_model("vin", "so2").embed(jnp.array([0.0]))) == pytest.approx([1, 0])
    with pytest.raises(ValueError, match="discrete model or at_rest"):
        models.PositionLatentModel("node", (6, 6), key=jax.random.PRNGKey(0))
    with pytest.raises(ValueError, match="latent must be one of"):
        models.PositionLatentModel("vin", (6, 6), key=jax.random.PRNGKey(0), latent="so3")


def _bce(logits, x):
    p = 1 / (1 + np.exp(-logits))
    return -(x * np.log(p) + (1 - x) * np.log(1 - p))


def _kl(m, s, m0, s0):
    return np.log(s0 / s) + (s**2 + (m - m0) ** 2) / (2 * s0**2) - 0.5


def test_the_seed_elbo_against_an_independent_computation():
    rng = np.random.default_rng(0)
    frames = jnp.asarray(rng.uniform(0, 1, (2, 4, 6, 6)), jnp.float32)
    for name, latent in (("at_rest", "r2"), ("vin", "so2")):
        m = _model(name, latent)
        eps = jnp.asarray(rng.standard_normal((2, 4, m.dof)), jnp.float32)
        got = float(seed_elbo(m, frames, eps))
        total = 0.0
        for b in range(2):
            mean = np.stack([np.asarray(m.encode(frames[b, t])[0]) for t in range(4)])
            scale = np.stack([np.asarray(m.encode(frames[b, t])[1]) for t in range(4)])
            q = mean + scale * np.asarray(eps[b])
            if m.static:
                qhat, kl = q, _kl(mean, scale, 0.0, 1.0)
            else:
                z0 = m.initial_state(jnp.asarray(q[0]), jnp.asarray(q[1]))
                qhat = np.asarray(m.positions(z0, 4))
                d = np.arctan2(np.sin(np.diff(mean, axis=0)), np.cos(np.diff(mean, axis=0)))
                kl = np.concatenate(
                    [_kl(mean[:2], scale[:2], 0, 1), _kl(d[1:], scale[2:] + scale[1:-1], 0, 0.1)]
                )
            logits = np.stack([np.asarray(m.decode(jnp.asarray(x))) for x in qhat])
            total += _bce(logits, np.asarray(frames[b])).sum() + kl.sum()
        assert got == pytest.approx(total / 2, rel=1e-4), name


def test_windows_are_drawn_without_replacement_with_noise_seeds():
    w = WindowDraws(n_traj=3, points=12, chunk=11, batch=200, seed=0)
    ix = w.take(2)
    assert ix.shape == (2, 6, 3) and ix.dtype == np.int32  # all 6 windows: the seed's full batch
    assert len({tuple(x) for x in ix[0, :, :2]}) == 6
    assert ix[..., 2].std() > 0
    small = WindowDraws(n_traj=3, points=12, chunk=11, batch=4, seed=0).take(1)
    assert small.shape == (1, 4, 3) and len({tuple(x) for x in small[0, :, :2]}) == 4


# ------------------------------------------------------------------------- data and configs
def test_the_seed_starts_far_from_rest_and_old_starts_unchanged():
    base = dict(n_train=40, n_test=2, train_points=3, test_points=3, size=8, seed=2)
    wide = systems.make_pixel_dataset(
        systems.PixelDatasetConfig(**base, min_angle=np.pi / 2, max_angle=np.pi - 0.1)
    )
    q0 = wide.z_train[:, 0, 0]
    assert np.all(np.abs(q0) >= np.pi / 2) and np.all(np.abs(q0) <= np.pi - 0.1)
    assert (q0 > 0).any() and (q0 < 0).any()
    # min_angle 0 keeps the HNN seed's draw: q0 ~ U(-a, a) from the same key as before
    small = systems.make_pixel_dataset(systems.PixelDatasetConfig(**base, max_angle=0.5))
    k_train, _ = jax.random.split(jax.random.PRNGKey(2))
    kq, _ = jax.random.split(k_train)
    expect = jax.random.uniform(kq, (40, 1), jnp.float64, -0.5, 0.5)[:, 0]
    np.testing.assert_allclose(small.z_train[:, 0, 0], np.asarray(expect))
    with pytest.raises(ValueError, match="min_angle"):
        systems.PixelDatasetConfig(min_angle=1.0, max_angle=0.5)


def test_frames_configs_take_the_seeds_data_and_check_their_models():
    cfgs = expand(V.VIN_BLOG, "quick")
    assert len(cfgs) == 20 and {c.seed for c in cfgs} == set(SEEDS)
    assert {(c.model, dict(c.model_options)["latent"]) for c in cfgs} == set(V.CELLS.values())
    c = cfgs[0]
    d = c.pixel_dataset_config()
    assert (d.min_angle, d.max_angle) == (math.pi / 2, math.pi - 0.1)
    assert d.train_points == 50 and d.test_points == 99 and dict(c.system_params)["g"] == 9.82
    # lr x steps as the seed's 3e-4 x 8000
    assert c.lr * c.steps == pytest.approx(V.SEED_LR * V.SEED_STEPS)
    pixel = expand(P.PIXEL_VIN, "quick")[0]
    assert pixel.pixel_dataset_config().min_angle == 0.0
    for bad, match in (
        (dict(model="node"), "discrete model or at_rest"),
        (dict(system="chain_pendulum", k=2, system_params=()), "one-link pendulum"),
        (dict(model_options=(("latent", "so3"),)), "latent must be one of"),
    ):
        with pytest.raises(ValueError, match=match):
            check_runnable(RunConfig(**{**c.to_dict(), **bad}))


@pytest.mark.slow
def test_frames_smoke_sweep_through_the_store(tmp_path):
    from bench.core import _runner

    cfgs = [check_runnable(c) for c in expand(V.VIN_BLOG, "smoke")]
    res, cache = tmp_path / "res", tmp_path / "cache"
    rows = _runner.sweep(
        cfgs,
        res,
        experiment=V.VIN_BLOG.name,
        profile="smoke",
        progress=False,
        cache_root=cache,
        workers=1,
    )
    assert len(rows) == 4 and all(r["status"] == "ok" for r in rows), rows
    runs = _store.load_runs(res)
    for m in FRAME_METRICS:
        assert np.isfinite(pd_num(runs[m])).all(), m
    assert ((runs["embedding_defect"] >= 0) & (runs["embedding_defect"] <= 1)).all()
    assert V.figure(res)  # the embeddings beside the truth


def pd_num(x):
    return np.asarray(x, dtype=float)


# ---------------------------------------------------------------------------- the verdicts
def _tables(
    vin=0.01, baseline=0.3, forecast_ratio=3.0, spread=0.1, recon=0.002, pixel=0.005, ours=3.0
):
    """Rows of both readings at smoke on seeds 0-4: embedding defects ``vin`` (VIN-SO(2)) and
    ``baseline`` (each baseline), the ResNet's pixel MSE ``forecast_ratio`` x the VIN's
    ``pixel`` (each per seed times exp(spread * SPREAD)), reconstructions ``recon`` against a
    mean frame of 0.03, static forecasts 0.2; ours (pixel_pendulum_vin): the ResNet's pixel
    MSE ``ours`` x the VIN's."""
    rows = []
    for s in SEEDS:
        j = math.exp(spread * SPREAD[s])
        for c0 in expand(V.VIN_BLOG, "smoke"):
            c = RunConfig(**{**c0.to_dict(), "seed": s})
            name = next(
                n for n, v in V.CELLS.items() if v == (c.model, dict(c.model_options)["latent"])
            )
            row = c.to_dict()
            row.update(
                config_hash=c.config_hash,
                train_hash=c.train_hash,
                experiment=V.VIN_BLOG.name,
                profile="smoke",
                status="ok",
                embedding_defect=(vin if name == "vin_so2" else baseline) * j,
                embedding_trust=1 - (vin if name == "vin_so2" else baseline) * j,
                embedding_jumps=0.0,
                recon_mse=recon,
                frame_mse_mean=0.03,
                pixel_mse=pixel * (forecast_ratio * j if name == "resnet" else 1.0),
                pixel_mse_late=pixel,
                pixel_mse_static=0.2,
            )
            rows.append(_store.jsonable(row))
        for c0 in expand(P.PIXEL_VIN, "smoke"):
            c = RunConfig(**{**c0.to_dict(), "seed": s})
            row = c.to_dict()
            mse = 0.005 * (ours * j if c.model == "resnet" else 1.0)
            row.update(
                config_hash=c.config_hash,
                train_hash=c.train_hash,
                experiment=P.PIXEL_VIN.name,
                profile="smoke",
                status="ok",
                pixel_mse=mse,
                pixel_mse_late=mse,
                pixel_mse_static=1.0,
                latent_energy_drift=0.01 if c.model == "vin" else math.nan,
            )
            rows.append(_store.jsonable(row))
    return _store.rows_frame(rows)


def _status(v):
    return {p.name.split(" ")[0] + " " + p.name.split(" ")[1]: p.status for p in v.parts}


def test_the_blog_reading_passes_fails_and_stays_undecided():
    v = V.claim_12(_tables())
    assert v.verdict == "reproduced", v.detail
    assert len(v.parts) == 5 and v.effect == pytest.approx(0.01, rel=0.05)
    # an embedding has no trivial predictor: the report's discriminating column reads n/a,
    # not unknown (which means trivial-predictor runs are missing)
    assert v.discriminating is None and not v.has_trivial
    assert _disc_mark(v) == "n/a"
    # the baselines' embeddings as consistent as the VIN's: (b) contradicted, not reproduced
    v = V.claim_12(_tables(baseline=0.01))
    assert v.verdict == "partly reproduced", v.detail
    assert [p.status for p in v.parts if p.name.startswith("(b)")] == ["contradicts"] * 3
    v = V.claim_12(_tables(vin=0.3, baseline=0.01, forecast_ratio=0.3))
    assert v.verdict == "not reproduced", v.detail
    assert v.parts[0].status == "contradicts"
    # everything at the margin with a wide spread: undecided
    mg = policy.margin("embedding").value
    v = V.claim_12(_tables(vin=mg, baseline=mg, forecast_ratio=1.25**2, spread=1.0))
    assert v.verdict == "inconclusive" and {p.status for p in v.parts} == {"undecided"}, v.detail
    r = _tables()
    assert V.claim_12(r[r["seed"] < 3]).verdict == "inconclusive"


def test_the_blog_reading_judges_only_models_that_learned():
    # autoencoders no better than the mean frame (3x, short of 4x): the embeddings not tested
    v = V.claim_12(_tables(recon=0.01))
    assert v.verdict == "inconclusive", v.detail
    assert all(p.status == "not tested" for p in v.parts[:4])
    assert {g.label for g in v.parts[0].gates if g.open is False} == {"VIN-SO(2) (frames)"}
    # forecasts no better than holding the second frame: (c) not tested, the rest holds; a
    # part not tested leaves the claim inconclusive
    v = V.claim_12(_tables(pixel=0.1, forecast_ratio=1.0))
    assert v.parts[-1].status == "not tested" and v.verdict == "inconclusive", v.detail
    assert {p.status for p in v.parts[:4]} == {"holds"}
    # a failed VIN run scores the worst defect
    r = _tables()
    vin = (r["model"] == "vin") & (r["observation"] == "frames") & (r["seed"] == 0)
    r.loc[vin, "status"] = "failed"
    assert V.defect_per_seed(r, "vin_so2").loc[0] == 1.0


def test_the_claim_takes_the_seeds_protocol_and_names_ours():
    both = _tables(vin=0.3, baseline=0.01, forecast_ratio=0.3, ours=3.0)
    v = V.claim_12(both)
    assert v.verdict == "not reproduced"
    assert v.other_readings == (("ours, the HNN seed's latent", "reproduced"),)
    # without runs of the seed's protocol the claim is ours alone
    ours_only = both[both["observation"] == "pixels"]
    assert V.claim_12(ours_only).verdict == "reproduced"
    assert V.reading(both.iloc[0:0]).verdict == "inconclusive"


def test_section_sets_the_two_protocols_side_by_side(tmp_path):
    _tables().to_parquet(tmp_path / "runs.parquet", index=False)
    text = V.section(tmp_path)
    vin = next(r for r in table_rows(text, "| model | seeds") if r["model"] == "VIN-SO(2)")
    assert (vin["seeds"], vin["failed"]) == ("5", "0")
    protocol = {r["protocol"]: r for r in table_rows(text, "| protocol | ours | the seed's")}
    for row in ("data", "targets", "loss", "optimiser", "steps", "metric", "learned"):
        assert row in protocol, row
    for reading in ("ours", "the seed's"):  # each reading's verdict on the seeds it rests on
        said = re.fullmatch(r"(.+) \(seeds (\S+)\)", protocol["verdict"][reading])
        assert said.groups() == ("reproduced", "0-4"), protocol["verdict"]
