"""The fixed-step loop every integrator shares: ``substeps`` steps per interval of ``ts`` as one
``lax.scan``, and the map from an integrator's states back to the model's ``z``."""

from __future__ import annotations

import jax
import jax.numpy as jnp

# Intervals up to this many are unrolled: training chunks are short (4 intervals) and the
# unrolled program lets XLA fuse across steps; long test rollouts stay a compact loop.
_UNROLL_MAX = 8


def _scan_intervals(advance, carry, ts, substeps):
    """Apply ``advance(carry, t, h)`` ``substeps`` times per interval of ``ts``.

    ``carry`` is a tuple whose first entry is the state ``z``. Returns the stacked states and
    the final carry.
    """

    def interval(carry, t_pair):
        t0, t1 = t_pair
        h = (t1 - t0) / substeps
        if substeps == 1:
            carry = advance(carry, t0, h)
        else:
            carry = jax.lax.fori_loop(
                0, substeps, lambda j, c: advance(c, t0 + j * h, h), carry, unroll=substeps <= 4
            )
        return carry, carry[0]

    n = ts.shape[0] - 1
    if n == 0:
        return carry[0][None], carry
    last, zs = jax.lax.scan(interval, carry, (ts[:-1], ts[1:]), unroll=n if n <= _UNROLL_MAX else 1)
    return jnp.concatenate([carry[0][None], zs], axis=0), last


def _decoded(model, z0, ys, args):
    """States z of the integrator's states ys (T, n): z0 itself first, then decode(ys[1:])."""
    if ys.shape[0] == 1:
        return z0[None]
    rest = jax.vmap(lambda y: model.decode(y, args))(ys[1:]).astype(z0.dtype)
    return jnp.concatenate([z0[None], rest], axis=0)
