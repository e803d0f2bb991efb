"""Learned positive-definite matrices: mass matrices and their inverses, via Cholesky factors."""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from ._features import Features
from ._mlp import MLP

# softplus(x + _SHIFT) = 1 at x = 0: a freshly initialised factor is close to the identity.
_SHIFT = math.log(math.e - 1.0)


MASS_EPS = 1e-3  # floor on the diagonal of a learned mass factor: M stays invertible


def cholesky_from_raw(raw: Array, dof: int, eps: float) -> Array:
    """Lower-triangular C from dof (dof + 1) / 2 numbers; diagonal softplus(.) + eps > 0."""
    rows, cols = np.tril_indices(dof)
    n_raw = rows.size
    # one gather (no scatter): strictly-lower entries from raw, the rest from a zero slot
    index = np.full((dof, dof), n_raw)
    strict = rows != cols
    index[rows[strict], cols[strict]] = np.flatnonzero(strict)
    diag_index = np.flatnonzero(~strict)
    lower = jnp.concatenate([raw, jnp.zeros((1,), raw.dtype)])[index]
    diag = jax.nn.softplus(raw[diag_index] + _SHIFT) + eps
    return lower + jnp.eye(dof, dtype=raw.dtype) * diag


class CholeskyNet(eqx.Module):
    """A positive-definite A(q) = C(q) C(q)^T (+ jitter I), C lower-triangular from an MLP.

    ``state_dependent=False`` makes C a free constant parameter instead (VIN mass, damping).
    ``init``: the MLP's (:class:`MLP`); the output layer's bias starts at zero whatever it is.
    """

    features: Features | None
    net: MLP | None
    raw: Array | None
    dof: int = eqx.field(static=True)
    eps: float = eqx.field(static=True)
    jitter: float = eqx.field(static=True)

    def __init__(
        self,
        features,
        width,
        depth,
        activation,
        dtype,
        *,
        key,
        state_dependent=True,
        eps=0.0,
        jitter=0.0,
        init="orthogonal",
    ):
        self.dof = features.dof
        self.eps = eps
        self.jitter = jitter
        n_raw = self.dof * (self.dof + 1) // 2
        if state_dependent:  # a mass or damping matrix never depends on a control input
            self.features = features.without_controls()
            net = MLP(
                self.features.size(False),
                n_raw,
                width,
                depth,
                activation,
                dtype,
                key=key,
                init=init,
            )
            # the Deconstructing paper's mass networks end in a layer without a bias
            self.net = eqx.tree_at(lambda m: m.biases[-1], net, jnp.zeros_like(net.biases[-1]))
            self.raw = None
        else:
            self.features = None
            self.net = None
            self.raw = jnp.zeros((n_raw,), dtype)

    def factor(self, q: Array, args: Array) -> Array:
        """C(q)."""
        raw = self.raw if self.net is None else self.net(self.features(q, None, args))
        return cholesky_from_raw(raw, self.dof, self.eps)

    def matrix(self, q: Array, args: Array) -> Array:
        """A(q) = C C^T + jitter I."""
        c = self.factor(q, args)
        a = c @ c.T
        if self.jitter:
            a = a + self.jitter * jnp.eye(self.dof, dtype=a.dtype)
        return a


class InverseMass(eqx.Module):
    """A mass matrix learned through its inverse: M^-1(q) = L L^T + jitter I from a
    :class:`CholeskyNet`, and ``factor(q)`` = C with C C^T = M = (M^-1)^-1 (the Deconstructing
    paper's non-separable HNN, whose network gives M^-1; the suite's HNN learns C itself)."""

    inverse: CholeskyNet

    def factor(self, q: Array, args: Array) -> Array:
        """C(q), the Cholesky factor of M = (M^-1)^-1."""
        minv = self.inverse.matrix(q, args)
        return jnp.linalg.cholesky(jnp.linalg.inv(minv))

    def matrix(self, q: Array, args: Array) -> Array:
        """M(q) = (M^-1(q))^-1."""
        return jnp.linalg.inv(self.inverse.matrix(q, args))
