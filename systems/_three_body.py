"""Three bodies under planar Newtonian gravity (the HNN seed's three-body task, its Appendix B)."""

from __future__ import annotations

from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ._base import AbstractSystem
from ._params import check_nonneg, check_positive, check_positive_values

# The seed's draw (greydanus/hamiltonian-nn, experiment-3body/data.py, random_config).
ORBIT_NOISE, R_MIN, R_MAX = 0.2, 0.9, 1.2
# 3^(-1/4): the speed factor of the seed's draw, sqrt(sin(pi/3) / (2 cos(pi/6)^2)), which makes
# the unperturbed state Lagrange's equilateral circular orbit (:func:`lagrange_orbit`)
_CIRCULAR = float(np.sqrt(np.sin(np.pi / 3) / (2 * np.cos(np.pi / 6) ** 2)))


def _rotate(x, angle):
    """Rotate 2-vectors (..., 2) counter-clockwise by ``angle``."""
    c, s = jnp.cos(angle), jnp.sin(angle)
    return jnp.stack([c * x[..., 0] - s * x[..., 1], s * x[..., 0] + c * x[..., 1]], axis=-1)


class ThreeBody(AbstractSystem):
    """Three point masses in a plane attracting by gravity, q = (x_1, y_1, x_2, y_2, x_3, y_3):
    L = 1/2 sum_i m_i |v_i|^2 + G sum_{i<j} m_i m_j / |x_i - x_j|.

    Energy, the total momentum and the angular momentum L_z = sum_i m_i (x_i vy_i - y_i vx_i)
    are conserved. The field is singular at a collision; the seed's draws are near-circular
    (speeds perturbed by up to 20% per component), so close encounters are rare but not
    excluded: the adaptive ground truth shortens its steps through them (``ground_truth_tol``),
    and states with two bodies at one point are refused (:meth:`check_states`).
    """

    masses: tuple[float, float, float] = eqx.field(static=True, default=(1.0, 1.0, 1.0))
    gravity: float = eqx.field(static=True, default=1.0)
    orbit_noise: float = eqx.field(static=True, default=ORBIT_NOISE)
    r_min: float = eqx.field(static=True, default=R_MIN)
    r_max: float = eqx.field(static=True, default=R_MAX)
    friction: float = eqx.field(static=True, default=0.0)
    angular: tuple[bool, ...] = eqx.field(static=True, default=(False,) * 6)
    name: str = eqx.field(static=True, default="three_body")
    n_args: int = eqx.field(static=True, default=0)
    # the ground truth's rtol = atol: over the seed's 5 s span the relative energy drift is at
    # most 3.0e-9 at 1e-11 (64 of its draws) and 1.2e-10 at 1e-13 (1000 draws, closest approach
    # 0.064; docs/studies/three_body.md)
    ground_truth_tol: ClassVar[float] = 1e-13

    def kinetic_energy(self, q, qdot, args=None):
        """T = 1/2 sum_i m_i |v_i|^2."""
        m = jnp.asarray(self.masses, dtype=jnp.float64)
        return 0.5 * jnp.sum(m * jnp.sum(qdot.reshape(3, 2) ** 2, axis=-1))

    def potential_energy(self, q, args=None):
        """V = -G sum_{i<j} m_i m_j / |x_i - x_j|."""
        x = q.reshape(3, 2)
        m = self.masses
        v = 0.0
        for i, j in ((0, 1), (0, 2), (1, 2)):
            v = v - self.gravity * m[i] * m[j] / jnp.linalg.norm(x[i] - x[j])
        return v

    def linear_momentum(self, z):
        """P = sum_i m_i v_i, shape (2,)."""
        m = jnp.asarray(self.masses, dtype=jnp.float64)
        return jnp.sum(m[:, None] * z[6:].reshape(3, 2), axis=0)

    def angular_momentum(self, z):
        """L_z = sum_i m_i (x_i vy_i - y_i vx_i) about the origin."""
        x, v = z[:6].reshape(3, 2), z[6:].reshape(3, 2)
        m = jnp.asarray(self.masses, dtype=jnp.float64)
        return jnp.sum(m * (x[:, 0] * v[:, 1] - x[:, 1] * v[:, 0]))

    def positions(self, z):
        """The bodies, shape (3, 2)."""
        return z[:6].reshape(3, 2)

    def check_states(self, z: np.ndarray) -> None:
        """ValueError for a state with two bodies at one point (the field is infinite there)."""
        x = np.asarray(z)[..., :6].reshape(*np.shape(z)[:-1], 3, 2)
        for i, j in ((0, 1), (0, 2), (1, 2)):
            if np.any(np.linalg.norm(x[..., i, :] - x[..., j, :], axis=-1) == 0):
                raise ValueError(
                    f"three_body states need distinct bodies; bodies {i + 1} and {j + 1} coincide"
                )

    @eqx.filter_jit
    def sample_initial(self, key, n: int):
        """The seed's near-circular orbits: body 1 at a direction uniform on the square
        [-1, 1]^2 scaled to a radius r ~ U(r_min, r_max), bodies 2 and 3 at it rotated by
        120 and 240 degrees; each body's velocity that of Lagrange's equilateral circular orbit
        (its position turned by 90 degrees, speed 3^(-1/4) r^(-1/2) for unit masses and
        G = 1), then each velocity component scaled by 1 + orbit_noise U(-1, 1)."""
        k_dir, k_r, k_noise = jax.random.split(key, 3)
        direction = jax.random.uniform(k_dir, (n, 2), jnp.float64, minval=-1.0, maxval=1.0)
        direction = direction / jnp.maximum(
            jnp.linalg.norm(direction, axis=-1, keepdims=True), 1e-300
        )
        r = jax.random.uniform(k_r, (n, 1), jnp.float64, minval=self.r_min, maxval=self.r_max)
        p1 = direction * r
        v1 = _rotate(p1, jnp.pi / 2) / r**1.5 * _CIRCULAR
        turns = 2 * jnp.pi / 3 * jnp.arange(3.0)
        pos = jax.vmap(lambda a: _rotate(p1, a), out_axes=1)(turns)  # (n, 3, 2)
        vel = jax.vmap(lambda a: _rotate(v1, a), out_axes=1)(turns)
        noise = jax.random.uniform(k_noise, (n, 3, 2), jnp.float64, minval=-1.0, maxval=1.0)
        vel = vel * (1.0 + self.orbit_noise * noise)
        return jnp.concatenate([pos.reshape(n, 6), vel.reshape(n, 6)], axis=-1)


