"""The Lagrangian neural network (lnn): Euler-Lagrange of a learned L(q, qdot)."""

from __future__ import annotations

from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import jax.random as jr

from ._base import AbstractContinuousModel, as_dtype, split
from ._dissipation import Dissipation
from ._features import Features
from ._mlp import MLP
from ._scalar import acceleration_from_lagrangian, lagrangian_energy
from ._scene import Scene


class LNN(AbstractContinuousModel):
    """dq/dt = qdot, qddot = (d2L/dqdot2)^-1 (dL/dq - (d2L/dqdot dq) qdot + Q) for a learned
    L(q, qdot) = MLP(cos q, sin q, qdot, args) + c |qdot|^2 (softplus, the LNN seed's
    initialisation).

    c = ``kinetic_prior`` (default 0.1, the constrained-HNN reference's term; 0 is the LNN
    seed's pure form). Without it a freshly initialised MLP has d2L/dqdot2 close to singular,
    so a few training trajectories reach accelerations of 1e3 and non-finite losses at step 0
    (measured on the quick profile: 3 of 9 LNN runs diverged); with it the Hessian starts near
    2c I and the network learns the rest. Measured again for the relativistic particle (quick,
    float32, seed 0): kinetic_prior=0 gives one training chunk of 200 with a non-finite step-0
    loss (max |qddot| 2e3 at init), so the run diverges at step 0, with the default g range and
    with the slow test set alike; seeds 1 and 2 have none (smoke sizes: none in 3 seeds).

    With friction Q = -D(q) qdot the energy E = qdot . dL/dqdot - L has dE/dt = qdot . Q <= 0.
    """

    structure: ClassVar[str | None] = "lagrangian"

    second_order: ClassVar[bool] = True
    scene: Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    solve: str = eqx.field(static=True)
    eps: float = eqx.field(static=True)
    kinetic_prior: float = eqx.field(static=True)
    features: Features
    net: MLP
    dissipation: Dissipation | None

    def __init__(
        self,
        scene,
        width,
        depth,
        activation,
        dtype,
        *,
        key,
        dissipation=False,
        solve="solve",
        eps=1e-3,
        init="lnn",
        kinetic_prior=0.1,
    ):
        self.scene, self.dtype, self.solve, self.eps = scene, dtype, solve, float(eps)
        self.kinetic_prior = float(kinetic_prior)
        kl, kd = jr.split(key)
        self.features = Features(scene, controls=False)  # L never sees u
        self.net = MLP(
            self.features.size(True), 1, width, depth, activation, dtype, key=kl, init=init
        )
        self.dissipation = (
            Dissipation(self.features, width, depth, activation, dtype, key=kd)
            if dissipation
            else None
        )

    def _lagrangian(self, q, v, args):
        return self.net(self.features(q, v, args))[0] + self.kinetic_prior * (v @ v)

    def lagrangian(self, q, v, args):
        q, v, args = (as_dtype(x, self.dtype) for x in (q, v, args))
        return self._lagrangian(q, v, args)

    def energy(self, z, args):
        q, v = split(as_dtype(z, self.dtype))
        return lagrangian_energy(lambda q_, v_: self.lagrangian(q_, v_, args), q, v)

    def acceleration(self, q, v, args):
        q, v, args = (as_dtype(x, self.dtype) for x in (q, v, args))
        force = None if self.dissipation is None else self.dissipation.force(q, v, args)
        return acceleration_from_lagrangian(
            lambda q_, v_: self._lagrangian(q_, v_, args),
            q,
            v,
            force=force,
            solve=self.solve,
            eps=self.eps,
        )

    def vector_field(self, t, z, args):
        q, v = split(as_dtype(z, self.dtype))
        return jnp.concatenate([v, self.acceleration(q, v, args)])
