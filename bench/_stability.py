"""Numerical stability at the extremes: long horizons, high energy, stiffness, speed, precision.

Not a training sweep: a list of small cases, each a function ``case(size) -> list[Row]`` that
ends in a recorded outcome for every variant it tries:

- ``ok`` with a finite ``value`` (the metric named in ``metric``),
- ``diverged`` with ``step``, the first integration step whose state is non-finite or beyond a
  bound (a trajectory that runs away is as useless as a NaN one),
- ``failed`` with the error message (an exception, a solver that ran out of ``max_steps``).

Every case runs inside :func:`guard`, which turns exceptions into ``failed`` rows and relabels an
``ok`` row whose value is not finite as ``diverged``, so no NaN leaves this module unlabelled.
Nothing hangs: every solve has a bounded number of steps.

Run all cases with ``python -m bench._stability [--profile smoke|quick|paper] [--results DIR]``
or :func:`run_stability`; it writes ``stability.csv`` / ``stability.parquet`` and the figure
``figures/stability.png`` / ``.pdf``; :func:`stability_section` renders REPORT.md's section.

Errors use the paper's relative state error ``||zhat - z|| / (||zhat|| + ||z||)`` and energy
drift ``|H(zhat) - H(z0)| / (|H(zhat)| + |H(z0)|)`` with the true energy H.
"""

from __future__ import annotations

import argparse
import math
import time
import traceback
from collections.abc import Callable
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import ClassVar

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

import systems

from ._errors import one_line

OUTCOMES = ("ok", "diverged", "failed")
DT = 0.03
# A trajectory is called diverged where |z| exceeds this multiple of the largest |z| of the
# true trajectories (non-angular coordinates only: a whirling angle grows without bound).
BOUND_FACTOR = 100.0
VALID_THRESHOLD = 0.1  # relative error above which a prediction stops being "valid"


# --------------------------------------------------------------------------- rows and guards
@dataclass(frozen=True)
class Row:
    """One recorded outcome. ``param`` is the case's numeric axis (dt, rtol, kappa, speed...)."""

    case: str
    variant: str
    metric: str
    outcome: str
    value: float = float("nan")
    step: int | None = None
    message: str = ""
    system: str = ""
    method: str = ""
    param: float = float("nan")
    dtype: str = "float64"

    def __post_init__(self):
        if self.outcome not in OUTCOMES:
            raise ValueError(f"outcome must be one of {', '.join(OUTCOMES)}; got {self.outcome!r}")


COLUMNS = tuple(f.name for f in fields(Row))


def guard(case: str, fn: Callable[[], list[Row]], variant: str = "*") -> list[Row]:
    """Run ``fn``; an exception becomes one ``failed`` row, a non-finite ``ok`` a ``diverged``."""
    try:
        rows = list(fn())
    except Exception as err:  # noqa: BLE001 - every failure must become a recorded outcome
        traceback.print_exc(limit=3)
        return [Row(case, variant, "*", "failed", message=one_line(err))]
    checked = []
    for r in rows:
        if r.outcome == "ok" and not math.isfinite(r.value):
            r = Row(**{**asdict(r), "outcome": "diverged", "message": "non-finite value"})
        checked.append(r)
    return checked


def first_bad_step(zs, bound: float | None = None, mask=None) -> int | None:
    """First index along axis -2 where any state is non-finite or (masked) ``|z| > bound``.

    ``zs``: (T, D) or (N, T, D). Returns None when every state is finite and bounded.
    """
    zs = np.asarray(zs, dtype=np.float64)
    bad = ~np.isfinite(zs)
    if bound is not None:
        big = np.abs(np.nan_to_num(zs, nan=0.0, posinf=np.inf)) > bound
        if mask is not None:
            big = big & np.asarray(mask, dtype=bool)
        bad = bad | big
    per_step = bad.any(axis=-1)
    if per_step.ndim == 2:
        per_step = per_step.any(axis=0)
    idx = np.flatnonzero(per_step)
    return int(idx[0]) if idx.size else None


def relative_error(zhat, z):
    """||zhat - z|| / (||zhat|| + ||z||) along the last axis (the paper's state error)."""
    zhat = np.asarray(zhat, dtype=np.float64)
    z = np.asarray(z, dtype=np.float64)
    num = np.linalg.norm(zhat - z, axis=-1)
    den = np.linalg.norm(zhat, axis=-1) + np.linalg.norm(z, axis=-1)
    return num / np.maximum(den, 1e-300)


