"""Control inputs: the zero-order hold of u in ``rollout``, the ``euler_so`` rule against the
closed-form driven oscillator, ``hnn_force`` (H conserved where F = 0, F on dp/dt only), the
parts that must not see u, the shape errors, and gradients through a controlled rollout."""

from __future__ import annotations

import _model_helpers  # noqa: F401 - float64 on
import equinox as eqx
import jax
import jax.numpy as jnp
import jax.random as jr
import numpy as np
import pytest

import models
from models import Integrator, Scene, rollout, rollout_batch
from models._integrators import _STEPS

# q = (angle, position), one static arg, two controls
CTRL = Scene(dof=2, angular=(True, False), n_args=1, n_controls=2)
ARGS = jnp.array([1.3])
TS = jnp.array([0.0, 0.1, 0.25, 0.3])
Z0 = jnp.array([0.4, -0.3, 0.2, 0.5])
U = jnp.array([[0.5, -1.0], [2.0, 0.3], [-1.5, 1.0]])
CONTROLLED = [n for n in models.available() if models.spec(n).controls]


def _make(name, scene=CTRL, key=0):
    return models.make(name, scene, key=jr.PRNGKey(key), width=8, dtype="float64")


@pytest.mark.parametrize("method", ["euler", "rk4"])
def test_node_rollout_holds_u_i_on_interval_i(method):
    model = _make("node")
    m = 3
    zs = rollout(model, Z0, TS, ARGS, Integrator(method, substeps=m), controls=U)
    step, z, expected = _STEPS[method], Z0, [Z0]
    for i in range(len(TS) - 1):  # the hand-written loop: u_i on [ts[i], ts[i+1]]
        a = jnp.concatenate([ARGS, U[i]])
        h = (TS[i + 1] - TS[i]) / m
        for j in range(m):
            z = step(lambda t, y, a=a: model.vector_field(t, y, a), TS[i] + j * h, z, h)
        expected.append(z)
    np.testing.assert_allclose(zs, jnp.stack(expected), rtol=1e-13, atol=1e-14)
    other = rollout(model, Z0, TS, ARGS, Integrator(method, substeps=m), controls=U[::-1])
    assert float(jnp.max(jnp.abs(other[-1] - zs[-1]))) > 1e-6  # u is an input


@pytest.mark.parametrize(
    "name",
    ["node", "resnet"]  # the implicit methods of the others cost ~15 s each: slow
    + [pytest.param(n, marks=pytest.mark.slow) for n in ("hnn_so", "mixture_hnn", "lnn")],
)
def test_uncontrolled_rollouts_are_unchanged_by_the_controls_path(name):
    scene = Scene(dof=2, angular=(True, False), n_args=1)
    model = _make(name, scene)
    empty = jnp.zeros((len(TS) - 1, 0))
    spec = models.spec(name)
    methods = ["rk4"]  # and one implicit method, whose stages carry a field value
    methods += [] if spec.discrete else ["leapfrog" if spec.second_order else "implicit_midpoint"]
    for method in methods:
        integrator = Integrator(method, substeps=2)
        plain = rollout(model, Z0, TS, ARGS, integrator)
        zero_width = rollout(model, Z0, TS, ARGS, integrator, controls=empty)  # per-interval args
        np.testing.assert_array_equal(plain, zero_width)


class _Driven(eqx.Module):
    """A network stand-in on the features (q, v, u): a(q, v, u) = -q + u."""

    def __call__(self, x):
        return -x[:1] + x[2:3]


DRIVEN = Scene(dof=1, angular=(False,), n_controls=1)


def _driven_node_so():
    return eqx.tree_at(lambda m: m.net, _make("node_so", DRIVEN), _Driven())


