"""Conformance of every registered model, and the structural (physics) checks of each bias."""

from __future__ import annotations

import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.random as jr
import numpy as np
import pytest

import models
from models import AbstractContinuousModel, Scene

jax.config.update("jax_enable_x64", True)

W = 16  # tiny networks: these tests check structure, not capacity
CHAIN2 = Scene(dof=2, angular=(True, True))
STRUCTURED = ("hnn", "hnn_so", "lnn", "vin", "vin_implicit")
VELOCITY_ONLY = ("lnn", "vin", "vin_implicit")
G = 9.81


def _apply(model, z, args):
    if isinstance(model, AbstractContinuousModel):
        return model.vector_field(0.0, z, args)
    return model.step(z, 0.03, args)


def _states(key, n, dof, dtype=jnp.float64):
    return jr.normal(key, (n, 2 * dof), dtype)


@functools.cache
def _trained_once(name):
    """float32: loss, vmapped outputs and parameter gradients in one jitted program, called
    twice with different values (it must trace once)."""
    model = models.make(name, CHAIN2, key=jr.PRNGKey(0), width=W)
    traces = []

    @eqx.filter_jit
    def check(model, zs, args):
        traces.append(1)

        def loss(m):
            pred = jax.vmap(lambda z: _apply(m, z, args))(zs)
            return jnp.mean(pred**2) + m.penalty(zs, args), pred

        return eqx.filter_value_and_grad(loss, has_aux=True)(model)

    args = jnp.zeros((0,))
    zs1 = 0.5 * _states(jr.PRNGKey(1), 6, 2)  # float64 inputs: the model must cast them
    zs2 = 0.5 * _states(jr.PRNGKey(2), 6, 2)
    (_, out1), grads = check(model, zs1, args)
    (_, out2), _ = check(model, zs2, args)
    return model, zs1, out1, out2, grads, len(traces)


@functools.cache
def _forward64(name):
    model = models.make(name, CHAIN2, key=jr.PRNGKey(0), width=W, dtype="float64")
    zs = 0.5 * _states(jr.PRNGKey(1), 6, 2)
    f = eqx.filter_jit(
        lambda m, zs: (_apply(m, zs[0], None), jax.vmap(lambda z: _apply(m, z, None))(zs))
    )
    return model, zs, *f(model, zs.astype(jnp.float32))


@pytest.mark.parametrize("name", models.available())
def test_conformance_float32_jit_vmap_grad(name):
    model, zs, out, out2, grads, n_traces = _trained_once(name)
    assert out.shape == (6, 4) and out.dtype == jnp.float32
    assert n_traces == 1  # one compile per configuration
    assert not np.allclose(out, out2)  # the second call used its own inputs
    leaves = jax.tree_util.tree_leaves(eqx.filter(grads, eqx.is_inexact_array))
    assert leaves and all(bool(jnp.all(jnp.isfinite(g))) for g in leaves)
    assert sum(float(jnp.sum(jnp.abs(g))) for g in leaves) > 0
    for leaf in jax.tree_util.tree_leaves(eqx.filter(model, eqx.is_inexact_array)):
        assert leaf.dtype == jnp.float32
    if isinstance(model, AbstractContinuousModel) and model.second_order:
        np.testing.assert_array_equal(out[:, :2], zs[:, 2:].astype(jnp.float32))


@pytest.mark.parametrize("name", models.available())
def test_conformance_float64_and_vmap_matches_unbatched(name):
    model, zs, single, outs = _forward64(name)
    assert outs.shape == (6, 4) and outs.dtype == jnp.float64 and single.dtype == jnp.float64
    for leaf in jax.tree_util.tree_leaves(eqx.filter(model, eqx.is_inexact_array)):
        assert leaf.dtype == jnp.float64
    np.testing.assert_allclose(outs[0], single, rtol=1e-12, atol=1e-12)
    if isinstance(model, AbstractContinuousModel) and model.second_order:
        # dq/dt = qdot exactly, and the field's second half is acceleration(q, v)
        zs32 = zs.astype(jnp.float32).astype(jnp.float64)
        np.testing.assert_array_equal(outs[:, :2], zs32[:, 2:])
        acc = model.acceleration(zs32[0, :2], zs32[0, 2:], None)
        np.testing.assert_allclose(acc, single[2:], rtol=1e-10, atol=1e-12)


