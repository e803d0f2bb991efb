"""How states enter a network: angles as (cos q, sin q), then velocities/momenta, then args,
then (where the network may depend on it) the control input u."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from ._scene import Scene, Standardisation


class Features(eqx.Module):
    """x = (cos q_a, sin q_a, q_c, [v], args, [u]) for angular coordinates a and the others c.

    Angles enter through cos and sin so that every network is 2 pi periodic in them (the
    paper's embedding); derivatives with respect to raw q flow through the embedding.

    In a controlled scene a model's ``args`` is (static args, u) of length n_args + n_controls.
    ``controls=True`` appends u to the input; ``without_controls()`` gives the features of a
    part that must not depend on u (a mass matrix, a potential, H or L): it reads the static
    args only. Either way the args must have the scene's full length (checked at trace time).

    With the scene's ``standardisation``, q_c, v (velocities or momenta alike) and u enter as
    (x - loc) / scale.
    """

    angular: tuple[bool, ...] = eqx.field(static=True)
    n_args: int = eqx.field(static=True)
    n_controls: int = eqx.field(static=True)
    controls: bool = eqx.field(static=True)
    standardisation: Standardisation | None = eqx.field(static=True)

    def __init__(self, scene: Scene, *, controls: bool = True):
        self.angular = scene.angular
        self.n_args = scene.n_args
        self.n_controls = scene.n_controls
        self.controls = bool(controls)
        self.standardisation = scene.standardisation

    def without_controls(self) -> Features:
        """The same embedding with u left out of the input."""
        scene = Scene(
            len(self.angular),
            self.angular,
            self.n_args,
            n_controls=self.n_controls,
            standardisation=self.standardisation,
        )
        return Features(scene, controls=False)

    @property
    def dof(self) -> int:
        return len(self.angular)

    @property
    def reads_controls(self) -> int:
        """How many control inputs this network reads (0 or n_controls)."""
        return self.n_controls if self.controls else 0

    def size(self, with_velocity: bool) -> int:
        n_ang = sum(self.angular)
        v = self.dof if with_velocity else 0
        return self.dof + n_ang + v + self.n_args + self.reads_controls

    def _standard(self, x: Array, which: str, index=slice(None)) -> Array:
        """x -> (x - loc) / scale with the standardisation's ``which`` ("q", "v", "u")
        statistics at ``index``; x itself without a standardisation."""
        st = self.standardisation
        if st is None:
            return x
        loc = np.asarray(getattr(st, f"{which}_loc"))[index]
        scale = np.asarray(getattr(st, f"{which}_scale"))[index]
        return (x - jnp.asarray(loc, x.dtype)) / jnp.asarray(scale, x.dtype)

    def __call__(self, q: Array, v: Array | None, args: Array) -> Array:
        ang = np.flatnonzero(self.angular)
        lin = np.flatnonzero(~np.asarray(self.angular, bool))
        parts = [jnp.cos(q[ang]), jnp.sin(q[ang]), self._standard(q[lin], "q", lin)]
        if v is not None:
            parts.append(self._standard(v, "v"))
        if self.n_controls == 0:
            if self.n_args:
                parts.append(args)
            return jnp.concatenate(parts)
        if args.shape[-1] != self.n_args + self.n_controls:
            raise ValueError(
                f"a controlled scene's args are (static args, u) of length "
                f"{self.n_args} + {self.n_controls}; got shape {args.shape}"
            )
        parts.append(args[: self.n_args])
        if self.reads_controls:
            parts.append(self._standard(args[self.n_args :], "u"))
        return jnp.concatenate(parts)
