"""One place that owns how a learned model is advanced in time.

``rollout(model, z0, ts, args, integrator)`` returns the states at the times ``ts``:

- continuous models (``dz/dt = F(t, z, args)``) with a Runge-Kutta or adaptive method are
  integrated in the model's own coordinates: ``dy/dt = model.internal_field(t, y, args)``
  from ``y0 = model.encode(z0, args)``, every saved state mapped back with ``model.decode``
  (identity maps by default; the Hamiltonian models in velocity scenes use canonical
  ``y = (q, p)``, where the field is just ``J grad H``). ``zs[0]`` is ``z0`` itself;
- with a fixed-step method they take ``substeps``
  equal steps ``h = (ts[i+1] - ts[i]) / substeps`` per interval (so non-uniform ``ts`` work),
  written as a ``jax.lax.scan`` over intervals with the Runge-Kutta stages by hand (the
  cheapest program for XLA: no solver state, no step-size control);
- ``adaptive`` hands the field to ``diffrax.diffeqsolve`` with a PID step-size controller and
  ``SaveAt(ts=ts)``;
- ``leapfrog`` is kick-drift-kick velocity Verlet on ``z = (q, v)`` using the model's
  ``acceleration(q, v, args)`` (second-order models only);
- discrete models (``step(z, dt, args)``) ignore the method: ``z_{n+1} = step(z_n, h, args)``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import jax
import jax.numpy as jnp

METHODS = ("euler", "rk4", "rk4_38", "leapfrog", "adaptive")
SOLVERS = ("tsit5", "dopri5", "dopri8")
# Intervals up to this many are unrolled: training chunks are short (4 intervals) and the
# unrolled program lets XLA fuse across steps; long test rollouts stay a compact loop.
_UNROLL_MAX = 8


@dataclass(frozen=True)
class Integrator:
    """How ``rollout`` advances a continuous model.

    ``method``: ``euler`` | ``rk4`` | ``rk4_38`` | ``leapfrog`` | ``adaptive``.
    ``substeps``: fixed steps per interval of ``ts`` (fixed-step methods and discrete models).
    ``rtol``, ``atol``, ``solver`` (``tsit5`` | ``dopri5`` | ``dopri8``), ``max_steps``: the
    adaptive solve.
    ``implicit_iterations``: leapfrog only; fixed-point iterations of the implicit second
    velocity kick for velocity-dependent accelerations (0: the explicit variant, see
    :func:`rollout`).
    """

    method: str = "rk4_38"
    substeps: int = 1
    rtol: float = 1e-6
    atol: float = 1e-8
    solver: str = "tsit5"
    max_steps: int = 100_000
    implicit_iterations: int = 0

    def __post_init__(self):
        if self.method not in METHODS:
            raise ValueError(f"integrator method {self.method!r}: allowed {', '.join(METHODS)}")
        if self.solver not in SOLVERS:
            raise ValueError(f"adaptive solver {self.solver!r}: allowed {', '.join(SOLVERS)}")
        if isinstance(self.substeps, bool) or not isinstance(self.substeps, int):
            raise ValueError(f"substeps must be an integer >= 1, got {self.substeps!r}")
        if self.substeps < 1:
            raise ValueError(f"substeps must be an integer >= 1, got {self.substeps}")
        for name in ("rtol", "atol"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and 0 < value < 1):
                raise ValueError(f"{name} must be a number in (0, 1), got {value!r}")
        k = self.implicit_iterations
        if isinstance(k, bool) or not isinstance(k, int) or k < 0:
            raise ValueError(f"implicit_iterations must be an integer >= 0, got {k!r}")
        if isinstance(self.max_steps, bool) or not isinstance(self.max_steps, int):
            raise ValueError(f"max_steps must be an integer >= 1, got {self.max_steps!r}")
        if self.max_steps < 1:
            raise ValueError(f"max_steps must be an integer >= 1, got {self.max_steps}")


def _kinds():
    # Imported late: the model hierarchy lives in a sibling module that imports nothing of ours.
    from ._base import AbstractContinuousModel, AbstractDiscreteModel

    return AbstractContinuousModel, AbstractDiscreteModel


def _kind(model) -> str:
    continuous, discrete = _kinds()
    if isinstance(model, discrete):
        return "discrete"
    if isinstance(model, continuous):
        return "continuous"
    raise ValueError(
        f"rollout needs an AbstractContinuousModel or AbstractDiscreteModel, got "
        f"{type(model).__name__}"
    )


def _check(model, integrator) -> str:
    if not isinstance(integrator, Integrator):
        raise ValueError(f"integrator must be a models.Integrator, got {type(integrator).__name__}")
    kind = _kind(model)
    if kind == "continuous" and integrator.method == "leapfrog" and not model.second_order:
        raise ValueError(
            f"leapfrog needs a second-order model (acceleration(q, v, args)); "
            f"{type(model).__name__} is first order: use euler, rk4, rk4_38 or adaptive"
        )
    return kind


# --- one step of each fixed-step method ------------------------------------------------------


def _euler(f, t, z, h):
    """z + h F(t, z)."""
    return z + h * f(t, z)


def _rk4(f, t, z, h):
    """Classical RK4: k1..k4 at c = (0, 1/2, 1/2, 1), weights (1, 2, 2, 1)/6."""
    k1 = f(t, z)
    k2 = f(t + 0.5 * h, z + (0.5 * h) * k1)
    k3 = f(t + 0.5 * h, z + (0.5 * h) * k2)
    k4 = f(t + h, z + h * k3)
    return z + (h / 6) * (k1 + 2 * k2 + 2 * k3 + k4)


def _rk4_38(f, t, z, h):
    """Kutta's 3/8 rule: c = (0, 1/3, 2/3, 1), a = (1/3; -1/3, 1; 1, -1, 1), b = (1, 3, 3, 1)/8."""
    k1 = f(t, z)
    k2 = f(t + h / 3, z + (h / 3) * k1)
    k3 = f(t + 2 * h / 3, z + h * (k2 - k1 / 3))
    k4 = f(t + h, z + h * (k1 - k2 + k3))
    return z + (h / 8) * (k1 + 3 * (k2 + k3) + k4)


