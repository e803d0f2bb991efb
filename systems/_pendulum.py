"""The ideal pendulum of the HNN seed: H = 3 (1 - cos q) + p^2."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp

from ._base import AbstractSystem
from ._params import check_nonneg, check_positive, check_real
from ._seed_sampling import radius_states

# The seed's H = 3 (1 - cos q) + p^2 is a point mass m on a rod of length l with
# m l^2 = 1/2 and m g l = 3: m = 1/2, l = 1, g = 6.
MASS, LENGTH, G = 0.5, 1.0, 6.0
RADII = (1.3, 2.3)  # the seed's radii of its initial states in (q, p)


class Pendulum(AbstractSystem):
    """A point mass m on a massless rod of length l, angle q from the downward vertical:
    L = 1/2 m l^2 qdot^2 - m g l (1 - cos q).

    p = m l^2 qdot; the seed's H = 3 (1 - cos q) + p^2 at the defaults. Not an alias of
    ``chain_pendulum`` with k = 1: the same field at masses=(0.5,), lengths=(1,), g=6 (V differs
    by the constant m g l), but the seed draws its initial states in (q, p) on circles of radius
    U(1.3, 2.3) (:func:`systems._seed_sampling.radius_states`), not as the chain does.
    Drag -f m l^2 qdot.
    """

    mass: float = eqx.field(static=True, default=MASS)
    length: float = eqx.field(static=True, default=LENGTH)
    g: float = eqx.field(static=True, default=G)
    r_min: float = eqx.field(static=True, default=RADII[0])
    r_max: float = eqx.field(static=True, default=RADII[1])
    friction: float = eqx.field(static=True, default=0.0)
    angular: tuple[bool, ...] = eqx.field(static=True, default=(True,))
    name: str = eqx.field(static=True, default="pendulum")
    n_args: int = eqx.field(static=True, default=0)

    def kinetic_energy(self, q, qdot, args=None):
        """T = 1/2 m l^2 qdot^2."""
        return 0.5 * self.mass * self.length**2 * jnp.sum(qdot**2)

    def potential_energy(self, q, args=None):
        """V = m g l (1 - cos q) (zero at rest)."""
        return self.mass * self.g * self.length * jnp.sum(1.0 - jnp.cos(q))

    def potential_range(self, args=None) -> float:
        """max V - min V = 2 m g l."""
        return 2.0 * self.mass * self.g * self.length

    def positions(self, z):
        """The bob, shape (1, 2): (l sin q, -l cos q), y up."""
        q = z[0]
        return jnp.stack([self.length * jnp.sin(q), -self.length * jnp.cos(q)])[None]

    @eqx.filter_jit
    def sample_initial(self, key, n: int):
        """The seed's states: (q, p) on circles of radius U(r_min, r_max), qdot = p / (m l^2)."""
        qp = radius_states(key, n, self.r_min, self.r_max)
        return jnp.concatenate([qp[:, :1], qp[:, 1:] / (self.mass * self.length**2)], axis=-1)


def pendulum(
    mass=MASS, length=LENGTH, g=G, r_min=RADII[0], r_max=RADII[1], friction=0.0
) -> Pendulum:
    """The HNN seed's pendulum (defaults: H = 3 (1 - cos q) + p^2)."""
    r_min, r_max = check_positive("r_min", r_min), check_positive("r_max", r_max)
    if r_min > r_max:
        raise ValueError(f"r_min must be <= r_max; got r_min={r_min!r}, r_max={r_max!r}")
    return Pendulum(
        mass=check_positive("mass", mass),
        length=check_positive("length", length),
        g=check_real("g", g),
        r_min=r_min,
        r_max=r_max,
        friction=check_nonneg("friction", friction),
    )
