"""Physics of the App. D.2 systems (gyroscope, rotor, magnet pendulum): conservation laws and a
second derivation of each, independent of the Euler-Lagrange machinery."""

from __future__ import annotations

import diffrax
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

import systems
from systems._magnet import bob_direction, dipole_energy
from systems._rigid import (
    GYRO_COM,
    GYRO_SECOND_MOMENTS,
    ROTOR_SECOND_MOMENTS,
    body_angular_velocity,
    euler_path,
    rotation_matrix,
)

G = 9.81
TS = np.linspace(0.0, 4.0, 41)


@pytest.fixture(scope="module", autouse=True)
def _x64():
    systems.enable_x64()


def _states(system, n=4, seed=0):
    return np.asarray(system.sample_initial(jax.random.PRNGKey(seed), n))


def _along(fn, zs):
    return np.asarray(jax.jit(jax.vmap(jax.vmap(fn)))(jnp.asarray(zs)))


def _constant(x, rtol, atol):
    """x (n, T, ...) stays at its t = 0 value."""
    x = np.asarray(x)
    np.testing.assert_allclose(x, np.broadcast_to(x[:, :1], x.shape), rtol=rtol, atol=atol)


def _hat(w):
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def _vee(a):
    return np.array([a[2, 1], a[0, 2], a[1, 0]])


# --------------------------------------------------------------------------- kinematics
def test_euler_kinematics_match_scipy_and_the_rotation_derivative():
    rng = np.random.default_rng(0)
    for _ in range(5):
        q, qd = rng.uniform(-3, 3, 3), rng.normal(size=3)
        r = np.asarray(rotation_matrix(jnp.asarray(q)))
        np.testing.assert_allclose(r, Rotation.from_euler("ZXZ", q).as_matrix(), atol=1e-14)
        _, rdot = jax.jvp(rotation_matrix, (jnp.asarray(q),), (jnp.asarray(qd),))
        w = np.asarray(body_angular_velocity(jnp.asarray(q), jnp.asarray(qd)))
        np.testing.assert_allclose(_vee(r.T @ np.asarray(rdot)), w, atol=1e-13)


@pytest.mark.parametrize("name", ["gyroscope", "rotor"])
def test_kinetic_energy_is_the_references_point_frame_form(name):
    """The reference's T = 1/2 m |v_com|^2 + 1/2 sum_i m s_i |d e_i/dt|^2 (s the second moments,
    e_i the body axes) equals ours, whose inertia is I_j = m (sum_i s_i - s_j)."""
    s = systems.make(name)
    z = _states(s, 6)
    m = s.mass
    if name == "gyroscope":
        moments = 100.0 * np.asarray(GYRO_SECOND_MOMENTS)
        c = np.asarray(GYRO_COM)
    else:
        moments, c = np.asarray(ROTOR_SECOND_MOMENTS), np.zeros(3)
    for zi in z:
        q, qd = zi[: s.dof], zi[s.dof :]
        ang, rates = (q, qd) if name == "gyroscope" else (q[3:], qd[3:])
        _, rdot = jax.jvp(rotation_matrix, (jnp.asarray(ang),), (jnp.asarray(rates),))
        rdot = np.asarray(rdot)
        v_com = rdot @ c if name == "gyroscope" else qd[:3]
        ref = 0.5 * m * v_com @ v_com + 0.5 * m * np.sum(moments * np.sum(rdot**2, axis=0))
        ours = float(s.kinetic_energy(jnp.asarray(q), jnp.asarray(qd)))
        np.testing.assert_allclose(ours, ref, rtol=1e-12)


def test_gyroscope_moments_are_the_meshs():
    g = systems.make("gyroscope")
    s = 100.0 * np.asarray(GYRO_SECOND_MOMENTS)
    np.testing.assert_allclose(g.inertia, 0.1 * np.array([s[1] + s[2], s[0] + s[2], s[0] + s[1]]))
    assert g.inertia[0] == g.inertia[1] < g.inertia[2]  # a symmetric, disk-like top
    r = systems.make("rotor")
    assert len(set(r.inertia)) == 3  # asymmetric


