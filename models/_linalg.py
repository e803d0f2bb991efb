"""Cholesky factorisation and solves for the small SPD matrices of the models (dof x dof).

Unrolled over the (static, small) size: on CPU, XLA lowers batched LAPACK calls to a loop of
tiny library calls and compiles them slowly, whereas the unrolled form is a few vectorised
elementwise operations that vmap and differentiate cheaply. Larger matrices use jnp.linalg.

A solve with a factor of :data:`_SPLIT` rows or more reads the factor's entries through one
split, whose derivative is one concatenation. Read one index at a time, each entry's derivative
is a pad to the whole matrix, and summing the pads costs O(n^4): with 12 x 12 factors (the
spring pendulum at k = 4) a profile put a quarter of the hnn step there. Below :data:`_SPLIT` the
per-index reads stay: they cost less there, and the two forms round differently in float32
(the same sums, fused otherwise), so switching would move the stored runs of every model that
solves with a small factor (the spring at k = 3 and HalfCheetah have 9 degrees of freedom).
"""

from __future__ import annotations

import jax.numpy as jnp
import jax.scipy.linalg as jsl
from jaxtyping import Array

_UNROLL = 12  # spring_pendulum(k=4) has 12 degrees of freedom
_SPLIT = 10


def _entries(x: Array) -> list:
    """The entries of ``x`` as scalars in row-major order (a vector's as a list, a matrix's as
    a list of rows), read by one split."""
    flat = [e.reshape(()) for e in jnp.split(x.reshape(-1), x.size)]
    if x.ndim == 1:
        return flat
    n = x.shape[1]
    return [flat[i * n : (i + 1) * n] for i in range(x.shape[0])]


def cholesky(a: Array) -> Array:
    """Lower-triangular C with C C^T = a, for symmetric positive-definite a."""
    n = a.shape[0]
    if n > _UNROLL:
        return jnp.linalg.cholesky(a)
    c = [[None] * n for _ in range(n)]
    for j in range(n):
        s = a[j, j] - sum((c[j][k] ** 2 for k in range(j)), start=0.0)
        c[j][j] = jnp.sqrt(s)
        for i in range(j + 1, n):
            s = a[i, j] - sum((c[i][k] * c[j][k] for k in range(j)), start=0.0)
            c[i][j] = s / c[j][j]
    zero = jnp.zeros((), a.dtype)
    return jnp.stack([jnp.stack([c[i][j] if j <= i else zero for j in range(n)]) for i in range(n)])


def cho_solve(c: Array, b: Array) -> Array:
    """x with (C C^T) x = b for a lower-triangular Cholesky factor C; b of shape (n,)."""
    n = c.shape[0]
    if n > _UNROLL:
        return jsl.cho_solve((c, True), b)
    if n >= _SPLIT:
        entries, b = _entries(c), _entries(b)

        def at(i, j):
            return entries[i][j]
    else:

        def at(i, j):  # each use its own read
            return c[i, j]

    y = []
    for i in range(n):  # C y = b
        y.append((b[i] - sum((at(i, k) * y[k] for k in range(i)), start=0.0)) / at(i, i))
    x = [None] * n
    for i in reversed(range(n)):  # C^T x = y
        x[i] = (y[i] - sum((at(k, i) * x[k] for k in range(i + 1, n)), start=0.0)) / at(i, i)
    return jnp.stack(x)


def spd_solve(a: Array, b: Array) -> Array:
    """x with a x = b for symmetric positive-definite a."""
    return cho_solve(cholesky(a), b)
