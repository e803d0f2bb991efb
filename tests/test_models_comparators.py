"""The trivial predictors, the paper's comparators (mixture_hnn, node_so_symreg, the naive HNN
on (q, qdot)) and the symplectic penalty of the TRUE chain-2 field in both coordinates."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.random as jr
import numpy as np
import pytest
from _model_helpers import CHAIN2, CHAIN2_CANONICAL, W, _states

import models
import systems
from models import AbstractContinuousModel, Scene

TS = jnp.linspace(0.0, 0.6, 21)


# --------------------------------------------------------------------------- trivial


def _maps(system):
    def velocity(q, p, a):
        return system.velocity(q, p)

    def momentum(q, v, a):
        return system.momentum(jnp.concatenate([q, v]))

    return velocity, momentum


@pytest.mark.parametrize("name", ["constant_velocity", "at_rest"])
def test_trivial_models_have_no_parameters_and_the_capability(name):
    for scene in (CHAIN2, CHAIN2_CANONICAL, Scene(3, (False,) * 3, n_args=1, damped=True)):
        model = models.make(name, scene, key=jr.PRNGKey(0), width=W, dtype="float64")
        assert isinstance(model, models.AbstractTrivialModel) and model.trivial
        assert models.n_parameters(model) == 0
        assert not isinstance(model, models.AbstractContinuousModel | models.AbstractDiscreteModel)
    assert name in models.trivial_models()


def test_constant_velocity_and_at_rest_in_velocity_coordinates():
    z0s = _states(jr.PRNGKey(1), 4, 2)
    cv = models.make("constant_velocity", CHAIN2, key=jr.PRNGKey(0), dtype="float64")
    rest = models.make("at_rest", CHAIN2, key=jr.PRNGKey(0), dtype="float64")
    ts = TS + 2.0  # predictions use times since the first time
    zs = np.asarray(cv.predict_batch(z0s, ts))
    t = np.asarray(TS)[None, :, None]
    np.testing.assert_allclose(zs[..., :2], z0s[:, None, :2] + t * z0s[:, None, 2:], atol=1e-14)
    np.testing.assert_allclose(zs[..., 2:], np.broadcast_to(z0s[:, None, 2:], zs[..., 2:].shape))
    zr = np.asarray(rest.predict_batch(z0s, ts))
    np.testing.assert_array_equal(zr[:, 0], z0s)  # the initial state itself
    np.testing.assert_array_equal(zr[:, 1:, :2], np.broadcast_to(z0s[:, None, :2], (4, 20, 2)))
    np.testing.assert_array_equal(zr[:, 1:, 2:], 0.0)


def test_constant_velocity_in_momentum_coordinates_is_physical_constant_velocity():
    """Chain-2 (q-dependent mass): p(t) = M(q(t)) qdot0 changes while qdot stays fixed."""
    chain = systems.make("chain_pendulum", k=2)
    velocity, momentum = _maps(chain)
    z0 = np.array([0.3, -0.5, 1.1, -0.7])
    y0 = jnp.concatenate([z0[:2], chain.momentum(jnp.asarray(z0))])
    cv = models.make("constant_velocity", CHAIN2_CANONICAL, key=jr.PRNGKey(0), dtype="float64")
    ys = np.asarray(eqx.filter_jit(cv.predict)(y0, TS, None, velocity=velocity, momentum=momentum))
    qs = z0[:2] + np.asarray(TS)[:, None] * z0[2:]
    np.testing.assert_allclose(ys[:, :2], qs, atol=1e-12)
    vs = jax.jit(jax.vmap(chain.velocity))(qs, ys[:, 2:])
    np.testing.assert_allclose(np.asarray(vs), np.broadcast_to(z0[2:], vs.shape), atol=1e-12)
    assert np.ptp(ys[:, 2]) > 1e-2  # the momentum is not held fixed
    rest = models.make("at_rest", CHAIN2_CANONICAL, key=jr.PRNGKey(0), dtype="float64")
    yr = np.asarray(
        eqx.filter_jit(rest.predict)(y0, TS, None, velocity=velocity, momentum=momentum)
    )
    np.testing.assert_allclose(yr[1:, 2:], 0.0, atol=1e-14)
    with pytest.raises(ValueError, match="velocity"):
        cv.predict(y0, TS, None)


def test_constant_velocity_relativistic_momentum_is_constant():
    particle = systems.make("relativistic_particle")
    velocity, momentum = _maps(particle)
    scene = Scene(1, (False,), n_args=1, canonical=True)
    cv = models.make("constant_velocity", scene, key=jr.PRNGKey(0), dtype="float64")
    p0 = 2.5  # qdot0 ~ 0.83
    ys = np.asarray(
        cv.predict(jnp.array([0.2, p0]), TS, jnp.array([1.0]), velocity=velocity, momentum=momentum)
    )
    v0 = float(particle.velocity(0.2, p0))
    np.testing.assert_allclose(ys[:, 1], p0, rtol=1e-12)
    np.testing.assert_allclose(ys[:, 0], 0.2 + np.asarray(TS) * v0, rtol=1e-12)


# --------------------------------------------------------------------------- mixture_hnn


def _zero_last(mlp):
    return eqx.tree_at(lambda m: (m.weights[-1], m.biases[-1]), mlp, replace_fn=jnp.zeros_like)


@pytest.mark.parametrize("scene", [CHAIN2, CHAIN2_CANONICAL])
def test_mixture_hnn_is_hnn_so_plus_a_free_field(scene):
    key = jr.PRNGKey(2)
    mix = models.make("mixture_hnn", scene, key=key, width=W, dtype="float64")
    zs = 0.5 * _states(jr.PRNGKey(3), 5, 2)
    # with the free MLP silenced it is exactly the separable HNN with the same Hamiltonian
    quiet = eqx.tree_at(lambda m: m.free, mix, _zero_last(mix.free))
    so = models.make("hnn_so", scene, key=key, width=W, dtype="float64")
    so = eqx.tree_at(lambda m: m.hamiltonian_part, so, mix.hamiltonian_part)
    f = eqx.filter_jit(jax.vmap(lambda m, z: m.vector_field(0.0, z, None), in_axes=(None, 0)))
    np.testing.assert_allclose(f(quiet, zs), f(so, zs), rtol=1e-10, atol=1e-12)

    # and the free field is added to the canonical derivative of the whole state
    @eqx.filter_jit
    def gap_and_free(mix, quiet, zs):
        ys = jax.vmap(lambda z: mix.encode(z, None))(zs)
        one = lambda y: mix.internal_field(0.0, y, None) - quiet.internal_field(0.0, y, None)
        free = lambda y: mix.free(mix.features(y[:2], y[2:], jnp.zeros((0,))))
        return jax.vmap(one)(ys), jax.vmap(free)(ys)

    gap, free = gap_and_free(mix, quiet, zs)
    np.testing.assert_allclose(gap, free, rtol=1e-10, atol=1e-14)
    assert float(jnp.min(jnp.abs(free[:, :2]))) > 0  # dq/dt is not qdot: not second order


def test_mixture_hnn_velocity_field_is_its_canonical_flow():
    mix = models.make("mixture_hnn", CHAIN2, key=jr.PRNGKey(4), width=W, dtype="float64")
    z0 = 0.5 * _states(jr.PRNGKey(5), 1, 2)[0]
    integ = models.Integrator("rk4", substeps=2)

    @eqx.filter_jit
    def gap(mix, z0, ts):  # one program for both steps: the horizon is its input
        a = models.rollout(mix, z0, ts, None, integ)  # integrated in (q, p)
        b = models.rollout(_InZ(mix), z0, ts, None, integ)  # integrated in (q, qdot)
        return jnp.max(jnp.abs(a - b))

    # two rk4 steps: the gap falls ~32x per halving of the step (local errors O(h^5))
    out = [float(gap(mix, z0, jnp.array([0.0, t]))) for t in (0.2, 0.1)]
    assert out[0] < 1e-4 and out[0] / max(out[1], 1e-300) > 10, out


class _InZ(AbstractContinuousModel):
    scene: Scene
    dtype: str
    inner: AbstractContinuousModel

    def __init__(self, inner):
        self.scene, self.dtype, self.inner = inner.scene, inner.dtype, inner

    def vector_field(self, t, z, args):
        return self.inner.vector_field(t, z, args)


# --------------------------------------------------------------------------- naive HNN


def test_hnn_without_momentum_map_is_j_grad_h_on_q_qdot():
    naive = models.make(
        "hnn", CHAIN2, key=jr.PRNGKey(6), width=W, dtype="float64", momentum_map=False
    )
    assert naive.mass is None
    canonical = models.make("hnn", CHAIN2_CANONICAL, key=jr.PRNGKey(6), width=W, dtype="float64")
    zs = 0.5 * _states(jr.PRNGKey(7), 6, 2)
    f = eqx.filter_jit(jax.vmap(lambda m, z: m.vector_field(0.0, z, None), in_axes=(None, 0)))
    # the same network, read on (q, qdot) as if qdot were p
    np.testing.assert_allclose(f(naive, zs), f(canonical, zs), rtol=1e-12)
    assert float(eqx.filter_jit(models.symplectic_error)(naive, zs, None)) < 1e-20
    mapped = models.make("hnn", CHAIN2, key=jr.PRNGKey(6), width=W, dtype="float64")
    assert mapped.mass is not None and models.n_parameters(mapped) > models.n_parameters(naive)


# --------------------------------------------------------------------------- node_so_symreg


def test_node_so_symreg_structure_and_penalty():
    model = models.make(
        "node_so_symreg", CHAIN2_CANONICAL, key=jr.PRNGKey(8), width=W, dtype="float64", weight=2.0
    )
    zs = 0.5 * _states(jr.PRNGKey(9), 6, 2)
    out, minv = eqx.filter_jit(
        lambda m, zs: (
            jax.vmap(lambda z: m.vector_field(0.0, z, None))(zs),
            jax.vmap(lambda z: m.inverse_mass.matrix(z[:2], jnp.zeros((0,))))(zs),
        )
    )(model, zs)
    np.testing.assert_allclose(out[:, :2], jnp.einsum("nij,nj->ni", minv, zs[:, 2:]), rtol=1e-12)
    assert np.all(np.linalg.eigvalsh(np.asarray(minv)) > 0)
    err = float(eqx.filter_jit(models.symplectic_error)(model, zs, None))
    assert err > 0
    penalty = eqx.filter_jit(lambda m, zs: m.penalty(zs, None))(model, zs)
    np.testing.assert_allclose(float(penalty), 2.0 * err, rtol=1e-12)


class _TrueChainField(AbstractContinuousModel):
    """The true chain-2 field in (q, qdot), or in canonical (q, p) by the chain rule:
    dq/dt = v(q, p), dp/dt = D momentum(q, v) . (v, a(q, v)) (no Hamiltonian is used)."""

    scene: Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    system: systems.AbstractSystem

    def vector_field(self, t, z, args):
        if not self.scene.canonical:
            return self.system.vector_field(t, z, None)
        q, p = z[:2], z[2:]
        v = self.system.velocity(q, p)
        a = self.system.acceleration(q, v)
        state, rate = jnp.concatenate([q, v]), jnp.concatenate([v, a])
        pdot = jax.jvp(self.system.momentum, (state,), (rate,))[1]
        return jnp.concatenate([v, pdot])


def test_true_chain_field_is_symplectic_only_in_canonical_coordinates():
    """The penalty that node_symreg / node_so_symreg put on their fields (the same function,
    models.symplectic_error) vanishes for the true dynamics in (q, p), not in (q, qdot)."""
    chain = systems.make("chain_pendulum", k=2)
    zs = chain.sample_initial(jr.PRNGKey(0), 8)
    ys = jax.jit(jax.vmap(lambda z: jnp.concatenate([z[:2], chain.momentum(z)])))(zs)
    canonical = _TrueChainField(CHAIN2_CANONICAL, "float64", chain)
    velocity = _TrueChainField(CHAIN2, "float64", chain)
    sym = eqx.filter_jit(models.symplectic_error)
    assert float(sym(canonical, ys, None)) < 1e-10
    assert float(sym(velocity, zs, None)) > 1.0
    # a random free field (output layer scaled so that its Jacobian is O(1)) is O(1) too
    node = models.make("node", CHAIN2_CANONICAL, key=jr.PRNGKey(1), width=W, dtype="float64")
    node = eqx.tree_at(lambda m: m.net.weights[-1], node, replace_fn=lambda w: 10.0 * w)
    assert float(sym(node, ys, None)) > 0.1


# --------------------------------------------------------------------------- LNN seed's form


def test_lnn_pure_form_on_the_relativistic_particle_is_finite_at_init():
    """kinetic_prior=0 (the LNN seed's L = MLP) at smoke width on relativistic states: finite
    accelerations at initialisation. (At quick width 128, seed 0 has one training chunk of 200
    whose step-0 loss is non-finite: see the LNN docstring; that is not hidden here.)"""
    scene = Scene(1, (False,), n_args=1)
    particle = systems.make("relativistic_particle")
    zs = particle.sample_initial(jr.PRNGKey(0), 64)
    gs = particle.sample_args(jr.PRNGKey(1), 64)
    for seed in range(3):
        lnn = models.make(
            "lnn", scene, key=jr.PRNGKey(seed), width=16, dtype="float64", kinetic_prior=0.0
        )
        acc = eqx.filter_jit(
            jax.vmap(lambda m, z, g: m.acceleration(z[:1], z[1:], g), in_axes=(None, 0, 0))
        )(lnn, zs, gs)
        assert bool(jnp.all(jnp.isfinite(acc))), seed