# ------------------------------------------------------------------------ conservation
def test_gyroscope_conserves_energy_and_both_axial_momenta():
    s = systems.make("gyroscope")
    zs = np.asarray(s.simulate_batch(_states(s), TS))
    e = _along(s.energy, zs)
    p = _along(s.momentum, zs)  # p_alpha: about the vertical; p_gamma: about the symmetry axis
    _constant(e, 1e-9, 1e-11)
    _constant(p[..., 0], 1e-8, 1e-11)
    _constant(p[..., 2], 1e-8, 1e-11)
    # p_alpha is the vertical component of the spatial angular momentum about the pivot
    i_p = np.diag(s.inertia) + s.mass * (np.dot(GYRO_COM, GYRO_COM) * np.eye(3))
    i_p -= s.mass * np.outer(GYRO_COM, GYRO_COM)
    z = zs[0, 7]
    w = np.asarray(body_angular_velocity(z[:3], z[3:]))
    l_space = np.asarray(rotation_matrix(z[:3])) @ (i_p @ w)
    np.testing.assert_allclose(l_space[2], p[0, 7, 0], rtol=1e-12)


def test_rotor_conserves_energy_and_linear_and_angular_momentum():
    s = systems.make("rotor")
    zs = np.asarray(s.simulate_batch(_states(s), TS))
    e = _along(s.energy, zs)
    lin = s.mass * zs[..., 6:9]
    ang = _along(s.angular_momentum, zs)
    _constant(e, 1e-9, 1e-13)
    _constant(lin, 1e-9, 1e-13)
    _constant(ang, 1e-8, 1e-12)


def test_magnet_pendulum_conserves_energy():
    s = systems.make("magnet_pendulum")
    zs = np.asarray(s.simulate_batch(_states(s), TS))
    e = _along(s.energy, zs)
    # measured: 3.7e-9 J at most over 4 s, against m g l = 29 J
    _constant(e, 1e-8, 1e-8)


# ------------------------------------------------- a second derivation: Euler's equations
def _euler_equations(inertia, torque):
    """d/dt (R, omega) for I omega' = I omega x omega + torque(R), R' = R hat(omega)."""
    inertia = np.diag(inertia) if np.ndim(inertia) == 1 else np.asarray(inertia)

    def f(t, y):
        r, w = y[:9].reshape(3, 3), y[9:]
        dw = np.linalg.solve(inertia, np.cross(inertia @ w, w) + torque(r))
        return np.concatenate([(r @ _hat(w)).ravel(), dw])

    return f


def _compare_rotation(system, z0, ang, inertia, torque):
    """Our truth (the gyroscope's Euler-Lagrange solve, the rotor's frame) against R and omega
    integrated by scipy (DOP853) from the same start: the rotation matrices and body angular
    velocities along the trajectory."""
    zs = np.asarray(system.simulate(z0, TS))
    d = system.dof
    r0 = np.asarray(rotation_matrix(z0[ang]))
    w0 = np.asarray(body_angular_velocity(z0[ang], z0[d:][ang]))
    sol = solve_ivp(
        _euler_equations(inertia, torque),
        (TS[0], TS[-1]),
        np.concatenate([r0.ravel(), w0]),
        method="DOP853",
        t_eval=TS,
        rtol=1e-12,
        atol=1e-12,
    )
    r_ref = sol.y[:9].T.reshape(-1, 3, 3)
    w_ref = sol.y[9:].T
    r_ours = np.stack([np.asarray(rotation_matrix(z[ang])) for z in zs])
    w_ours = np.stack([np.asarray(body_angular_velocity(z[ang], z[d:][ang])) for z in zs])
    np.testing.assert_allclose(r_ours, r_ref, atol=1e-7)
    np.testing.assert_allclose(w_ours, w_ref, atol=1e-6 * np.abs(w_ref).max())
    return zs


