"""The 3-D spring pendulum in Cartesian coordinates ("simple coordinates")."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
from jax import Array

from ._base import AbstractSystem, reference_masses_lengths
from ._params import check_count, check_nonneg, check_positive, check_positive_values, check_real

G = 9.81
INITIALS = ("equilibrium", "paper")


class SpringPendulum(AbstractSystem):
    """k bobs in 3-D joined in a chain by springs of constant kappa; z is up.

    q = (x_1, y_1, z_1, x_2, ...). Spring 1 joins bob 1 to the origin with rest length 0,
    spring i > 1 joins bob i-1 to bob i with rest length 1.
    L = T - V, T = 1/2 sum_i m_i |v_i|^2,
    V = g sum_i m_i z_i + 1/2 kappa |x_1|^2 + sum_{i>1} 1/2 kappa (|x_i - x_{i-1}| - 1)^2.
    Drag -f m_i v_i on each bob: vdot -> vdot - f v.

    ``initial`` picks the distribution of :meth:`sample_initial`: "equilibrium" (default) about
    the true static equilibrium, "paper" about the reference's heights (see there).
    """

    masses: Array
    g: float = eqx.field(static=True)
    spring_constant: float = eqx.field(static=True)
    friction: float = eqx.field(static=True)
    angular: tuple[bool, ...] = eqx.field(static=True)
    initial: str = eqx.field(static=True)
    name: str = eqx.field(static=True, default="spring_pendulum")
    n_args: int = eqx.field(static=True, default=0)

    def __init__(
        self,
        masses,
        g: float = G,
        spring_constant: float = 10.0,
        friction=0.0,
        initial: str = "equilibrium",
    ):
        self.initial = initial
        self.masses = jnp.asarray(masses, dtype=jnp.float64)
        self.g = float(g)
        self.spring_constant = float(spring_constant)
        self.friction = float(friction)
        self.angular = (False,) * (3 * int(self.masses.shape[0]))

    @property
    def bodies(self) -> int:
        return int(self.masses.shape[0])

    def kinetic_energy(self, q, qdot, args=None):
        """T = 1/2 sum_i m_i |v_i|^2."""
        v = qdot.reshape(self.bodies, 3)
        return 0.5 * jnp.sum(self.masses * jnp.sum(v**2, axis=-1))

    def potential_energy(self, q, args=None):
        """Gravity plus springs (rest lengths 0 for the first, 1 for the others)."""
        x = q.reshape(self.bodies, 3)
        gravity = self.g * jnp.sum(self.masses * x[:, 2])
        # The first spring has rest length 0: |x_1|^2 has a smooth gradient at x_1 = 0 where
        # the norm's has none.
        first = 0.5 * self.spring_constant * jnp.sum(x[0] ** 2)
        stretch = jnp.linalg.norm(jnp.diff(x, axis=0), axis=-1) - 1.0
        others = 0.5 * self.spring_constant * jnp.sum(stretch**2)
        return gravity + first + others

    def equilibrium(self) -> Array:
        """Static equilibrium: bob i hangs below bob i-1 by r_i + g sum_{j>=i} m_j / kappa."""
        tail_mass = jnp.cumsum(self.masses[::-1])[::-1]
        rest = jnp.ones(self.bodies).at[0].set(0.0)
        drop = rest + self.g * tail_mass / self.spring_constant
        x = jnp.zeros((self.bodies, 3)).at[:, 2].set(-jnp.cumsum(drop))
        return x.reshape(-1)

    def reference_heights(self) -> Array:
        """The reference's "equilibrium" (ngruver/decon-hnn, spring_pendulum.py): bob i at
        height cumsum_j<=i (-g sum_{l>=j} m'_l / kappa), ignoring the rest length 1 of springs
        2..k and taking the masses m' in draw order (the bodies get them reversed), so bob i
        sits about i - 1 m above :meth:`equilibrium` (k = 2: 0.87 m; k = 3: 0.96, 1.92)."""
        draw_order = self.masses[::-1]
        tail_mass = jnp.cumsum(draw_order[::-1])[::-1]
        heights = jnp.cumsum(-self.g * tail_mass / self.spring_constant)
        return jnp.zeros((self.bodies, 3)).at[:, 2].set(heights).reshape(-1)

    def positions(self, z):
        """Bob positions (k, 3)."""
        return z[: self.dof].reshape(self.bodies, 3)

    @eqx.filter_jit
    def sample_initial(self, key, n: int):
        """Centre + 0.8 N(0,1) vertically + 0.4 N(0,1) on every coordinate; v ~ 0.6 N(0,1).

        The centre is :meth:`equilibrium` (``initial="equilibrium"``) or the reference's
        :meth:`reference_heights` (``initial="paper"``); the noise is the reference's.
        """
        k_z, k_q, k_v = jax.random.split(key, 3)
        centre = self.reference_heights() if self.initial == "paper" else self.equilibrium()
        q = jnp.broadcast_to(centre, (n, self.dof))
        vertical = 0.8 * jax.random.normal(k_z, (n, self.bodies), dtype=jnp.float64)
        q = q.reshape(n, self.bodies, 3).at[:, :, 2].add(vertical).reshape(n, self.dof)
        q = q + 0.4 * jax.random.normal(k_q, (n, self.dof), dtype=jnp.float64)
        v = 0.6 * jax.random.normal(k_v, (n, self.dof), dtype=jnp.float64)
        return jnp.concatenate([q, v], axis=-1)


def spring_pendulum(
    k, masses=None, g=G, spring_constant=10.0, friction=0.0, initial="equilibrium"
) -> SpringPendulum:
    """A spring pendulum of k bobs; masses default to the reference table.

    ``initial``: "equilibrium" (initial states about the true equilibrium) or "paper" (about
    the heights of the paper's public code, bob i about i - 1 m higher).
    """
    if not isinstance(initial, str) or initial not in INITIALS:
        raise ValueError(f"initial must be one of {', '.join(INITIALS)}; got {initial!r}")
    k = check_count("k", k)
    ref_m, _ = reference_masses_lengths(k)
    masses = ref_m if masses is None else check_positive_values("masses", masses, k)
    g = check_real("g", g)
    spring_constant = check_positive("spring_constant", spring_constant)
    friction = check_nonneg("friction", friction)
    return SpringPendulum(
        masses, g=g, spring_constant=spring_constant, friction=friction, initial=initial
    )