@functools.cache
def _variant(name):
    """A damped scene with one args input, mixed coordinates, canonical where allowed."""
    scene = Scene(
        dof=2,
        angular=(True, False),
        n_args=1,
        damped=True,
        canonical=name not in VELOCITY_ONLY,
    )
    model = models.make(name, scene, key=jr.PRNGKey(3), width=W, dtype="float64")
    f = eqx.filter_jit(jax.vmap(_apply, in_axes=(None, 0, None)))
    zs = 0.5 * _states(jr.PRNGKey(4), 5, 2)
    return model, f(model, zs, jnp.array([1.0])), f(model, zs, jnp.array([2.0]))


@pytest.mark.parametrize("name", models.available())
def test_variant_scene_uses_args_and_dissipation(name):
    model, out1, out2 = _variant(name)
    assert out1.shape == (5, 4) and bool(jnp.all(jnp.isfinite(out1)))
    assert float(jnp.max(jnp.abs(out1 - out2))) > 1e-8  # args are inputs
    if name in STRUCTURED:
        assert model.dissipation is not None
    plain = models.make(
        name, _variant(name)[0].scene, key=jr.PRNGKey(3), width=W, dissipation=False
    )
    assert getattr(plain, "dissipation", None) is None


def test_registry_and_errors():
    assert models.available() == [
        "node",
        "node_so",
        "hnn",
        "hnn_so",
        "node_symreg",
        "lnn",
        "vin",
        "vin_implicit",
        "resnet",
    ]
    key = jr.PRNGKey(0)
    with pytest.raises(ValueError, match="hnn_so"):
        models.make("hnn_s0", CHAIN2, key=key)
    with pytest.raises(ValueError, match="weight"):
        models.make("node_symreg", CHAIN2, key=key, wieght=1.0)
    with pytest.raises(ValueError, match="allowed: \\[\\]"):
        models.make("node", CHAIN2, key=key, weight=1.0)
    with pytest.raises(ValueError, match="solve"):
        models.make("lnn", CHAIN2, key=key, solve="qr")
    for bad in (
        {"width": 0},
        {"depth": 1.5},
        {"activation": "sin"},
        {"dtype": "float16"},
        {"dissipation": "yes"},
    ):
        with pytest.raises(ValueError):
            models.make("node", CHAIN2, key=key, **bad)
    with pytest.raises(ValueError, match="velocity"):
        models.make("lnn", Scene(dof=1, angular=(False,), canonical=True), key=key)
    with pytest.raises(ValueError):
        Scene(dof=2, angular=(True,))


def test_parameter_count_and_inits():
    node = models.make("node", CHAIN2, key=jr.PRNGKey(0), width=32, depth=3)
    n_in = 2 * 2 + 2  # (cos q, sin q) for two angles, then qdot
    assert models.n_parameters(node) == (n_in + 1) * 32 + 2 * (32 + 1) * 32 + (32 + 1) * 4
    w = node.net.weights[1]
    np.testing.assert_allclose(w.T @ w, 0.25 * np.eye(32), atol=1e-5)  # orthogonal, gain 0.5
    lnn = models.make("lnn", CHAIN2, key=jr.PRNGKey(0), width=256)
    assert lnn.net.activation == "softplus"
    stds = [float(jnp.std(x)) for x in lnn.net.weights]  # LNN seed appendix B, eq. 3
    np.testing.assert_allclose(stds[:2], [2.2 / 16, 0.58 / 16], rtol=0.05)
    assert 10 < stds[2] < 22  # output layer sigma = sqrt(256) = 16 (256 samples)


# --------------------------------------------------------------------------- energy


def _energy_fn(model):
    if isinstance(model, models.AbstractContinuousModel) and hasattr(model, "hamiltonian"):
        return model.hamiltonian
    return model.energy