def test_gyroscope_matches_eulers_equations_about_the_pivot():
    s = systems.make("gyroscope")
    c = np.asarray(GYRO_COM)
    i_p = np.diag(s.inertia) + s.mass * (c @ c * np.eye(3) - np.outer(c, c))

    def torque(r):  # c x (gravity in the body frame)
        return np.cross(c, r.T @ np.array([0.0, 0.0, -s.mass * G]))

    _compare_rotation(s, _states(s, 1, seed=3)[0], slice(0, 3), i_p, torque)


def test_rotor_matches_eulers_equations_through_a_close_pass_of_the_pole():
    """The draw (of 64) whose tilt comes nearest the Euler singularity in 4 s."""
    s = systems.make("rotor")
    z0s = _states(s, 64, seed=1)
    zs = np.asarray(s.simulate_batch(z0s, TS))
    closest = np.abs(np.sin(zs[..., 4])).min(axis=1)
    i = int(np.argmin(closest))
    assert closest[i] < 0.05
    out = _compare_rotation(s, z0s[i], slice(3, 6), np.asarray(s.inertia), lambda r: np.zeros(3))
    np.testing.assert_allclose(out[:, :3], z0s[i, :3] + TS[:, None] * z0s[i, 6:9], atol=1e-10)


def _chart_solve(system, z0s, ts, max_steps=100_000):
    """The Euler-Lagrange equations in the angles themselves (``vector_field``), Dopri8."""
    term = diffrax.ODETerm(system.vector_field)

    def one(z0):
        return diffrax.diffeqsolve(
            term,
            diffrax.Dopri8(),
            ts[0],
            ts[-1],
            None,
            z0,
            args=jnp.zeros(0),
            saveat=diffrax.SaveAt(ts=jnp.asarray(ts)),
            stepsize_controller=diffrax.PIDController(rtol=1e-11, atol=1e-11),
            max_steps=max_steps,
            throw=False,
        ).ys

    return np.asarray(jax.jit(jax.vmap(one))(jnp.asarray(z0s)))


def test_rotor_truth_is_the_euler_lagrange_solution_away_from_the_pole():
    """The ground truth integrates the frame (R, omega); where the tilt keeps clear of the pole
    it is the Euler-Lagrange solution in ZXZ angles, whose T the models' energies use."""
    s = systems.make("rotor")
    z0s = _states(s, 32, seed=4)
    zs = np.asarray(s.simulate_batch(z0s, TS))
    chart = _chart_solve(s, z0s, TS)
    clear = np.abs(np.sin(chart[..., 4])).min(axis=1) > 0.1
    assert clear.sum() >= 16
    np.testing.assert_allclose(zs[clear, 0], z0s[clear], atol=1e-12)
    np.testing.assert_allclose(zs[clear][..., :6], chart[clear][..., :6], atol=1e-8)
    np.testing.assert_allclose(zs[clear][..., 6:], chart[clear][..., 6:], atol=1e-7)


def _passing_the_pole(s, t_pass, miss):
    """A rotor start whose symmetry-breaking tilt comes within ``miss`` of the ZXZ pole at
    ``t_pass``: the frame at the pass (beta = ``miss``) integrated back to t = 0 with scipy."""
    r_pass = Rotation.from_euler("ZXZ", [0.3, miss, -1.1]).as_matrix()
    w_pass = np.array([1.3, -0.4, 2.1])
    back = solve_ivp(
        _euler_equations(np.asarray(s.inertia), lambda r: np.zeros(3)),
        (t_pass, 0.0),
        np.concatenate([r_pass.ravel(), w_pass]),
        method="DOP853",
        rtol=1e-13,
        atol=1e-13,
    )
    r0, w0 = back.y[:9, -1].reshape(1, 3, 3), back.y[9:, -1][None]
    angles, rates = euler_path(jnp.asarray(r0), jnp.asarray(w0), jnp.array([0.0, 1.0, 0.0]))
    com = np.array([0.1, -0.2, 0.05, 0.3, 0.0, -0.1])
    return np.concatenate([com[:3], np.asarray(angles[0]), com[3:], np.asarray(rates[0])])


