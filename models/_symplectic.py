"""The soft symplectic bias: how far a vector field is from being (locally) Hamiltonian."""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jaxtyping import Array

from ._base import AbstractContinuousModel, as_dtype
from ._scalar import symplectic_matrix


def symplectic_error(model, zs, args) -> Array:
    """mean over states of ||J DF - (J DF)^T||_F^2, DF = dF/dz the Jacobian of the field.

    Zero exactly when J DF is symmetric, i.e. F is locally J grad H. ``zs``: (..., 2 dof);
    ``args``: (n_args,) shared, or (..., n_args) per state (leading axes like zs); in a
    controlled scene n_args + n_controls (static args, then the u held at each state).
    """
    if not isinstance(model, AbstractContinuousModel):
        raise ValueError(f"symplectic_error needs a continuous model, got {type(model).__name__}")
    zs = as_dtype(zs, model.dtype)
    n = zs.shape[-1]
    args = as_dtype(args, model.dtype)
    n_args = model.scene.args_size
    if args.ndim <= 1:
        args = jnp.broadcast_to(args.reshape(n_args), zs.shape[:-1] + (n_args,))
    flat_z = zs.reshape(-1, n)
    flat_a = jnp.broadcast_to(args, zs.shape[:-1] + (n_args,)).reshape(flat_z.shape[0], n_args)
    J = symplectic_matrix(n // 2, model.dtype)

    def one(z, a):
        jdf = J @ jax.jacfwd(lambda y: model.vector_field(0.0, y, a))(z)
        return jnp.sum((jdf - jdf.T) ** 2)

    return jnp.mean(jax.vmap(one)(flat_z, flat_a))
