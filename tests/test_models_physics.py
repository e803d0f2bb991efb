"""Structural (physics) checks of each bias: conservation, dissipation, symplecticity, the
Euler-Lagrange solve against closed forms, and the variational integrators' order and symmetry."""

from __future__ import annotations

import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.random as jr
import numpy as np
import pytest
from _model_helpers import CHAIN2, STRUCTURED, VELOCITY_ONLY, G, W, _apply, _states  # noqa: F401

import models
from models import AbstractContinuousModel, Scene

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
    assert float(eqx.filter_jit(models.symplectic_error)(model, zs, None)) < 1e-10


def test_node_is_not_symplectic_and_symreg_penalises_it():
    node = models.make("node", CHAIN2, key=jr.PRNGKey(8), width=W, dtype="float64")
    reg = models.make(
        "node_symreg", CHAIN2, key=jr.PRNGKey(8), width=W, dtype="float64", weight=3.0
    )
    zs = _states(jr.PRNGKey(9), 8, 2).reshape(2, 4, 4)  # (trajectory, time, state)
    sym = eqx.filter_jit(models.symplectic_error)
    err = float(sym(node, zs, None))
    assert err > 1e-6
    assert float(node.penalty(zs, None)) == 0.0
    np.testing.assert_allclose(float(eqx.filter_jit(reg.penalty)(zs, None)), 3.0 * err, rtol=1e-12)
    # the error is a mean over states, so the flattened batch gives the same value
    np.testing.assert_allclose(float(sym(node, zs.reshape(8, 4), None)), err)
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

    m1: float = M1
    m2: float = M2
    l1: float = L1
    l2: float = L2

    def __call__(self, x):
        c1, c2, s1, s2, v1, v2 = x
        m1, m2, l1, l2 = self.m1, self.m2, self.l1, self.l2
        cd = c1 * c2 + s1 * s2
        return jnp.stack(
            [
                0.5 * (m1 + m2) * l1**2 * v1**2
                + 0.5 * m2 * l2**2 * v2**2
                + m2 * l1 * l2 * v1 * v2 * cd
                + (m1 + m2) * G * l1 * c1
                + m2 * G * l2 * c2
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


def test_lnn_kinetic_prior_is_exactly_c_v_squared():
    kw = dict(key=jr.PRNGKey(3), width=W, dtype="float64")
    pure = models.make("lnn", CHAIN2, kinetic_prior=0.0, **kw)
    prior = models.make("lnn", CHAIN2, **kw)  # default c = 0.1
    q, v = jnp.array([0.3, -1.2]), jnp.array([0.7, 2.0])
    gap = prior.lagrangian(q, v, None) - pure.lagrangian(q, v, None)
    np.testing.assert_allclose(gap, 0.1 * (v @ v), rtol=1e-12)


def test_lnn_with_true_lagrangian_is_the_true_system():
    # the pure form (no kinetic prior): the swapped-in network is the whole Lagrangian
    lnn = models.make("lnn", CHAIN2, key=jr.PRNGKey(0), width=W, dtype="float64", kinetic_prior=0.0)
    field = eqx.filter_jit(jax.vmap(lambda m, z: m.vector_field(0.0, z, None), (None, 0)))
    zs = _states(jr.PRNGKey(11), 8, 2)
    true_lnn = eqx.tree_at(lambda m: m.net, lnn, _FeatureLagrangian())
    closed = jax.vmap(_double_pendulum_acc)(zs[:, :2], zs[:, 2:])
    np.testing.assert_allclose(field(true_lnn, zs)[:, 2:], closed, rtol=1e-8, atol=1e-8)
    # third route: the systems package's own equations of motion, at its own parameters
    systems = pytest.importorskip("systems")
    sys = systems.make("chain_pendulum", k=2)
    (m1, m2), (l1, l2) = (np.asarray(sys.masses), np.asarray(sys.lengths))
    sys_lnn = eqx.tree_at(lambda m: m.net, lnn, _FeatureLagrangian(m1, m2, l1, l2))
    truth = jax.jit(jax.vmap(lambda z: sys.vector_field(0.0, z, None)))(zs)
    np.testing.assert_allclose(field(sys_lnn, zs), truth, rtol=1e-8, atol=1e-8)


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


# --------------------------------------------------------------------------- canonical rollout


class _InZ(AbstractContinuousModel):
    """The same model integrated in its state coordinates z (identity encode/decode)."""

    scene: Scene
    dtype: str
    inner: AbstractContinuousModel

    def __init__(self, inner):
        self.scene, self.dtype, self.inner = inner.scene, inner.dtype, inner

    def vector_field(self, t, z, args):
        return self.inner.vector_field(t, z, args)


@functools.cache
def _canonical_pair(name, damped):
    scene = Scene(dof=2, angular=(True, True), damped=damped)
    model = models.make(name, scene, key=jr.PRNGKey(11), width=W, dtype="float64")
    # a freshly initialised H is nearly flat (fields ~0.01): scale the output layers so that
    # the flow and the variation of the mass matrix are O(1) and the rk4 error is visible
    part = model.hamiltonian_part
    energy_net = part.potential if name == "hnn_so" else part.net
    mass_net = part.inverse_mass.net if name == "hnn_so" else model.mass.net
    model = eqx.tree_at(
        lambda m: (_energy_net(m).weights[-1], _mass_net(m).weights[-1]),
        model,
        (30.0 * energy_net.weights[-1], 5.0 * mass_net.weights[-1]),
    )
    z0s = 0.7 * _states(jr.PRNGKey(12), 3, 2)
    return model, z0s


def _energy_net(m):
    part = m.hamiltonian_part
    return part.net if hasattr(m, "mass") else part.potential


def _mass_net(m):
    return m.mass.net if hasattr(m, "mass") else m.hamiltonian_part.inverse_mass.net


@pytest.mark.parametrize(
    "name, damped",
    [("hnn_so", True)]  # the other three: slow (the same mechanism, 2-5 s each)
    + [pytest.param("hnn", True, marks=pytest.mark.slow)]
    + [pytest.param(n, False, marks=pytest.mark.slow) for n in ("hnn", "hnn_so")],
)
def test_canonical_rollout_is_the_velocity_flow(name, damped):
    """Integrating J grad H in (q, p) and decoding gives the (q, qdot) integration of
    vector_field up to the rk4 error: over two steps, the gap falls ~32x per halving of the
    step (local errors O(h^5)). One program serves both steps (the horizon is its input)."""
    model, z0s = _canonical_pair(name, damped)
    back = jax.vmap(lambda z: model.decode(model.encode(z, None), None))(z0s)
    np.testing.assert_allclose(back, z0s, rtol=1e-12, atol=1e-12)
    gaps = _rk4_gaps(model)
    coarse, fine = (np.asarray(gaps(z0s, jnp.array([0.0, t]))) for t in (0.3, 0.15))
    for c, f in zip(coarse, fine, strict=True):
        assert 1e-12 < c < 1e-2, c
        assert c / f > 10, (c, f)


def _rk4_gaps(model):
    """``gaps(z0s, ts)``: per state, the largest gap between two rk4 steps over ``ts`` of
    ``model`` (integrated in its own coordinates) and of the same field in z."""
    integ = models.Integrator("rk4", substeps=2)

    @jax.jit
    def gaps(z0s, ts):
        def one(z0):
            a = models.rollout(model, z0, ts, None, integ)
            b = models.rollout(_InZ(model), z0, ts, None, integ)
            return jnp.max(jnp.abs(a - b))

        return jax.vmap(one)(z0s)

    return gaps


@pytest.mark.parametrize("name", ["hnn", "hnn_so"])
def test_canonical_rk4_rollout_conserves_learned_energy(name):
    """The learned H(z) of the decoded states of an undamped canonical rk4 rollout drifts
    only by the rk4 error (a wrong encode/decode pair would change H at every save)."""
    model, z0s = _canonical_pair(name, False)
    ts = jnp.linspace(0.0, 1.0, 11)
    zs = jax.jit(lambda z: models.rollout(model, z, ts, None, models.Integrator("rk4", 4)))(z0s[0])
    energy = np.asarray(jax.vmap(lambda z: model.hamiltonian(z, None))(zs))
    flow = np.ptp(np.asarray(zs[:, 2:]))  # the state does move
    assert flow > 1e-2 and np.ptp(energy) < 1e-6 * (1 + abs(energy[0])), (flow, energy)


@pytest.mark.slow  # keeps make test under 10 min on a 2-core CPU
@pytest.mark.parametrize("name", ["hnn", "hnn_so"])
def test_canonical_rollout_adaptive_and_energy(name):
    """Adaptive canonical rollout equals the z-coordinate one to solver tolerance, and the
    learned H(z) of the decoded states is conserved along it."""
    model, z0s = _canonical_pair(name, False)
    ts = jnp.linspace(0.0, 1.0, 6)
    integ = models.Integrator("adaptive", rtol=1e-10, atol=1e-12)
    a = jax.jit(lambda z: models.rollout(model, z, ts, None, integ))(z0s[0])
    b = jax.jit(lambda z: models.rollout(_InZ(model), z, ts, None, integ))(z0s[0])
    np.testing.assert_allclose(a, b, atol=1e-7)
    energy = jax.vmap(lambda z: model.hamiltonian(z, None))(a)
    assert np.ptp(np.asarray(energy)) < 1e-8 * (1 + abs(float(energy[0])))
