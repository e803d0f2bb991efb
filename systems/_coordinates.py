"""The one (q, qdot) <-> (q, p) conversion of stored states, with the TRUE system's maps.

``p = dL/dqdot`` (:meth:`AbstractSystem.momentum`) and its inverse ``qdot = M(q)^-1 p``
(:meth:`AbstractSystem.velocity`), applied to every state of a batch of trajectories
(..., 2 dof) in one compiled program. Non-finite states stay non-finite (they are mapped as
zeros and masked back), so a diverged prediction can be converted too.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from ._precision import require_x64

__all__ = ["derivatives", "to_momentum", "to_velocity"]


def _convert(fn, system, zs, args) -> np.ndarray:
    require_x64("to_momentum / to_velocity")
    zs = np.asarray(zs, dtype=np.float64)
    if zs.ndim == 1:
        return _convert(fn, system, zs[None], None if args is None else np.asarray(args)[None])[0]
    n, d = zs.shape[0], zs.shape[-1] // 2
    a = np.zeros((n, 0)) if args is None else np.asarray(args, dtype=np.float64).reshape(n, -1)
    finite = np.all(np.isfinite(zs), axis=-1, keepdims=True)
    safe = np.where(finite, zs, 0.0)
    flat = safe.reshape(n, -1, 2 * d)

    def per_state(q, x, aa):
        return fn(system, q, x, None if aa.size == 0 else aa)

    per_traj = jax.vmap(per_state, in_axes=(0, 0, None))
    second = jax.jit(jax.vmap(per_traj))(
        jnp.asarray(flat[..., :d]), jnp.asarray(flat[..., d:]), jnp.asarray(a)
    )
    out = np.concatenate([zs[..., :d], np.asarray(second).reshape(zs[..., d:].shape)], axis=-1)
    return np.where(finite, out, np.nan)


def to_momentum(system, zs, args=None) -> np.ndarray:
    """States (N, ..., 2d) in (q, qdot) -> (q, p) with ``system.momentum``. ``args``: None
    (the system's defaults) or one row per trajectory (N, n_args); a state (2d,) takes
    ``args`` (n_args,)."""
    return _convert(lambda s, q, v, a: s.momentum(jnp.concatenate([q, v]), a), system, zs, args)


def to_velocity(system, zs, args=None) -> np.ndarray:
    """States (N, ..., 2d) in (q, p) -> (q, qdot) with ``system.velocity`` (the inverse of
    :func:`to_momentum`); ``args`` as there."""
    return _convert(lambda s, q, p, a: s.velocity(q, p, a), system, zs, args)


def derivatives(system, zs, args=None, canonical: bool = False) -> np.ndarray:
    """The true time derivatives dz/dt at states ``zs`` (N, ..., 2d), float64.

    In (q, qdot) (``canonical=False``) the system's vector field (qdot, qddot). In (q, p) it is
    (qdot, dp/dt) with qdot = M(q)^-1 p and dp/dt = d/dt dL/dqdot along the motion: one jvp of
    :meth:`AbstractSystem.momentum` in the direction of the (q, qdot) field (friction included,
    which Hamilton's equations alone would miss). ``args`` as in :func:`to_momentum`. The
    training targets of ``TrainConfig(target="derivative")`` (the HNN and LNN seeds' protocol).
    """
    require_x64("derivatives")
    zs = np.asarray(zs, dtype=np.float64)
    if zs.ndim == 1:
        a = None if args is None else np.asarray(args)[None]
        return derivatives(system, zs[None], a, canonical)[0]
    n, d = zs.shape[0], zs.shape[-1] // 2
    a = np.zeros((n, 0)) if args is None else np.asarray(args, dtype=np.float64).reshape(n, -1)
    flat = zs.reshape(n, -1, 2 * d)

    def per_state(z, aa):
        aa = None if aa.size == 0 else aa
        q, x = z[:d], z[d:]
        v = system.velocity(q, x, aa) if canonical else x
        zv = jnp.concatenate([q, v])
        f = system.vector_field(0.0, zv, aa)
        if not canonical:
            return f
        _, pdot = jax.jvp(lambda y: system.momentum(y, aa), (zv,), (f,))
        return jnp.concatenate([v, pdot])

    per_traj = jax.vmap(per_state, in_axes=(0, None))
    out = jax.jit(jax.vmap(per_traj))(jnp.asarray(flat), jnp.asarray(a))
    return np.asarray(out, dtype=np.float64).reshape(zs.shape)
