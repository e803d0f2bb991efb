"""The scene's standardisation (the paper's MuJoCo networks): its statistics against a closed
form, a standardised network against the plain one with its first and last layers rewritten
(an affine reparametrisation derived by hand), angles left to their embedding, the one-line
refusals, and a controlled run that builds it from its own training windows."""

from __future__ import annotations

import dataclasses

import _model_helpers  # noqa: F401 - float64 on
import equinox as eqx
import jax.numpy as jnp
import jax.random as jr
import numpy as np
import pytest

import models
from bench.core import RunConfig, expand
from bench.core import _controlled as C
from bench.studies.decon import mujoco as X
from models import Scene, Standardisation

D, NU, DT = 2, 3, 0.05


def _stats(seed=0):
    r = np.random.default_rng(seed)
    return Standardisation(
        q_loc=r.normal(size=D) * 5,
        q_scale=r.uniform(0.5, 4, D),
        v_loc=r.normal(size=D),
        v_scale=r.uniform(0.5, 4, D),
        u_loc=r.normal(size=NU),
        u_scale=r.uniform(0.5, 4, NU),
        rate_loc=r.normal(size=2 * D),
        rate_scale=r.uniform(0.5, 4, 2 * D),
    )


def test_the_statistics_of_uniformly_accelerated_windows_are_their_closed_form():
    """Windows of q(t) = q0 + v0 t + a t^2 / 2 with one acceleration a: the finite-difference
    dv/dt is a exactly (its std 0, so its scale 1), the finite-difference dq/dt is the mean
    velocity over each step, v0 + a (t + dt / 2)."""
    r = np.random.default_rng(1)
    n, c = 50, 3
    a = np.array([0.7, -2.0])
    q0, v0 = r.normal(size=(n, D)), r.normal(size=(n, D))
    t = np.arange(c)[None, :, None] * DT
    q = q0[:, None] + v0[:, None] * t + 0.5 * a * t**2
    v = v0[:, None] + a * t
    z, u = np.concatenate([q, v], -1), r.normal(size=(n, c, NU))
    s = Standardisation.from_windows(z, u, DT)
    np.testing.assert_allclose(s.rate_loc[D:], a, rtol=1e-10)
    assert s.rate_scale[D:] == (1.0, 1.0)
    mean_speed = v0[:, None] + a * (t[:, :-1] + DT / 2)
    np.testing.assert_allclose(s.rate_loc[:D], mean_speed.reshape(-1, D).mean(0), rtol=1e-10)
    np.testing.assert_allclose(s.rate_scale[:D], mean_speed.reshape(-1, D).std(0), rtol=1e-10)
    np.testing.assert_allclose(s.u_loc, u.reshape(-1, NU).mean(0))
    np.testing.assert_allclose(s.q_scale, q.reshape(-1, D).std(0))


def _rewritten(plain, stats: Standardisation, out: slice):
    """The plain network with the standardisation folded into its weights: x_s = (x - m) / s
    gives x_s W = x (W / s) - (m / s) W; y = l + r (h W + b) = h (W r) + (l + r b)."""
    m = np.concatenate([stats.q_loc, stats.v_loc, stats.u_loc])
    s = np.concatenate([stats.q_scale, stats.v_scale, stats.u_scale])
    loc, scale = np.asarray(stats.rate_loc)[out], np.asarray(stats.rate_scale)[out]
    w, b = list(plain.net.weights), list(plain.net.biases)
    b[0] = b[0] - (m / s) @ w[0]
    w[0] = w[0] / s[:, None]
    b[-1] = loc + scale * b[-1]
    w[-1] = w[-1] * scale[None, :]
    net = eqx.tree_at(lambda n: (n.weights, n.biases), plain.net, (tuple(w), tuple(b)))
    return eqx.tree_at(lambda mo: mo.net, plain, net)


@pytest.mark.parametrize("name", ["node", "node_so"])
def test_a_standardised_network_is_the_plain_one_with_rewritten_weights(name):
    stats = _stats()
    plain_scene = Scene(dof=D, angular=(False,) * D, n_controls=NU)
    scene = Scene(dof=D, angular=(False,) * D, n_controls=NU, standardisation=stats)
    kw = dict(key=jr.PRNGKey(3), width=16, dtype="float64")
    std, plain = models.make(name, scene, **kw), models.make(name, plain_scene, **kw)
    out = slice(None) if name == "node" else slice(D, None)
    rewritten = _rewritten(plain, stats, out)
    r = np.random.default_rng(2)
    for _ in range(5):
        z = jnp.asarray(r.normal(size=2 * D) * 3)
        u = jnp.asarray(r.normal(size=NU) * 2)
        a, b = std.vector_field(0.0, z, u), rewritten.vector_field(0.0, z, u)
        np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-12)
        assert float(jnp.max(jnp.abs(a - plain.vector_field(0.0, z, u)))) > 1e-3


def test_angles_keep_their_embedding_and_the_rest_is_standardised():
    stats = dataclasses.replace(_stats(), u_loc=(), u_scale=())
    angular = (True, False)
    f = models._features.Features(Scene(dof=D, angular=angular, standardisation=stats))
    q, v = jnp.array([0.4, 7.0]), jnp.array([1.0, -2.0])
    x = f(q, v, jnp.zeros((0,)))
    expected = [
        np.cos(0.4),
        np.sin(0.4),
        (7.0 - stats.q_loc[1]) / stats.q_scale[1],
        *((np.asarray(v) - stats.v_loc) / stats.v_scale),
    ]
    np.testing.assert_allclose(x, expected, rtol=1e-12)


@pytest.mark.parametrize(
    "change, message",
    [
        (dict(q_scale=(1.0,)), "q_scale must have 2 entries"),
        (dict(v_scale=(1.0, 0.0)), "scales must be finite and > 0"),
        (dict(rate_scale=(1.0, np.inf, 1.0, 1.0)), "scales must be finite and > 0"),
    ],
)
def test_a_bad_standardisation_is_one_line(change, message):
    fields = {k: getattr(_stats(), k) for k in Standardisation.__dataclass_fields__}
    with pytest.raises(ValueError, match=message) as e:
        Standardisation(**(fields | change))
    assert "\n" not in str(e.value)


def test_a_scene_refuses_statistics_of_another_shape():
    with pytest.raises(ValueError, match="n_controls=2 controls; got 2 and 3"):
        Scene(dof=D, angular=(False,) * D, n_controls=2, standardisation=_stats())


def test_standardise_is_a_controlled_runs_field_in_its_hash():
    with pytest.raises(ValueError, match="controlled runs only.*allowed: False"):
        RunConfig(system="spring", standardise=True)
    c = next(c for c in expand(X.NAME, "smoke") if c.model == "node")
    assert c.standardise
    raw = dataclasses.replace(c, standardise=False)
    assert raw.config_hash != c.config_hash
    assert RunConfig.from_dict({**raw.to_dict(), "standardise": float("nan")}) == raw
    with pytest.raises(ValueError, match="standardise must be True or False"):
        dataclasses.replace(c, standardise="yes")


def test_a_controlled_run_standardises_with_its_own_training_windows():
    c = next(c for c in expand(X.NAME, "smoke") if c.model == "node_so")
    built = C.build(c)
    expected = Standardisation.from_windows(built.split.train_z, built.split.train_u, c.dt)
    assert built.model.scene.standardisation == expected
    assert C.build(dataclasses.replace(c, standardise=False)).model.scene.standardisation is None