def _driven_exact(z0, ts, u):
    """q'' = -q + u_i on [ts[i], ts[i+1]]: q = u + (q0 - u) cos t + v0 sin t per interval."""
    q, v = float(z0[0]), float(z0[1])
    for i in range(len(ts) - 1):
        dt, ui = float(ts[i + 1] - ts[i]), float(u[i, 0])
        q, v = (
            ui + (q - ui) * np.cos(dt) + v * np.sin(dt),
            -(q - ui) * np.sin(dt) + v * np.cos(dt),
        )
    return np.array([q, v])


def test_euler_so_one_step_formula():
    model = _driven_node_so()
    q, v, u, h = 0.7, -0.4, 0.9, 0.05
    z1 = rollout(model, jnp.array([q, v]), jnp.array([0.0, h]), None, Integrator("euler_so"),
                 controls=jnp.array([[u]]))[1]  # fmt: skip
    a = -q + u
    np.testing.assert_allclose(z1, [q + h * v + 0.5 * h * h * a, v + h * a], rtol=1e-15)
    net = _make("node_so")  # a learned acceleration: the same rule with a(q, v, (args, u))
    z0 = jnp.array([0.4, -0.3, 0.2, 0.5])
    z1 = rollout(net, z0, TS[:2], ARGS, Integrator("euler_so"), controls=U[:1])[1]
    acc = net.acceleration(z0[:2], z0[2:], jnp.concatenate([ARGS, U[0]]))
    h = TS[1]
    np.testing.assert_allclose(z1[:2], z0[:2] + h * z0[2:] + 0.5 * h * h * acc, rtol=1e-14)
    np.testing.assert_allclose(z1[2:], z0[2:] + h * acc, rtol=1e-14)
    with pytest.raises(ValueError, match="euler_so needs a second-order model"):
        rollout(_make("node"), Z0, TS, ARGS, Integrator("euler_so"), controls=U)


@pytest.mark.parametrize(
    "method, order, substeps",
    [
        ("euler_so", 1, (8, 16, 32, 64)),
        ("rk4", 4, (2, 4, 8)),
        ("leapfrog", 2, (4, 8, 16)),
        ("leapfrog_explicit", 2, (4, 8, 16)),
        ("implicit_midpoint", 2, (4, 8, 16)),
    ],
)
def test_driven_oscillator_converges_at_the_method_order(method, order, substeps):
    """A switch of u at the wrong time, or a stale acceleration carried across it, costs an
    O(h) error and shows as order 1 for the higher-order methods."""
    model = _driven_node_so()
    ts = jnp.linspace(0.0, 2.0, 5)
    u = jnp.array([[0.3], [-0.5], [0.8], [0.1]])
    z0 = jnp.array([0.7, -0.4])
    exact = _driven_exact(z0, ts, u)
    errors = []
    for m in substeps:
        zs = rollout(model, z0, ts, None, Integrator(method, substeps=m), controls=u)
        errors.append(float(jnp.linalg.norm(zs[-1] - exact)))
    slope = np.polyfit(np.log(0.5 / np.array(substeps)), np.log(errors), 1)[0]
    assert abs(slope - order) < 0.15, (method, slope, errors)
    assert models.ORDERS[method] == order and method in models.DESCRIPTIONS


