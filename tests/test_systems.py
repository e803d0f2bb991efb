"""Physics checks of the systems registry: closed forms, conservation laws, reversibility."""

from __future__ import annotations

import math

import diffrax
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import systems
from systems import _base

G = 9.81
# One save grid and one batch size for every simulation here, so each system compiles once.
TS = np.linspace(0.0, 6.0, 301)
N = 4
REFERENCE_TABLE = {
    1: ([1.0391], [1.1722]),
    2: ([1.1722, 1.0391], [1.0359, 1.0822]),
    3: ([1.0822, 1.1722, 1.0391], [1.1167, 0.9389, 1.0359]),
    4: ([1.0359, 1.0822, 1.1722, 1.0391], [1.3134, 0.9501, 1.1167, 0.9389]),
}
CONSERVATIVE = [
    ("chain_pendulum", {"k": 1}),
    ("chain_pendulum", {"k": 2}),
    ("chain_pendulum", {"k": 3}),
    ("spring_pendulum", {"k": 1}),
    ("spring_pendulum", {"k": 2}),
    ("relativistic_particle", {}),
]  # the HNN seed's systems: conservation and closed forms in tests/test_systems_seed.py
# every registered system (a new one is picked up here), at k = 2 where it takes a k
ALL_DEFAULT = [
    (name, {"k": 2} if "k" in systems.parameters(name) else {}) for name in systems.available()
]


def jvmap(fn, **kwargs):
    """jit(vmap(fn)): eager vmaps of autodiff code dispatch op by op, which is slow here."""
    return jax.jit(jax.vmap(fn, **kwargs))


def _ids(cases):
    return [f"{n}-{p.get('k', '')}" for n, p in cases]


def _random_states(system, seed=0, n=8):
    """Random states; one n for most tests so that each sampler compiles once per system."""
    return np.asarray(system.sample_initial(jax.random.PRNGKey(seed), n))


def _batched(fn, system):
    return jvmap(lambda z: fn(z[: system.dof], z[system.dof :]))


# ------------------------------------------------------------------------------ registry
def test_available_names():
    names = systems.available()
    for name in [
        "chain_pendulum",
        "spring_pendulum",
        "relativistic_particle",
        "damped_chain_pendulum",
        "damped_spring_pendulum",
        "mass_spring",
        "pendulum",
        "two_body",
        "three_body",
        "gyroscope",
        "rotor",
        "magnet_pendulum",
    ]:
        assert name in names


def test_damped_aliases_default_friction():
    assert systems.make("damped_chain_pendulum", k=2).friction == pytest.approx(0.4)
    assert systems.make("damped_spring_pendulum", k=2).friction == pytest.approx(0.4)
    assert systems.make("damped_chain_pendulum", k=2, friction=0.1).friction == 0.1
    assert systems.make("chain_pendulum", k=2).friction == 0.0


def test_unknown_name_suggests_closest():
    with pytest.raises(ValueError, match="chain_pendulum") as info:
        systems.make("chain_pendulm", k=2)
    assert "did you mean 'chain_pendulum'" in str(info.value)
    assert "relativistic_particle" in str(info.value)


@pytest.mark.parametrize(
    "name, params, match",
    [
        ("chain_pendulum", {"k": 0}, "k must be an integer >= 1"),
        ("chain_pendulum", {"k": 2.0}, "k must be an integer"),
        ("chain_pendulum", {"k": True}, "k must be an integer"),
        ("chain_pendulum", {}, "needs parameter"),
        ("chain_pendulum", {"k": 2, "masses": [1.0, -1.0]}, "masses must be 2 finite positive"),
        ("chain_pendulum", {"k": 2, "masses": [1.0]}, "masses must be 2"),
        ("chain_pendulum", {"k": 2, "lengths": [1.0, np.nan]}, "lengths must be 2"),
        ("chain_pendulum", {"k": 2, "lengths": [1.0, 0.0]}, "lengths must be 2"),
        ("chain_pendulum", {"k": 2, "friction": -0.1}, "friction must be"),
        ("chain_pendulum", {"k": 2, "friction": math.inf}, "friction must be"),
        ("chain_pendulum", {"k": 2, "g": math.nan}, "g must be"),
        ("chain_pendulum", {"k": 2, "mass": 1.0}, "unknown parameter.*allowed: k, masses"),
        ("spring_pendulum", {"k": 2, "spring_constant": 0.0}, "spring_constant"),
        ("spring_pendulum", {"k": 2, "lengths": [1, 1]}, "unknown parameter"),
        ("damped_spring_pendulum", {"k": 2, "friction": -1.0}, "friction"),
        ("relativistic_particle", {"k": 1}, "unknown parameter.*allowed: g"),
        ("relativistic_particle", {"g": "a"}, "g must be"),
        ("relativistic_particle", {"v0_max": 1.0}, "v0_max must be in"),
        ("relativistic_particle", {"v0_max": -0.1}, "v0_max must be"),
        ("relativistic_particle", {"g_min": 1.0, "g_max": 0.5}, "g_min must be <= g_max"),
        (
            "spring_pendulum",
            {"k": 2, "initial": "rest"},
            "initial must be one of equilibrium, paper",
        ),
    ],
)
def test_bad_params_of_the_paper_systems_raise(name, params, match):
    with pytest.raises(ValueError, match=match):
        systems.make(name, **params)


