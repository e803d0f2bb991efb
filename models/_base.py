"""The model family: abstract classes that the bench, the integrators and the tests rely on."""

from __future__ import annotations

import abc
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array

from ._scene import Scene


def as_dtype(x, dtype) -> Array:
    """Cast an input (state, args, time step) to the model's dtype; None args -> shape (0,)."""
    if x is None:
        return jnp.zeros((0,), dtype)
    return jnp.asarray(x, dtype)


def split(z: Array) -> tuple[Array, Array]:
    """(q, second half) of a state z = (q, qdot) or (q, p) along its last axis."""
    d = z.shape[-1] // 2
    return z[..., :d], z[..., d:]


class AbstractModel(eqx.Module):
    """A learned model of the dynamics of a :class:`Scene`.

    ``penalty(zs, args)`` is a soft-bias term that the trainer adds to the loss, evaluated on
    the rollout states zs (..., 2 dof); zero unless a model defines one.
    """

    scene: eqx.AbstractVar[Scene]
    dtype: eqx.AbstractVar[str]
    # Capability markers, read by ``models.spec``: the energy structure the model is built on
    # ("hamiltonian", "lagrangian" or None) and whether it is a parameter-free predictor;
    # ``takes_controls``: some part of it reads the control input u of a controlled scene
    # (the tail of ``args``); ``forced``: a free learned force enters its field, so its learned
    # energy is not conserved even without damping.
    structure: ClassVar[str | None] = None
    trivial: ClassVar[bool] = False
    takes_controls: ClassVar[bool] = False
    forced: ClassVar[bool] = False

    def penalty(self, zs, args) -> Array:
        return jnp.zeros((), self.dtype)


class AbstractContinuousModel(AbstractModel):
    """A learned vector field dz/dt = F(t, z, args), integrated by ``models.rollout``.

    Second-order models have dq/dt = qdot exactly and expose ``acceleration(q, v, args)``, so
    that a leapfrog integrator can use them.
    """

    second_order: ClassVar[bool] = False

    @abc.abstractmethod
    def vector_field(self, t, z, args) -> Array:
        """dz/dt for one state z (2 dof,) and args (n_args,), or (n_args + n_controls,) =
        (static args, u) in a controlled scene."""

    def acceleration(self, q, v, args) -> Array:
        """qddot(q, v); only second-order models define it."""
        raise NotImplementedError(f"{type(self).__name__} is not a second-order model")

    # The coordinates the integrator works in. ``rollout`` (fixed-step Runge-Kutta and
    # adaptive) integrates dy/dt = internal_field(t, y, args) from y0 = encode(z0) and maps
    # every saved state back with decode; the continuous flow must be the same as that of
    # vector_field in z, i.e. internal_field(t, encode(z)) = D encode(z) vector_field(t, z).
    # A model overrides the three together when its field is cheaper in other coordinates
    # (the Hamiltonian models: canonical (q, p) instead of (q, qdot)).

    def encode(self, z, args) -> Array:
        """y = phi(z): the integrator's coordinates of a state z (identity by default)."""
        return z

    def decode(self, y, args) -> Array:
        """z = phi^-1(y) (identity by default)."""
        return y

    def internal_field(self, t, y, args) -> Array:
        """dy/dt in the integrator's coordinates (by default vector_field itself)."""
        return self.vector_field(t, y, args)


class AbstractDiscreteModel(AbstractModel):
    """A learned map z_n -> z_{n+1} over one time step dt: the integrator is the model."""

    @abc.abstractmethod
    def step(self, z, dt, args) -> Array:
        """z_{n+1} for one state z (2 dof,), time step dt and args (n_args,) ((static args,
        u) in a controlled scene)."""
