"""The dissipation bias: a learned generalised friction force Q = -D(q) qdot, D PSD."""

from __future__ import annotations

import equinox as eqx
from jaxtyping import Array

from ._features import Features
from ._mass import CholeskyNet


class Dissipation(eqx.Module):
    """Q(q, qdot) = -D(q) qdot with D(q) = C(q) C(q)^T positive semi-definite.

    Added to dp/dt (Hamiltonian models) or to the Euler-Lagrange right-hand side (LNN), it
    makes the learned energy non-increasing: dE/dt = qdot . Q = -qdot^T D qdot <= 0. This is
    the SymODEN-style damping term (a structured friction, not a free MLP forcing), because the
    damped systems of the benchmark have exactly this form (chain: D = f M(q); spring: f M).
    ``state_dependent=False`` learns a constant D (used by the VINs, whose mass is constant).
    """

    damping: CholeskyNet

    def __init__(
        self, features: Features, width, depth, activation, dtype, *, key, state_dependent=True
    ):
        self.damping = CholeskyNet(
            features, width, depth, activation, dtype, key=key, state_dependent=state_dependent
        )

    def matrix(self, q: Array, args: Array) -> Array:
        return self.damping.matrix(q, args)

    def force(self, q: Array, qdot: Array, args: Array) -> Array:
        c = self.damping.factor(q, args)
        return -(c @ (c.T @ qdot))