@pytest.mark.parametrize("k", [1, 2, 3, 4])
def test_reference_table_reproduced(k):
    masses, lengths = systems.reference_masses_lengths(k)
    np.testing.assert_allclose(masses, REFERENCE_TABLE[k][0], atol=5e-5)
    np.testing.assert_allclose(lengths, REFERENCE_TABLE[k][1], atol=5e-5)
    chain = systems.make("chain_pendulum", k=k)
    np.testing.assert_allclose(chain.masses, masses, rtol=0)
    np.testing.assert_allclose(chain.lengths, lengths, rtol=0)
    np.testing.assert_allclose(systems.make("spring_pendulum", k=k).masses, masses, rtol=0)


def test_reference_generator_extends_to_k5():
    masses, lengths = systems.reference_masses_lengths(5)
    assert masses.shape == lengths.shape == (5,)
    assert np.all((masses > 0.6) & (masses < 1.4) & (lengths > 0.6) & (lengths < 1.4))
    rng = np.random.RandomState(0)
    np.testing.assert_array_equal(masses, rng.uniform(0.6, 1.4, 5)[::-1])


# ----------------------------------------------------------------- conformance, all systems
@pytest.mark.parametrize("name, params", ALL_DEFAULT, ids=_ids(ALL_DEFAULT))
def test_conformance(name, params):
    s = systems.make(name, **params)
    assert isinstance(s, systems.AbstractSystem)
    assert len(s.angular) == s.dof and s.default_args().shape == (s.n_args,)
    z = _random_states(s)
    assert z.shape == (8, 2 * s.dof) and np.all(np.isfinite(z))
    assert s.sample_args(jax.random.PRNGKey(1), 5).shape == (5, s.n_args)
    term = diffrax.ODETerm(s.vector_field)  # the field plugs straight into diffrax

    def routes(zz):
        p = s.momentum(zz)
        return s.vector_field(0.0, zz, None), term.vf(0.0, zz, None), p, s.velocity(zz[: s.dof], p)

    dz, dz_term, p, v = jvmap(routes)(z)
    assert dz.shape == z.shape and dz.dtype == jnp.float64
    np.testing.assert_array_equal(dz[:, : s.dof], z[:, s.dof :])  # dq/dt = qdot
    np.testing.assert_array_equal(dz_term, dz)
    # momentum and velocity are inverse maps.
    np.testing.assert_allclose(v, z[:, s.dof :], rtol=1e-12, atol=1e-12)
    assert s.positions(jnp.asarray(z[0])).ndim == 2


# ----------------------------------------------------------------------- closed forms
def test_single_pendulum_closed_form():
    s = systems.make("chain_pendulum", k=1, masses=[0.7], lengths=[1.3])
    z = _random_states(s)
    acc = _batched(s.acceleration, s)(z)[:, 0]
    np.testing.assert_allclose(acc, -G / 1.3 * np.sin(z[:, 0]), rtol=1e-10, atol=1e-12)


def test_double_pendulum_closed_form():
    m1, m2, l1, l2 = 1.3, 0.8, 0.9, 1.4
    s = systems.make("chain_pendulum", k=2, masses=[m1, m2], lengths=[l1, l2])
    z = _random_states(s)
    t1, t2, w1, w2 = z.T
    d = t1 - t2
    den = 2 * m1 + m2 - m2 * np.cos(2 * d)
    a1 = (
        -G * (2 * m1 + m2) * np.sin(t1)
        - m2 * G * np.sin(t1 - 2 * t2)
        - 2 * np.sin(d) * m2 * (w2**2 * l2 + w1**2 * l1 * np.cos(d))
    ) / (l1 * den)
    a2 = (
        2
        * np.sin(d)
        * (w1**2 * l1 * (m1 + m2) + G * (m1 + m2) * np.cos(t1) + w2**2 * l2 * m2 * np.cos(d))
    ) / (l2 * den)
    acc = _batched(s.acceleration, s)(z)
    np.testing.assert_allclose(acc, np.stack([a1, a2], 1), rtol=1e-10, atol=1e-10)


