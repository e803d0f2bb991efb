"""The integrators keep their promises on real fields, in float64.

- convergence order on the chain pendulum (k = 2, the true field from ``systems``, whose
  acceleration depends on the velocity through its Coriolis terms): leapfrog ~2 (its explicit
  variant ~1), implicit midpoint ~2, rk4 and rk4_38 ~4, against ``systems``' Dopri8 truth;
- symplecticity of one step on a learned non-separable H(q, p) and on the separable HNN's
  q-dependent mass: the step's Jacobian Phi satisfies Phi^T J Phi = J;
- the learned H of a random network stays within a bounded band over 10^4 steps under the
  symplectic methods, with no secular drift, while explicit Euler drifts;
- gradients through the implicit stages (implicit function theorem) match finite differences.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

jax.config.update("jax_enable_x64", True)

import models  # noqa: E402
import systems  # noqa: E402
from bench.studies.stability import true_model  # noqa: E402
from models._integrators import Integrator, rollout  # noqa: E402


def _j(d):
    eye, zero = jnp.eye(d), jnp.zeros((d, d))
    return jnp.block([[zero, eye], [-eye, zero]])


@pytest.fixture(scope="module")
def chain():
    sysm = systems.make("chain_pendulum", k=2)
    z0 = np.asarray(sysm.sample_initial(jax.random.PRNGKey(1), 1))[0]
    horizon = 0.8
    truth = np.asarray(sysm.simulate(z0, np.linspace(0.0, horizon, 5)))
    return true_model(sysm), jnp.asarray(z0), horizon, truth


@pytest.mark.parametrize(
    ("method", "low", "high", "dts"),
    [
        ("leapfrog", 1.9, 2.2, (0.05, 0.025, 0.0125)),
        ("implicit_midpoint", 1.9, 2.2, (0.05, 0.025, 0.0125)),
        ("leapfrog_explicit", 0.7, 1.3, (0.1, 0.05, 0.025)),
        ("rk4", 3.9, 4.8, (0.05, 0.025, 0.0125)),
        # rk4_38 is rk4's sibling (same order, ~10 s): slow, to keep make test under 10 min
        pytest.param("rk4_38", 3.9, 4.8, (0.05, 0.025, 0.0125), marks=pytest.mark.slow),
    ],
)
def test_convergence_order_on_chain_pendulum(chain, method, low, high, dts):
    model, z0, horizon, truth = chain
    errors = []
    ts = jnp.linspace(0.0, horizon, 5)
    for dt in dts:
        n = round(horizon / 4 / dt)
        zs = rollout(model, z0, ts, None, Integrator(method, substeps=n))
        errors.append(float(np.max(np.abs(np.asarray(zs) - truth))))
    order = np.polyfit(np.log(dts), np.log(errors), 1)[0]
    assert low <= order <= high, (method, order, errors)
    assert max(errors) < 0.5  # the asymptotic regime, not a blow-up


@pytest.fixture(scope="module")
def learned_h():
    """A random non-separable H(q, p) = MLP(cos q, sin q, p) in a canonical scene."""
    scene = models.Scene(dof=2, angular=(True, True), canonical=True)
    return models.make("hnn", scene, key=jax.random.PRNGKey(0), width=16, dtype="float64")


@pytest.mark.parametrize("method", ["leapfrog", "implicit_midpoint"])
def test_one_step_is_symplectic_on_a_learned_nonseparable_h(learned_h, method):
    y0 = jnp.array([0.3, -0.5, 0.4, 0.2])
    h = 3.0  # a long step: rk4 visibly breaks the J-form here (below)

    def step(m):
        return lambda y: rollout(learned_h, y, jnp.array([0.0, h]), None, Integrator(m))[-1]

    phi = jax.jacfwd(step(method))(y0)
    assert float(jnp.max(jnp.abs(phi.T @ _j(2) @ phi - _j(2)))) < 1e-9
    assert not np.allclose(phi, np.eye(4), atol=1e-3)  # the step actually moves
    phi_rk4 = jax.jacfwd(step("rk4"))(y0)
    assert float(jnp.max(jnp.abs(phi_rk4.T @ _j(2) @ phi_rk4 - _j(2)))) > 1e-8


@pytest.mark.slow
@pytest.mark.parametrize("method", ["leapfrog", "implicit_midpoint"])
def test_one_step_is_symplectic_for_the_separable_hnn_mass(method):
    # hnn_so in velocity coordinates integrates in (q, p); its H has a q-dependent mass, so
    # it is not separable in the Stormer-Verlet sense: the internal step must still be
    # symplectic, the explicit velocity Verlet's is not
    scene = models.Scene(dof=2, angular=(True, True))
    model = models.make("hnn_so", scene, key=jax.random.PRNGKey(1), width=16, dtype="float64")
    y0 = jnp.array([0.3, -0.5, 0.4, 0.2])

    def step(m):
        def internal(y):
            z = rollout(model, model.decode(y, None), jnp.array([0.0, 0.3]), None, Integrator(m))
            return model.encode(z[-1], None)

        return internal

    phi = jax.jacfwd(step(method))(y0)
    assert float(jnp.max(jnp.abs(phi.T @ _j(2) @ phi - _j(2)))) < 1e-9
    phi_x = jax.jacfwd(step("leapfrog_explicit"))(y0)
    assert float(jnp.max(jnp.abs(phi_x.T @ _j(2) @ phi_x - _j(2)))) > 1e-7


@pytest.mark.slow  # keeps make test under 10 min on a 2-core CPU
def test_learned_h_bounded_over_ten_thousand_steps():
    scene = models.Scene(dof=1, angular=(True,), canonical=True)
    model = models.make("hnn", scene, key=jax.random.PRNGKey(0), width=16, dtype="float64")
    z0 = jnp.array([0.5, 0.3])
    ts = jnp.arange(10_001) * 0.1
    energy = jax.vmap(lambda z: model.hamiltonian(z, None))

    def blocks(method):
        """max |H(z_t) - H(z_0)| over each tenth of the rollout, and how far q moved."""
        zs = jax.jit(lambda z: rollout(model, z, ts, None, Integrator(method)))(z0)
        dh = np.abs(np.asarray(energy(zs)) - float(energy(z0[None])[0]))
        return dh[1:].reshape(10, 1000).max(axis=1), np.ptp(np.asarray(zs[:, 0]))

    euler, _ = blocks("euler")
    for method in ("implicit_midpoint", "leapfrog"):
        band, moved = blocks(method)
        assert moved > 1.0  # the trajectory went somewhere
        # bounded: the second half's band is no wider than a few times the first half's
        assert band[5:].max() < 3 * band[:5].max(), (method, band)
        assert band.max() < 1e-7, (method, band)
        # the non-symplectic explicit Euler drifts by orders of magnitude more
        assert band.max() < 1e-3 * euler.max(), (method, band.max(), euler.max())


@pytest.mark.parametrize(
    ("method", "name"),
    [
        ("implicit_midpoint", "node_so"),
        pytest.param("leapfrog", "node_so", marks=pytest.mark.slow),
        pytest.param("leapfrog", "hnn_so", marks=pytest.mark.slow),
        pytest.param("implicit_midpoint", "hnn_so", marks=pytest.mark.slow),
    ],
)
@pytest.mark.slow  # keeps make test under 10 min on a 2-core CPU
def test_gradient_through_implicit_stages_matches_finite_differences(method, name):
    scene = models.Scene(dof=2, angular=(True, True))
    model = models.make(name, scene, key=jax.random.PRNGKey(2), width=8, dtype="float64")
    z0 = jnp.array([0.3, -0.5, 0.4, 0.2])
    ts = jnp.linspace(0.0, 0.3, 4)

    def loss(m):
        return jnp.sum(rollout(m, z0, ts, None, Integrator(method)) ** 2)

    params, static = eqx.partition(model, eqx.is_inexact_array)
    flat, tree = jax.tree_util.tree_flatten(params)
    keys = jax.random.split(jax.random.PRNGKey(5), len(flat))
    dirs = [jax.random.normal(k, x.shape, x.dtype) for k, x in zip(keys, flat, strict=True)]

    def moved(eps):
        shifted = [x + eps * d for x, d in zip(flat, dirs, strict=True)]
        return eqx.combine(jax.tree_util.tree_unflatten(tree, shifted), static)

    grads = jax.tree_util.tree_leaves(eqx.filter_grad(loss)(model))
    ad = sum(float(jnp.sum(g * d)) for g, d in zip(grads, dirs, strict=True))
    fd = (float(loss(moved(1e-6))) - float(loss(moved(-1e-6)))) / 2e-6
    assert abs(ad - fd) < 1e-6 * max(1.0, abs(fd)), (ad, fd)


@pytest.mark.slow
def test_newton_and_fixed_point_stages_agree(chain):
    model, z0, horizon, _ = chain
    ts = jnp.linspace(0.0, horizon, 17)
    for method in ("leapfrog", "implicit_midpoint"):
        a = rollout(model, z0, ts, None, Integrator(method))
        b = rollout(model, z0, ts, None, Integrator(method, implicit_solver="newton"))
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-9)
