"""Control inputs in a rollout: the zero-order hold of u as per-interval args (static args, u_i)."""

from __future__ import annotations

import jax.numpy as jnp


def _discrete(model) -> bool:
    from ._base import AbstractDiscreteModel

    return isinstance(model, AbstractDiscreteModel)


def _control_sequence(model, ts, args, controls, integrator, dtype):
    """Per-interval args (len(ts) - 1, n_args + n_controls) = (static args, u_i), or None.

    A controlled scene needs ``controls`` of shape (len(ts) - 1, n_controls); an uncontrolled
    one takes None (or a zero-width array). One-line ValueErrors name the expected shape."""
    n_u = int(getattr(model.scene, "n_controls", 0))
    expected = (ts.shape[0] - 1, n_u)
    what = f"controls must have shape (len(ts) - 1, n_controls) = {expected}"
    if controls is None:
        if n_u:
            raise ValueError(f"the scene has n_controls={n_u}: {what}, got None")
        return None
    controls = jnp.asarray(controls)
    if controls.shape != expected:
        raise ValueError(f"{what}, got shape {controls.shape}")
    if n_u and integrator.method == "adaptive" and not _discrete(model):
        raise ValueError(
            "adaptive cannot hold a piecewise-constant control (its steps cross the interval "
            "boundaries); use a fixed-step method (euler, rk4, rk4_38, euler_so, leapfrog, "
            "leapfrog_explicit, implicit_midpoint)"
        )
    n_args = model.scene.n_args
    static = jnp.zeros((0,), dtype) if args is None else jnp.asarray(args, dtype)
    if static.shape != (n_args,):
        raise ValueError(f"args must have shape (n_args,) = ({n_args},), got {static.shape}")
    static = jnp.broadcast_to(static, (expected[0], n_args))
    return jnp.concatenate([static, controls.astype(dtype)], axis=1)