@functools.cache
def _energy_rate(name, canonical, damped):
    scene = Scene(dof=2, angular=(True, True), damped=damped, canonical=canonical)
    model = models.make(name, scene, key=jr.PRNGKey(5), width=W, dtype="float64")
    E = _energy_fn(model)

    @jax.jit
    @jax.vmap
    def rate(z):
        g = jax.grad(E)(z, None)
        f = model.vector_field(0.0, z, None)
        return g @ f, jnp.linalg.norm(g) * jnp.linalg.norm(f)

    return rate(_states(jr.PRNGKey(6), 32, 2))


@pytest.mark.parametrize(
    "name,canonical",
    [("hnn", False), ("hnn", True), ("hnn_so", False), ("hnn_so", True), ("lnn", False)],
)
def test_learned_energy_conserved_by_its_field(name, canonical):
    rate, scale = _energy_rate(name, canonical, False)
    assert float(jnp.max(jnp.abs(rate) / scale)) < 1e-10


@pytest.mark.parametrize(
    "name,canonical",
    [("hnn", False), ("hnn", True), ("hnn_so", False), ("hnn_so", True), ("lnn", False)],
)
def test_dissipation_makes_learned_energy_decrease(name, canonical):
    rate, scale = _energy_rate(name, canonical, True)
    assert float(jnp.max(rate / scale)) < 1e-10
    assert float(jnp.mean(rate / scale)) < -1e-4  # and it does dissipate


def test_separable_hamiltonian_form():
    model = models.make("hnn_so", CHAIN2, key=jr.PRNGKey(7), width=W, dtype="float64")
    part = model.hamiltonian_part
    q, p = jnp.array([0.4, -1.1]), jnp.array([0.7, 0.2])
    H = lambda p_: part(q, p_, jnp.zeros((0,)))
    # H - V quadratic in p, with Hessian M^-1(q) positive definite
    np.testing.assert_allclose(H(2 * p) - H(0 * p), 4 * (H(p) - H(0 * p)), rtol=1e-12)
    hess = jax.hessian(H)(p)
    np.testing.assert_allclose(hess, part.inverse_mass.matrix(q, None), rtol=1e-12)
    assert bool(jnp.all(jnp.linalg.eigvalsh(hess) > 0))
    # in velocity coordinates the learned energy is 1/2 v^T M v + V
    v = jnp.array([0.3, -0.5])
    z = jnp.concatenate([q, v])
    mom = model.momentum(q, v, None)
    np.testing.assert_allclose(
        model.hamiltonian(z, None), 0.5 * v @ mom + part.potential_energy(q, None), rtol=1e-12
    )


# --------------------------------------------------------------------------- symplecticity


@pytest.mark.parametrize("name", ["hnn", "hnn_so"])
def test_hamiltonian_fields_are_symplectic(name):
    scene = Scene(dof=2, angular=(True, False), canonical=True)
    model = models.make(name, scene, key=jr.PRNGKey(8), width=W, dtype="float64")
    zs = _states(jr.PRNGKey(9), 8, 2)
    assert float(models.symplectic_error(model, zs, None)) < 1e-10


def test_node_is_not_symplectic_and_symreg_penalises_it():
    node = models.make("node", CHAIN2, key=jr.PRNGKey(8), width=W, dtype="float64")
    reg = models.make(
        "node_symreg", CHAIN2, key=jr.PRNGKey(8), width=W, dtype="float64", weight=3.0
    )
    zs = _states(jr.PRNGKey(9), 8, 2).reshape(2, 4, 4)  # (trajectory, time, state)
    err = float(models.symplectic_error(node, zs, None))
    assert err > 1e-6
    assert float(node.penalty(zs, None)) == 0.0
    np.testing.assert_allclose(float(reg.penalty(zs, None)), 3.0 * err, rtol=1e-12)
    # the error is a mean over states, so the flattened batch gives the same value
    np.testing.assert_allclose(float(models.symplectic_error(node, zs.reshape(8, 4), None)), err)
    with pytest.raises(ValueError):
        models.symplectic_error(models.make("vin", CHAIN2, key=jr.PRNGKey(0), width=W), zs, None)


# --------------------------------------------------------------------------- Lagrangian

M1, M2, L1, L2 = 1.1722, 1.0391, 1.0359, 1.0822  # the reference chain-2 masses and lengths


