"""Setup shared by the model test files: tiny sizes, the chain-2 scene, and small helpers."""

import jax
import jax.numpy as jnp
import jax.random as jr

import models
from models import AbstractContinuousModel, Scene

jax.config.update("jax_enable_x64", True)

W = 16  # tiny networks: these tests check structure, not capacity
CHAIN2 = Scene(dof=2, angular=(True, True))
CHAIN2_CANONICAL = Scene(dof=2, angular=(True, True), canonical=True)
# the models with parameters (the trivial predictors have none and no vector field)
TRAINABLE = [n for n in models.available() if n not in models.trivial_models()]
# the models with a dissipation switch, and those that accept velocity coordinates only
STRUCTURED = tuple(n for n in models.available() if models.spec(n).takes_dissipation)
VELOCITY_ONLY = tuple(n for n in models.available() if models.spec(n).coordinates == ("velocity",))
G = 9.81


def _apply(model, z, args):
    if isinstance(model, AbstractContinuousModel):
        return model.vector_field(0.0, z, args)
    return model.step(z, 0.03, args)


def _scene_for(name, scene=CHAIN2):
    """``scene``, made canonical when the model accepts only momentum coordinates."""
    if "velocity" in models.coordinates(name):
        return scene
    return Scene(scene.dof, scene.angular, scene.n_args, scene.damped, canonical=True)


def _states(key, n, dof, dtype=jnp.float64):
    return jr.normal(key, (n, 2 * dof), dtype)