def test_rotor_truth_passes_within_1e_9_of_the_pole_in_a_few_hundred_steps():
    """The Euler-Lagrange equations in the angles need rates ~ 1/sin(beta) there and run out of
    steps; the frame's equations do not see the pole. Energy and the spatial angular momentum
    hold at every sample, including those beside the pass."""
    s = systems.make("rotor")
    ts = np.linspace(0.0, 1.0, 21)  # the pass at 0.513 falls between samples
    z0 = _passing_the_pole(s, 0.513, 1e-9)
    zs, st = s.simulate(z0, ts, stats=True)
    zs = np.asarray(zs)
    assert np.isfinite(zs).all() and int(st["num_steps"]) < 1000
    assert np.abs(np.sin(zs[:, 4])).min() < 0.1  # the samples either side of the pass
    e = _along(s.energy, zs[None])
    ang = _along(s.angular_momentum, zs[None])
    _constant(e, 1e-9, 1e-13)
    _constant(ang, 1e-8, 1e-12)
    assert not np.isfinite(_chart_solve(s, z0[None], ts, max_steps=20_000)).all()


def test_euler_path_reads_back_the_angles_of_each_branch_and_turn():
    """Angles -> R, omega -> angles is the identity on either branch of sin(beta), any 2 pi
    turns of the start, and both are continuous from one sample to the next."""
    key = jax.random.PRNGKey(5)
    angles = jax.random.uniform(key, (50, 3), minval=-1.0, maxval=1.0) * jnp.array([3.0, 1.4, 3.0])
    angles = angles.at[:, 1].add(jnp.where(angles[:, 1] > 0, 0.1, -0.1))
    rates = jax.random.normal(jax.random.PRNGKey(6), (50, 3))
    path = jnp.cumsum(angles * 0.02, axis=0) + jnp.array([7.0, 1.2, -13.0])  # slow, 2 pi turns
    for start_shift in (0.0, 2 * np.pi):
        start = path[0] + jnp.array([start_shift, 0.0, -start_shift])
        shifted = path + jnp.array([start_shift, 0.0, -start_shift])
        r = jax.vmap(rotation_matrix)(shifted)
        w = jax.vmap(body_angular_velocity)(shifted, rates)
        got, got_rates = euler_path(r, w, start)
        np.testing.assert_allclose(got, shifted, atol=1e-12)
        np.testing.assert_allclose(got_rates, rates, atol=1e-10)
    flipped = path * jnp.array([1.0, -1.0, 1.0])  # sin(beta) < 0 throughout
    r = jax.vmap(rotation_matrix)(flipped)
    w = jax.vmap(body_angular_velocity)(flipped, rates)
    got, got_rates = euler_path(r, w, flipped[0])
    np.testing.assert_allclose(got, flipped, atol=1e-12)
    np.testing.assert_allclose(got_rates, rates, atol=1e-10)


# ------------------------------------------ the magnet pendulum: Newton with the rod constraint
def test_magnet_pendulum_matches_newton_with_the_rod_force():
    """Cartesian Newton: m a = F - (F . n) n - m |v|^2 / l n, F = -grad V(x) of the Cartesian
    potential (gravity and the dipoles, m0 = q x / |x|^2), against d2x/dt2 of our solution."""
    s = systems.make("magnet_pendulum")
    pos, dip = (np.asarray(a) for a in s.magnets())

    def v_cart(x):
        m0 = s.moment * x / jnp.dot(x, x)
        pairs = zip(pos, dip, strict=True)
        u = sum(dipole_energy(m0, jnp.asarray(d), jnp.asarray(p) - x) for p, d in pairs)
        return s.mass * G * x[2] + u

    grad_v = jax.grad(v_cart)

    def both(z):
        q, qd = z[:2], z[2:]
        qdd = s.acceleration(q, qd)

        def x_of_t(t):
            return s.length * bob_direction(q + t * qd + 0.5 * t**2 * qdd)

        x = x_of_t(0.0)
        v = jax.jacfwd(x_of_t)(0.0)
        a = jax.jacfwd(jax.jacfwd(x_of_t))(0.0)
        n = x / s.length
        f = -grad_v(x)
        return a, (f - jnp.dot(f, n) * n) / s.mass - jnp.dot(v, v) / s.length * n

    a, a_newton = jax.jit(jax.vmap(both))(jnp.asarray(_states(s, 8, seed=2)))
    np.testing.assert_allclose(a, a_newton, rtol=1e-10, atol=1e-10 * float(jnp.abs(a).max()))