_STEPS = {"euler": _euler, "rk4": _rk4, "rk4_38": _rk4_38}


def _scan_intervals(advance, carry, ts, substeps):
    """Apply ``advance(carry, t, h)`` ``substeps`` times per interval of ``ts``; stack states.

    ``carry`` is a tuple whose first entry is the state ``z``.
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
        return carry[0][None]
    _, zs = jax.lax.scan(interval, carry, (ts[:-1], ts[1:]), unroll=n if n <= _UNROLL_MAX else 1)
    return jnp.concatenate([carry[0][None], zs], axis=0)


def _adaptive(model, z0, ts, args, integrator):
    import diffrax

    solver = {"tsit5": diffrax.Tsit5, "dopri5": diffrax.Dopri5, "dopri8": diffrax.Dopri8}[
        integrator.solver
    ]()
    sol = diffrax.diffeqsolve(
        diffrax.ODETerm(lambda t, y, a: model.internal_field(t, y, a).astype(y.dtype)),
        solver,
        t0=ts[0],
        t1=ts[-1],
        dt0=ts[1] - ts[0],
        y0=model.encode(z0, args).astype(z0.dtype),
        args=args,
        saveat=diffrax.SaveAt(ts=ts),
        stepsize_controller=diffrax.PIDController(rtol=integrator.rtol, atol=integrator.atol),
        max_steps=integrator.max_steps,
        # A rollout that blows up or runs out of steps is an outcome to record, not an error:
        # diffrax then fills the unreached save points with inf, which the metrics count as
        # failed predictions from that time on.
        throw=False,
    )
    tableau = solver.tableau
    per_step = tableau.num_stages - (1 if tableau.fsal else 0)
    steps = sol.stats["num_steps"]
    stats = {
        "nfe": 1 + per_step * steps,
        "num_steps": steps,
        "num_accepted_steps": sol.stats["num_accepted_steps"],
        "num_rejected_steps": sol.stats["num_rejected_steps"],
    }
    return _decoded(model, z0, sol.ys, args), stats


def _decoded(model, z0, ys, args):
    """States z of the integrator's states ys (T, n): z0 itself first, then decode(ys[1:])."""
    if ys.shape[0] == 1:
        return z0[None]
    rest = jax.vmap(lambda y: model.decode(y, args))(ys[1:]).astype(z0.dtype)
    return jnp.concatenate([z0[None], rest], axis=0)


