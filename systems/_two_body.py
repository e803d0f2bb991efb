"""Two bodies under planar Newtonian gravity (the HNN seed's two-body task)."""

from __future__ import annotations

from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ._base import AbstractSystem
from ._params import check_nonneg, check_positive, check_positive_values

# The seed's draw (greydanus/hamiltonian-nn, experiment-2body/data.py, random_config).
ORBIT_NOISE, R_MIN, R_MAX = 0.05, 0.5, 1.5


class TwoBody(AbstractSystem):
    """Two point masses in a plane attracting by gravity, q = (x_1, y_1, x_2, y_2):
    L = 1/2 sum_i m_i |v_i|^2 + G m_1 m_2 / |x_1 - x_2|.

    The field is singular at a collision; the seed's near-circular orbits keep the bodies at
    distance >= about 1.4 (2 x the smallest radius 0.5 x sqrt 2 x 0.95). Energy and angular
    momentum L_z = sum_i m_i (x_i vy_i - y_i vx_i) are conserved, and with equal masses and
    the seed's states the centre of mass is at the origin and at rest.
    """

    masses: tuple[float, float] = eqx.field(static=True, default=(1.0, 1.0))
    gravity: float = eqx.field(static=True, default=1.0)
    orbit_noise: float = eqx.field(static=True, default=ORBIT_NOISE)
    r_min: float = eqx.field(static=True, default=R_MIN)
    r_max: float = eqx.field(static=True, default=R_MAX)
    friction: float = eqx.field(static=True, default=0.0)
    angular: tuple[bool, ...] = eqx.field(static=True, default=(False,) * 4)
    name: str = eqx.field(static=True, default="two_body")
    n_args: int = eqx.field(static=True, default=0)
    # the ground truth's rtol = atol: at 1e-11 the energy drifts 2.3e-9 over ten orbits of the
    # seed's draws, at 1e-13 1.0e-10 (tests/test_systems_seed.py)
    ground_truth_tol: ClassVar[float] = 1e-13

    def kinetic_energy(self, q, qdot, args=None):
        """T = 1/2 sum_i m_i |v_i|^2."""
        m = jnp.asarray(self.masses, dtype=jnp.float64)
        return 0.5 * jnp.sum(m * jnp.sum(qdot.reshape(2, 2) ** 2, axis=-1))

    def potential_energy(self, q, args=None):
        """V = -G m_1 m_2 / |x_1 - x_2|."""
        x = q.reshape(2, 2)
        return -self.gravity * self.masses[0] * self.masses[1] / jnp.linalg.norm(x[0] - x[1])

    def angular_momentum(self, z):
        """L_z = sum_i m_i (x_i vy_i - y_i vx_i) about the origin."""
        x, v = z[:4].reshape(2, 2), z[4:].reshape(2, 2)
        m = jnp.asarray(self.masses, dtype=jnp.float64)
        return jnp.sum(m * (x[:, 0] * v[:, 1] - x[:, 1] * v[:, 0]))

    def positions(self, z):
        """The bodies, shape (2, 2)."""
        return z[:4].reshape(2, 2)

    @eqx.filter_jit
    def sample_initial(self, key, n: int):
        """The seed's near-circular orbits: body 1 at (x, y), x, y ~ U(r_min, r_max), with the
        velocity of a circular orbit about the origin for equal unit masses and G = 1,
        (-y, x) / (2 r^1.5), scaled by 1 + orbit_noise N(0, 1); body 2 mirrored through the
        origin (position and velocity), so the centre of mass is at rest at the origin."""
        k_pos, k_noise = jax.random.split(key)
        pos = jax.random.uniform(
            k_pos, (n, 2), dtype=jnp.float64, minval=self.r_min, maxval=self.r_max
        )
        r = jnp.linalg.norm(pos, axis=-1, keepdims=True)
        vel = jnp.stack([-pos[:, 1], pos[:, 0]], axis=-1) / (2.0 * r**1.5)
        vel = vel * (1.0 + self.orbit_noise * jax.random.normal(k_noise, (n, 1), jnp.float64))
        return jnp.concatenate([pos, -pos, vel, -vel], axis=-1)


def two_body(
    masses=(1.0, 1.0), gravity=1.0, orbit_noise=ORBIT_NOISE, r_min=R_MIN, r_max=R_MAX, friction=0.0
) -> TwoBody:
    """Planar two-body gravity; defaults: the seed's unit masses, G = 1 and its orbit draw."""
    r_min, r_max = check_positive("r_min", r_min), check_positive("r_max", r_max)
    if r_min > r_max:
        raise ValueError(f"r_min must be <= r_max; got r_min={r_min!r}, r_max={r_max!r}")
    return TwoBody(
        masses=tuple(float(m) for m in check_positive_values("masses", masses, 2)),
        gravity=check_positive("gravity", gravity),
        orbit_noise=check_nonneg("orbit_noise", orbit_noise),
        r_min=r_min,
        r_max=r_max,
        friction=check_nonneg("friction", friction),
    )


def circular_orbit(r: float, t: np.ndarray, gravity: float = 1.0, mass: float = 1.0):
    """Closed form for equal masses m: body 1 on the circle of radius r about the origin,
    angular rate w = sqrt(G m / (4 r^3)), starting at (r, 0) counter-clockwise; body 2
    opposite. Returns states (len(t), 8) in this system's layout."""
    w = np.sqrt(gravity * mass / (4.0 * r**3))
    c, s = np.cos(w * t), np.sin(w * t)
    x1 = np.stack([r * c, r * s], axis=-1)
    v1 = np.stack([-r * w * s, r * w * c], axis=-1)
    return np.concatenate([x1, -x1, v1, -v1], axis=-1)
