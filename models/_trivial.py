"""Trivial predictors: the reference lines that every learned model must beat.

They have no trainable parameters and are not integrated: ``predict(z0, ts, args)`` gives the
whole trajectory in closed form. The bench recognises them by the capability
``isinstance(model, AbstractTrivialModel)`` (equivalently ``model.trivial``), trains nothing
and evaluates their predictions with the metrics of every other model.

Momentum coordinates (a canonical scene, z = (q, p)): the prediction is made for the physical
state, so ``predict`` needs the TRUE system's maps ``velocity(q, p, args)`` and
``momentum(q, qdot, args)`` (the runner passes them); it decodes z0 to (q0, qdot0), predicts
in (q, qdot), and encodes every predicted state back to (q, p). Without the maps a canonical
prediction raises a ValueError.
"""

from __future__ import annotations

import abc
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array

from ._base import AbstractModel, as_dtype
from ._scene import Scene


class AbstractTrivialModel(AbstractModel):
    """A predictor without parameters, given by its closed-form trajectory in (q, qdot)."""

    trivial: ClassVar[bool] = True
    scene: eqx.AbstractVar[Scene]
    dtype: eqx.AbstractVar[str]

    @abc.abstractmethod
    def predict_velocity(self, q0, v0, ts) -> tuple[Array, Array]:
        """(q(t), qdot(t)), each (T, dof), from q0, qdot0 at times ts - ts[0]."""

    def predict(self, z0, ts, args=None, *, velocity=None, momentum=None) -> Array:
        """The predicted states (T, 2 dof) at ``ts``, in the scene's coordinates."""
        z0 = as_dtype(z0, self.dtype)
        ts = as_dtype(ts, self.dtype)
        d = self.scene.dof
        q0, x0 = z0[:d], z0[d:]
        if self.scene.canonical:
            if velocity is None or momentum is None:
                raise ValueError(
                    f"{type(self).__name__} in momentum coordinates needs the true system's "
                    "velocity(q, p, args) and momentum(q, qdot, args) maps"
                )
            v0 = jnp.asarray(velocity(q0, x0, args), self.dtype)
        else:
            v0 = x0
        qs, vs = self.predict_velocity(q0, v0, ts - ts[0])
        if self.scene.canonical:
            ps = jax.vmap(lambda q, v: jnp.asarray(momentum(q, v, args), self.dtype))(qs, vs)
            return jnp.concatenate([qs, ps], axis=-1)
        return jnp.concatenate([qs, vs], axis=-1)

    def predict_batch(self, z0s, ts, args=None, *, velocity=None, momentum=None) -> Array:
        """``predict`` over a batch z0s (N, 2 dof); args None, (n_args,) or (N, n_args)."""
        if args is None or jnp.ndim(args) <= 1:
            return jax.vmap(
                lambda z: self.predict(z, ts, args, velocity=velocity, momentum=momentum)
            )(z0s)
        return jax.vmap(lambda z, a: self.predict(z, ts, a, velocity=velocity, momentum=momentum))(
            z0s, args
        )


class ConstantVelocity(AbstractTrivialModel):
    """q(t) = q0 + t qdot0, qdot(t) = qdot0: the flow of dq/dt = qdot, dqdot/dt = 0.

    In momentum coordinates it is still constant velocity of the physical state: p(t) is the
    true momentum of (q(t), qdot0), which is not constant where the mass matrix depends on q.
    """

    scene: Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)

    def __init__(self, scene, dtype="float32"):
        self.scene, self.dtype = scene, dtype

    def predict_velocity(self, q0, v0, ts):
        qs = q0[None] + ts[:, None] * v0[None]
        return qs, jnp.broadcast_to(v0, qs.shape)


class AtRest(AbstractTrivialModel):
    """q(t) = q0, qdot(t) = 0 for t > 0: "the system has come to rest where it started".

    Chosen over z(t) = z0 (velocities held) because, for a damped scene, "at rest" means the
    velocities have decayed; qdot(t0) = qdot0 at the initial time itself, which the metrics
    exclude. In momentum coordinates p(t > 0) = momentum(q0, 0) = 0.
    """

    scene: Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)

    def __init__(self, scene, dtype="float32"):
        self.scene, self.dtype = scene, dtype

    def predict_velocity(self, q0, v0, ts):
        qs = jnp.broadcast_to(q0, (ts.shape[0], q0.shape[0]))
        moving = (ts > 0)[:, None]
        return qs, jnp.where(moving, jnp.zeros_like(qs), v0[None])