def energy_drift(system, zs, args=None):
    """|H(z_t) - H(z_0)| / (|H(z_t)| + |H(z_0)|) with the true H, for zs (..., T, D)."""
    zs = jnp.asarray(zs, dtype=jnp.float64)
    flat = zs.reshape(-1, zs.shape[-1])
    h = jax.vmap(lambda z: system.energy(z, args))(flat).reshape(zs.shape[:-1])
    h0 = h[..., :1]
    return np.asarray(jnp.abs(h - h0) / jnp.maximum(jnp.abs(h) + jnp.abs(h0), 1e-300))


def _cast(tree, dtype):
    """Cast every floating array leaf (system masses, model weights) to ``dtype``."""
    dtype = jnp.dtype(dtype)

    def cast(x):
        if eqx.is_array(x) and jnp.issubdtype(x.dtype, jnp.floating):
            return x.astype(dtype)
        return x

    return jax.tree_util.tree_map(cast, tree)


# --------------------------------------------------------------------------- sizes
@dataclass(frozen=True)
class StabilitySize:
    """How big each case is. ``smoke`` for tests, ``quick`` for ``make``, ``paper`` for a GPU."""

    n_traj: int = 8
    long_steps: int = 10_000  # integration steps of the long-horizon case (dt = 0.03)
    train_steps: int = 400  # training budget of the small long-horizon models (0: untrained)
    n_train: int = 200
    width: int = 64
    models: tuple[str, ...] = ("node", "node_so", "hnn_so", "lnn", "vin")
    integrators: tuple[str, ...] = ("euler", "rk4", "leapfrog", "adaptive")
    horizon: float = 3.0  # seconds of the ground-truth cases
    rtols: tuple[float, ...] = (1e-3, 1e-5, 1e-7, 1e-9)
    spring_constants: tuple[float, ...] = (1e3, 1e4, 1e5)
    speeds: tuple[float, ...] = (0.99, 0.999, 0.9999)
    dts: tuple[float, ...] = (1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 3e-2, 0.1, 0.3)
    high_energy_steps: int = 200
    dt_methods: tuple[str, ...] = ("euler", "rk4", "leapfrog")
    stiff_solvers: tuple[str, ...] = ("tsit5", "kvaerno5")
    lnn_probe: bool = True  # also probe freshly initialised LNN models with each solve


SIZES = {
    "smoke": StabilitySize(
        n_traj=2,
        long_steps=100,
        train_steps=0,
        n_train=16,
        width=16,
        models=("node_so", "lnn"),
        integrators=("rk4", "leapfrog", "adaptive"),
        horizon=1.0,
        rtols=(1e-3, 1e-8),
        spring_constants=(1e3, 1e5),
        speeds=(0.99, 0.999),
        dts=(1e-3, 1e-2, 0.1),
        high_energy_steps=30,
    ),
    "quick": StabilitySize(),
    "paper": StabilitySize(n_traj=64, train_steps=8000, n_train=800, width=256),
}


def _size(size) -> StabilitySize:
    if isinstance(size, StabilitySize):
        return size
    if size not in SIZES:
        raise ValueError(f"stability profile must be one of {', '.join(SIZES)}; got {size!r}")
    return SIZES[size]


# --------------------------------------------------------------------------- integration
def true_model(system, dtype: str = "float64"):
    """The true system wrapped as a second-order continuous model, so that ``models.rollout``
    (the one owner of fixed-step integration) integrates the true field exactly as it
    integrates a learned one."""
    import models
    from models._base import AbstractContinuousModel

    class TrueDynamics(AbstractContinuousModel):
        system: object
        scene: models.Scene = eqx.field(static=True)
        dtype: str = eqx.field(static=True)
        second_order: ClassVar[bool] = True

        def vector_field(self, t, z, args):
            return self.system.vector_field(t, z, args)

        def acceleration(self, q, v, args):
            return self.system.acceleration(q, v, args)

    scene = models.Scene(
        dof=system.dof,
        angular=tuple(system.angular),
        n_args=system.n_args,
        damped=system.friction > 0,
    )
    return TrueDynamics(system=system, scene=scene, dtype=str(dtype))


def fixed_step(system, z0, ts, method: str, dtype="float64", substeps: int = 1, args=None):
    """The true field integrated by ``models.rollout`` with a fixed-step method, in ``dtype``.

    float32 is emulated end to end: the system's arrays, the state, the times and the
    parameters are cast, so every product of the field is evaluated in float32.
    """
    import models

    sysd = _cast(system, dtype)
    if args is None:
        args = system.default_args()
    args = jnp.asarray(args, dtype=dtype)
    z0 = jnp.asarray(z0, dtype=dtype)
    ts = jnp.asarray(ts, dtype=dtype)
    integ = models.Integrator(method=method, substeps=substeps)
    batched = z0.ndim == 2
    fn = models.rollout_batch if batched else models.rollout
    a = jnp.broadcast_to(args, (z0.shape[0], args.shape[-1])) if batched else args
    return np.asarray(eqx.filter_jit(fn)(true_model(sysd, dtype), z0, ts, a, integ))


