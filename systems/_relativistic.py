"""The 1-D relativistic particle in a uniform potential (LNN seed, c = 1, unit mass)."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ._base import AbstractSystem
from ._params import check_positive, check_real

G_DEFAULT = 1.0
G_RANGE = (0.5, 2.0)
MAX_SPEED = 0.9


class RelativisticParticle(AbstractSystem):
    """L = (1 - qdot^2)^(-1/2) - 1 + g q, the Lagrangian of the LNN seed.

    T = (1 - qdot^2)^(-1/2) - 1, V = -g q. Canonical momentum p = qdot (1 - qdot^2)^(-3/2)
    (not qdot), and the Euler-Lagrange equation dp/dt = g gives
    qddot = g (1 - qdot^2)^(5/2) / (1 + 2 qdot^2), so |qdot| < 1 for all time.
    ``args = (g,)`` per trajectory; ``self.g`` (default 1.0) is used when ``args`` is None.
    Training data draw g uniform on [g_min, g_max] (default [0.5, 2.0]; :meth:`sample_args`,
    the seed gives no range) and start speeds uniform on [-v0_max, v0_max] (default 0.9).
    """

    g: float = eqx.field(static=True, default=G_DEFAULT)
    v0_max: float = eqx.field(static=True, default=MAX_SPEED)
    g_min: float = eqx.field(static=True, default=G_RANGE[0])
    g_max: float = eqx.field(static=True, default=G_RANGE[1])
    friction: float = eqx.field(static=True, default=0.0)
    angular: tuple[bool, ...] = eqx.field(static=True, default=(False,))
    name: str = eqx.field(static=True, default="relativistic_particle")
    n_args: int = eqx.field(static=True, default=1)

    def default_args(self):
        return jnp.array([self.g], dtype=jnp.float64)

    def kinetic_energy(self, q, qdot, args=None):
        """T = (1 - qdot^2)^(-1/2) - 1."""
        return jnp.sum((1.0 - qdot**2) ** -0.5 - 1.0)

    def potential_energy(self, q, args=None):
        """V = -g q with g = args[0]."""
        return -self._args(args)[0] * jnp.sum(q)

    def velocity(self, q, p, args=None):
        """Inverse of p = qdot (1 - qdot^2)^(-3/2), in closed form.

        With s = qdot / sqrt(1 - qdot^2), p = s + s^3, whose one real root is
        s = 2/sqrt(3) sinh(asinh(3 sqrt(3) p / 2) / 3) (trigonometric Cardano form, free of
        cancellation); one Newton step polishes it to rounding; qdot = s / sqrt(1 + s^2).
        """
        del q, args
        s = 2.0 / jnp.sqrt(3.0) * jnp.sinh(jnp.arcsinh(1.5 * jnp.sqrt(3.0) * p) / 3.0)
        s = s - (s + s**3 - p) / (1.0 + 3.0 * s**2)
        return s / jnp.sqrt(1.0 + s**2)

    def acceleration_closed_form(self, q, qdot, args=None):
        """qddot = g (1 - qdot^2)^(5/2) / (1 + 2 qdot^2) (independent route to the same field)."""
        g = self._args(args)[0]
        return g * (1.0 - qdot**2) ** 2.5 / (1.0 + 2.0 * qdot**2)

    def positions(self, z):
        """The particle's position, shape (1, 1)."""
        return z[:1].reshape(1, 1)

    def check_states(self, z: np.ndarray) -> None:
        if not np.all(np.abs(z[..., 1]) < 1.0):
            raise ValueError("relativistic_particle needs |qdot| < 1 (c = 1) in every state")

    @eqx.filter_jit
    def sample_initial(self, key, n: int):
        """q ~ N(0, 1), qdot ~ U(-v0_max, v0_max): inside the light cone |qdot| < 1."""
        k_q, k_v = jax.random.split(key)
        q = jax.random.normal(k_q, (n, 1), dtype=jnp.float64)
        v = jax.random.uniform(
            k_v, (n, 1), dtype=jnp.float64, minval=-self.v0_max, maxval=self.v0_max
        )
        return jnp.concatenate([q, v], axis=-1)

    @eqx.filter_jit
    def sample_args(self, key, n: int):
        """g ~ U(g_min, g_max) per trajectory, shape (n, 1)."""
        return jax.random.uniform(
            key, (n, 1), dtype=jnp.float64, minval=self.g_min, maxval=self.g_max
        )


def relativistic_particle(
    g=G_DEFAULT, v0_max=MAX_SPEED, g_min=G_RANGE[0], g_max=G_RANGE[1]
) -> RelativisticParticle:
    """The relativistic particle with default potential gradient g.

    ``v0_max`` in (0, 1) bounds the initial speeds; random g (``random_args``) are drawn from
    [g_min, g_max] (g_min <= g_max, both finite).
    """
    g = check_real("g", g)
    v0_max = check_positive("v0_max", v0_max)
    if not v0_max < 1.0:
        raise ValueError(f"v0_max must be in (0, 1) (speeds below c = 1); got {v0_max!r}")
    g_min, g_max = check_real("g_min", g_min), check_real("g_max", g_max)
    if g_min > g_max:
        raise ValueError(f"g_min must be <= g_max; got g_min={g_min!r}, g_max={g_max!r}")
    return RelativisticParticle(g=g, v0_max=v0_max, g_min=g_min, g_max=g_max)