def _double_pendulum_L(q, v):
    d = q[0] - q[1]
    return (
        0.5 * (M1 + M2) * L1**2 * v[0] ** 2
        + 0.5 * M2 * L2**2 * v[1] ** 2
        + M2 * L1 * L2 * v[0] * v[1] * jnp.cos(d)
        + (M1 + M2) * G * L1 * jnp.cos(q[0])
        + M2 * G * L2 * jnp.cos(q[1])
    )


def _double_pendulum_acc(q, v):
    """The closed form (absolute angles from the downward vertical)."""
    t1, t2 = q
    w1, w2 = v
    d = t1 - t2
    den = 2 * M1 + M2 - M2 * jnp.cos(2 * d)
    a1 = (
        -G * (2 * M1 + M2) * jnp.sin(t1)
        - M2 * G * jnp.sin(t1 - 2 * t2)
        - 2 * jnp.sin(d) * M2 * (w2**2 * L2 + w1**2 * L1 * jnp.cos(d))
    ) / (L1 * den)
    a2 = (
        2
        * jnp.sin(d)
        * (w1**2 * L1 * (M1 + M2) + G * (M1 + M2) * jnp.cos(t1) + w2**2 * L2 * M2 * jnp.cos(d))
    ) / (L2 * den)
    return jnp.stack([a1, a2])


class _FeatureLagrangian(eqx.Module):
    """The double pendulum's L written on the model's inputs (cos q1, cos q2, sin q1, sin q2,
    v1, v2): swapped in for the LNN's network, it makes the LNN the true system."""

    def __call__(self, x):
        c1, c2, s1, s2, v1, v2 = x
        cd = c1 * c2 + s1 * s2
        return jnp.stack(
            [
                0.5 * (M1 + M2) * L1**2 * v1**2
                + 0.5 * M2 * L2**2 * v2**2
                + M2 * L1 * L2 * v1 * v2 * cd
                + (M1 + M2) * G * L1 * c1
                + M2 * G * L2 * c2
            ]
        )


@pytest.mark.parametrize("solve", ["solve", "pinv", "regularised"])
def test_euler_lagrange_solve_gives_true_accelerations(solve):
    zs = _states(jr.PRNGKey(10), 16, 2)
    eps = 1e-9 if solve == "regularised" else 1e-3
    acc = jax.vmap(
        lambda z: models.acceleration_from_lagrangian(
            _double_pendulum_L, z[:2], z[2:], solve=solve, eps=eps
        )
    )(zs)
    np.testing.assert_allclose(
        acc, jax.vmap(_double_pendulum_acc)(zs[:, :2], zs[:, 2:]), rtol=1e-7, atol=1e-7
    )


def test_lnn_with_true_lagrangian_is_the_true_system():
    systems = pytest.importorskip("systems")
    lnn = models.make("lnn", CHAIN2, key=jr.PRNGKey(0), width=W, dtype="float64")
    lnn = eqx.tree_at(lambda m: m.net, lnn, _FeatureLagrangian())
    zs = _states(jr.PRNGKey(11), 8, 2)
    field = jax.vmap(lambda z: lnn.vector_field(0.0, z, None))(zs)
    closed = jax.vmap(_double_pendulum_acc)(zs[:, :2], zs[:, 2:])
    np.testing.assert_allclose(field[:, 2:], closed, rtol=1e-8, atol=1e-8)
    # third route: the systems package (its own equations of motion for the same pendulum)
    sys = systems.make("chain_pendulum", k=2)
    truth = jax.vmap(lambda z: sys.vector_field(0.0, z, None))(zs)
    np.testing.assert_allclose(field, truth, rtol=1e-6, atol=1e-6)


# --------------------------------------------------------------------------- variational

PEND = Scene(dof=1, angular=(True,))


class _TruePotential(eqx.Module):
    def __call__(self, x):  # x = (cos q, sin q); unit mass and length
        return jnp.stack([-G * x[0]])


class _UnitMass(eqx.Module):
    def factor(self, q, args):
        return jnp.eye(1)

    def matrix(self, q, args):
        return jnp.eye(1)


class _TrueResidualLagrangian(eqx.Module):
    def __call__(self, x):  # L = 1/2 v^2 (the model's prior) + g cos q
        return jnp.stack([G * x[0]])


