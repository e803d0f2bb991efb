"""The HNN seed's systems against closed forms and second derivations: the
mass-spring's exact solution and Hamiltonian, the pendulum's Hamiltonian, its small-angle
period and the chain pendulum's field, two-body circular orbits in closed form, and energy and
angular momentum kept to 1e-9 over ten orbits of the seed's near-circular draws; the three-body
energy by hand, Lagrange's equilateral solution, and energy and both momenta kept to 1e-9 over
the seed's span."""

from __future__ import annotations

import jax
import numpy as np
import pytest

import systems
from systems._three_body import lagrange_orbit
from systems._two_body import circular_orbit

KEY = jax.random.PRNGKey(3)


def _vmapped(fn):
    return jax.jit(jax.vmap(fn))


def test_mass_spring_exact_solution_and_seed_hamiltonian():
    s = systems.make("mass_spring")
    z0 = np.asarray(s.sample_initial(KEY, 6))
    ts = np.linspace(0.0, 3.0, 30)  # the seed's grid
    zs = np.asarray(s.simulate_batch(z0, ts))
    q0, v0 = z0[:, :1], z0[:, 1:]
    exact_q = q0 * np.cos(2 * ts) + v0 / 2 * np.sin(2 * ts)  # omega = sqrt(k / m) = 2
    np.testing.assert_allclose(zs[..., 0], exact_q, atol=1e-9)
    p = np.asarray(_vmapped(s.momentum)(z0))[:, 0]
    h = np.asarray(_vmapped(s.energy)(z0))
    np.testing.assert_allclose(h, z0[:, 0] ** 2 + p**2, rtol=1e-12)  # the seed's H = q^2 + p^2
    assert np.all((h >= 0.1**2 - 1e-12) & (h <= 1.0 + 1e-12))  # radii in [0.1, 1]


def test_pendulum_seed_hamiltonian_and_chain_field():
    s = systems.make("pendulum")
    z0 = np.asarray(s.sample_initial(KEY, 6))
    p = np.asarray(_vmapped(s.momentum)(z0))[:, 0]
    h = np.asarray(_vmapped(s.energy)(z0))
    np.testing.assert_allclose(h, 3 * (1 - np.cos(z0[:, 0])) + p**2, rtol=1e-12)
    r = np.hypot(z0[:, 0], p)
    assert np.all((r >= 1.3 - 1e-12) & (r <= 2.3 + 1e-12))
    # a second derivation of the field: the chain pendulum with one link of the same m, l, g
    chain = systems.make("chain_pendulum", k=1, masses=(0.5,), lengths=(1.0,), g=6.0)
    f = _vmapped(lambda z: s.vector_field(0.0, z, None))(z0)
    g = _vmapped(lambda z: chain.vector_field(0.0, z, None))(z0)
    np.testing.assert_allclose(f, g, rtol=1e-12, atol=1e-12)


def test_pendulum_small_angle_period():
    s = systems.make("pendulum")
    ts = np.linspace(0.0, 5.0, 101)
    z0 = np.array([[1e-3, 0.0]])  # the nonlinear phase drift: ~ 1e-3 x 5 sqrt(6) 1e-6 / 16
    zs = np.asarray(s.simulate_batch(z0, ts))
    np.testing.assert_allclose(zs[0, :, 0], 1e-3 * np.cos(np.sqrt(6.0) * ts), atol=2e-9)


def test_two_body_circular_orbit_closed_form():
    s = systems.make("two_body")
    r = 0.9
    period = 2 * np.pi / np.sqrt(1.0 / (4 * r**3))
    ts = np.linspace(0.0, period, 50)
    exact = circular_orbit(r, ts)
    zs = np.asarray(s.simulate_batch(exact[:1], ts))[0]
    np.testing.assert_allclose(zs, exact, atol=1e-9)


def test_two_body_seed_orbits_conserve_energy_and_angular_momentum_over_ten_orbits():
    s = systems.make("two_body")
    z0 = np.asarray(s.sample_initial(KEY, 4))
    # centre of mass at the origin and at rest
    np.testing.assert_allclose(z0[:, :2] + z0[:, 2:4], 0.0, atol=1e-15)
    np.testing.assert_allclose(z0[:, 4:6] + z0[:, 6:], 0.0, atol=1e-15)
    r = np.linalg.norm(z0[:, :2], axis=-1)
    ten_orbits = 10 * 4 * np.pi * r.max() ** 1.5  # the circular period is 4 pi r^1.5
    ts = np.linspace(0.0, ten_orbits, 201)
    zs = np.asarray(s.simulate_batch(z0, ts))
    flat = zs.reshape(-1, 8)
    e = np.asarray(_vmapped(s.energy)(flat)).reshape(zs.shape[:2])
    lz = np.asarray(_vmapped(s.angular_momentum)(flat)).reshape(zs.shape[:2])
    assert np.max(np.abs(e - e[:, :1]) / np.abs(e[:, :1])) < 1e-9
    assert np.max(np.abs(lz - lz[:, :1]) / np.abs(lz[:, :1])) < 1e-9
    # the orbits are near-circular (the seed's 5% speed noise), not plunging
    dist = np.linalg.norm(zs[..., :2] - zs[..., 2:4], axis=-1)
    assert dist.min() > 0.5 and dist.max() < 2 * 3 * r.max()