def three_body(
    masses=(1.0, 1.0, 1.0),
    gravity=1.0,
    orbit_noise=ORBIT_NOISE,
    r_min=R_MIN,
    r_max=R_MAX,
    friction=0.0,
) -> ThreeBody:
    """Planar three-body gravity; defaults: the seed's unit masses, G = 1 and its orbit draw."""
    r_min, r_max = check_positive("r_min", r_min), check_positive("r_max", r_max)
    if r_min > r_max:
        raise ValueError(f"r_min must be <= r_max; got r_min={r_min!r}, r_max={r_max!r}")
    return ThreeBody(
        masses=tuple(float(m) for m in check_positive_values("masses", masses, 3)),
        gravity=check_positive("gravity", gravity),
        orbit_noise=check_nonneg("orbit_noise", orbit_noise),
        r_min=r_min,
        r_max=r_max,
        friction=check_nonneg("friction", friction),
    )


def lagrange_orbit(r: float, t: np.ndarray, gravity: float = 1.0, mass: float = 1.0):
    """Lagrange's equilateral solution for three equal masses m on the circle of radius r
    (side s = r sqrt 3): the triangle turns rigidly at w = sqrt(G 3m / s^3), body 1 starting
    at (r, 0) counter-clockwise. Returns states (len(t), 12) in this system's layout."""
    w = np.sqrt(gravity * 3 * mass / (np.sqrt(3.0) * r) ** 3)
    x, v = [], []
    for i in range(3):
        a = w * t + 2 * np.pi * i / 3
        x.append(np.stack([r * np.cos(a), r * np.sin(a)], axis=-1))
        v.append(np.stack([-r * w * np.sin(a), r * w * np.cos(a)], axis=-1))
    return np.concatenate(x + v, axis=-1)
