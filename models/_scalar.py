"""Vector fields derived from a learned scalar: J grad H, and the Euler-Lagrange solve.

Every structured model goes through these functions, so that the bias "the dynamics come from
an energy-like scalar" is implemented once.
"""

from __future__ import annotations

from collections.abc import Callable

import jax
import jax.numpy as jnp
from jaxtyping import Array

SOLVES = ("solve", "pinv", "regularised")


def symplectic_matrix(dof: int, dtype) -> Array:
    """J = [[0, I], [-I, 0]], so that a Hamiltonian field is dz/dt = J grad H(z)."""
    eye = jnp.eye(dof, dtype=dtype)
    zero = jnp.zeros((dof, dof), dtype)
    return jnp.block([[zero, eye], [-eye, zero]])


def hamiltonian_field(H: Callable, q: Array, p: Array) -> tuple[Array, Array]:
    """(dq/dt, dp/dt) = (dH/dp, -dH/dq) for a scalar H(q, p); one backward pass."""
    dHdq, dHdp = jax.grad(H, argnums=(0, 1))(q, p)
    return dHdp, -dHdq


def acceleration_from_lagrangian(
    L: Callable,
    q: Array,
    v: Array,
    force: Array | None = None,
    solve: str = "solve",
    eps: float = 1e-3,
) -> Array:
    """qddot from the Euler-Lagrange equation of a scalar L(q, v) with generalised force Q.

    (d2L/dv2) qddot = dL/dq - (d2L/dv dq) v + Q.

    The Hessian columns and the mixed term are Hessian-vector products of one linearisation
    of grad L (dof + 1 forward passes), never a full Hessian of (q, v). ``solve``: "solve"
    (LU), "pinv" (the LNN seed's pseudo-inverse) or "regularised" (Hessian + eps I).
    """
    dof = q.shape[0]
    (dLdq, _), lin = jax.linearize(jax.grad(L, argnums=(0, 1)), q, v)
    eye = jnp.eye(dof, dtype=v.dtype)
    tq = jnp.concatenate([jnp.zeros_like(eye), v[None]])
    tv = jnp.concatenate([eye, jnp.zeros_like(v)[None]])
    _, dgv = jax.vmap(lin)(tq, tv)
    hess, mixed = dgv[:dof], dgv[dof]  # hess symmetric: rows = columns
    rhs = dLdq - mixed
    if force is not None:
        rhs = rhs + force
    if solve == "solve":
        return jnp.linalg.solve(hess, rhs)
    if solve == "pinv":
        return jnp.linalg.pinv(hess, hermitian=True) @ rhs
    if solve == "regularised":
        return jnp.linalg.solve(hess + eps * eye, rhs)
    raise ValueError(f"solve must be one of {SOLVES}, got {solve!r}")


def velocity_hessian(L: Callable, q: Array, v: Array) -> Array:
    """d2L/dv2 (dof, dof), the matrix the Euler-Lagrange solve inverts; for L = T - V with
    T = 1/2 v^T M(q) v it is the mass matrix M(q)."""
    return jax.hessian(L, argnums=1)(q, v)


def lagrangian_energy(L: Callable, q: Array, v: Array) -> Array:
    """E = v . dL/dv - L, the energy that an autonomous L conserves."""
    lval, dLdv = jax.value_and_grad(L, argnums=1)(q, v)
    return v @ dLdv - lval