def adaptive(system, z0, ts, rtol, atol=None, solver="tsit5", args=None, max_steps=200_000):
    """The true field by diffrax with PID step control; returns (ys, nfe, result message).

    ``nfe`` counts evaluations for the explicit solvers (stages per step, FSAL saved); for
    the implicit ``kvaerno5`` it is the number of steps (its Newton iterations are not counted).

    ``throw=False``: running out of ``max_steps`` is recorded, not raised; ys then holds inf.
    """
    solvers = {
        "tsit5": diffrax.Tsit5,
        "dopri5": diffrax.Dopri5,
        "dopri8": diffrax.Dopri8,
        "kvaerno5": diffrax.Kvaerno5,
    }
    if solver not in solvers:
        raise ValueError(f"solver must be one of {', '.join(solvers)}; got {solver!r}")
    atol = rtol * 1e-2 if atol is None else atol
    args = system.default_args() if args is None else jnp.asarray(args)
    ts = jnp.asarray(ts, dtype=jnp.float64)
    sol = _adaptive_solve(
        system, jnp.asarray(z0, jnp.float64), ts, args, solvers[solver](), rtol, atol, max_steps
    )
    steps = int(sol.stats["num_steps"])
    stages = {"tsit5": 6, "dopri5": 6, "dopri8": 12, "kvaerno5": 0}[solver]
    ok = sol.result == diffrax.RESULTS.successful
    msg = "" if ok else f"diffrax: {diffrax.RESULTS[sol.result]}".strip()
    return np.asarray(sol.ys), (1 + stages * steps) if stages else steps, msg


@eqx.filter_jit
def _adaptive_solve(system, z0, ts, args, solver, rtol, atol, max_steps):
    return diffrax.diffeqsolve(
        diffrax.ODETerm(system.vector_field),
        solver,
        t0=ts[0],
        t1=ts[-1],
        dt0=None,
        y0=z0,
        args=args,
        saveat=diffrax.SaveAt(ts=ts),
        stepsize_controller=diffrax.PIDController(rtol=rtol, atol=atol),
        max_steps=max_steps,
        throw=False,
    )


def _grid(n_steps: int, dt: float = DT) -> np.ndarray:
    return dt * np.arange(n_steps + 1, dtype=np.float64)


def _velocity_mask(system) -> np.ndarray:
    """Which state entries a bound applies to: every non-angular one."""
    return np.concatenate([~np.asarray(system.angular), np.ones(system.dof, dtype=bool)])


def _bound(system, truth) -> float:
    mask = _velocity_mask(system)
    return BOUND_FACTOR * float(np.max(np.abs(np.asarray(truth)[..., mask])) + 1.0)


# --------------------------------------------------------------------------- cases
def case_dt_sweep(size) -> list[Row]:
    """Fixed-step error vs dt on the chain pendulum (k = 2) over ``size.horizon`` seconds.

    For each method in (euler, rk4, leapfrog) and dt: the relative state error at the final
    time against the float64 Dopri8 ground truth, or ``diverged`` with the step. Plus the
    fitted order of convergence log(err)/log(dt) over the dts where the error is in
    (1e-11, 1e-2) (float64 rounding below, the asymptotic regime ends above).
    """
    size = _size(size)
    sysm = systems.make("chain_pendulum", k=2)
    z0 = np.asarray(sysm.sample_initial(jax.random.PRNGKey(1), 1))[0]
    truth = np.asarray(sysm.simulate(z0, np.array([0.0, size.horizon])))
    rows = []
    for method in size.dt_methods:
        dts, errs = [], []
        for dt in size.dts:
            n = max(1, round(size.horizon / dt))
            ts = np.linspace(0.0, size.horizon, n + 1)
            variant = f"{method}/dt={dt:g}"
            zs = fixed_step(sysm, z0, ts, method)
            bad = first_bad_step(zs, _bound(sysm, truth), _velocity_mask(sysm))
            common = dict(system="chain_pendulum", method=method, param=dt)
            if bad is not None:
                rows.append(Row("dt_sweep", variant, "final_error", "diverged", step=bad, **common))
                continue
            err = float(relative_error(zs[-1], truth[-1]))
            rows.append(Row("dt_sweep", variant, "final_error", "ok", err, **common))
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
                    system="chain_pendulum",
                    method=method,
                )
            )
    return rows


