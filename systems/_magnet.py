"""A spherical pendulum with a magnetic bob above two fixed magnets (the Deconstructing paper's
App. D.2 "magnet pendulum", from Finzi et al. 2020), in spherical angles about a horizontal pole.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ._base import AbstractSystem
from ._params import check_count, check_positive, check_real

G = 9.81
MAGNET_RADIUS = 0.1  # magnets at (0.1 cos a, 0.1 sin a, -1.05 l), a = 2 pi i / n
MAGNET_DEPTH = 1.05
# spherical angles are singular at sin(theta) = 0, the bob horizontal on the -x or +x axis
POLE = 1e-3


def bob_direction(angles):
    """Unit vector of the rod for angles (phi, theta) about the pole -x: spherical coordinates
    (cos phi sin theta, sin phi sin theta, cos theta) in a frame turned 90 degrees about y,
    i.e. (-cos theta, sin phi sin theta, cos phi sin theta) in space (z up); hanging straight
    down is (phi, theta) = (pi, pi / 2)."""
    phi, theta = angles[0], angles[1]
    st = jnp.sin(theta)
    return jnp.stack([-jnp.cos(theta), jnp.sin(phi) * st, jnp.cos(phi) * st])


def dipole_energy(m0, m1, r):
    """Interaction energy of point dipoles m0, m1 at separation r (mu0 = 1):
    U = (m0 . m1 |r|^2 - 3 (m0 . r)(m1 . r)) / (4 pi |r|^5), i.e. -m0 . B1 with
    B1 = (3 r (m1 . r) / |r|^2 - m1) / (4 pi |r|^3)."""
    r2 = jnp.dot(r, r)
    return (jnp.dot(m0, m1) * r2 - 3.0 * jnp.dot(m0, r) * jnp.dot(m1, r)) / (4.0 * jnp.pi * r2**2.5)


class MagnetPendulum(AbstractSystem):
    """A bob of mass m on a massless rod of length l from the origin (a spherical pendulum, z up)
    carrying a magnetic dipole m0 = q r / |r|^2 along the rod, above ``n_magnets`` fixed dipoles
    q e_z at (0.1 cos a_i, 0.1 sin a_i, -1.05 l), a_i = 2 pi i / n.

    q = (phi, theta), spherical angles about the horizontal pole -x (:func:`bob_direction`), so
    the pendulum's rest state is far from the coordinates' singularity.
    L = 1/2 m |rdot|^2 - m g z - sum_i U(m0, m_i, r_i - r) with the physical dipole-dipole
    energy U (:func:`dipole_energy`); the reference's code flips the sign of its m0 . m_i term
    (docs/studies/rigid_bodies.md). Only energy is conserved.
    """

    mass: float = eqx.field(static=True, default=3.0)
    length: float = eqx.field(static=True, default=1.0)
    moment: float = eqx.field(static=True, default=0.3)
    n_magnets: int = eqx.field(static=True, default=2)
    g: float = eqx.field(static=True, default=G)
    friction: float = eqx.field(static=True, default=0.0)
    angular: tuple[bool, ...] = eqx.field(static=True, default=(True, True))
    name: str = eqx.field(static=True, default="magnet_pendulum")
    n_args: int = eqx.field(static=True, default=0)

    def magnets(self):
        """Positions (n, 3) and dipoles (n, 3) of the fixed magnets."""
        a = 2.0 * np.pi * np.arange(self.n_magnets) / self.n_magnets
        pos = np.stack(
            [
                MAGNET_RADIUS * np.cos(a),
                MAGNET_RADIUS * np.sin(a),
                -MAGNET_DEPTH * self.length + 0 * a,
            ],
            axis=-1,
        )
        dip = np.zeros_like(pos)
        dip[:, 2] = self.moment
        return jnp.asarray(pos), jnp.asarray(dip)

    def kinetic_energy(self, q, qdot, args=None):
        """T = 1/2 m |rdot|^2, rdot = l d(bob_direction)/dq qdot."""
        _, v = jax.jvp(bob_direction, (q,), (qdot,))
        return 0.5 * self.mass * self.length**2 * jnp.dot(v, v)

    def potential_energy(self, q, args=None):
        """V = m g z + sum_i U(m0, m_i, r_i - r), m0 = q r / |r|^2."""
        r = self.length * bob_direction(q)
        m0 = self.moment * r / jnp.dot(r, r)
        pos, dip = self.magnets()
        u = jax.vmap(lambda p, m: dipole_energy(m0, m, p - r))(pos, dip)
        return self.mass * self.g * r[2] + jnp.sum(u)

    def positions(self, z):
        """The bob, shape (1, 3)."""
        return (self.length * bob_direction(z[:2]))[None]

    def check_states(self, z):
        near = np.abs(np.sin(np.asarray(z)[:, 1])) < POLE
        if np.any(near):
            raise ValueError(
                f"{self.name}: the angles are singular at sin(theta) = 0 (the rod along the "
                f"x axis); initial states need |sin(theta)| >= {POLE:g}"
            )

    @eqx.filter_jit
    def sample_initial(self, key, n: int):
        """The reference's draw: phi = pi + 0.3 N(0, 1), theta = pi / 2 + 0.2 N(0, 1), rates
        0.05 N(0, 1) and 0.4 N(0, 1): near the rest state above the magnets."""
        x = jax.random.normal(key, (n, 4), dtype=jnp.float64)
        return jnp.stack(
            [jnp.pi + 0.3 * x[:, 0], jnp.pi / 2 + 0.2 * x[:, 1], 0.05 * x[:, 2], 0.4 * x[:, 3]],
            axis=-1,
        )


def magnet_pendulum(mass=3.0, length=1.0, moment=0.3, n_magnets=2, g=G) -> MagnetPendulum:
    """The reference's magnet pendulum: mass 3, length 1, dipole strength 0.3, two magnets."""
    return MagnetPendulum(
        mass=check_positive("mass", mass),
        length=check_positive("length", length),
        moment=check_real("moment", moment),
        n_magnets=check_count("n_magnets", n_magnets),
        g=check_real("g", g),
    )