def test_shape_errors():
    model = _make("node")
    with pytest.raises(ValueError, match=r"n_controls=2: controls must have shape .* = \(3, 2\)"):
        rollout(model, Z0, TS, ARGS)
    for bad in (U[:2], U[:, :1], U[None]):
        with pytest.raises(ValueError, match=r"= \(3, 2\), got shape"):
            rollout(model, Z0, TS, ARGS, controls=bad)
    plain = _make("node", Scene(dof=2, angular=(True, False), n_args=1))
    with pytest.raises(ValueError, match=r"= \(3, 0\), got shape \(3, 2\)"):
        rollout(plain, Z0, TS, ARGS, controls=U)
    with pytest.raises(ValueError, match="adaptive cannot hold a piecewise-constant control"):
        rollout(model, Z0, TS, ARGS, Integrator("adaptive"), controls=U)
    z0s, args = jnp.stack([Z0, Z0]), jnp.stack([ARGS, ARGS])
    with pytest.raises(ValueError, match=r"\(N, len\(ts\) - 1, n_controls\) = \(2, 3, 2\), got"):
        rollout_batch(model, z0s, TS, args, controls=U)
    with pytest.raises(ValueError, match=r"= \(2, 3, 2\), got None"):
        rollout_batch(model, z0s, TS, args)
    batched = rollout_batch(model, z0s, TS, args, controls=jnp.stack([U, U[::-1]]))
    np.testing.assert_allclose(batched[0], rollout(model, Z0, TS, ARGS, controls=U), rtol=1e-12)
    with pytest.raises(ValueError, match="n_controls must be an int >= 0"):
        Scene(dof=1, angular=(False,), n_controls=-1)
    with pytest.raises(ValueError, match="'hnn' has no part that reads a control input"):
        models.make("hnn", CTRL, key=jr.PRNGKey(0))


@pytest.mark.parametrize("name", CONTROLLED)
def test_controlled_models_read_u_and_their_maps_do_not(name):
    model = _make(name, CTRL if "velocity" in models.coordinates(name) else _canonical(CTRL))
    if models.spec(name).discrete:
        apply = lambda z, a: model.step(z, 0.1, a)
    else:
        apply = lambda z, a: model.vector_field(0.0, z, a)
    a1, a2 = jnp.concatenate([ARGS, U[0]]), jnp.concatenate([ARGS, U[1]])
    assert float(jnp.max(jnp.abs(apply(Z0, a1) - apply(Z0, a2)))) > 1e-8
    if not models.spec(name).discrete:  # the coordinate maps (learned masses) never see u
        np.testing.assert_array_equal(model.encode(Z0, a1), model.encode(Z0, a2))
        y = model.encode(Z0, a1)
        np.testing.assert_array_equal(model.decode(y, a1), model.decode(y, a2))
    if hasattr(model, "hamiltonian"):
        assert model.hamiltonian(Z0, a1) == model.hamiltonian(Z0, a2)
    with pytest.raises(ValueError, match=r"args are \(static args, u\) of length 1 \+ 2"):
        apply(Z0, ARGS)


def _canonical(scene):
    return Scene(
        scene.dof, scene.angular, scene.n_args, canonical=True, n_controls=scene.n_controls
    )


def _hnn_force(zero_force):
    model = _make("hnn_force")
    if zero_force:
        last = lambda m: (m.force.weights[-1], m.force.biases[-1])
        model = eqx.tree_at(last, model, tuple(jnp.zeros_like(x) for x in last(model)))
    return model


def test_hnn_force_conserves_h_without_force_and_f_enters_dp_dt_only():
    spec = models.spec("hnn_force")
    assert spec.hamiltonian and spec.forced and spec.controls and spec.second_order
    assert not models.spec("hnn_so").forced and not models.spec("hnn_so").controls
    ts = jnp.linspace(0.0, 2.0, 11)
    u = jr.normal(jr.PRNGKey(5), (10, 2))
    energy = jax.vmap(lambda z, a: _hnn_force(True).hamiltonian(z, a))
    run = eqx.filter_jit(lambda m: rollout(m, Z0, ts, ARGS, Integrator("rk4", 20), controls=u))
    for zero_force, bound in ((True, 1e-8), (False, None)):
        model = _hnn_force(zero_force)
        zs = run(model)
        full = jnp.concatenate([jnp.broadcast_to(ARGS, (10, 1)), u], axis=1)
        h = energy(zs[1:], full) - model.hamiltonian(Z0, full[0])
        if bound is not None:
            assert float(jnp.max(jnp.abs(h))) < bound
        else:
            assert float(jnp.max(jnp.abs(h))) > 1e-3  # a nonzero F does work
    model = _hnn_force(False)
    a1, a2 = jnp.concatenate([ARGS, U[0]]), jnp.concatenate([ARGS, U[1]])
    y = model.encode(Z0, a1)
    f1, f2 = model.internal_field(0.0, y, a1), model.internal_field(0.0, y, a2)
    np.testing.assert_array_equal(f1[:2], f2[:2])  # dq/dt = dH/dp: no u
    q, p = y[:2], y[2:]
    np.testing.assert_allclose(
        f1[2:] - f2[2:], model.force_term(q, p, a1) - model.force_term(q, p, a2), rtol=1e-12
    )
    # dH/dt along the field is the power of F: qdot . F(q, p, u)
    grad_h = jax.grad(lambda y_: model.hamiltonian_part(y_[:2], y_[2:], a1))(y)
    np.testing.assert_allclose(grad_h @ f1, f1[:2] @ model.force_term(q, p, a1), rtol=1e-10)
    np.testing.assert_array_equal(model.vector_field(0.0, Z0, a1)[:2], Z0[2:])