def case_precision(size) -> list[Row]:
    """float32 vs float64 ground truth: the same fixed-step RK4 (dt/4) in both precisions.

    The float64 run's error against Dopri8 is the truncation error; the float32 run's is
    truncation plus rounding; their difference isolates the precision's share.
    """
    size = _size(size)
    rows = []
    for name, params in (("chain_pendulum", {"k": 2}), ("spring_pendulum", {"k": 2})):
        sysm = systems.make(name, **params)
        z0 = np.asarray(sysm.sample_initial(jax.random.PRNGKey(2), size.n_traj))
        n = round(size.horizon / DT)
        ts = _grid(n)
        truth = np.asarray(sysm.simulate_batch(z0, ts))
        for dtype in ("float32", "float64"):
            zs = fixed_step(sysm, z0, ts, "rk4", dtype=dtype, substeps=4)
            bad = first_bad_step(zs, _bound(sysm, truth), _velocity_mask(sysm))
            common = dict(system=name, method="rk4", param=DT / 4, dtype=dtype)
            if bad is not None:
                rows.append(
                    Row(
                        "precision",
                        f"{name}/{dtype}",
                        "final_error",
                        "diverged",
                        step=bad,
                        **common,
                    )
                )
                continue
            err = float(np.median(relative_error(zs[:, -1], truth[:, -1])))
            drift = float(np.median(energy_drift(sysm, zs)[:, -1]))
            rows.append(Row("precision", f"{name}/{dtype}", "final_error", "ok", err, **common))
            rows.append(Row("precision", f"{name}/{dtype}", "energy_drift", "ok", drift, **common))
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

    Tsit5 with PID control at each rtol (atol = rtol / 100) over ``size.horizon`` seconds:
    the largest energy drift along the trajectory, and the evaluations it took.
    """
    size = _size(size)
    sysm = systems.make("chain_pendulum", k=2)
    ts = _grid(round(size.horizon / DT))
    rows = []
    for label, z0 in high_energy_states(sysm).items():
        for rtol in size.rtols:
            variant = f"{label}/rtol={rtol:g}"
            common = dict(system="chain_pendulum", method="tsit5", param=rtol)
            ys, nfe, msg = adaptive(sysm, z0, ts, rtol)
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


def case_stiffness(size) -> list[Row]:
    """Stiff spring pendulum (k = 2 bobs, spring constant 1e3..1e5) at dt = 0.03.

    The highest normal mode has omega ~ sqrt(kappa (1/m1 + 1/m2 + ...)); classical RK4 is
    stable only for |omega dt| < 2.78, so at dt = 0.03 it must blow up from kappa ~ 1e4 on.
    Fixed-step RK4 records its divergence step (or its error), adaptive Tsit5 (rtol 1e-7)
    records its error against Dopri8 at 1e-11 and its evaluations, Kvaerno5 (implicit) too.
    """
    size = _size(size)
    rows = []
    n = round(size.horizon / DT)
    ts = _grid(n)
    for kappa in size.spring_constants:
        sysm = systems.make("spring_pendulum", k=2, spring_constant=kappa)
        eq = np.asarray(sysm.equilibrium())
        key = jax.random.PRNGKey(3)
        # A small displacement from equilibrium: the stiff mode is excited but its energy
        # (kappa |dx|^2 / 2) stays moderate, so that a failure is the integrator's.
        dq = 0.05 * np.asarray(jax.random.normal(key, (sysm.dof,), dtype=jnp.float64))
        z0 = np.concatenate([eq + dq, np.zeros(sysm.dof)])
        truth = np.asarray(sysm.simulate(z0, ts))
        bound = _bound(sysm, truth)
        common = dict(system="spring_pendulum", param=kappa)
        zs = fixed_step(sysm, z0, ts, "rk4")
        bad = first_bad_step(zs, bound, _velocity_mask(sysm))
        v = f"kappa={kappa:g}/rk4"
        if bad is not None:
            rows.append(
                Row("stiffness", v, "final_error", "diverged", step=bad, method="rk4", **common)
            )
        else:
            err = float(relative_error(zs[-1], truth[-1]))
            rows.append(Row("stiffness", v, "final_error", "ok", err, method="rk4", **common))
        rows.append(Row("stiffness", v, "nfe", "ok", float(4 * n), method="rk4", **common))
        for solver in size.stiff_solvers:
            v = f"kappa={kappa:g}/{solver}"
            ys, nfe, msg = adaptive(sysm, z0, ts, 1e-7, 1e-9, solver=solver)
            bad = first_bad_step(ys, bound, _velocity_mask(sysm))
            if msg or bad is not None:
                rows.append(
                    Row(
                        "stiffness",
                        v,
                        "final_error",
                        "failed" if msg else "diverged",
                        step=bad,
                        message=msg,
                        method=solver,
                        **common,
                    )
                )
                continue
            err = float(relative_error(ys[-1], truth[-1]))
            rows.append(Row("stiffness", v, "final_error", "ok", err, method=solver, **common))
            metric = "nfe" if solver != "kvaerno5" else "num_steps"
            rows.append(Row("stiffness", v, metric, "ok", float(nfe), method=solver, **common))
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


def case_relativistic(size) -> list[Row]:
    """Relativistic particle near the light cone, float32 vs float64.

    Round trip: |velocity(q, momentum(q, qdot)) - qdot| / (1 - |qdot|), the error measured in
    units of the distance to the light cone (an error of 1 would put qdot on or beyond c);
    momentum error: p = qdot (1 - qdot^2)^(-3/2) in the dtype vs float64 at the same qdot.
    Energy drift of the dynamics: float64 Tsit5 at rtol 1e-9 and fixed-step RK4 in float32
    and float64 (dt = 0.03) over ``size.horizon`` seconds, started towards and against g.
    """
    size = _size(size)
    sysm = systems.make("relativistic_particle")
    g = jnp.asarray([1.0])
    rows = []
    for speed in size.speeds:
        for dtype in ("float32", "float64"):
            rows += relativistic_roundtrip(sysm, speed, dtype)
        ts = _grid(round(size.horizon / DT))
        for sign in (1.0, -1.0):
            z0 = np.array([0.0, sign * speed])
            tag = "with_g" if sign > 0 else "against_g"
            ys, nfe, msg = adaptive(sysm, z0, ts, 1e-9, 1e-12, args=g)
            common = dict(system="relativistic_particle", param=speed)
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
                        method="tsit5",
                        **common,
                    )
                )
            else:
                drift = float(np.max(energy_drift(sysm, ys, g)))
                rows.append(
                    Row("relativistic", v, "energy_drift", "ok", drift, method="tsit5", **common)
                )
            for dtype in ("float32", "float64"):
                v = f"v={speed:g}/{tag}/rk4/{dtype}"
                zs = fixed_step(sysm, z0, ts, "rk4", dtype=dtype, args=g)
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
                            method="rk4",
                            dtype=dtype,
                            **common,
                        )
                    )
                    continue
                drift = float(np.max(energy_drift(sysm, zs, g)))
                rows.append(
                    Row(
                        "relativistic",
                        v,
                        "energy_drift",
                        "ok",
                        drift,
                        method="rk4",
                        dtype=dtype,
                        **common,
                    )
                )
    return rows


# ---- LNN with a near-singular Hessian
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


# ---- trained models: long horizons and high energy
_MODEL_CACHE: dict = {}


def _train_small(name: str, size: StabilitySize):
    """A small model of ``name`` on chain_pendulum k = 2 (cached per process)."""
    import models

    key = (name, size)
    if key in _MODEL_CACHE:
        return _MODEL_CACHE[key]
    sysm = systems.make("chain_pendulum", k=2)
    scene = models.Scene(dof=2, angular=tuple(sysm.angular))
    model = models.make(name, scene, key=jax.random.PRNGKey(0), width=size.width)
    info = "untrained"
    if size.train_steps > 0:
        import bench

        ds = systems.make_dataset(
            systems.DatasetConfig(
                system="chain_pendulum",
                system_params=(("k", 2),),
                n_generated=size.n_train,
                n_train=size.n_train,
                n_test=2,
            )
        )
        res = bench.train(model, ds, bench.TrainConfig(steps=size.train_steps, batch=64))
        model = res.model
        info = f"trained {res.steps_done} steps ({res.status})"
    _MODEL_CACHE[key] = (model, info)
    return model, info


def _applies(model, method: str) -> bool:
    from models._base import AbstractDiscreteModel

    if isinstance(model, AbstractDiscreteModel):
        return method == "rk4"  # a discrete model has one integrator: itself (label it once)
    return method != "leapfrog" or bool(model.second_order)


def case_long_horizon(size) -> list[Row]:
    """Small trained models rolled out ``size.long_steps`` steps of dt = 0.03 (10^4 at quick).

    Per model and integrator: divergence rate (fraction of trajectories non-finite or beyond
    the bound), median final energy drift of the surviving ones, median valid prediction time
    (seconds until the relative error first exceeds 0.1) and the rollout seconds.
    """
    import models

    size = _size(size)
    sysm = systems.make("chain_pendulum", k=2)
    ts = _grid(size.long_steps)
    z0 = np.asarray(sysm.sample_initial(jax.random.PRNGKey(4), size.n_traj))
    truth = np.asarray(sysm.simulate_batch(z0, ts))
    bound = _bound(sysm, truth)
    mask = _velocity_mask(sysm)
    rows = []
    for name in size.models:

        def one(name=name):
            model, info = _train_small(name, size)
            out = []
            for method in size.integrators:
                if not _applies(model, method):
                    continue
                label = "native" if not hasattr(model, "vector_field") else method
                out += _long_rollout(
                    model, info, name, label, method, sysm, z0, ts, truth, bound, mask, models
                )
            return out

        rows += guard("long_horizon", one, f"{name}/*")
    return rows


def _long_rollout(model, info, name, label, method, sysm, z0, ts, truth, bound, mask, models):
    variant = f"{name}/{label}"
    common = dict(system="chain_pendulum", method=label, param=float(len(ts) - 1), dtype="float32")
    integ = models.Integrator(
        method=method if method != "adaptive" else "adaptive",
        rtol=1e-6,
        atol=1e-8,
        max_steps=50 * len(ts),
    )
    fn = eqx.filter_jit(models.rollout_batch)
    z0f = jnp.asarray(z0, jnp.float32)
    tsf = jnp.asarray(ts, jnp.float32)
    try:
        fn(model, z0f[:1], tsf[:3], None, integ)  # compile outside the timing
        start = time.perf_counter()
        zs = np.asarray(jax.block_until_ready(fn(model, z0f, tsf, None, integ)))
        seconds = time.perf_counter() - start
    except Exception as err:  # noqa: BLE001 - an adaptive solve out of steps raises
        return [
            Row(
                "long_horizon",
                variant,
                "divergence_rate",
                "failed",
                message=one_line(err),
                **common,
            )
        ]
    bad_traj = [first_bad_step(z, bound, mask) for z in zs]
    diverged = np.array([b is not None for b in bad_traj])
    rate = float(diverged.mean())
    first = min((b for b in bad_traj if b is not None), default=None)
    rows = [
        Row(
            "long_horizon",
            variant,
            "divergence_rate",
            "ok",
            rate,
            step=first,
            message=info,
            **common,
        ),
        Row("long_horizon", variant, "rollout_seconds", "ok", seconds, message=info, **common),
    ]
    if diverged.all():
        rows.append(
            Row(
                "long_horizon",
                variant,
                "energy_drift",
                "diverged",
                step=first,
                message="every trajectory diverged",
                **common,
            )
        )
        return rows
    good = ~diverged
    drift = energy_drift(sysm, zs[good])[:, -1]
    err = relative_error(zs[good], truth[good])
    over = err > VALID_THRESHOLD
    valid_t = np.where(over.any(axis=1), ts[np.argmax(over, axis=1)], ts[-1])
    rows.append(
        Row(
            "long_horizon",
            variant,
            "energy_drift",
            "ok",
            float(np.median(drift)),
            message=info,
            **common,
        )
    )
    rows.append(
        Row(
            "long_horizon",
            variant,
            "valid_time",
            "ok",
            float(np.median(valid_t)),
            message=info,
            **common,
        )
    )
    return rows


def case_high_energy_models(size) -> list[Row]:
    """The small trained models (RK4) from the high-energy and near-top states of
    :func:`high_energy_states`: relative error after ``size.high_energy_steps`` steps, or the
    divergence step. Out of distribution on purpose: the training states are far lower."""
    import models

    size = _size(size)
    sysm = systems.make("chain_pendulum", k=2)
    states = high_energy_states(sysm)
    z0 = np.stack(list(states.values()))
    ts = _grid(size.high_energy_steps)
    truth = np.asarray(sysm.simulate_batch(z0, ts))
    bound, mask = _bound(sysm, truth), _velocity_mask(sysm)
    rows = []
    for name in size.models:

        def one(name=name):
            model, info = _train_small(name, size)
            zs = np.asarray(
                eqx.filter_jit(models.rollout_batch)(
                    model,
                    jnp.asarray(z0, jnp.float32),
                    jnp.asarray(ts, jnp.float32),
                    None,
                    models.Integrator("rk4"),
                )
            )
            out = []
            for i, label in enumerate(states):
                common = dict(system="chain_pendulum", method="rk4", dtype="float32")
                bad = first_bad_step(zs[i], bound, mask)
                v = f"{name}/{label}"
                if bad is not None:
                    out.append(
                        Row(
                            "high_energy_models",
                            v,
                            "final_error",
                            "diverged",
                            step=bad,
                            message=info,
                            **common,
                        )
                    )
                    continue
                err = float(relative_error(zs[i, -1], truth[i, -1]))
                out.append(
                    Row("high_energy_models", v, "final_error", "ok", err, message=info, **common)
                )
            return out

        rows += guard("high_energy_models", one, f"{name}/*")
    return rows


def _as_float64_model(model, name: str, size: StabilitySize):
    """``model``'s parameters in a float64 build of the same model (same static structure)."""
    import models

    scene = model.scene
    m64 = models.make(name, scene, key=jax.random.PRNGKey(0), width=size.width, dtype="float64")
    p64, static64 = eqx.partition(m64, eqx.is_array)
    leaves = [
        x.astype(jnp.float64) for x in jax.tree_util.tree_leaves(eqx.filter(model, eqx.is_array))
    ]
    params = jax.tree_util.tree_unflatten(jax.tree_util.tree_structure(p64), leaves)
    return eqx.combine(params, static64)


