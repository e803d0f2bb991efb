"""Rows, guards, sizes and the shared integration helpers of the stability cases.

Everything here stands on the suite's shared machinery: ground truth is ``systems``'
``simulate_batch`` (Dopri8 at 1e-11 by default; other tolerances and solvers through its
``rtol``/``atol``/``solver`` keywords), fixed-step and adaptive rollouts of the true field go
through ``models.rollout`` (the true system wrapped as a model by :func:`true_model`), and
errors, energy drift and the valid-prediction time are those of ``bench.core._metrics`` (angle
differences wrapped, one threshold for valid prediction).
"""

from __future__ import annotations

import dataclasses
import math
import traceback
from collections.abc import Callable
from dataclasses import asdict, dataclass, fields
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from models import DESCRIPTIONS, METHODS

from ...core import energies, energy_violation_curve, one_line, valid_prediction_time
from ...core import relative_error as _relative_error

OUTCOMES = ("ok", "diverged", "failed")
DT = 0.03
# A trajectory is called diverged where |z| exceeds this multiple of the largest |z| of the
# true trajectories (non-angular coordinates only: a whirling angle grows without bound).
BOUND_FACTOR = 100.0
# What each method label in the tables is (``models.DESCRIPTIONS`` and this study's choices).
METHOD_NOTES = {
    **DESCRIPTIONS,
    "adaptive": "Tsit5, PID rtol 1e-6",
    "native": "the discrete model's own step",
}


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


# --------------------------------------------------------------------------- metrics
def relative_error(system, zhat, z):
    """``bench.core._metrics.relative_error`` with the system's angles wrapped, shape (..., T)."""
    return _relative_error(zhat, z, tuple(system.angular))


def energy_drift(system, zs, args=None):
    """|H(z_t) - H(z_0)| / (|H(z_t)| + |H(z_0)|) with the true H (``bench.core._metrics``'
    energies and violation curve), for zs (..., T, D); 1 from the first non-finite state."""
    zs = np.asarray(zs, dtype=np.float64)
    h = energies(system, zs, args)
    return energy_violation_curve(h, np.broadcast_to(h[..., :1], h.shape))


def valid_time(system, zhat, z, ts):
    """``bench.core._metrics.valid_prediction_time`` of the wrapped relative error."""
    return valid_prediction_time(relative_error(system, zhat, z), ts)


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
    integrators: tuple[str, ...] = (
        "euler",
        "rk4",
        "leapfrog",
        "leapfrog_explicit",
        "implicit_midpoint",
        "adaptive",
    )
    horizon: float = 3.0  # seconds of the ground-truth cases
    rtols: tuple[float, ...] = (1e-3, 1e-5, 1e-7, 1e-9)
    spring_constants: tuple[float, ...] = (1e3, 1e4, 1e5)
    speeds: tuple[float, ...] = (0.99, 0.999, 0.9999)
    dts: tuple[float, ...] = (3e-4, 1e-3, 3e-3, 1e-2, 3e-2, 0.1, 0.3)
    high_energy_steps: int = 200
    # every fixed-step method but euler_so (the paper's rule for controlled transitions)
    dt_methods: tuple[str, ...] = tuple(m for m in METHODS if m not in ("adaptive", "euler_so"))
    stiff_solvers: tuple[str, ...] = ("tsit5", "kvaerno5")
    stiff_horizon: float = 1.0  # seconds of the stiffness case (each call counted on the host)
    stiff_fixed: tuple[str, ...] = ("rk4", "implicit_midpoint")
    lnn_probe: bool = True  # also probe freshly initialised LNN models with each solve