@pytest.mark.parametrize(
    ("name", "params", "match"),
    [
        ("mass_spring", {"mass": 0.0}, "mass"),
        ("pendulum", {"r_min": 2.0, "r_max": 1.0}, "r_min must be <= r_max"),
        ("two_body", {"masses": (1.0,)}, "masses"),
        ("two_body", {"k": 2}, "unknown parameter"),
        ("three_body", {"masses": (1.0, 1.0)}, "masses"),
        ("three_body", {"r_min": 1.5}, "r_min must be <= r_max"),
    ],
)
def test_bad_params_of_the_seed_systems_raise(name, params, match):
    with pytest.raises(ValueError, match=match):
        systems.make(name, **params)


# ------------------------------------------------------------------------------ three-body
def _three_body_invariants(s, zs):
    flat = zs.reshape(-1, 12)
    e = np.asarray(_vmapped(s.energy)(flat)).reshape(zs.shape[:2])
    lz = np.asarray(_vmapped(s.angular_momentum)(flat)).reshape(zs.shape[:2])
    p = np.asarray(_vmapped(s.linear_momentum)(flat)).reshape(*zs.shape[:2], 2)
    return e, lz, p


def test_three_body_energy_is_kinetic_plus_pairwise_gravity():
    s = systems.make("three_body", masses=(1.0, 2.0, 0.5), gravity=1.5)
    z = np.asarray(s.sample_initial(KEY, 5))
    x, v = z[:, :6].reshape(-1, 3, 2), z[:, 6:].reshape(-1, 3, 2)
    m = np.array([1.0, 2.0, 0.5])
    t = 0.5 * np.sum(m * np.sum(v**2, -1), -1)
    u = sum(
        -1.5 * m[i] * m[j] / np.linalg.norm(x[:, i] - x[:, j], axis=-1)
        for i, j in ((0, 1), (0, 2), (1, 2))
    )
    np.testing.assert_allclose(np.asarray(_vmapped(s.energy)(z)), t + u, rtol=1e-13)


def test_three_body_lagrange_equilateral_orbit_closed_form():
    s = systems.make("three_body")
    r = 1.0
    period = 2 * np.pi / np.sqrt(3.0 / (np.sqrt(3.0) * r) ** 3)  # w^2 = G M / s^3
    ts = np.linspace(0.0, period, 50)
    exact = lagrange_orbit(r, ts)
    zs = np.asarray(s.simulate_batch(exact[:1], ts))[0]
    # Lagrange's equal-mass triangle is unstable: errors grow, but not to 1e-8 in one turn
    np.testing.assert_allclose(zs, exact, atol=1e-8)


def test_three_body_seed_draw_without_noise_is_lagrange_rigid_rotation():
    s = systems.make("three_body", orbit_noise=0.0)
    z0 = np.asarray(s.sample_initial(KEY, 3))
    x0 = z0[:, :6].reshape(-1, 3, 2)
    r = np.linalg.norm(x0, axis=-1)
    assert np.all((r >= 0.9 - 1e-12) & (r <= 1.2 + 1e-12))
    np.testing.assert_allclose(r, r[:, :1] * np.ones(3), rtol=1e-13)
    ts = np.linspace(0.0, 5.0, 20)  # the seed's span and grid
    zs = np.asarray(s.simulate_batch(z0, ts))
    for zi, ri in zip(zs, r[:, 0], strict=True):
        # the closed form, rotated to the drawn start
        angle = np.arctan2(zi[0, 1], zi[0, 0])
        c, sn = np.cos(angle), np.sin(angle)
        exact = lagrange_orbit(ri, ts).reshape(len(ts), 6, 2)
        exact = np.stack([c * exact[..., 0] - sn * exact[..., 1],
                          sn * exact[..., 0] + c * exact[..., 1]], -1)  # fmt: skip
        np.testing.assert_allclose(zi, exact.reshape(len(ts), 12), atol=1e-8)


def test_three_body_seed_orbits_conserve_energy_and_momenta():
    s = systems.make("three_body")
    z0 = np.asarray(s.sample_initial(KEY, 16))
    # speeds within the seed's 20% of the circular orbit's, per component
    x0, v0 = z0[:, :6].reshape(-1, 3, 2), z0[:, 6:].reshape(-1, 3, 2)
    r = np.linalg.norm(x0[:, :1], axis=-1, keepdims=True)
    circ = 3**-0.25 * r**-0.5 * np.stack([-x0[..., 1], x0[..., 0]], -1) / r
    scale = v0 / circ
    assert np.all((scale > 0.8 - 1e-12) & (scale < 1.2 + 1e-12)) and scale.std() > 0.05
    ts = np.linspace(0.0, 5.0, 20)
    zs = np.asarray(s.simulate_batch(z0, ts))
    e, lz, p = _three_body_invariants(s, zs)
    assert np.max(np.abs(e - e[:, :1]) / np.abs(e[:, :1])) < 1e-9
    assert np.max(np.abs(lz - lz[:, :1])) < 1e-9 * np.max(np.abs(lz))
    assert np.max(np.abs(p - p[:, :1])) < 1e-9


def test_three_body_refuses_coincident_bodies():
    s = systems.make("three_body")
    z = np.asarray(lagrange_orbit(1.0, np.zeros(1)))
    z[0, 2:4] = z[0, 0:2]
    with pytest.raises(ValueError, match="bodies 1 and 2 coincide"):
        s.simulate_batch(z, np.linspace(0.0, 1.0, 3))