def _zero_force(model):
    last = lambda m: (m.force.weights[-1], m.force.biases[-1])
    return eqx.tree_at(last, model, tuple(jnp.zeros_like(x) for x in last(model)))


def test_hnn_force_paper_is_the_reference_codes_field():
    """The paper's code's controlled HNN: dq/dt the standardised velocity whatever the networks
    learn, dqdot/dt minus the gradient of H in the standardised position (central differences
    here) plus F; without a standardisation and with F = 0, H = |qdot|^2 / 2 + V(q) is
    conserved (M = I)."""
    st = models.Standardisation(
        q_loc=(0.1, 0.2), q_scale=(2.0, 0.5), v_loc=(0.3, -0.1), v_scale=(1.5, 4.0),
        u_loc=(0.0, 0.0), u_scale=(1.0, 1.0), rate_loc=(0.0,) * 4, rate_scale=(1.0,) * 4,
    )  # fmt: skip
    scene = Scene(dof=2, angular=(False, False), n_args=1, n_controls=2, standardisation=st)
    model = _make("hnn_force_paper", scene)
    spec = models.spec("hnn_force_paper")
    assert spec.forced and spec.controls and not spec.second_order and spec.structure is None
    a = jnp.concatenate([ARGS, U[0]])
    f = model.vector_field(0.0, Z0, a)
    q_loc, q_scale = jnp.array(st.q_loc), jnp.array(st.q_scale)
    np.testing.assert_allclose(f[:2], (Z0[2:] - jnp.array(st.v_loc)) / jnp.array(st.v_scale))
    h_s = lambda qs: model.potential_energy(qs * q_scale + q_loc, a)
    qs0, eps = (Z0[:2] - q_loc) / q_scale, 1e-5
    fd = jnp.array([(h_s(qs0 + eps * e) - h_s(qs0 - eps * e)) / (2 * eps) for e in jnp.eye(2)])
    force = model.force(model.features(Z0[:2], Z0[2:], a))
    np.testing.assert_allclose(f[2:], -fd + force, rtol=1e-7, atol=1e-9)
    assert float(jnp.max(jnp.abs(force))) > 1e-3  # F enters
    plain = _zero_force(_make("hnn_force_paper"))
    ts, u = jnp.linspace(0.0, 2.0, 11), jr.normal(jr.PRNGKey(5), (10, 2))
    zs = rollout(plain, Z0, ts, ARGS, Integrator("rk4", 20), controls=u)
    full = jnp.concatenate([jnp.broadcast_to(ARGS, (10, 1)), u], axis=1)
    energy = jax.vmap(lambda z, a_: 0.5 * z[2:] @ z[2:] + plain.potential_energy(z[:2], a_))
    h = energy(zs[1:], full) - energy(Z0[None], full[:1])[0]
    assert float(jnp.max(jnp.abs(h))) < 1e-8


