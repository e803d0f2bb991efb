"""Integrators and rollout against closed forms: harmonic oscillator z = (q, v), q'' = -w^2 q.

Exact flow: q(t) = q0 cos(wt) + v0/w sin(wt), v(t) = -q0 w sin(wt) + v0 cos(wt).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

jax.config.update("jax_enable_x64", True)

from models._base import AbstractContinuousModel, AbstractDiscreteModel  # noqa: E402
from models._integrators import (  # noqa: E402
    Integrator,
    count_evaluations,
    rollout,
    rollout_batch,
)
from models._scene import Scene  # noqa: E402

W = 1.3
Z0 = jnp.array([0.7, -0.4])
SCENE = Scene(dof=1, angular=(False,), n_args=1)


class Oscillator(AbstractContinuousModel):
    """Stand-in second-order model: q'' = s (-w^2 q - gamma v), s = args[0] (1 when None)."""

    w: float = W
    gamma: float = 0.0
    scene: Scene = eqx.field(static=True, default=SCENE)
    dtype: str = eqx.field(static=True, default="float64")
    second_order = True

    def acceleration(self, q, v, args):
        scale = 1.0 if args is None else args[0]
        return scale * (-(self.w**2) * q - self.gamma * v)

    def vector_field(self, t, z, args):
        q, v = z[:1], z[1:]
        return jnp.concatenate([v, self.acceleration(q, v, args)])


class FirstOrder(AbstractContinuousModel):
    scene: Scene = eqx.field(static=True, default=SCENE)
    dtype: str = eqx.field(static=True, default="float64")
    second_order = False

    def vector_field(self, t, z, args):
        return -z


class OscillatorFlow(AbstractDiscreteModel):
    """Stand-in discrete model: the exact oscillator flow over dt."""

    w: float = W
    scene: Scene = eqx.field(static=True, default=SCENE)
    dtype: str = eqx.field(static=True, default="float64")

    def step(self, z, dt, args):
        c, s = jnp.cos(self.w * dt), jnp.sin(self.w * dt)
        q, v = z[0], z[1]
        return jnp.stack([q * c + v / self.w * s, -q * self.w * s + v * c])


def exact(ts, z0=Z0, w=W):
    q0, v0 = z0
    ts = np.asarray(ts)
    q = q0 * np.cos(w * ts) + v0 / w * np.sin(w * ts)
    v = -q0 * w * np.sin(w * ts) + v0 * np.cos(w * ts)
    return np.stack([q, v], axis=-1)


@pytest.fixture(scope="module")
def osc():
    return Oscillator(w=W)


def test_standins_are_models(osc):
    assert isinstance(osc, AbstractContinuousModel)
    assert isinstance(OscillatorFlow(w=W), AbstractDiscreteModel)


@pytest.mark.parametrize(
    ("method", "order", "dts"),
    [
        ("euler", 1, [0.04, 0.02, 0.01, 0.005]),
        ("rk4", 4, [0.2, 0.1, 0.05, 0.025]),
        ("rk4_38", 4, [0.2, 0.1, 0.05, 0.025]),
        ("leapfrog", 2, [0.1, 0.05, 0.025, 0.0125]),
        ("leapfrog_explicit", 2, [0.1, 0.05, 0.025, 0.0125]),
        ("implicit_midpoint", 2, [0.1, 0.05, 0.025, 0.0125]),
    ],
)
def test_convergence_order(osc, method, order, dts):
    t1 = 2.0
    ts = jnp.array([0.0, 0.5, t1])  # non-uniform on purpose
    errors = []
    for dt in dts:
        # the 0.5 s interval gets 0.5/dt substeps; the 1.5 s one 3x that: substeps per interval
        # are equal, so use a fine uniform grid instead to keep h = dt everywhere.
        n = int(round(t1 / dt))
        grid = jnp.linspace(0.0, t1, n + 1)
        zs = rollout(osc, Z0, grid, None, Integrator(method))
        errors.append(np.max(np.abs(np.asarray(zs[-1]) - exact([t1])[0])))
    slope = np.polyfit(np.log(dts), np.log(errors), 1)[0]
    assert abs(slope - order) < 0.25, (method, slope, errors)
    del ts


def test_substeps_equal_refined_grid(osc):
    ts = jnp.array([0.0, 0.3, 0.5, 1.1])  # non-uniform
    fine = jnp.sort(jnp.concatenate([ts, 0.5 * (ts[1:] + ts[:-1])]))
    for method in ("euler", "rk4_38", "leapfrog", "implicit_midpoint"):
        coarse = rollout(osc, Z0, ts, None, Integrator(method, substeps=2))
        refined = rollout(osc, Z0, fine, None, Integrator(method))
        np.testing.assert_allclose(coarse, refined[::2], rtol=0, atol=1e-13)
        assert not np.allclose(coarse, rollout(osc, Z0, ts, None, Integrator(method)), atol=1e-6)


def test_fixed_step_hits_saved_times(osc):
    ts = jnp.array([0.0, 0.1, 0.35, 0.4, 1.0])
    zs = rollout(osc, Z0, ts, None, Integrator("rk4", substeps=20))
    np.testing.assert_allclose(zs, exact(ts), atol=1e-9)
    assert zs.shape == (5, 2) and zs.dtype == jnp.float64


def test_adaptive_out_of_steps_is_recorded_not_raised(osc):
    # a solve that cannot finish returns non-finite states from where it stopped (the metrics
    # count them as failed predictions) instead of raising inside a sweep
    ts = jnp.linspace(0.0, 10.0, 21)
    zs = rollout(osc, Z0, ts, None, Integrator("adaptive", rtol=1e-12, atol=1e-14, max_steps=4))
    finite = np.isfinite(np.asarray(zs)).all(axis=1)
    assert finite[0] and not finite[-1]
    np.testing.assert_allclose(zs[0], Z0)


@pytest.mark.parametrize("solver", ["tsit5", "dopri5", "dopri8"])
def test_adaptive_meets_tolerance(osc, solver):
    ts = jnp.linspace(0.0, 10.0, 21)
    tight, stats_tight = rollout(
        osc,
        Z0,
        ts,
        None,
        Integrator("adaptive", rtol=1e-10, atol=1e-12, solver=solver),
        return_stats=True,
    )
    loose, stats_loose = rollout(
        osc,
        Z0,
        ts,
        None,
        Integrator("adaptive", rtol=1e-4, atol=1e-6, solver=solver),
        return_stats=True,
    )
    err_tight = np.max(np.abs(np.asarray(tight) - exact(ts)))
    err_loose = np.max(np.abs(np.asarray(loose) - exact(ts)))
    # global error over ~2 periods stays within a small multiple of the local tolerance
    assert err_tight < 1e-8
    assert err_loose < 1e-2
    assert err_tight < err_loose
    assert int(stats_tight["nfe"]) > int(stats_loose["nfe"]) > 0


def _counting(model):
    calls = []

    # Oscillator.vector_field calls acceleration exactly once, so this counts both routes.
    class Counting(type(model)):
        def acceleration(self, q, v, args):
            jax.debug.callback(lambda: calls.append(1))
            return super().acceleration(q, v, args)

    return Counting(w=model.w), calls


@pytest.mark.parametrize(
    "integrator",
    [
        Integrator("euler", substeps=3),
        Integrator("rk4"),
        Integrator("rk4_38", substeps=2),
        Integrator("leapfrog_explicit", substeps=3),
        Integrator("leapfrog", implicit_iterations=2),
        Integrator("implicit_midpoint", implicit_iterations=3),
        Integrator("adaptive", rtol=1e-7, atol=1e-9),
    ],
    ids=lambda i: i.method,
)
def test_count_evaluations_matches_calls(osc, integrator):
    model, calls = _counting(osc)
    ts = jnp.linspace(0.0, 2.0, 6)
    zs, stats = rollout(model, Z0, ts, None, integrator, return_stats=True)
    jax.block_until_ready(zs)
    jax.effects_barrier()
    if integrator.method == "adaptive":
        # diffrax's step counts give nfe up to the FSAL stage redone after some rejections
        assert (
            int(stats["nfe"]) <= len(calls) <= int(stats["nfe"]) + int(stats["num_rejected_steps"])
        )
        assert int(stats["num_steps"]) > 5
    else:
        assert len(calls) == int(stats["nfe"]) == count_evaluations(model, ts, integrator)


def test_leapfrog_bounded_energy_euler_grows(osc):
    h = 0.1
    ts = jnp.arange(10_001) * h
    zs = np.asarray(rollout(osc, Z0, ts, None, Integrator("leapfrog")))

    def energy(z):
        return 0.5 * (z[..., 1] ** 2 + W**2 * z[..., 0] ** 2)

    e0 = energy(np.asarray(Z0))
    rel = (energy(zs) - e0) / e0
    # Stormer-Verlet conserves a modified energy: the error oscillates at O((h w)^2), no drift.
    assert np.max(np.abs(rel)) < (h * W) ** 2
    assert abs(rel[-1000:].mean() - rel[:1000].mean()) < 0.02 * np.max(np.abs(rel))
    # explicit Euler multiplies the energy by (1 + (h w)^2) every step
    ze = np.asarray(rollout(osc, Z0, ts[:1001], None, Integrator("euler")))
    np.testing.assert_allclose(energy(ze[-1]) / e0, (1 + (h * W) ** 2) ** 1000, rtol=1e-9)


@pytest.mark.parametrize(
    ("method", "iterations", "order"),
    [
        ("leapfrog_explicit", 0, 1),
        ("leapfrog", 0, 2),
        ("leapfrog", 3, 2),
        ("implicit_midpoint", 0, 2),
    ],
)
def test_leapfrog_order_velocity_dependent(method, iterations, order):
    # explicit variant: first order once a depends on v; implicit kick: second order again
    damped = Oscillator(w=W, gamma=0.5)
    t1 = 2.0
    ref = rollout(damped, Z0, jnp.array([0.0, t1]), None, Integrator("rk4", substeps=2000))[-1]
    dts = [0.1, 0.05, 0.025]
    errors = []
    for dt in dts:
        n = int(round(t1 / dt))
        zs = rollout(
            damped,
            Z0,
            jnp.array([0.0, t1]),
            None,
            Integrator(method, substeps=n, implicit_iterations=iterations),
        )
        errors.append(float(jnp.max(jnp.abs(zs[-1] - ref))))
    slope = np.polyfit(np.log(dts), np.log(errors), 1)[0]
    assert abs(slope - order) < 0.3, (method, iterations, slope, errors)


def test_damped_leapfrog_decays(osc):
    damped = Oscillator(w=W, gamma=0.3)
    ts = jnp.linspace(0.0, 10.0, 201)
    zs = np.asarray(rollout(damped, Z0, ts, None, Integrator("leapfrog", substeps=4)))
    ref = np.asarray(rollout(damped, Z0, ts, None, Integrator("adaptive", rtol=1e-10, atol=1e-12)))
    # second order with the implicit kick: close to the adaptive reference at h = 0.0125
    assert np.max(np.abs(zs - ref)) < 1e-4
    e = 0.5 * (zs[:, 1] ** 2 + W**2 * zs[:, 0] ** 2)
    assert e[-1] < 0.1 * e[0]


def test_discrete_model_ignores_method():
    flow = OscillatorFlow(w=W)
    ts = jnp.array([0.0, 0.2, 0.3, 0.9, 1.0])
    for integrator in (Integrator("euler"), Integrator("adaptive"), Integrator("rk4", substeps=3)):
        zs = rollout(flow, Z0, ts, None, integrator)
        np.testing.assert_allclose(zs, exact(ts), atol=1e-12)
    assert count_evaluations(flow, ts, Integrator("rk4", substeps=3)) == 12


def test_rollout_batch_equals_loop():
    model = Oscillator(w=W, gamma=0.1)
    z0s = jnp.array([[0.7, -0.4], [0.1, 0.2], [-1.0, 0.5]])
    args = jnp.array([[1.0], [2.0], [0.5]])  # scales the field per trajectory
    ts = jnp.linspace(0.0, 1.0, 7)
    for integrator in (Integrator("rk4_38"), Integrator("leapfrog", substeps=2)):
        batch = rollout_batch(model, z0s, ts, args, integrator)
        loop = jnp.stack(
            [rollout(model, z, ts, a, integrator) for z, a in zip(z0s, args, strict=True)]
        )
        np.testing.assert_allclose(batch, loop, rtol=1e-13, atol=1e-14)
        assert batch.shape == (3, 7, 2)
    # args actually change the trajectory
    assert not np.allclose(batch[1], rollout(model, z0s[1], ts, None, integrator))


def test_float32_state_stays_float32(osc):
    zs = rollout(osc, Z0.astype(jnp.float32), jnp.linspace(0.0, 1.0, 4), None, Integrator("rk4"))
    assert zs.dtype == jnp.float32


@pytest.mark.parametrize(
    "kwargs",
    [
        {"method": "rk5"},
        {"method": "Euler"},
        {"solver": "heun"},
        {"substeps": 0},
        {"substeps": 1.5},
        {"rtol": -1.0},
        {"atol": 0.0},
        {"max_steps": 0},
        {"implicit_iterations": -1},
        {"method": "gauss2"},
        {"implicit_solver": "broyden"},
        {"implicit_max_steps": 0},
    ],
)
def test_bad_integrator(kwargs):
    with pytest.raises(ValueError, match="allowed|must be"):
        Integrator(**kwargs)


def test_bad_uses(osc):
    with pytest.raises(ValueError, match="second-order"):
        rollout(FirstOrder(), Z0, jnp.linspace(0, 1, 3), None, Integrator("leapfrog"))
    with pytest.raises(ValueError, match="second-order"):
        rollout(FirstOrder(), Z0, jnp.linspace(0, 1, 3), None, Integrator("leapfrog_explicit"))
    for method in ("adaptive", "leapfrog", "implicit_midpoint"):
        with pytest.raises(ValueError, match="return_stats"):
            count_evaluations(osc, jnp.linspace(0, 1, 3), Integrator(method))
    with pytest.raises(ValueError, match="Integrator"):
        rollout(osc, Z0, jnp.linspace(0, 1, 3), None, "rk4")
    with pytest.raises(ValueError, match="AbstractContinuousModel"):
        rollout(eqx.nn.Linear(2, 2, key=jax.random.key(0)), Z0, jnp.linspace(0, 1, 3), None)
