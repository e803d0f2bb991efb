"""The ideal 1-D mass-spring of the HNN seed: H = q^2 + p^2."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp

from ._base import AbstractSystem
from ._params import check_nonneg, check_positive
from ._seed_sampling import radius_states

# The seed's H = p^2 + q^2 is T = p^2 / (2 m), V = 1/2 k q^2 with m = 1/2, k = 2 (omega = 2).
MASS, SPRING = 0.5, 2.0
RADII = (0.1, 1.0)  # the seed's radii of its initial states in (q, p)


class MassSpring(AbstractSystem):
    """A mass m on a spring of constant k, 1-D: L = 1/2 m qdot^2 - 1/2 k q^2.

    p = m qdot, H = p^2 / (2 m) + 1/2 k q^2; the seed's H = q^2 + p^2 at the defaults
    (m = 1/2, k = 2), so q(t) = A cos(2 t + phi), period pi. Drag -f m qdot.
    Initial states: the seed's (:func:`systems._seed_sampling.radius_states`), drawn in (q, p)
    on the circles of radius r ~ U(r_min, r_max) = U(0.1, 1.0), then qdot = p / m.
    """

    mass: float = eqx.field(static=True, default=MASS)
    spring_constant: float = eqx.field(static=True, default=SPRING)
    r_min: float = eqx.field(static=True, default=RADII[0])
    r_max: float = eqx.field(static=True, default=RADII[1])
    friction: float = eqx.field(static=True, default=0.0)
    angular: tuple[bool, ...] = eqx.field(static=True, default=(False,))
    name: str = eqx.field(static=True, default="mass_spring")
    n_args: int = eqx.field(static=True, default=0)

    def kinetic_energy(self, q, qdot, args=None):
        """T = 1/2 m qdot^2."""
        return 0.5 * self.mass * jnp.sum(qdot**2)

    def potential_energy(self, q, args=None):
        """V = 1/2 k q^2."""
        return 0.5 * self.spring_constant * jnp.sum(q**2)

    def positions(self, z):
        """The mass's displacement, shape (1, 1)."""
        return z[:1].reshape(1, 1)

    @eqx.filter_jit
    def sample_initial(self, key, n: int):
        """The seed's states: (q, p) on circles of radius U(r_min, r_max), qdot = p / m."""
        qp = radius_states(key, n, self.r_min, self.r_max)
        return jnp.concatenate([qp[:, :1], qp[:, 1:] / self.mass], axis=-1)


def mass_spring(
    mass=MASS, spring_constant=SPRING, r_min=RADII[0], r_max=RADII[1], friction=0.0
) -> MassSpring:
    """The HNN seed's mass-spring (defaults: H = q^2 + p^2)."""
    r_min, r_max = check_positive("r_min", r_min), check_positive("r_max", r_max)
    if r_min > r_max:
        raise ValueError(f"r_min must be <= r_max; got r_min={r_min!r}, r_max={r_max!r}")
    return MassSpring(
        mass=check_positive("mass", mass),
        spring_constant=check_positive("spring_constant", spring_constant),
        r_min=r_min,
        r_max=r_max,
        friction=check_nonneg("friction", friction),
    )
