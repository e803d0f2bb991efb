"""The HNN seed's initial states for its 1-D tasks (greydanus/hamiltonian-nn, data.py).

A direction (q, p) uniform on [-1, 1]^2, normalised, scaled to a radius drawn uniformly from
[r_min, r_max]: the states lie on the circles q^2 + p^2 = r^2, which for the mass-spring are
its energy levels (H = q^2 + p^2 = r^2). Shared by ``mass_spring`` and ``pendulum``.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp


def radius_states(key, n: int, r_min: float, r_max: float):
    """``n`` canonical states (q, p) at radii uniform on [r_min, r_max], shape (n, 2)."""
    k_dir, k_r = jax.random.split(key)
    direction = jax.random.uniform(k_dir, (n, 2), dtype=jnp.float64, minval=-1.0, maxval=1.0)
    # a direction of length 0 has probability 0; the floor keeps a traced draw finite anyway
    norm = jnp.maximum(jnp.linalg.norm(direction, axis=-1, keepdims=True), 1e-300)
    radius = jax.random.uniform(k_r, (n, 1), dtype=jnp.float64, minval=r_min, maxval=r_max)
    return direction / norm * radius