def test_chain_energy_is_t_plus_v():
    s = systems.make("chain_pendulum", k=2)
    z = _random_states(s)
    (m1, m2), (l1, l2) = np.asarray(s.masses), np.asarray(s.lengths)
    t1, t2, w1, w2 = z.T
    kin = 0.5 * (m1 + m2) * l1**2 * w1**2 + 0.5 * m2 * l2**2 * w2**2
    kin += m2 * l1 * l2 * w1 * w2 * np.cos(t1 - t2)
    pot = -(m1 + m2) * G * l1 * np.cos(t1) - m2 * G * l2 * np.cos(t2)
    np.testing.assert_allclose(jvmap(s.energy)(z), kin + pot, rtol=1e-12)


def test_chain_positions_respect_links():
    s = systems.make("chain_pendulum", k=3)
    z = _random_states(s)
    pos = np.asarray(jvmap(s.positions)(z))
    links = np.diff(np.concatenate([np.zeros((8, 1, 2)), pos], axis=1), axis=1)
    np.testing.assert_allclose(
        np.linalg.norm(links, axis=-1), np.broadcast_to(s.lengths, (8, 3)), rtol=1e-12
    )


def test_potential_range():
    s = systems.make("chain_pendulum", k=3)
    up = s.potential_energy(jnp.full(3, jnp.pi))
    down = s.potential_energy(jnp.zeros(3))
    assert s.potential_range() == pytest.approx(float(up - down), rel=1e-12)
    v = jvmap(lambda z: s.potential_energy(z[:3]))(_random_states(s))
    assert np.all((v >= down - 1e-12) & (v <= up + 1e-12))
    assert math.isnan(systems.make("spring_pendulum", k=2).potential_range())
    assert math.isnan(systems.make("relativistic_particle").potential_range())


@pytest.mark.parametrize("k", [1, 2])
def test_spring_closed_form_force(k):
    kappa, masses = 7.0, np.array([0.9, 1.6])[:k]
    s = systems.make("spring_pendulum", k=k, masses=masses, spring_constant=kappa)
    z = _random_states(s)
    x = z[:, : 3 * k].reshape(8, k, 3)
    force = -masses[None, :, None] * G * np.array([0.0, 0.0, 1.0])
    force = force + np.zeros_like(x)
    force[:, 0] -= kappa * x[:, 0]  # rest length 0: Hooke's law on the position itself
    if k == 2:
        d = x[:, 1] - x[:, 0]
        r = np.linalg.norm(d, axis=-1, keepdims=True)
        pull = kappa * (r - 1.0) * d / r
        force[:, 0] += pull
        force[:, 1] -= pull
    acc = _batched(s.acceleration, s)(z)
    np.testing.assert_allclose(
        acc, (force / masses[None, :, None]).reshape(8, -1), rtol=1e-10, atol=1e-10
    )


@pytest.mark.parametrize("k", [1, 2, 3, 4])
def test_spring_equilibrium_is_fixed_point(k):
    s = systems.make("spring_pendulum", k=k)
    q = np.asarray(s.equilibrium())
    m = np.asarray(s.masses)
    # Hand check: bob 1 at z = -g M/kappa, each next one 1 + g (tail mass)/kappa lower.
    tail = np.cumsum(m[::-1])[::-1]
    expected_z = -np.cumsum(G * tail / 10.0 + np.r_[0.0, np.ones(k - 1)])
    np.testing.assert_allclose(q.reshape(k, 3)[:, 2], expected_z, rtol=1e-14)
    np.testing.assert_array_equal(q.reshape(k, 3)[:, :2], 0.0)
    field = jvmap(lambda z: s.vector_field(0.0, z, None))
    zero = np.zeros_like(q)
    dz = field(np.stack([np.concatenate([q, zero]), np.concatenate([q + 0.01, zero])]))
    np.testing.assert_allclose(dz[0], 0.0, atol=1e-12)
    assert np.max(np.abs(dz[1])) > 0.05  # ...and not a fixed point 1 cm away