def _true_vin():
    vin = models.make("vin", PEND, key=jr.PRNGKey(0), width=W, dtype="float64")
    return eqx.tree_at(lambda m: (m.potential, m.mass), vin, (_TruePotential(), _UnitMass()))


def _true_vin_implicit():
    vin = models.make("vin_implicit", PEND, key=jr.PRNGKey(0), width=W, dtype="float64")
    return eqx.tree_at(lambda m: m.net, vin, _TrueResidualLagrangian())


@functools.cache
def _pendulum_reference(T):
    import diffrax

    def f(t, z, args):
        return jnp.stack([z[1], -G * jnp.sin(z[0])])

    sol = diffrax.diffeqsolve(
        diffrax.ODETerm(f),
        diffrax.Dopri8(),
        0.0,
        T,
        1e-3,
        jnp.array([1.0, 0.5]),
        stepsize_controller=diffrax.PIDController(rtol=1e-13, atol=1e-13),
    )
    return sol.ys[0]


@eqx.filter_jit
def _run(model, z0, dt, n):
    def body(z, _):
        if isinstance(model, models.AbstractDiscreteModel) and hasattr(model, "step_with_status"):
            z1, ok = model.step_with_status(z, dt, None)
        else:
            z1, ok = model.step(z, dt, None), True
        return z1, ok

    return jax.lax.scan(body, z0, None, length=n)


@pytest.mark.parametrize("make_model", [_true_vin, _true_vin_implicit], ids=["vin", "implicit"])
def test_vin_with_true_lagrangian_is_second_order(make_model):
    model = make_model()
    T = 1.2
    z0 = jnp.array([1.0, 0.5])
    errors = []
    for n in (40, 80):
        zn, ok = _run(model, z0, T / n, n)
        assert bool(jnp.all(ok))  # every Newton solve converged
        errors.append(float(jnp.linalg.norm(zn - _pendulum_reference(T))))
    ratio = errors[0] / errors[1]
    assert 3.5 < ratio < 4.5, (errors, ratio)


def test_vin_implicit_agrees_with_explicit_vin():
    z0 = jnp.array([1.0, 0.5])
    diffs = []
    for n in (40, 80):
        a, _ = _run(_true_vin(), z0, 1.2 / n, n)
        b, _ = _run(_true_vin_implicit(), z0, 1.2 / n, n)
        diffs.append(float(jnp.linalg.norm(a - b)))
    assert diffs[0] < 0.05 and 3.0 < diffs[0] / diffs[1] < 5.0


@pytest.mark.parametrize("make_model", [_true_vin, _true_vin_implicit], ids=["vin", "implicit"])
def test_vin_is_time_reversible(make_model):
    model = make_model()
    z0 = jnp.array([1.0, 0.5])
    flip = jnp.array([1.0, -1.0])
    zn, _ = _run(model, z0, 0.05, 60)
    back, _ = _run(model, zn * flip, 0.05, 60)
    np.testing.assert_allclose(back * flip, z0, atol=1e-9)


def test_forced_vin_dissipates_kinetic_energy():
    scene = Scene(dof=2, angular=(False, False), damped=True)
    vin = models.make("vin", scene, key=jr.PRNGKey(0), width=W, dtype="float64")
    free = eqx.tree_at(lambda m: m.potential, vin, lambda x: jnp.zeros((1,)))
    plain = eqx.tree_at(lambda m: m.dissipation, free, None, is_leaf=lambda x: x is None)
    z0 = jnp.array([0.1, -0.3, 1.0, -2.0])
    _, plain_traj = _run_traj(plain, z0)
    _, damped_traj = _run_traj(free, z0)
    e_plain = jax.vmap(lambda z: plain.energy(z, None))(plain_traj)
    e_damped = jax.vmap(lambda z: free.energy(z, None))(damped_traj)
    np.testing.assert_allclose(e_plain, e_plain[0], rtol=1e-12)  # free particle: conserved
    assert bool(jnp.all(jnp.diff(e_damped) < 0))


@eqx.filter_jit
def _run_traj(model, z0):
    def body(z, _):
        z1 = model.step(z, 0.1, None)
        return z1, z1

    return jax.lax.scan(body, z0, None, length=20)