def test_dipole_energy_closed_forms():
    """Antiparallel dipoles q along z: coaxial at distance d repel, U = 2 q^2 / (4 pi d^3);
    side by side they attract, U = -q^2 / (4 pi d^3)."""
    q, d = 0.3, 0.2
    up, down = jnp.array([0.0, 0.0, q]), jnp.array([0.0, 0.0, -q])
    coax = dipole_energy(down, up, jnp.array([0.0, 0.0, -d]))
    side = dipole_energy(down, up, jnp.array([d, 0.0, 0.0]))
    np.testing.assert_allclose(coax, 2 * q**2 / (4 * np.pi * d**3), rtol=1e-14)
    np.testing.assert_allclose(side, -(q**2) / (4 * np.pi * d**3), rtol=1e-14)


def test_magnet_pendulum_hangs_at_rest_between_the_magnets():
    """Straight down, (phi, theta) = (pi, pi / 2), is an equilibrium by symmetry."""
    s = systems.make("magnet_pendulum")
    np.testing.assert_allclose(bob_direction(jnp.array([np.pi, np.pi / 2])), [0, 0, -1], atol=1e-15)
    acc = s.acceleration(jnp.array([np.pi, np.pi / 2]), jnp.zeros(2))
    np.testing.assert_allclose(acc, 0.0, atol=1e-12)


# ------------------------------------------------------------------- draws and the domain
def test_draws_follow_the_reference_and_avoid_the_pole():
    g, r, m = (systems.make(n) for n in ("gyroscope", "rotor", "magnet_pendulum"))
    zg, zr, zm = (_states(s, 2000) for s in (g, r, m))
    assert np.all((zg[:, 1] >= 0.05) & (zg[:, 1] <= 1.5))
    spin = np.abs(zg[:, 5])
    assert 9.5 < spin.mean() < 11.5 and np.all(np.abs(zg[:, 3]) <= 4.5)
    assert np.all(np.abs(np.sin(zr[:, 4])) >= 0.05) and np.all(np.abs(zr[:, :3]) <= 0.3 + 1e-12)
    np.testing.assert_allclose(zm.mean(0), [np.pi, np.pi / 2, 0, 0], atol=0.03)
    np.testing.assert_allclose(zm.std(0), [0.3, 0.2, 0.05, 0.4], rtol=0.08)


@pytest.mark.parametrize("name, index", [("gyroscope", 1), ("rotor", 4), ("magnet_pendulum", 1)])
def test_states_at_the_coordinate_pole_are_refused(name, index):
    s = systems.make(name)
    z = np.zeros((1, 2 * s.dof))
    z[0, index] = 1e-5
    with pytest.raises(ValueError, match="singular"):
        s.simulate_batch(z, TS)


@pytest.mark.parametrize(
    "name, params, match",
    [
        ("gyroscope", {"mass": 0.0}, "mass must be"),
        ("rotor", {"k": 2}, "unknown parameter"),
        ("magnet_pendulum", {"n_magnets": 0}, "n_magnets must be"),
        ("magnet_pendulum", {"length": -1.0}, "length must be"),
    ],
)
def test_bad_parameters_raise(name, params, match):
    with pytest.raises(ValueError, match=match):
        systems.make(name, **params)
