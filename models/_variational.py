"""Variational integrators: the discrete steps of the VIN models.

Both steps are second order and, without forcing, symplectic and time reversible.
"""

from __future__ import annotations

from collections.abc import Callable

import jax
import jax.numpy as jnp
import optimistix as optx
from jaxtyping import Array

from ._linalg import cho_solve, spd_solve


def verlet_step(
    grad_U: Callable, chol_M: Array, q: Array, v: Array, dt, damping: Array | None = None
) -> tuple[Array, Array]:
    """Velocity (Stormer-)Verlet for L = 1/2 v^T M v - U(q), M constant, optional friction.

    q1 = q0 + dt v0 + dt^2/2 M^-1 (-grad U(q0) - D v0)
    M v1 = M v0 - dt/2 (grad U(q0) + grad U(q1)) - dt/2 D (v0 + v1)

    The friction force -D v enters with the trapezoidal rule (a discrete Lagrange-d'Alembert
    forcing, F^- = F^+ = dt/2 (-D v)), which keeps the step second order and, for D PSD,
    contractive in the kinetic energy; the v1 equation is linear, so it is one solve.
    """
    g0 = grad_U(q)
    f0 = -g0 if damping is None else -g0 - damping @ v
    q1 = q + dt * v + 0.5 * dt**2 * cho_solve(chol_M, f0)
    g1 = grad_U(q1)
    if damping is None:
        v1 = v - 0.5 * dt * cho_solve(chol_M, g0 + g1)
    else:
        m = chol_M @ chol_M.T
        rhs = m @ v - 0.5 * dt * (g0 + g1) - 0.5 * dt * (damping @ v)
        v1 = spd_solve(m + 0.5 * dt * damping, rhs)
    return q1, v1


def newton_tolerance(dtype) -> float:
    return 1e-10 if jnp.dtype(dtype) == jnp.float64 else 1e-5


def midpoint_variational_step(
    L: Callable,
    q: Array,
    v: Array,
    dt,
    force: Callable | None = None,
    max_steps: int = 20,
) -> tuple[Array, Array, Array]:
    """One step of the midpoint-rule variational integrator of a general L(q, v).

    L_d(q0, q1) = dt L((q0 + q1)/2, (q1 - q0)/dt). In position-momentum form, with the
    continuous Legendre map p = dL/dv at both ends (so the state stays z = (q, qdot)):

        p0 = dL/dv(q0, v0)
        p0 + D1 L_d(q0, q1) + F_d(q0, q1) = 0      -> q1  (Newton, guess q0 + dt v0)
        p1 = D2 L_d(q0, q1) + F_d(q0, q1)
        dL/dv(q1, v1) = p1                          -> v1  (Newton, guess 2 (q1-q0)/dt - v0)

    with the discrete Lagrange-d'Alembert force F_d = dt/2 Q(midpoint, (q1-q0)/dt). Both
    solves are differentiated implicitly (optimistix's ImplicitAdjoint). Returns (q1, v1, ok),
    ok true when both Newton solves converged.
    """
    tol = newton_tolerance(v.dtype)
    solver = optx.Newton(rtol=tol, atol=tol)

    def Ld(a, b):
        return dt * L(0.5 * (a + b), (b - a) / dt)

    def Fd(a, b):
        if force is None:
            return jnp.zeros_like(a)
        return 0.5 * dt * force(0.5 * (a + b), (b - a) / dt)

    dLdv = jax.grad(L, argnums=1)
    p0 = dLdv(q, v)

    def position_residual(q1, _):
        return p0 + jax.grad(Ld, argnums=0)(q, q1) + Fd(q, q1)

    sol_q = optx.root_find(position_residual, solver, q + dt * v, max_steps=max_steps, throw=False)
    q1 = sol_q.value
    p1 = jax.grad(Ld, argnums=1)(q, q1) + Fd(q, q1)

    def legendre_residual(v1, _):
        return dLdv(q1, v1) - p1

    sol_v = optx.root_find(
        legendre_residual, solver, 2.0 * (q1 - q) / dt - v, max_steps=max_steps, throw=False
    )
    ok = (sol_q.result == optx.RESULTS.successful) & (sol_v.result == optx.RESULTS.successful)
    return q1, sol_v.value, ok
