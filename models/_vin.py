"""Variational integrator networks: the Verlet VIN (vin) and the general implicit one
(vin_implicit).
"""

from __future__ import annotations

from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.random as jr

from ._base import AbstractDiscreteModel, as_dtype, split
from ._dissipation import Dissipation
from ._features import Features
from ._mass import MASS_EPS, CholeskyNet
from ._mlp import MLP
from ._scene import Scene
from ._variational import midpoint_variational_step, verlet_step


class VIN(AbstractDiscreteModel):
    """Variational integrator network: velocity Verlet of L = 1/2 v^T M v - U(q).

    M = C C^T a learned constant positive-definite matrix (C starts at the identity), U an
    MLP. With dissipation a learned constant PSD friction D enters as a trapezoidal discrete
    Lagrange-d'Alembert force (see :func:`verlet_step`).
    """

    structure: ClassVar[str | None] = "lagrangian"

    scene: Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    features: Features
    potential: MLP
    mass: CholeskyNet
    dissipation: Dissipation | None

    def __init__(self, scene, width, depth, activation, dtype, *, key, dissipation=False):
        self.scene, self.dtype = scene, dtype
        self.features = Features(scene, controls=False)  # L never sees u
        self.potential = MLP(self.features.size(False), 1, width, depth, activation, dtype, key=key)
        self.mass = CholeskyNet(
            self.features,
            width,
            depth,
            activation,
            dtype,
            key=key,
            state_dependent=False,
            eps=MASS_EPS,
        )
        self.dissipation = (
            Dissipation(
                self.features, width, depth, activation, dtype, key=key, state_dependent=False
            )
            if dissipation
            else None
        )

    def potential_energy(self, q, args):
        return self.potential(self.features(q, None, args))[0]

    def lagrangian(self, q, v, args):
        q, v, args = (as_dtype(x, self.dtype) for x in (q, v, args))
        m = self.mass.matrix(q, args)
        return 0.5 * v @ (m @ v) - self.potential_energy(q, args)

    def energy(self, z, args):
        q, v = split(as_dtype(z, self.dtype))
        args = as_dtype(args, self.dtype)
        m = self.mass.matrix(q, args)
        return 0.5 * v @ (m @ v) + self.potential_energy(q, args)

    def step(self, z, dt, args):
        q, v = split(as_dtype(z, self.dtype))
        args, dt = as_dtype(args, self.dtype), as_dtype(dt, self.dtype)
        grad_U = jax.grad(lambda q_: self.potential_energy(q_, args))
        damping = None if self.dissipation is None else self.dissipation.matrix(q, args)
        q1, v1 = verlet_step(grad_U, self.mass.factor(q, args), q, v, dt, damping)
        return jnp.concatenate([q1, v1])


class ImplicitVIN(AbstractDiscreteModel):
    """Variational integrator network for a general L(q, v) = 1/2 |v|^2 + MLP(q, v, args).

    One step is the midpoint-rule discrete Euler-Lagrange equation, solved by Newton with
    implicit differentiation (:func:`midpoint_variational_step`); the state velocity is mapped
    to and from the discrete momenta with the continuous Legendre map. The 1/2 |v|^2 prior
    keeps d2L/dv2 near the identity at initialisation, so both Newton solves are well posed;
    the MLP can learn any correction. With dissipation, Q = -D(q) v (learned PSD D(q)).
    """

    structure: ClassVar[str | None] = "lagrangian"

    scene: Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    newton_steps: int = eqx.field(static=True)
    features: Features
    net: MLP
    dissipation: Dissipation | None

    def __init__(
        self, scene, width, depth, activation, dtype, *, key, dissipation=False, newton_steps=20
    ):
        self.scene, self.dtype, self.newton_steps = scene, dtype, int(newton_steps)
        kl, kd = jr.split(key)
        self.features = Features(scene, controls=False)  # L never sees u
        self.net = MLP(self.features.size(True), 1, width, depth, activation, dtype, key=kl)
        self.dissipation = (
            Dissipation(self.features, width, depth, activation, dtype, key=kd)
            if dissipation
            else None
        )

    def lagrangian(self, q, v, args):
        q, v, args = (as_dtype(x, self.dtype) for x in (q, v, args))
        return 0.5 * (v @ v) + self.net(self.features(q, v, args))[0]

    def step_with_status(self, z, dt, args):
        """(z_{n+1}, converged): the step and whether both Newton solves converged."""
        q, v = split(as_dtype(z, self.dtype))
        args, dt = as_dtype(args, self.dtype), as_dtype(dt, self.dtype)
        L = lambda q_, v_: 0.5 * (v_ @ v_) + self.net(self.features(q_, v_, args))[0]
        force = None
        if self.dissipation is not None:
            force = lambda q_, v_: self.dissipation.force(q_, v_, args)
        q1, v1, ok = midpoint_variational_step(L, q, v, dt, force, self.newton_steps)
        return jnp.concatenate([q1, v1]), ok

    def step(self, z, dt, args):
        return self.step_with_status(z, dt, args)[0]