def case_model_precision(size) -> list[Row]:
    """The same small models rolled out in float32 and, with the same weights, in float64.

    RK4 over min(long_steps, 1000) steps of dt = 0.03 from the chain pendulum's states: the
    relative difference between the two rollouts at the end, and the first time it exceeds
    1e-3 (how fast rounding is amplified by the learned dynamics).
    """
    import models

    size = _size(size)
    sysm = systems.make("chain_pendulum", k=2)
    n = min(size.long_steps, 1000)
    ts = _grid(n)
    z0 = np.asarray(sysm.sample_initial(jax.random.PRNGKey(5), size.n_traj))
    rows = []
    for name in size.models:

        def one(name=name):
            model, info = _train_small(name, size)
            fn = eqx.filter_jit(models.rollout_batch)
            integ = models.Integrator("rk4")
            z32 = np.asarray(
                fn(model, jnp.asarray(z0, jnp.float32), jnp.asarray(ts, jnp.float32), None, integ)
            )
            m64 = _as_float64_model(model, name, size)
            z64 = np.asarray(fn(m64, jnp.asarray(z0), jnp.asarray(ts), None, integ))
            v = f"{name}/float32_vs_float64"
            common = dict(system="chain_pendulum", method="rk4", param=float(n), dtype="both")
            bad = first_bad_step(np.concatenate([z32, z64]))
            if bad is not None:
                return [
                    Row(
                        "model_precision",
                        v,
                        "final_difference",
                        "diverged",
                        step=bad,
                        message=info,
                        **common,
                    )
                ]
            diff = relative_error(z32, z64)
            over = diff > 1e-3
            t_sep = np.where(over.any(axis=1), ts[np.argmax(over, axis=1)], ts[-1])
            return [
                Row(
                    "model_precision",
                    v,
                    "final_difference",
                    "ok",
                    float(np.median(diff[:, -1])),
                    message=info,
                    **common,
                ),
                Row(
                    "model_precision",
                    v,
                    "separation_time",
                    "ok",
                    float(np.median(t_sep)),
                    message=info,
                    **common,
                ),
            ]

        rows += guard("model_precision", one, f"{name}/*")
    return rows


