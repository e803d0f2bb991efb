"""Stability case of the Euler-Lagrange solve: an LNN's near-singular velocity Hessian."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

import systems

from ...core import one_line
from ._core import Row, _cast, _size

SOLVES = ("solve", "pinv", "regularised")


@eqx.filter_jit
def _system_cond(system, q, v):
    """cond(d2L/dqdot2) at (q, v), by SVD."""
    return jnp.linalg.cond(jax.hessian(system.lagrangian, argnums=1)(q, v))


@eqx.filter_jit
def _system_accel(system, q, v, solve):
    """The models' shared Euler-Lagrange solve with the system's true L plugged in (the
    system's arrays are traced: one compile for every mass ratio)."""
    import models

    return models.acceleration_from_lagrangian(system.lagrangian, q, v, solve=solve)


@eqx.filter_jit
def _degenerate_accel(q, v, solve):
    import models

    return models.acceleration_from_lagrangian(_degenerate_lagrangian, q, v, solve=solve)


def _degenerate_lagrangian(q, v):
    """L = 1/2 (v1 + v2)^2 + cos q1 + 2 cos q2: its velocity Hessian [[1, 1], [1, 1]] is
    exactly singular (rank 1), the limit that a learned L can approach."""
    return 0.5 * (v[0] + v[1]) ** 2 + jnp.cos(q[0]) + 2.0 * jnp.cos(q[1])


def _model_solve_available() -> bool:
    try:
        import models

        return "lnn" in models.available()
    except Exception:  # noqa: BLE001 - models may not be importable yet
        return False


def case_lnn_singular(size) -> list[Row]:
    """Euler-Lagrange solves on a near-singular mass matrix, in float32 (the models' dtype).

    The true chain-pendulum Lagrangian (k = 2) plugged into the models' shared
    ``acceleration_from_lagrangian``, with the first mass m1 -> 0 and both links aligned:
    det M = m2 l1^2 l2^2 (m1 + m2 sin^2(q1 - q2)) -> 0, cond(M) ~ 1/m1. Each solve ("solve"
    LU, "pinv", "regularised" = Hessian + 1e-3 I) in float32 is compared with the float64 LU
    solve (the truth up to cond * 1e-16). A Lagrangian with an exactly singular Hessian
    records what each solve returns. A non-finite output is recorded as ``diverged``.
    Where ``models`` has an LNN, a freshly initialised one is also probed with each solve
    at aligned states (its learned Hessian's condition and finiteness).
    """

    size = _size(size)
    rows = []
    q = jnp.asarray([0.3, 0.3])
    v = jnp.asarray([0.7, -0.4])
    q32, v32 = q.astype(jnp.float32), v.astype(jnp.float32)
    cases = []
    for m1 in (1e-2, 1e-4, 1e-6, 1e-8):
        sysm = systems.make("chain_pendulum", k=2, masses=[m1, 1.0])
        ref = _system_accel(sysm, q, v, "solve")
        cond = float(_system_cond(sysm, q, v))
        cases.append((f"m1={m1:g}", _cast(sysm, "float32"), np.asarray(ref), cond))
    cases.append(("degenerate", None, None, float("inf")))
    for label, sys32, ref, cond in cases:
        for solve in SOLVES:
            variant = f"{label}/{solve}"
            common = dict(
                system="chain_pendulum" if ref is not None else "degenerate",
                method=solve,
                param=cond,
                dtype="float32",
            )
            if sys32 is None:
                acc = _degenerate_accel(q32, v32, solve)
            else:
                acc = _system_accel(sys32, q32, v32, solve)
            acc = np.asarray(acc, dtype=np.float64)
            if not np.all(np.isfinite(acc)):
                rows.append(
                    Row(
                        "lnn_singular",
                        variant,
                        "accel_error",
                        "diverged",
                        step=0,
                        message=f"non-finite acceleration, cond={cond:.3g}",
                        **common,
                    )
                )
                continue
            if ref is None:  # no true acceleration exists: record its size only
                rows.append(
                    Row(
                        "lnn_singular",
                        variant,
                        "accel_norm",
                        "ok",
                        float(np.linalg.norm(acc)),
                        **common,
                    )
                )
                continue
            err = float(np.linalg.norm(acc - ref) / (np.linalg.norm(ref) + 1e-300))
            rows.append(Row("lnn_singular", variant, "accel_error", "ok", err, **common))
    if size.lnn_probe:
        rows += _lnn_model_probe(size)
    return rows


def _lnn_model_probe(size) -> list[Row]:
    if not _model_solve_available():
        return [
            Row(
                "lnn_singular",
                "model/*",
                "accel_finite",
                "failed",
                message="models has no 'lnn' yet",
            )
        ]
    import models

    rows = []
    scene = models.Scene(dof=2, angular=(True, True))
    states = jnp.asarray(np.random.default_rng(0).normal(size=(64, 4)), dtype=jnp.float32)
    for solve in SOLVES:
        variant = f"model/{solve}"
        try:
            m = models.make("lnn", scene, key=jax.random.PRNGKey(0), width=size.width, solve=solve)
        except ValueError as err:
            rows.append(
                Row(
                    "lnn_singular",
                    variant,
                    "accel_finite",
                    "failed",
                    message=one_line(err),
                    method=solve,
                )
            )
            continue
        f = jax.vmap(lambda z, m=m: m.vector_field(0.0, z, None))
        out = np.asarray(f(states))
        frac = float(np.mean(np.all(np.isfinite(out), axis=-1)))
        rows.append(
            Row("lnn_singular", variant, "accel_finite", "ok", frac, method=solve, dtype="float32")
        )
        if hasattr(m, "lagrangian"):
            conds = jax.vmap(
                lambda z, m=m: jnp.linalg.cond(
                    jax.hessian(m.lagrangian, argnums=1)(z[:2], z[2:], None)
                )
            )(states)
            rows.append(
                Row(
                    "lnn_singular",
                    variant,
                    "cond_median",
                    "ok",
                    float(np.median(np.asarray(conds))),
                    method=solve,
                    dtype="float32",
                )
            )
    return rows
