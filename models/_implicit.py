"""The structure-preserving integrators: generalised Stormer-Verlet (``leapfrog``), explicit
velocity Verlet (``leapfrog_explicit``) and the implicit midpoint rule, their implicit stages
solved by ``optimistix`` and differentiated by the implicit function theorem."""

from __future__ import annotations

import jax.numpy as jnp

from ._scan import _decoded, _scan_intervals

# The implicit stages converge when successive iterates agree to eps ** IMPLICIT_POWER of the
# dtype (relative and absolute): 1.8e-12 in float64, 6.4e-6 in float32, where the rounding
# noise of a learned field (an LNN's Hessian solve) keeps iterates from agreeing any closer.
IMPLICIT_POWER = 0.75


def implicit_tolerance(dtype) -> float:
    """rtol = atol of the implicit stages: eps(dtype) ** ``IMPLICIT_POWER``."""
    return float(jnp.finfo(dtype).eps) ** IMPLICIT_POWER


def _stage(fn, guess, params, integrator):
    """The fixed point ``K = fn(K, params)`` from ``guess``; returns ``(K, evaluations)``.

    optimistix's fixed-point iteration (or Newton on ``fn(K) - K``) to
    :func:`implicit_tolerance`, differentiated by the implicit function theorem; or exactly
    ``implicit_iterations`` plain iterations when that is > 0. Newton's count adds the
    Jacobian's ``len(K)`` forward-mode products as one evaluation each.
    """
    k = integrator.implicit_iterations
    if k > 0:
        for _ in range(k):
            guess = fn(guess, params)
        return guess, k
    import optimistix as optx

    tol = implicit_tolerance(guess.dtype)
    if integrator.implicit_solver == "newton":
        sol = optx.root_find(
            lambda y, a: fn(y, a) - y,
            optx.Newton(rtol=tol, atol=tol, norm=_norm),
            guess,
            params,
            max_steps=integrator.implicit_max_steps,
            throw=False,
        )
        per_step = 1 + guess.shape[-1]
    else:
        sol = optx.fixed_point(
            fn,
            optx.FixedPointIteration(rtol=tol, atol=tol, norm=_norm),
            guess,
            params,
            max_steps=integrator.implicit_max_steps,
            throw=False,
        )
        per_step = 1
    return sol.value, per_step * sol.stats["num_steps"]


def _norm(x):
    """optimistix's max norm in the default float dtype, whatever the state's dtype (its
    solver state is created in the default dtype; a float32 state under x64 must match)."""
    import optimistix as optx

    return optx.max_norm(x).astype(jnp.result_type(float))


def _extrapolate(k, k_prev):
    """Initial guess of the next stage value: linear extrapolation of the last two, O(h^2)."""
    return 2 * k - k_prev


def _velocity_kick(a, p):
    """The implicit last kick of leapfrog as a fixed point in a = a(q1, v_half + h/2 a)."""
    model, q1, v_half, half_h, args = p
    return model.acceleration(q1, v_half + half_h * a, args).astype(a.dtype)


def _field_at(model, t, y, args):
    return model.internal_field(t, y, args).astype(y.dtype)


def _sv_momentum(k, p):
    """Stage 1 of generalised Stormer-Verlet: K = F(t, (q, p + h/2 K_p))."""
    model, t, q, mom, half_h, args = p
    d = q.shape[-1]
    return _field_at(model, t, jnp.concatenate([q, mom + half_h * k[d:]]), args)


def _sv_position(k, p):
    """Stage 2 of generalised Stormer-Verlet: K = F(t + h, (q + h/2 (f_a + K_q), p_half))."""
    model, t, q, f_a, p_half, half_h, args = p
    d = q.shape[-1]
    return _field_at(model, t, jnp.concatenate([q + half_h * (f_a + k[:d]), p_half]), args)


def _midpoint(k, p):
    """Implicit midpoint stage: K = F(t + h/2, y + h/2 K)."""
    model, t, y, half_h, args = p
    return _field_at(model, t, y + half_h * k, args)