CASES: dict[str, Callable[[StabilitySize], list[Row]]] = {
    "dt_sweep": case_dt_sweep,
    "precision": case_precision,
    "high_energy_truth": case_high_energy_truth,
    "stiffness": case_stiffness,
    "relativistic": case_relativistic,
    "lnn_singular": case_lnn_singular,
    "long_horizon": case_long_horizon,
    "high_energy_models": case_high_energy_models,
    "model_precision": case_model_precision,
}


def run_cases(profile="quick", cases=None, progress: bool = True) -> list[Row]:
    """Every case (or the named ones) at ``profile``'s size, each inside :func:`guard`."""
    size = _size(profile)
    names = list(CASES) if cases is None else list(cases)
    unknown = [c for c in names if c not in CASES]
    if unknown:
        raise ValueError(f"unknown stability case(s) {unknown}; allowed: {', '.join(CASES)}")
    rows = []
    for name in names:
        start = time.perf_counter()
        got = guard(name, lambda name=name: CASES[name](size))
        if progress:
            outcomes = {o: sum(r.outcome == o for r in got) for o in OUTCOMES}
            print(
                f"[stability] {name}: {len(got)} rows {outcomes} "
                f"in {time.perf_counter() - start:.1f}s",
                flush=True,
            )
        rows += got
    return rows


