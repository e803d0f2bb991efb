"""How states enter a network: angles as (cos q, sin q), then velocities/momenta, then args."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from ._scene import Scene


class Features(eqx.Module):
    """x = (cos q_a, sin q_a, q_c, [v], args) for angular coordinates a and the others c.

    Angles enter through cos and sin so that every network is 2 pi periodic in them (the
    paper's embedding); derivatives with respect to raw q flow through the embedding.
    """

    angular: tuple[bool, ...] = eqx.field(static=True)
    n_args: int = eqx.field(static=True)

    def __init__(self, scene: Scene):
        self.angular = scene.angular
        self.n_args = scene.n_args

    @property
    def dof(self) -> int:
        return len(self.angular)

    def size(self, with_velocity: bool) -> int:
        n_ang = sum(self.angular)
        return self.dof + n_ang + (self.dof if with_velocity else 0) + self.n_args

    def __call__(self, q: Array, v: Array | None, args: Array) -> Array:
        ang = np.flatnonzero(self.angular)
        lin = np.flatnonzero(~np.asarray(self.angular, bool))
        parts = [jnp.cos(q[ang]), jnp.sin(q[ang]), q[lin]]
        if v is not None:
            parts.append(v)
        if self.n_args:
            parts.append(args)
        return jnp.concatenate(parts)