def _leapfrog_velocity(model, z0, ts, args, integrator, seq=None):
    """Leapfrog on z = (q, v) with the model's acceleration; see :func:`rollout`. With
    controls the carried acceleration is re-evaluated with the new u at the start of each
    interval (one evaluation more per interval)."""
    d = z0.shape[-1] // 2
    dtype = z0.dtype
    explicit = integrator.method == "leapfrog_explicit"

    def accel(q, v, a):
        return model.acceleration(q, v, a).astype(dtype)

    def advance(c, t, h, args):
        z, a, a_prev, n = c
        q, v = z[:d], z[d:]
        v_half = v + (0.5 * h) * a
        q_new = q + h * v_half
        if explicit:
            a_new, cost = accel(q_new, v_half, args), 1
        else:
            params = (model, q_new, v_half, 0.5 * h, args)
            a_new, cost = _stage(_velocity_kick, _extrapolate(a, a_prev), params, integrator)
        z_new = jnp.concatenate([q_new, v_half + (0.5 * h) * a_new])
        return (z_new, a_new, a, n + cost)

    if seq is None or not model.scene.n_controls:  # u constant: the carried a stays valid
        a0, enter, n0 = accel(z0[:d], z0[d:], _first(args, seq)), None, 1
    else:

        def enter(c, args):
            z, _, _, n = c
            a = accel(z[:d], z[d:], args)
            return (z, a, a, n + 1)

        a0, n0 = jnp.zeros((d,), dtype), 0
    zs, last = _scan_intervals(
        advance,
        (z0, a0, a0, jnp.full((), n0, jnp.int32)),
        ts,
        integrator.substeps,
        args,
        seq,
        enter,
    )
    return zs, last[-1]


def _first(args, seq):
    """The args of the first interval."""
    return args if seq is None else seq[0]


def _leapfrog_canonical(model, z0, ts, args, integrator, seq=None):
    """Generalised Stormer-Verlet on the partitioned field F = (f, g) of ``internal_field`` in
    the model's coordinates y = (q, p); see :func:`rollout`."""
    d = z0.shape[-1] // 2
    dtype = z0.dtype

    def advance(c, t, h, args):
        y, k, k_prev, n = c
        q, p = y[:d], y[d:]
        half = 0.5 * h
        k1, n1 = _stage(
            _sv_momentum, _extrapolate(k, k_prev), (model, t, q, p, half, args), integrator
        )
        p_half = p + half * k1[d:]
        params = (model, t + h, q, k1[:d], p_half, half, args)
        k2, n2 = _stage(_sv_position, k1, params, integrator)
        y_new = jnp.concatenate([q + half * (k1[:d] + k2[:d]), p_half + half * k2[d:]])
        return (y_new, k2, k, n + n1 + n2)

    y0 = model.encode(z0, _first(args, seq)).astype(dtype)
    k0 = _field_at(model, ts[0], y0, _first(args, seq))
    ys, last = _scan_intervals(
        advance, (y0, k0, k0, jnp.ones((), jnp.int32)), ts, integrator.substeps, args, seq
    )
    return _decoded(model, z0, ys, args, seq), last[-1]


def _implicit_midpoint(model, z0, ts, args, integrator, seq=None):
    """Implicit midpoint in the model's coordinates y; see :func:`rollout`."""
    dtype = z0.dtype

    def advance(c, t, h, args):
        y, k, k_prev, n = c
        params = (model, t + 0.5 * h, y, 0.5 * h, args)
        k_new, cost = _stage(_midpoint, _extrapolate(k, k_prev), params, integrator)
        return (y + h * k_new, k_new, k, n + cost)

    y0 = model.encode(z0, _first(args, seq)).astype(dtype)
    k0 = _field_at(model, ts[0], y0, _first(args, seq))
    ys, last = _scan_intervals(
        advance, (y0, k0, k0, jnp.ones((), jnp.int32)), ts, integrator.substeps, args, seq
    )
    return _decoded(model, z0, ys, args, seq), last[-1]