def rollout(
    model, z0, ts, args, integrator: Integrator = Integrator(), *, return_stats: bool = False
):
    """States of ``model`` started at ``z0`` at the times ``ts``: shape ``(len(ts), 2d)``.

    ``zs[0] = z0``. The state keeps ``z0``'s dtype (the trainer casts data to the model's
    dtype first). Fixed-step methods take ``integrator.substeps`` steps of
    ``h = (ts[i+1] - ts[i]) / substeps`` per interval.

    ``leapfrog`` (velocity Verlet, kick-drift-kick, ``a = model.acceleration``)::

        v' = v + h/2 a(q, v);  q_new = q + h v';  a_new = a(q_new, v');  v_new = v' + h/2 a_new

    and ``a_new`` is reused as the first kick of the next step (one acceleration per step).
    When ``a`` does not depend on ``v`` this is the exact symplectic, time-reversible,
    second-order Stormer-Verlet map. When it does (damping; Coriolis terms of a learned
    mass matrix) this explicit variant evaluates the velocity-dependent part at the half-step
    velocity: it is then neither symplectic nor time-reversible, and first order in that part.
    ``implicit_iterations = k > 0`` instead solves the second kick
    ``v_new = v' + h/2 a(q_new, v_new)`` by k fixed-point iterations started from the explicit
    value (1 + k accelerations per step): the generalised leapfrog, time-reversible when
    ``a(q, -v) = a(q, v)`` (no drift of a conserved energy) and second order.

    With ``return_stats=True`` returns ``(zs, stats)``; ``stats["nfe"]`` counts vector-field
    evaluations. For ``adaptive`` it is ``1 + (stages - fsal) * num_steps`` from diffrax's step
    counts, which can undercount by at most one evaluation per rejected step (the first-same-
    as-last stage that diffrax recomputes after some rejections); ``stats`` then also holds
    ``num_steps``, ``num_accepted_steps`` and ``num_rejected_steps``.
    """
    kind = _check(model, integrator)
    z0 = jnp.asarray(z0)
    ts = jnp.asarray(ts)
    if ts.ndim != 1 or ts.shape[0] < 1:
        raise ValueError(f"ts must be a 1-d array of times, got shape {ts.shape}")
    ts = ts.astype(z0.dtype) if jnp.issubdtype(z0.dtype, jnp.floating) else ts
    m = integrator.substeps
    dtype = z0.dtype
    stats = None

    if kind == "discrete":

        def advance(c, t, h):
            return (model.step(c[0], h, args).astype(dtype),)

        zs = _scan_intervals(advance, (z0,), ts, m)
    elif integrator.method == "adaptive":
        if ts.shape[0] < 2:
            zs, stats = z0[None], {"nfe": jnp.asarray(0)}
        else:
            zs, stats = _adaptive(model, z0, ts, args, integrator)
    elif integrator.method == "leapfrog":
        d = z0.shape[-1] // 2

        def accel(q, v):
            return model.acceleration(q, v, args).astype(dtype)

        def advance(c, t, h):
            z, a = c
            q, v = z[:d], z[d:]
            v_half = v + (0.5 * h) * a
            q_new = q + h * v_half
            a_new = accel(q_new, v_half)
            for _ in range(integrator.implicit_iterations):
                a_new = accel(q_new, v_half + (0.5 * h) * a_new)
            return (jnp.concatenate([q_new, v_half + (0.5 * h) * a_new]), a_new)

        zs = _scan_intervals(advance, (z0, accel(z0[:d], z0[d:])), ts, m)
    else:
        step = _STEPS[integrator.method]

        def f(t, y):
            return model.internal_field(t, y, args).astype(dtype)

        def advance(c, t, h):
            return (step(f, t, c[0], h),)

        ys = _scan_intervals(advance, (model.encode(z0, args).astype(dtype),), ts, m)
        zs = _decoded(model, z0, ys, args)

    if not return_stats:
        return zs
    if stats is None:
        stats = {"nfe": count_evaluations(model, ts, integrator)}
    return zs, stats


def rollout_batch(
    model, z0s, ts, args, integrator: Integrator = Integrator(), *, return_stats: bool = False
):
    """``rollout`` vmapped over initial states ``z0s (N, 2d)`` and per-trajectory ``args``.

    ``args`` is ``(N, P)`` (or ``None``); ``ts`` is shared. Returns ``(N, T, 2d)``.
    """
    _check(model, integrator)
    z0s = jnp.asarray(z0s)
    if z0s.ndim != 2:
        raise ValueError(f"z0s must have shape (N, 2d), got {z0s.shape}")
    args_axis = None if args is None else 0

    def one(z0, a):
        return rollout(model, z0, ts, a, integrator, return_stats=return_stats)

    return jax.vmap(one, in_axes=(0, args_axis))(z0s, args)


def count_evaluations(model, ts, integrator: Integrator = Integrator()) -> Any:
    """Vector-field evaluations per trajectory of a fixed-step rollout over ``ts``.

    Per step: euler 1, rk4 and rk4_38 4, leapfrog 1 + implicit_iterations (plus one initial
    acceleration, reused afterwards), a discrete model 1 ``step``. For ``adaptive`` the count
    is known only after the solve: use ``rollout(..., return_stats=True)``.
    """
    kind = _check(model, integrator)
    steps = (len(ts) - 1) * integrator.substeps
    if kind == "discrete":
        return steps
    if integrator.method == "adaptive":
        raise ValueError(
            "count_evaluations: adaptive cost is known after the solve; "
            "use rollout(..., return_stats=True) (allowed here: euler, rk4, rk4_38, leapfrog)"
        )
    if integrator.method == "leapfrog":
        return steps * (1 + integrator.implicit_iterations) + (1 if steps > 0 else 0)
    return steps * {"euler": 1, "rk4": 4, "rk4_38": 4}[integrator.method]
