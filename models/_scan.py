"""The fixed-step loop every integrator shares: ``substeps`` steps per interval of ``ts`` as one
``lax.scan``, and the map from an integrator's states back to the model's ``z``."""

from __future__ import annotations

import jax
import jax.numpy as jnp

# Intervals up to this many are unrolled: training chunks are short (4 intervals) and the
# unrolled program lets XLA fuse across steps; long test rollouts stay a compact loop.
_UNROLL_MAX = 8


def _scan_intervals(advance, carry, ts, substeps, args, seq=None, enter=None):
    """Apply ``advance(carry, t, h, a)`` ``substeps`` times per interval of ``ts``.

    ``carry`` is a tuple whose first entry is the state ``z``. ``a`` is ``args`` on every
    interval, or ``seq[i]`` on interval i when a per-interval sequence is given (a controlled
    rollout: (static args, u_i), zero-order hold); ``enter(carry, a)`` then runs at the start of
    each interval (a method that carries a field value refreshes it with the new u). Returns
    the stacked states and the final carry.
    """

    def interval(carry, x):
        t0, t1, a = x if seq is not None else (*x, args)
        if enter is not None:
            carry = enter(carry, a)
        h = (t1 - t0) / substeps
        if substeps == 1:
            carry = advance(carry, t0, h, a)
        else:
            carry = jax.lax.fori_loop(
                0, substeps, lambda j, c: advance(c, t0 + j * h, h, a), carry, unroll=substeps <= 4
            )
        return carry, carry[0]

    n = ts.shape[0] - 1
    if n == 0:
        return carry[0][None], carry
    xs = (ts[:-1], ts[1:]) if seq is None else (ts[:-1], ts[1:], seq)
    last, zs = jax.lax.scan(interval, carry, xs, unroll=n if n <= _UNROLL_MAX else 1)
    return jnp.concatenate([carry[0][None], zs], axis=0), last


def _decoded(model, z0, ys, args, seq=None):
    """States z of the integrator's states ys (T, n): z0 itself first, then decode(ys[1:]);
    with a per-interval ``seq`` state i + 1 is decoded with the args of interval i."""
    if ys.shape[0] == 1:
        return z0[None]
    if seq is None:
        rest = jax.vmap(lambda y: model.decode(y, args))(ys[1:])
    else:
        rest = jax.vmap(model.decode)(ys[1:], seq)
    return jnp.concatenate([z0[None], rest.astype(z0.dtype)], axis=0)
