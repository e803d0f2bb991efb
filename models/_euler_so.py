"""The paper's explicit rule for second-order models (its MuJoCo experiment's integrator)."""

from __future__ import annotations

import jax.numpy as jnp

from ._scan import _scan_intervals


def _euler_so(model, z0, ts, args, m, seq):
    """The paper's rule (decon-hnn ``CoupledNODE``: dq/dt = (2 v + h dv/dt) / 2 under Euler):

        a = a(q, v, u);  q_new = q + h v + h^2/2 a;  v_new = v + h a

    in z = (q, v), one acceleration per step. Local errors O(h^3) in q and O(h^2) in v, so the
    global error is O(h): first order (exact in q for a constant acceleration)."""
    d = z0.shape[-1] // 2
    dtype = z0.dtype

    def advance(c, t, h, a):
        q, v = c[0][:d], c[0][d:]
        acc = model.acceleration(q, v, a).astype(dtype)
        return (jnp.concatenate([q + h * v + (0.5 * h * h) * acc, v + h * acc]),)

    return _scan_intervals(advance, (z0,), ts, m, args, seq)[0]
