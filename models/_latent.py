"""Dynamics learned in the latent space of an autoencoder (the HNN and VIN seeds' pixel
models): encode an observation to z, step z with one of the suite's dynamics models on a
latent :class:`Scene`, decode the states back to observations.

The dynamics part is any registered model (``models.make``) on the scene of ``latent_dof``
plain (non-angular) coordinates: canonical z = (q, p) where the model accepts momenta (``hnn``:
J grad H; ``node``: the HNN seed's baseline MLP field), z = (q, qdot) otherwise (``vin``: the
VIN seed's variational integrator; ``resnet``: its residual baseline). Rollouts go through
``models.rollout`` like every other model's.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.random as jr
from jaxtyping import Array

from ._autoencoder import Autoencoder
from ._base import AbstractModel
from ._hnn import HNN
from ._integrators import Integrator, rollout
from ._registry import coordinates, make
from ._scene import Scene
from ._vin import VIN

_RK4 = Integrator("rk4_38")


def latent_scene(name: str, latent_dof: int = 1) -> Scene:
    """The latent scene of dynamics model ``name``: canonical where it accepts momenta."""
    return Scene(
        dof=latent_dof,
        angular=(False,) * latent_dof,
        canonical="momentum" in coordinates(name),
    )


class LatentModel(eqx.Module):
    """An :class:`Autoencoder` with 2 ``latent_dof`` latent numbers and a dynamics model on
    them. ``predict(x0, ts, integrator)`` encodes x0, rolls the latent state out over ``ts``
    and decodes every state: (len(ts), *obs_shape); ``latent_energy(z)`` the model's learned
    conserved scalar (the HNN's H, the VIN's discrete energy 1/2 v^T M v + U), None for a
    model without one. ``options``: the dynamics model's options (``models.make``), e.g.
    ``{"init": "hnn_seed"}``."""

    autoencoder: Autoencoder
    dynamics: AbstractModel

    def __init__(
        self,
        name: str,
        obs_shape,
        *,
        key,
        latent_dof: int = 1,
        width: int = 200,
        depth: int = 2,
        ae_width: int = 200,
        activation: str | None = None,
        ae_activation: str = "relu",
        dtype: str = "float32",
        options=(),
    ):
        ka, kd = jr.split(key)
        scene = latent_scene(name, latent_dof)
        self.autoencoder = Autoencoder(
            obs_shape, 2 * latent_dof, ae_width, 2, ae_activation, dtype, key=ka
        )
        self.dynamics = make(
            name,
            scene,
            key=kd,
            width=width,
            depth=depth,
            activation=activation,
            dtype=dtype,
            **dict(options),
        )

    def encode(self, x) -> Array:
        return self.autoencoder.encode(x)

    def decode(self, z) -> Array:
        return self.autoencoder.decode(z)

    def rollout(self, z0, ts, integrator: Integrator = _RK4) -> Array:
        """Latent states (len(ts), 2 latent_dof) from z0."""
        return rollout(self.dynamics, z0, ts, None, integrator)

    def predict(self, x0, ts, integrator: Integrator = _RK4) -> Array:
        zs = self.rollout(self.encode(x0), ts, integrator)
        return jax.vmap(self.decode)(zs)

    @property
    def has_energy(self) -> bool:
        return isinstance(self.dynamics, HNN | VIN)

    def latent_energy(self, z) -> Array | None:
        if isinstance(self.dynamics, HNN):
            return self.dynamics.hamiltonian(z, None)
        if isinstance(self.dynamics, VIN):
            return self.dynamics.energy(z, None)
        return None
