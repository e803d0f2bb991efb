"""Setup shared by the model test files: tiny sizes, the chain-2 scene, and small helpers."""

import jax
import jax.numpy as jnp
import jax.random as jr

from models import AbstractContinuousModel, Scene

jax.config.update("jax_enable_x64", True)

W = 16  # tiny networks: these tests check structure, not capacity
CHAIN2 = Scene(dof=2, angular=(True, True))
STRUCTURED = ("hnn", "hnn_so", "lnn", "vin", "vin_implicit")
VELOCITY_ONLY = ("lnn", "vin", "vin_implicit")
G = 9.81


def _apply(model, z, args):
    if isinstance(model, AbstractContinuousModel):
        return model.vector_field(0.0, z, args)
    return model.step(z, 0.03, args)


def _states(key, n, dof, dtype=jnp.float64):
    return jr.normal(key, (n, 2 * dof), dtype)
