"""The planar chain pendulum in absolute link angles ("complex coordinates")."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from ._base import AbstractSystem, reference_masses_lengths
from ._params import check_count, check_nonneg, check_positive_values, check_real

G = 9.81


class ChainPendulum(AbstractSystem):
    """k bobs in a vertical plane; link i (length l_i) joins bob i-1 (bob 0 = origin) to bob i.

    q = theta, the absolute angle of each link from the downward vertical;
    x_i = sum_{j<=i} l_j sin theta_j, y_i = -sum_{j<=i} l_j cos theta_j.
    L = T - V, T = 1/2 sum_i m_i |v_i|^2, V = g sum_i m_i y_i. Drag -f m_i v_i on each bob,
    which in these coordinates is exactly qddot -> qddot - f qdot.
    """

    masses: Array
    lengths: Array
    g: float = eqx.field(static=True)
    friction: float = eqx.field(static=True)
    angular: tuple[bool, ...] = eqx.field(static=True)
    name: str = eqx.field(static=True, default="chain_pendulum")
    n_args: int = eqx.field(static=True, default=0)

    def __init__(self, masses, lengths, g: float = G, friction: float = 0.0):
        self.masses = jnp.asarray(masses, dtype=jnp.float64)
        self.lengths = jnp.asarray(lengths, dtype=jnp.float64)
        self.g = float(g)
        self.friction = float(friction)
        self.angular = (True,) * int(self.masses.shape[0])

    def _cartesian(self, q, qdot):
        x = jnp.cumsum(self.lengths * jnp.sin(q))
        y = -jnp.cumsum(self.lengths * jnp.cos(q))
        vx = jnp.cumsum(self.lengths * jnp.cos(q) * qdot)
        vy = jnp.cumsum(self.lengths * jnp.sin(q) * qdot)
        return x, y, vx, vy

    def kinetic_energy(self, q, qdot, args=None):
        """T = 1/2 sum_i m_i (vx_i^2 + vy_i^2)."""
        _, _, vx, vy = self._cartesian(q, qdot)
        return 0.5 * jnp.sum(self.masses * (vx**2 + vy**2))

    def potential_energy(self, q, args=None):
        """V = g sum_i m_i y_i."""
        y = -jnp.cumsum(self.lengths * jnp.cos(q))
        return self.g * jnp.sum(self.masses * y)

    def positions(self, z):
        """Bob positions (k, 2): (x_i, y_i), y up."""
        x, y, _, _ = self._cartesian(z[: self.dof], z[self.dof :])
        return jnp.stack([x, y], axis=-1)

    def potential_range(self, args=None) -> float:
        """max V - min V = 2 g sum_j l_j sum_{i>=j} m_i (all links up minus all links down)."""
        tail_mass = np.cumsum(np.asarray(self.masses)[::-1])[::-1]
        return float(2.0 * self.g * np.sum(np.asarray(self.lengths) * tail_mass))

    @eqx.filter_jit
    def sample_initial(self, key, n: int):
        """Random states spread like those of the paper's public code.

        Angles and rates N(0, 1); Cartesian bob positions jittered by 0.2 N(0, 1) and projected
        back onto the links (the angle of each jittered link vector); Cartesian velocities set to
        3 (0.5 v + 0.4 N(0, 1)) and projected back by least squares on the link Jacobian.
        """
        k = self.dof
        k_th, k_om, k_pos, k_vel = jax.random.split(key, 4)
        theta = jax.random.normal(k_th, (n, k), dtype=jnp.float64)
        omega = jax.random.normal(k_om, (n, k), dtype=jnp.float64)
        pos_noise = 0.2 * jax.random.normal(k_pos, (n, k, 2), dtype=jnp.float64)
        vel_noise = 0.4 * jax.random.normal(k_vel, (n, 2 * k), dtype=jnp.float64)

        x, y, vx, vy = jax.vmap(self._cartesian)(theta, omega)
        pos = jnp.stack([x, y], axis=-1) + pos_noise
        links = jnp.diff(pos, axis=1, prepend=jnp.zeros((n, 1, 2)))
        theta2 = jnp.arctan2(links[..., 0], -links[..., 1])
        target = 3.0 * (0.5 * jnp.concatenate([vx, vy], axis=-1) + vel_noise)
        # Link Jacobian d(x, y)/d theta: row i, column j is l_j (cos, sin) theta_j for j <= i.
        tri = jnp.tril(jnp.ones((k, k)))
        lc = self.lengths * jnp.cos(theta2)
        ls = self.lengths * jnp.sin(theta2)
        jac = jnp.concatenate([tri * lc[:, None, :], tri * ls[:, None, :]], axis=1)
        jtj = jnp.einsum("nij,nik->njk", jac, jac)
        jtv = jnp.einsum("nij,ni->nj", jac, target)
        omega2 = jnp.linalg.solve(jtj, jtv[..., None])[..., 0]
        return jnp.concatenate([theta2, omega2], axis=-1)


def chain_pendulum(k, masses=None, lengths=None, g=G, friction=0.0) -> ChainPendulum:
    """A chain pendulum of k links; masses/lengths default to the reference table."""
    k = check_count("k", k)
    ref_m, ref_l = reference_masses_lengths(k)
    masses = ref_m if masses is None else check_positive_values("masses", masses, k)
    lengths = ref_l if lengths is None else check_positive_values("lengths", lengths, k)
    g = check_real("g", g)
    friction = check_nonneg("friction", friction)
    return ChainPendulum(masses, lengths, g=g, friction=friction)
