"""Stability cases of the true dynamics: step size, precision, high energy, stiffness, speed."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

import systems

from ._core import (
    DT,
    Row,
    _cast,
    _size,
    bound,
    counting,
    energy_drift,
    first_bad_step,
    grid,
    relative_error,
    rollout_true,
    solve,
    velocity_mask,
)

# The reference's own ground-truth setting (float32 dopri5), run against float64 truth.
REFERENCE_SETTING = {"solver": "dopri5", "rtol": 1e-7, "atol": 1e-9}


def _integrator(method, **kw):
    import models

    return models.Integrator(method, **kw)


def case_dt_sweep(size) -> list[Row]:
    """Fixed-step error vs dt on the chain pendulum (k = 2) over ``size.horizon`` seconds.

    For each method and dt: the relative state error at the final time against the float64
    Dopri8 ground truth (``systems``' simulate), or ``diverged`` with the step; the fitted
    order of convergence (slope of log err vs log dt over the dts where the error is in
    (1e-11, 1e-2): float64 rounding below, the asymptotic regime ends above); and the
    vector-field evaluations per step (median over dts; implicit stages count iterations).
    """
    size = _size(size)
    sysm = systems.make("chain_pendulum", k=2)
    z0 = np.asarray(sysm.sample_initial(jax.random.PRNGKey(1), 1))[0]
    truth = np.asarray(sysm.simulate(z0, np.array([0.0, size.horizon])))
    rows = []
    common = dict(system="chain_pendulum")
    for method in size.dt_methods:
        dts, errs, per_step = [], [], []
        for dt in size.dts:
            n = max(1, round(size.horizon / dt))
            ts = np.linspace(0.0, size.horizon, n + 1)
            variant = f"{method}/dt={dt:g}"
            zs, nfe = rollout_true(sysm, z0, ts, _integrator(method), stats=True)
            per_step.append(float(nfe) / n)
            bad = first_bad_step(zs, bound(sysm, truth), velocity_mask(sysm))
            if bad is not None:
                rows.append(
                    Row(
                        "dt_sweep",
                        variant,
                        "final_error",
                        "diverged",
                        step=bad,
                        method=method,
                        param=dt,
                        **common,
                    )
                )
                continue
            err = float(relative_error(sysm, zs[-1:], truth[-1:])[0])
            rows.append(
                Row(
                    "dt_sweep", variant, "final_error", "ok", err, method=method, param=dt, **common
                )
            )
            dts.append(dt)
            errs.append(err)
        fit = [(d, e) for d, e in zip(dts, errs, strict=True) if 1e-11 < e < 1e-2]
        if len(fit) >= 2:
            slope = np.polyfit(np.log([d for d, _ in fit]), np.log([e for _, e in fit]), 1)[0]
            rows.append(
                Row(
                    "dt_sweep",
                    f"{method}/order",
                    "order",
                    "ok",
                    float(slope),
                    method=method,
                    **common,
                )
            )
        rows.append(
            Row(
                "dt_sweep",
                f"{method}/cost",
                "nfe_per_step",
                "ok",
                float(np.median(per_step)),
                method=method,
                **common,
            )
        )
    return rows


def case_precision(size) -> list[Row]:
    """float32 vs float64: the same fixed-step RK4 (dt/4) in both precisions, and the
    reference's own setting (float32 dopri5, rtol 1e-7, atol 1e-9), against float64 truth.

    The float64 RK4 run's error is the truncation error; the float32 run's is truncation plus
    rounding; their difference isolates the precision's share. The reference's setting asks
    float32 for a relative tolerance (1e-7) below its own epsilon (1.2e-7).
    """
    size = _size(size)
    rows = []
    n = round(size.horizon / DT)
    ts = grid(n)
    variants = [
        ("rk4", "float32", _integrator("rk4", substeps=4), DT / 4),
        ("rk4", "float64", _integrator("rk4", substeps=4), DT / 4),
        (
            "dopri5",
            "float32",
            _integrator("adaptive", max_steps=20 * n + 1000, **REFERENCE_SETTING),
            REFERENCE_SETTING["rtol"],
        ),
    ]
    for name, params in (("chain_pendulum", {"k": 2}), ("spring_pendulum", {"k": 2})):
        sysm = systems.make(name, **params)
        z0 = np.asarray(sysm.sample_initial(jax.random.PRNGKey(2), size.n_traj))
        truth = np.asarray(sysm.simulate_batch(z0, ts))
        for method, dtype, integ, param in variants:
            label = f"{name}/{dtype}" if method == "rk4" else f"{name}/{dtype}/reference_dopri5"
            common = dict(system=name, method=method, param=param, dtype=dtype)
            zs = rollout_true(sysm, z0, ts, integ, dtype=dtype)
            bad = first_bad_step(zs, bound(sysm, truth), velocity_mask(sysm))
            if bad is not None:
                rows.append(Row("precision", label, "final_error", "diverged", step=bad, **common))
                continue
            err = float(np.median(relative_error(sysm, zs[:, -1:], truth[:, -1:])))
            drift = float(np.median(energy_drift(sysm, zs)[:, -1]))
            rows.append(Row("precision", label, "final_error", "ok", err, **common))
            rows.append(Row("precision", label, "energy_drift", "ok", drift, **common))
    return rows


def _chain_state_with_energy(sysm, kinetic: float, q=None) -> np.ndarray:
    """q (default all links down), qdot along (1, ..., 1) scaled so that T(q, qdot) = kinetic."""
    q = np.zeros(sysm.dof) if q is None else np.asarray(q, dtype=np.float64)
    u = np.ones(sysm.dof)
    t_unit = float(sysm.kinetic_energy(jnp.asarray(q), jnp.asarray(u)))
    return np.concatenate([q, u * math.sqrt(kinetic / t_unit)])


def high_energy_states(sysm) -> dict[str, np.ndarray]:
    """Chain-pendulum states at an energy relative to the top of the potential.

    From all links hanging down (V = V_min), kinetic energy (1 + eps) * (V_max - V_min): just
    below (eps = -1e-3) or above (+1e-3) the energy of the all-links-up equilibrium, the
    double pendulum's analogue of the separatrix; and whirling at eps = 9 (ten times it).
    """
    top = sysm.potential_range()
    return {
        "below_top": _chain_state_with_energy(sysm, (1 - 1e-3) * top),
        "above_top": _chain_state_with_energy(sysm, (1 + 1e-3) * top),
        "whirling": _chain_state_with_energy(sysm, 10.0 * top),
    }


def case_high_energy_truth(size) -> list[Row]:
    """Ground-truth energy drift per solver tolerance at high and near-separatrix energy.

    ``systems``' simulate with Tsit5 at each rtol (atol = rtol / 100) over ``size.horizon``
    seconds: the largest energy drift along the trajectory, and the evaluations it took.
    """
    size = _size(size)
    sysm = systems.make("chain_pendulum", k=2)
    ts = grid(round(size.horizon / DT))
    rows = []
    for label, z0 in high_energy_states(sysm).items():
        for rtol in size.rtols:
            variant = f"{label}/rtol={rtol:g}"
            common = dict(system="chain_pendulum", method="tsit5", param=rtol)
            ys, nfe, msg = solve(sysm, z0, ts, rtol)
            bad = first_bad_step(ys)
            if msg or bad is not None:
                outcome = "failed" if msg else "diverged"
                rows.append(
                    Row(
                        "high_energy_truth",
                        variant,
                        "energy_drift",
                        outcome,
                        step=bad,
                        message=msg,
                        **common,
                    )
                )
                continue
            drift = float(np.max(energy_drift(sysm, ys)))
            rows.append(Row("high_energy_truth", variant, "energy_drift", "ok", drift, **common))
            rows.append(Row("high_energy_truth", variant, "nfe", "ok", float(nfe), **common))
    return rows


def _stiff_variant(sysm, z0, ts, truth, method, kappa) -> list[Row]:
    """One solver on the stiff spring pendulum: its final error and its counted evaluations."""
    counted, calls = counting(sysm)
    if method in ("tsit5", "kvaerno5", "dopri5", "dopri8"):
        ys, _, msg = solve(counted, z0, ts, 1e-7, 1e-9, solver=method)
    else:
        integ = _integrator(method, implicit_solver="newton")
        ys, msg = rollout_true(counted, z0, ts, integ), ""
    jax.effects_barrier()
    nfe = float(calls[0])
    v = f"kappa={kappa:g}/{method}"
    common = dict(system="spring_pendulum", param=kappa, method=method)
    rows = []
    bad = first_bad_step(ys, bound(sysm, truth), velocity_mask(sysm))
    if msg or bad is not None:
        rows.append(
            Row(
                "stiffness",
                v,
                "final_error",
                "failed" if msg else "diverged",
                step=bad,
                message=msg,
                **common,
            )
        )
    else:
        err = float(relative_error(sysm, ys[-1:], truth[-1:])[0])
        rows.append(Row("stiffness", v, "final_error", "ok", err, **common))
    rows.append(Row("stiffness", v, "nfe", "ok", nfe, message="counted calls", **common))
    return rows


def case_stiffness(size) -> list[Row]:
    """Stiff spring pendulum (k = 2 bobs, spring constant 1e3..1e5): does an implicit
    solver help?

    The highest normal mode has omega ~ sqrt(kappa (1/m1 + 1/m2 + ...)); classical RK4 is
    stable only for |omega dt| < 2.78, so at dt = 0.03 it blows up from kappa ~ 1e4 on.
    Over ``size.stiff_horizon`` seconds, variants: fixed-step RK4 and implicit midpoint
    (A-stable, Newton-solved stages) at dt = 0.03, adaptive Tsit5 (explicit) and Kvaerno5
    (implicit, ESDIRK) at rtol 1e-7, atol 1e-9 through ``systems``' simulate. One cost unit
    for all: counted calls of the vector field (a forward-mode Jacobian for Newton counts as
    one call). The error is against Dopri8 at 1e-11. The oscillation is undamped and stiff
    only through its fast
    mode, which an accurate answer must still resolve: an implicit method is stable at a
    large step but gains no accuracy there (the midpoint rule shifts the fast phase), and
    Kvaerno5's Newton iterations cost more evaluations than Tsit5's small explicit steps.
    """
    size = _size(size)
    rows = []
    n = round(min(size.horizon, size.stiff_horizon) / DT)
    ts = grid(n)
    for kappa in size.spring_constants:
        sysm = systems.make("spring_pendulum", k=2, spring_constant=kappa)
        eq = np.asarray(sysm.equilibrium())
        key = jax.random.PRNGKey(3)
        # A small displacement from equilibrium: the stiff mode is excited but its energy
        # (kappa |dx|^2 / 2) stays moderate, so that a failure is the integrator's.
        dq = 0.05 * np.asarray(jax.random.normal(key, (sysm.dof,), dtype=jnp.float64))
        z0 = np.concatenate([eq + dq, np.zeros(sysm.dof)])
        truth = np.asarray(sysm.simulate(z0, ts))
        for method in (*size.stiff_fixed, *size.stiff_solvers):
            rows += _stiff_variant(sysm, z0, ts, truth, method, kappa)
    return rows


def relativistic_roundtrip(sysm, speed: float, dtype: str, g: float = 1.0) -> list[Row]:
    """Rows ``roundtrip_error`` and ``momentum_error`` of :func:`case_relativistic` at one
    speed and dtype."""
    g = jnp.asarray([g])
    rows = []
    s32 = _cast(sysm, dtype)
    z = jnp.asarray([0.0, speed], dtype=dtype)
    a = g.astype(dtype)
    p = s32.momentum(z, a)
    v = s32.velocity(z[:1], p, a)
    err = float(jnp.abs(v[0] - jnp.asarray(speed, dtype)) / (1 - speed))
    common = dict(system="relativistic_particle", method="closed_form", param=speed, dtype=dtype)
    outcome = "ok" if math.isfinite(err) else "diverged"
    rows.append(
        Row(
            "relativistic",
            f"v={speed:g}/{dtype}",
            "roundtrip_error",
            outcome,
            err,
            step=None if outcome == "ok" else 0,
            **common,
        )
    )
    # p of the same (rounded) speed in float64: what 1 - qdot^2 cancellation costs.
    p64 = sysm.momentum(jnp.asarray(z, jnp.float64), g)
    perr = float(jnp.abs(p[0] - p64[0]) / jnp.abs(p64[0]))
    rows.append(Row("relativistic", f"v={speed:g}/{dtype}", "momentum_error", "ok", perr, **common))
    return rows


def _relativistic_rk4(sysm, z0, ts, g, speed, tag) -> list[Row]:
    """float32 and float64 RK4 near light speed: energy drift, velocity change, stagnation."""
    rows, dv = [], {}
    for dtype in ("float64", "float32"):
        v = f"v={speed:g}/{tag}/rk4/{dtype}"
        common = dict(system="relativistic_particle", param=speed, method="rk4", dtype=dtype)
        zs = rollout_true(sysm, z0, ts, _integrator("rk4"), dtype=dtype, args=g)
        # |qdot| >= 1 is outside the domain: as good as a NaN.
        outside = np.flatnonzero(~(np.abs(zs[:, 1]) < 1.0))
        bad = first_bad_step(zs)
        bad = int(outside[0]) if outside.size and bad is None else bad
        if bad is not None:
            rows.append(
                Row(
                    "relativistic",
                    v,
                    "energy_drift",
                    "diverged",
                    step=bad,
                    message="left |qdot| < 1 or non-finite",
                    **common,
                )
            )
            continue
        dv[dtype] = float(np.max(np.abs(zs[:, 1] - zs[0, 1])))
        stagnant = dtype == "float32" and dv[dtype] == 0.0
        note = "stagnant: the float32 velocity never changes, drift is an artefact" * stagnant
        drift = float(np.max(energy_drift(sysm, zs, g)))
        rows.append(Row("relativistic", v, "energy_drift", "ok", drift, message=note, **common))
        rows.append(Row("relativistic", v, "velocity_change", "ok", dv[dtype], **common))
        if dtype == "float32" and "float64" in dv:
            ratio = dv["float32"] / dv["float64"] if dv["float64"] > 0 else float("nan")
            rows.append(
                Row(
                    "relativistic",
                    f"v={speed:g}/{tag}/rk4/float32_vs_float64",
                    "velocity_change_ratio",
                    "ok",
                    ratio,
                    message=note,
                    **{**common, "dtype": "both"},
                )
            )
            rows.append(
                Row(
                    "relativistic",
                    f"v={speed:g}/{tag}/rk4/float32_vs_float64",
                    "stagnant",
                    "ok",
                    float(stagnant),
                    message=note,
                    **{**common, "dtype": "both"},
                )
            )
    return rows


def case_relativistic(size) -> list[Row]:
    """Relativistic particle near the light cone, float32 vs float64.

    Round trip: |velocity(q, momentum(q, qdot)) - qdot| / (1 - |qdot|), the error measured in
    units of the distance to the light cone (an error of 1 would put qdot on or beyond c);
    momentum error: p = qdot (1 - qdot^2)^(-3/2) in the dtype vs float64 at the same qdot.
    Dynamics over ``size.horizon`` seconds, started towards and against g: float64 Tsit5 at
    rtol 1e-9 (energy drift), and fixed-step RK4 (dt = 0.03) in float32 and float64: energy
    drift, the largest velocity change |qdot(t) - qdot(0)|, the float32/float64 ratio of that
    change, and ``stagnant`` = 1 where the float32 velocity never changes at all (each RK4
    increment is below half an ulp of qdot: a drift of 0 there measures nothing).
    """
    size = _size(size)
    sysm = systems.make("relativistic_particle")
    g = np.asarray([1.0])
    rows = []
    ts = grid(round(size.horizon / DT))
    for speed in size.speeds:
        for dtype in ("float32", "float64"):
            rows += relativistic_roundtrip(sysm, speed, dtype)
        for sign in (1.0, -1.0):
            z0 = np.array([0.0, sign * speed])
            tag = "with_g" if sign > 0 else "against_g"
            ys, _, msg = solve(sysm, z0, ts, 1e-9, 1e-12, args=g)
            common = dict(system="relativistic_particle", param=speed, method="tsit5")
            v = f"v={speed:g}/{tag}/tsit5"
            if msg or first_bad_step(ys) is not None:
                rows.append(
                    Row(
                        "relativistic",
                        v,
                        "energy_drift",
                        "failed" if msg else "diverged",
                        step=first_bad_step(ys),
                        message=msg,
                        **common,
                    )
                )
            else:
                drift = float(np.max(energy_drift(sysm, ys, g)))
                rows.append(Row("relativistic", v, "energy_drift", "ok", drift, **common))
            rows += _relativistic_rk4(sysm, z0, ts, g, speed, tag)
    return rows