def to_frame(rows):
    import pandas as pd

    return pd.DataFrame([asdict(r) for r in rows], columns=list(COLUMNS))


def run_stability(results_dir="results", profile: str = "quick", cases=None):
    """Run the cases; write ``stability.csv``/``.parquet`` and the figure; return the frame."""
    results_dir = Path(results_dir)
    results_dir.mkdir(parents=True, exist_ok=True)
    df = to_frame(run_cases(profile, cases))
    df.insert(0, "profile", profile)
    df.to_csv(results_dir / "stability.csv", index=False)
    try:
        df.to_parquet(results_dir / "stability.parquet", index=False)
    except Exception as err:  # noqa: BLE001 - parquet is a convenience copy of the CSV
        print(f"[stability] parquet not written: {one_line(err)}")
    stability_figure(results_dir)
    return df


# --------------------------------------------------------------------------- figure and report
def _load(results_dir):
    import pandas as pd

    path = Path(results_dir) / "stability.csv"
    return pd.read_csv(path) if path.exists() else None


def stability_figure(results_dir="results") -> list[Path]:
    """Four panels: error vs dt, stiff solvers' evaluations, tolerance vs drift, long horizon."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    df = _load(results_dir)
    if df is None or df.empty:
        return []
    fig, axes = plt.subplots(2, 2, figsize=(11, 8))

    ax = axes[0, 0]
    d = df[(df.case == "dt_sweep") & (df.metric == "final_error")]
    for method, g in d.groupby("method"):
        ok = g[g.outcome == "ok"]
        ax.loglog(ok.param, ok.value.clip(lower=1e-16), "o-", label=method)
        div = g[g.outcome == "diverged"]
        ax.plot(div.param, np.ones(len(div)), "x", color=ax.lines[-1].get_color(), ms=10)
    ax.set(
        xlabel="dt",
        ylabel="relative error at final time",
        title="chain pendulum: fixed step vs dt (x = diverged)",
    )
    ax.legend()

    ax = axes[0, 1]
    d = df[(df.case == "stiffness") & (df.metric == "nfe")]
    for method, g in d.groupby("method"):
        ax.loglog(g.param, g.value, "o-", label=method)
    e = df[(df.case == "stiffness") & (df.metric == "final_error") & (df.outcome == "diverged")]
    for _, r in e.iterrows():
        same = d[(d.method == r.method) & (d.param == r.param)]
        y = float(same.value.iloc[0]) if len(same) else 1.0
        ax.annotate(
            f"{r.method} diverged @ step {int(r.step)}", (r.param, y), fontsize=7, rotation=20
        )
    ax.set(
        xlabel="spring constant",
        ylabel="vector-field evaluations",
        title="stiff spring pendulum, dt = 0.03",
    )
    ax.legend()

    ax = axes[1, 0]
    d = df[(df.case == "high_energy_truth") & (df.metric == "energy_drift") & (df.outcome == "ok")]
    for label, g in d.groupby(d.variant.str.split("/").str[0]):
        ax.loglog(g.param, g.value.clip(lower=1e-17), "o-", label=label)
    ax.set(xlabel="rtol", ylabel="max energy drift", title="ground truth at high energy")
    ax.legend()

    ax = axes[1, 1]
    d = df[(df.case == "long_horizon") & (df.metric == "divergence_rate")]
    if not d.empty:
        ax.barh(d.variant, d.value.fillna(1.0))
        ax.set(
            xlabel="fraction of trajectories diverged",
            title=f"long horizon ({int(d.param.iloc[0])} steps)",
        )
    else:
        ax.set_axis_off()
    fig.tight_layout()
    out = Path(results_dir) / "figures"
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / "stability.png", out / "stability.pdf"]
    for p in paths:
        fig.savefig(p, dpi=120)
    plt.close(fig)
    return paths


def _fmt(r) -> str:
    if r.outcome == "ok":
        return f"{r.value:.3g}"
    if r.outcome == "diverged":
        step = (
            ""
            if r.step is None or (isinstance(r.step, float) and math.isnan(r.step))
            else (f" @ step {int(r.step)}")
        )
        return f"diverged{step}"
    return f"failed ({str(r.message)[:60]})"


def stability_section(results_dir="results") -> str:
    """REPORT.md's stability section: one table per case from ``stability.csv``."""
    df = _load(results_dir)
    if df is None or df.empty:
        return (
            "## Numerical stability\n\nNo `stability.csv` yet: run `python -m bench._stability`.\n"
        )
    lines = [
        "## Numerical stability",
        "",
        f"Profile `{df.profile.iloc[0]}`. Every variant ends in `ok` (a value), `diverged` "
        "(with the first non-finite or runaway step) or `failed` (with the error). "
        "Errors: relative state error ||zhat - z|| / (||zhat|| + ||z||); energy drift "
        "|H - H0| / (|H| + |H0|) with the true H.",
        "",
    ]
    for case, g in df.groupby("case", sort=False):
        doc = (CASES[case].__doc__ or "").strip().split("\n")[0] if case in CASES else ""
        lines += [
            f"### {case}",
            "",
            doc,
            "",
            "| variant | metric | result |",
            "| --- | --- | --- |",
        ]
        for r in g.itertuples():
            lines.append(f"| {r.variant} | {r.metric} | {_fmt(r)} |")
        lines.append("")
    counts = df.outcome.value_counts().to_dict()
    lines.append(f"Outcomes: {counts}.")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench._stability", description=__doc__)
    parser.add_argument("--profile", default="quick", choices=list(SIZES))
    parser.add_argument("--results", default="results")
    parser.add_argument("--case", action="append", choices=list(CASES))
    ns = parser.parse_args(argv)
    df = run_stability(ns.results, ns.profile, ns.case)
    print(df.to_string(max_rows=400))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