def test_relativistic_closed_form_acceleration():
    s = systems.make("relativistic_particle", g=1.7)
    v = np.linspace(-0.999, 0.999, 41)
    z = np.stack([np.linspace(-3, 3, 41), v], 1)
    auto = _batched(s.acceleration, s)(z)[:, 0]
    closed = jvmap(lambda zz: s.acceleration_closed_form(zz[:1], zz[1:]))(z)[:, 0]
    np.testing.assert_allclose(auto, closed, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(closed, 1.7 * (1 - v**2) ** 2.5 / (1 + 2 * v**2), rtol=1e-13)
    # args override the default g.
    acc = s.acceleration(jnp.zeros(1), jnp.array([0.3]), jnp.array([-0.5]))
    assert float(acc[0]) == pytest.approx(-0.5 * (1 - 0.09) ** 2.5 / 1.18, rel=1e-12)


def test_relativistic_momentum_velocity_round_trip():
    s = systems.make("relativistic_particle")
    v = np.concatenate([np.linspace(-0.9999, 0.9999, 201), [0.0, 1e-9, -1e-12]])
    p_closed = v * (1 - v**2) ** -1.5
    p = jvmap(lambda vv: s.momentum(jnp.array([0.0, vv])))(v)[:, 0]
    np.testing.assert_allclose(p, p_closed, rtol=1e-12)
    back = jvmap(lambda pp: s.velocity(jnp.zeros(1), pp[None]))(p)[:, 0]
    np.testing.assert_allclose(back, v, rtol=2e-15, atol=1e-300)
    # Huge momenta stay inside the light cone.
    fast = s.velocity(jnp.zeros(1), jnp.array([1e8]))
    assert 0.999 < float(fast[0]) < 1.0
    # Energy is the Legendre transform H = p v - L with L = gamma - 1 + g q.
    z = jnp.array([0.4, 0.6])
    gamma = 1 / math.sqrt(1 - 0.36)
    expected = 0.6 * 0.6 * gamma**3 - (gamma - 1 + 1.0 * 0.4)
    assert float(s.energy(z)) == pytest.approx(expected, rel=1e-13)


def test_relativistic_sampling_inside_light_cone():
    s = systems.make("relativistic_particle")
    z = _random_states(s, n=500)
    assert np.max(np.abs(z[:, 1])) < 0.9 and np.std(z[:, 1]) > 0.3
    g = np.asarray(s.sample_args(jax.random.PRNGKey(3), 500))
    assert g.shape == (500, 1) and np.all((g >= 0.5) & (g <= 2.0)) and np.std(g) > 0.2


def test_relativistic_sampling_ranges_are_parameters():
    s = systems.make("relativistic_particle", v0_max=0.3, g_min=0.05, g_max=0.3)
    z = _random_states(s, n=500)
    assert np.max(np.abs(z[:, 1])) <= 0.3 and np.std(z[:, 1]) > 0.1
    g = np.asarray(s.sample_args(jax.random.PRNGKey(3), 500))
    assert np.all((g >= 0.05) & (g <= 0.3)) and np.ptp(g) > 0.2


@pytest.mark.parametrize("k, offsets", [(2, (0.0, 0.87)), (3, (0.0, 0.96, 1.92))])
def test_spring_paper_initial_states_start_above_equilibrium(k, offsets):
    """The paper's code: its heights ignore the rest lengths of springs 2..k (and take
    the masses in draw order), so bob i starts about i - 1 m above the true equilibrium."""
    paper = systems.make("spring_pendulum", k=k, initial="paper")
    z = _random_states(paper, n=4000)
    eq = np.asarray(paper.equilibrium()).reshape(k, 3)
    offset = z[:, : 3 * k].reshape(-1, k, 3) - eq
    np.testing.assert_allclose(np.mean(offset[:, :, 2], 0), offsets, atol=0.05)
    np.testing.assert_allclose(np.mean(offset[:, :, :2], 0), 0.0, atol=0.05)
    exact = np.asarray(paper.reference_heights()).reshape(k, 3)[:, 2] - eq[:, 2]
    np.testing.assert_allclose(exact, offsets, atol=0.005)
    # same noise as the default distribution, only the centre moves; velocities unchanged
    default = _random_states(systems.make("spring_pendulum", k=k), n=4000)
    np.testing.assert_allclose(z[:, 3 * k :], default[:, 3 * k :])
    shift = np.asarray(paper.reference_heights()) - eq.reshape(-1)
    np.testing.assert_allclose(
        z[:, : 3 * k] - default[:, : 3 * k], np.broadcast_to(shift, (4000, 3 * k)), atol=1e-12
    )


def test_initial_state_spread():
    chain = systems.make("chain_pendulum", k=2)
    z = _random_states(chain, n=2000)
    assert 0.7 < np.std(z[:, :2]) < 1.5  # angles ~ N(0, 1)
    assert np.std(z[:, 2:]) > 1.0  # fast: velocities scaled by 3 (0.5 v + 0.4 noise)
    spring = systems.make("spring_pendulum", k=2)
    z = _random_states(spring, n=2000)
    offset = z[:, :6] - np.asarray(spring.equilibrium())
    np.testing.assert_allclose(np.mean(offset, 0), 0.0, atol=0.1)
    np.testing.assert_allclose(np.std(offset, 0), [0.4, 0.4, math.hypot(0.4, 0.8)] * 2, rtol=0.1)
    np.testing.assert_allclose(np.std(z[:, 6:], 0), 0.6, rtol=0.1)


# ---------------------------------------------------------------------------- friction
@pytest.mark.parametrize(
    "name, params", [("chain_pendulum", {"k": 3}), ("spring_pendulum", {"k": 2})]
)
def test_friction_subtracts_f_qdot(name, params):
    plain = systems.make(name, **params)
    damped = systems.make(name, friction=0.4, **params)
    z = _random_states(plain)
    a0 = _batched(plain.acceleration, plain)(z)
    a1 = _batched(damped.acceleration, damped)(z)
    np.testing.assert_allclose(a1, a0 - 0.4 * z[:, plain.dof :], rtol=1e-10, atol=1e-10)


# ------------------------------------------------------------------------- simulation
@pytest.fixture(scope="module")
def trajectories():
    """N trajectories on TS for every conservative system (one compile each)."""
    out = {}
    for name, params in CONSERVATIVE:
        s = systems.make(name, **params)
        z0 = _random_states(s, seed=7)[:N]
        args = s.sample_args(jax.random.PRNGKey(8), N) if s.n_args else None
        out[(name, params.get("k"))] = (s, args, np.asarray(s.simulate_batch(z0, TS, args)))
    return out


def _energy_along(s, zs, args):
    if args is None:
        return np.asarray(jvmap(jvmap(s.energy))(zs))
    per = jvmap(s.energy, in_axes=(0, None))
    return np.asarray(jvmap(per)(zs, args))


@pytest.mark.parametrize("name, params", CONSERVATIVE, ids=_ids(CONSERVATIVE))
def test_energy_conservation(trajectories, name, params):
    s, args, zs = trajectories[(name, params.get("k"))]
    assert zs.shape == (N, len(TS), 2 * s.dof) and zs.dtype == np.float64
    e = _energy_along(s, zs, args)
    drift = np.abs(e - e[:, :1]) / np.maximum(np.abs(e[:, :1]), 1.0)
    assert np.max(drift) < 1e-7
    # The motion is not trivial: the state moves a lot.
    assert np.min(np.max(np.abs(zs - zs[:, :1]), axis=(1, 2))) > 0.1


@pytest.mark.parametrize("name, params", CONSERVATIVE, ids=_ids(CONSERVATIVE))
def test_time_reversibility(trajectories, name, params):
    s, args, zs = trajectories[(name, params.get("k"))]
    d = s.dof
    flipped = np.concatenate([zs[:, -1, :d], -zs[:, -1, d:]], axis=-1)
    # Every field here is even in qdot (qddot(q, -qdot) = qddot(q, qdot)), so the flipped
    # end state retraces the path.
    back = np.asarray(s.simulate_batch(flipped, TS, args))
    start = np.concatenate([zs[:, 0, :d], -zs[:, 0, d:]], axis=-1)
    scale = np.max(np.abs(zs))
    # Chaotic chains amplify the 1e-11 local errors over 6 s; still far below any model error.
    np.testing.assert_allclose(back[:, -1], start, atol=1e-5 * scale)


def test_small_angle_period(trajectories):
    s = systems.make("chain_pendulum", k=1)
    amp = np.array([1e-3, -2e-3, 5e-4, 1e-3])
    z0 = np.stack([amp, np.zeros(N)], 1)
    theta = np.asarray(s.simulate_batch(z0, TS))[:, :, 0]
    period = 2 * np.pi * math.sqrt(float(s.lengths[0]) / G)
    for th in theta:
        i = np.nonzero(np.sign(th[:-1]) != np.sign(th[1:]))[0]
        crossings = TS[i] - th[i] * (TS[i + 1] - TS[i]) / (th[i + 1] - th[i])
        assert len(crossings) >= 4
        measured = 2 * (crossings[-1] - crossings[0]) / (len(crossings) - 1)
        assert measured == pytest.approx(period, rel=1e-6)


@pytest.mark.parametrize(
    "name, params",
    [
        ("damped_chain_pendulum", {"k": 2}),
        pytest.param("damped_spring_pendulum", {"k": 2}, marks=pytest.mark.slow),
    ],
)
def test_damped_energy_decays_monotonically(name, params):
    s = systems.make(name, **params)
    undamped = systems.make(name.removeprefix("damped_"), **params)
    zs = np.asarray(s.simulate_batch(_random_states(undamped, seed=2)[:N], TS))
    e = _energy_along(s, zs, None)
    assert np.all(np.diff(e, axis=1) <= 1e-9)
    assert np.all(e[:, -1] < e[:, 0] - 1.0)
    # dE/dt = -f sum m_i |v_i|^2 = -2 f T: check at one point by finite differences.
    kin = np.asarray(jvmap(jvmap(lambda z: s.kinetic_energy(z[: s.dof], z[s.dof :])))(zs))
    dt = TS[1] - TS[0]
    de = (e[:, 2:] - e[:, :-2]) / (2 * dt)
    np.testing.assert_allclose(de, -2 * 0.4 * kin[:, 1:-1], atol=0.05 * np.max(np.abs(de)))


def test_simulate_traced_once_per_shape(trajectories):
    _, _, zs = trajectories[("chain_pendulum", 2)]
    before = _base._solve_batch._cached._cache_size()
    other = systems.make("chain_pendulum", k=2, masses=[0.8, 1.1], lengths=[1.0, 0.7])
    again = other.simulate_batch(_random_states(other, seed=11)[:N], TS)
    assert _base._solve_batch._cached._cache_size() == before  # masses are traced, not baked
    assert not np.allclose(again, zs)


@pytest.mark.slow
def test_simulate_single_matches_batch(trajectories):
    s, _, zs = trajectories[("chain_pendulum", 2)]
    np.testing.assert_allclose(s.simulate(zs[1, 0], TS), zs[1], rtol=1e-9, atol=1e-9)


def test_simulate_bad_inputs():
    chain = systems.make("chain_pendulum", k=2)
    ts = np.linspace(0, 1, 5)
    z0 = np.zeros(4)
    cases = [
        (lambda: chain.simulate(np.array([np.nan, 0, 0, 0]), ts), "finite"),
        (lambda: chain.simulate(np.zeros(3), ts), r"shape \(4,\)"),
        (lambda: chain.simulate(z0, ts[::-1]), "strictly increasing"),
        (lambda: chain.simulate(z0, np.array([0.0, 1.0, 1.0])), "strictly increasing"),
        (lambda: chain.simulate(z0, np.array([0.0, np.inf])), "finite"),
        (lambda: chain.simulate(z0, np.array([0.0])), "at least 2"),
        (lambda: chain.simulate(z0, "abc"), "real float array"),
        (lambda: chain.simulate(z0, ts, args=np.ones(1)), "args must have shape"),
        (lambda: chain.simulate_batch(np.zeros((2, 5)), ts), r"shape \(N >= 1, 4\)"),
        (lambda: chain.simulate_batch(np.zeros(4), ts), r"shape \(N >= 1, 4\)"),
    ]
    rel = systems.make("relativistic_particle")
    cases += [
        (lambda: rel.simulate(np.array([0.0, 1.0]), ts), r"\|qdot\| < 1"),
        (lambda: rel.simulate(np.array([0.0, -1.5]), ts), r"\|qdot\| < 1"),
        (lambda: rel.simulate(np.array([0.0, 0.5]), ts, args=np.ones((1, 1))), "args must"),
        (lambda: rel.simulate_batch(np.zeros((3, 2)), ts, args=np.ones((2, 1))), "args must"),
        (lambda: rel.simulate(np.array([0.0, 0.5]), ts, args=[np.nan]), "finite"),
    ]
    for fn, match in cases:
        with pytest.raises(ValueError, match=match):
            fn()