def test_hnn_force_floor_bounds_the_inverse_mass_spectrum_in_h_and_the_field():
    """``inverse_mass_floor``: with the factor's network driven to L ~ 0, M^-1 = floor I, and
    H's kinetic term and the field read the same M^-1 (H against 1/2 p^T M^-1 p + V, and
    dq/dt = M^-1 p against the gradient of H)."""
    a = jnp.concatenate([ARGS, U[0]])
    for floor in (1e-4, 0.1, 2.0):
        model = models.make(
            "hnn_force", CTRL, key=jr.PRNGKey(0), width=8, dtype="float64",
            inverse_mass_floor=floor,
        )  # fmt: skip
        inv = model.hamiltonian_part.inverse_mass
        last = lambda m: (m.net.weights[-1], m.net.biases[-1])
        rows, cols = np.tril_indices(2)
        bias = jnp.asarray(np.where(rows == cols, -40.0, 0.0))  # softplus(-40) ~ 0 on L's diagonal
        flat = eqx.tree_at(last, inv, (jnp.zeros_like(last(inv)[0]), bias))
        model = eqx.tree_at(lambda m: m.hamiltonian_part.inverse_mass, model, flat)
        q, p = Z0[:2], jnp.array([0.7, -1.1])
        minv = model.hamiltonian_part.inverse_mass.matrix(q, a)
        np.testing.assert_allclose(minv, floor * np.eye(2), rtol=1e-9, atol=1e-15)
        h = model.hamiltonian_part(q, p, a) - model.hamiltonian_part.potential_energy(q, a)
        np.testing.assert_allclose(h, 0.5 * floor * (p @ p), rtol=1e-9)
        qdot = jax.grad(model.hamiltonian_part, argnums=1)(q, p, a)
        np.testing.assert_allclose(qdot, floor * p, rtol=1e-9)
    default = _make("hnn_force").hamiltonian_part.inverse_mass.jitter
    plain = Scene(dof=2, angular=(True, False), n_args=1)
    assert default == _make("hnn_so", scene=plain).hamiltonian_part.inverse_mass.jitter == 1e-4
    for bad in (0, -0.1, True, "0.1"):
        with pytest.raises(ValueError, match="inverse_mass_floor must be a number > 0"):
            models.make("hnn_force", CTRL, key=jr.PRNGKey(0), inverse_mass_floor=bad)


def test_gradients_reach_the_force_network_through_a_controlled_rollout():
    model = _make("hnn_force")
    z0s, args = jnp.stack([Z0, -Z0]), jnp.stack([ARGS, ARGS])
    controls = jnp.stack([U, -U])

    @eqx.filter_jit
    def loss(m, c):
        zs = rollout_batch(m, z0s, TS, args, Integrator("euler_so", substeps=2), controls=c)
        return jnp.sum(zs**2)

    grads, du = eqx.filter_grad(lambda mc: loss(*mc))((model, controls))  # one compilation
    leaves = jax.tree_util.tree_leaves(eqx.filter(grads.force, eqx.is_inexact_array))
    assert all(bool(jnp.all(jnp.isfinite(g))) for g in leaves)
    assert sum(float(jnp.sum(jnp.abs(g))) for g in leaves) > 0
    assert bool(jnp.all(jnp.sum(jnp.abs(du), axis=-1) > 0))  # every u_i moves the states


def test_float32_controlled_rollout_keeps_its_dtype_and_traces_once():
    model = models.make("node_so", CTRL, key=jr.PRNGKey(0), width=8)  # float32
    traces = []

    @eqx.filter_jit
    def run(m, u):
        traces.append(1)
        return rollout(m, Z0.astype(jnp.float32), TS, ARGS, Integrator("euler_so", 2), controls=u)

    first, second = run(model, U), run(model, 2 * U)  # float64 controls are cast
    assert first.dtype == jnp.float32 and len(traces) == 1
    assert not np.allclose(first, second)