SIZES = {
    "smoke": StabilitySize(
        n_traj=2,
        long_steps=100,
        train_steps=0,
        n_train=16,
        width=16,
        models=("node_so", "lnn"),
        integrators=("rk4", "leapfrog", "implicit_midpoint", "adaptive"),
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
    from models import AbstractContinuousModel

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


def rollout_true(system, z0, ts, integrator, dtype="float64", args=None, stats=False):
    """The true field integrated by ``models.rollout`` with ``integrator``, in ``dtype``.

    float32 is emulated end to end: the system's arrays, the state, the times and the
    parameters are cast, so every product of the field is evaluated in float32. ``z0`` (D,)
    or (N, D). With ``stats`` also returns the evaluation count per trajectory.
    """
    import models

    sysd = _cast(system, dtype)
    if args is None:
        args = system.default_args()
    args = jnp.asarray(args, dtype=dtype)
    z0 = jnp.asarray(z0, dtype=dtype)
    ts = jnp.asarray(ts, dtype=dtype)
    batched = z0.ndim == 2
    fn = models.rollout_batch if batched else models.rollout
    a = jnp.broadcast_to(args, (z0.shape[0], args.shape[-1])) if batched else args
    out = eqx.filter_jit(fn)(true_model(sysd, dtype), z0, ts, a, integrator, return_stats=True)
    zs, info = out
    return (np.asarray(zs), np.asarray(info["nfe"])) if stats else np.asarray(zs)


def fixed_step(system, z0, ts, method: str, dtype="float64", substeps: int = 1, args=None):
    """:func:`rollout_true` with ``models.Integrator(method, substeps=substeps)``."""
    import models

    return rollout_true(system, z0, ts, models.Integrator(method, substeps=substeps), dtype, args)


def solve(system, z0, ts, rtol, atol=None, solver="tsit5", args=None):
    """``system.simulate`` (or ``simulate_batch`` for z0 (N, D)) at ``rtol``/``atol`` with
    ``solver``; returns (ys, nfe, message). ``atol`` defaults to rtol / 100; ``message`` is
    empty unless a solve failed (then ys holds inf from where it stopped)."""
    atol = rtol * 1e-2 if atol is None else atol
    z0 = np.asarray(z0, dtype=np.float64)
    fn = system.simulate_batch if z0.ndim == 2 else system.simulate
    ys, info = fn(z0, ts, args, rtol=rtol, atol=atol, solver=solver, stats=True)
    ok = bool(np.all(np.asarray(info["ok"])))
    msg = "" if ok else f"{solver} did not finish (out of steps or non-finite)"
    return np.asarray(ys), np.asarray(info["nfe"]), msg


_COUNTED: dict[type, type] = {}
_CALLS = [0]


def _bump():
    _CALLS[0] += 1


def counting(system):
    """``(system', calls)``: a copy of ``system`` whose ``vector_field`` counts its calls in
    ``calls[0]`` (a host callback per evaluation; a forward-mode Jacobian counts once).

    One counting class per system type, so that a compiled solve is reused across parameters;
    the counter is shared: read it right after the solve (after ``jax.effects_barrier()``).
    """
    cls = type(system)
    if cls not in _COUNTED:

        class Counted(cls):
            def vector_field(self, t, z, args):
                jax.debug.callback(_bump)
                return super().vector_field(t, z, args)

        _COUNTED[cls] = Counted
    copy = object.__new__(_COUNTED[cls])
    for f in dataclasses.fields(system):
        object.__setattr__(copy, f.name, getattr(system, f.name))
    _CALLS[0] = 0
    return copy, _CALLS


def grid(n_steps: int, dt: float = DT) -> np.ndarray:
    return dt * np.arange(n_steps + 1, dtype=np.float64)


def velocity_mask(system) -> np.ndarray:
    """Which state entries a bound applies to: every non-angular one."""
    return np.concatenate([~np.asarray(system.angular), np.ones(system.dof, dtype=bool)])


def bound(system, truth) -> float:
    mask = velocity_mask(system)
    return BOUND_FACTOR * float(np.max(np.abs(np.asarray(truth)[..., mask])) + 1.0)


def fmt_outcome(r) -> str:
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
