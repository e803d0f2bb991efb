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
- ``leapfrog`` is the generalised (implicit) Stormer-Verlet method, second order and
  time-symmetric for every second-order model, symplectic for a Hamiltonian field in
  canonical coordinates; ``leapfrog_explicit`` is the explicit kick-drift-kick velocity Verlet
  (first order once the acceleration depends on the velocity);
- ``implicit_midpoint`` (``y_{n+1} = y_n + h F((y_n + y_{n+1}) / 2)``) is symplectic for
  every Hamiltonian field, separable or not, in the model's own (canonical) coordinates;
- the implicit stages are solved by ``optimistix`` (fixed-point iteration or Newton) to a
  tolerance tied to the state's dtype, and differentiated by the implicit function theorem
  (``optimistix.ImplicitAdjoint``), so training through them costs no unrolled iterations;
- ``euler_so`` is the paper's Euler rule for controlled second-order models (order 1);
- discrete models (``step(z, dt, args)``) ignore the method: ``z_{n+1} = step(z_n, h, args)``;
- ``controls`` (a controlled scene) hold u_i on interval i (zero-order hold): the model's
  args on that interval are (static args, u_i); see :func:`rollout`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import jax
import jax.numpy as jnp

from ._controls import _control_sequence
from ._euler_so import _euler_so
from ._implicit import (
    _implicit_midpoint,
    _leapfrog_canonical,
    _leapfrog_velocity,
)
from ._scan import _decoded, _scan_intervals

METHODS = (
    "euler",
    "rk4",
    "rk4_38",
    "leapfrog",
    "leapfrog_explicit",
    "implicit_midpoint",
    "adaptive",
    "euler_so",
)
SOLVERS = ("tsit5", "dopri5", "dopri8")
IMPLICIT_SOLVERS = ("fixed_point", "newton")
# Methods that need a second-order model (or a canonical scene) and their convergence orders.
LEAPFROGS = ("leapfrog", "leapfrog_explicit")
SECOND_ORDER_ONLY = ("leapfrog_explicit", "euler_so")  # need acceleration(q, v, args)
ORDERS = {
    "euler": 1,
    "rk4": 4,
    "rk4_38": 4,
    "leapfrog": 2,
    "leapfrog_explicit": 2,  # 1 once the acceleration depends on the velocity
    "implicit_midpoint": 2,
    "euler_so": 1,  # q takes the h^2/2 term, v is explicit Euler
}
# What each method is, in a phrase (report tables name methods by these).
DESCRIPTIONS = {
    "euler": "explicit Euler (order 1)",
    "rk4": "classical RK4 (order 4)",
    "rk4_38": "Kutta's 3/8 rule (order 4)",
    "leapfrog": "generalised Stormer-Verlet: implicit velocity kick, in (q, p) for Hamiltonian "
    "models (order 2; symplectic for H)",
    "leapfrog_explicit": "explicit velocity Verlet (order 1 once the acceleration depends on v)",
    "implicit_midpoint": "implicit midpoint (order 2, symplectic for any H)",
    "adaptive": "diffrax adaptive Runge-Kutta with PID step control",
    "euler_so": "the paper's Euler rule for second-order models: q + h v + h^2/2 a, v + h a "
    "(order 1)",
}


# The implicit stages' tolerance and steppers: models/_implicit.py.
@dataclass(frozen=True)
class Integrator:
    """How ``rollout`` advances a continuous model.

    ``method``: ``euler`` | ``rk4`` | ``rk4_38`` | ``leapfrog`` | ``leapfrog_explicit`` |
    ``implicit_midpoint`` | ``adaptive`` | ``euler_so``.
    ``substeps``: fixed steps per interval of ``ts`` (fixed-step methods and discrete models).
    ``rtol``, ``atol``, ``solver`` (``tsit5`` | ``dopri5`` | ``dopri8``), ``max_steps``: the
    adaptive solve.
    ``implicit_solver`` (``fixed_point`` | ``newton``), ``implicit_max_steps``: the nonlinear
    solve of the implicit stages of ``leapfrog`` and ``implicit_midpoint`` (optimistix, to
    ``implicit_tolerance`` of the state's dtype; a stage that does not converge keeps its last
    iterate). ``implicit_iterations = k > 0`` replaces the solve by exactly k fixed-point
    iterations (a fixed cost, no convergence test, differentiated through the iterations).
    """

    method: str = "rk4_38"
    substeps: int = 1
    rtol: float = 1e-6
    atol: float = 1e-8
    solver: str = "tsit5"
    max_steps: int = 100_000
    implicit_iterations: int = 0
    implicit_solver: str = "fixed_point"
    implicit_max_steps: int = 32

    def __post_init__(self):
        if self.method not in METHODS:
            raise ValueError(f"integrator method {self.method!r}: allowed {', '.join(METHODS)}")
        if self.solver not in SOLVERS:
            raise ValueError(f"adaptive solver {self.solver!r}: allowed {', '.join(SOLVERS)}")
        if self.implicit_solver not in IMPLICIT_SOLVERS:
            raise ValueError(
                f"implicit solver {self.implicit_solver!r}: allowed {', '.join(IMPLICIT_SOLVERS)}"
            )
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
        k = self.implicit_max_steps
        if isinstance(k, bool) or not isinstance(k, int) or k < 1:
            raise ValueError(f"implicit_max_steps must be an integer >= 1, got {k!r}")


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
    if kind == "continuous" and integrator.method in LEAPFROGS and not _leapfrog_ok(model):
        raise ValueError(
            f"{integrator.method} needs a second-order model (acceleration(q, v, args)) or a "
            f"canonical scene; {type(model).__name__} is first order: use euler, rk4, rk4_38, "
            "implicit_midpoint or adaptive"
        )
    method = integrator.method
    if kind == "continuous" and method in SECOND_ORDER_ONLY and not model.second_order:
        raise ValueError(
            f"{method} needs a second-order model (acceleration(q, v, args)); "
            f"{type(model).__name__} is first order: use euler, leapfrog or implicit_midpoint"
        )
    return kind


def _canonical(model) -> bool:
    """Whether leapfrog works on the partitioned field (dq/dt, dp/dt) of ``internal_field``:
    the model integrates in other coordinates than (q, qdot) (a Hamiltonian model's (q, p)),
    or it is a first-order model of a canonical scene."""
    from ._base import AbstractContinuousModel

    if not model.second_order:
        return bool(getattr(model.scene, "canonical", False))
    return type(model).encode is not AbstractContinuousModel.encode


def _leapfrog_ok(model) -> bool:
    return bool(model.second_order) or bool(getattr(model.scene, "canonical", False))


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


def rollout(
    model,
    z0,
    ts,
    args,
    integrator: Integrator = Integrator(),
    *,
    controls=None,
    return_stats: bool = False,
):
    """States of ``model`` started at ``z0`` at the times ``ts``: shape ``(len(ts), 2d)``.

    ``zs[0] = z0``. The state keeps ``z0``'s dtype (the trainer casts data to the model's
    dtype first). Fixed-step methods take ``integrator.substeps`` steps of
    ``h = (ts[i+1] - ts[i]) / substeps`` per interval.

    ``controls`` (len(ts) - 1, n_controls), needed exactly when ``model.scene.n_controls`` >
    0: a zero-order hold, interval i [ts[i], ts[i+1]] is integrated with u_i, i.e. every
    field evaluation (and encode/decode) on it gets ``args_i = concat(args, u_i)``; the state
    is continuous across intervals. Every fixed-step method and discrete models support it
    (``leapfrog`` in (q, v) re-evaluates its carried acceleration with u_i at the start of
    each interval); ``adaptive`` raises.

    ``euler_so`` (second-order models; the paper's rule for its MuJoCo models, 8 substeps
    per transition): ``a = a(q, v, u); q_new = q + h v + h^2/2 a; v_new = v + h a``, order 1.

    ``leapfrog`` is the generalised Stormer-Verlet method (Hairer, Lubich & Wanner,
    *Geometric Numerical Integration*, VI.3). For a second-order model integrated in
    z = (q, v) (``a = model.acceleration``), kick-drift-kick with an implicit last kick::

        v' = v + h/2 a(q, v);  q_new = q + h v';  v_new = v' + h/2 a(q_new, v_new)

    solved for ``a_new = a(q_new, v_new)``, which is reused as the first kick of the next
    step. It is second order and time-symmetric whatever ``a`` depends on (damping, the
    Coriolis terms of a chain or of a learned mass matrix); when ``a`` does not depend on v the
    solve converges at once and the map is the classical symplectic Stormer-Verlet. For a model
    that integrates in canonical y = (q, p) (``encode`` overridden: the Hamiltonian models;
    or a first-order model of a canonical scene), with ``internal_field = (f, g)``::

        p' = p + h/2 g(q, p');  q_new = q + h/2 (f(q, p') + f(q_new, p'));
        p_new = p' + h/2 g(q_new, p')

    (two implicit stages): symplectic and second order for every H(q, p), separable or not,
    e.g. the q-dependent mass of ``hnn_so``.

    ``leapfrog_explicit`` is the explicit velocity Verlet (one acceleration per step)::

        v' = v + h/2 a(q, v);  q_new = q + h v';  v_new = v' + h/2 a(q_new, v')

    symplectic and second order only when ``a`` does not depend on v; with a
    velocity-dependent ``a`` it is neither symplectic nor time-reversible and FIRST order.

    ``implicit_midpoint``: ``y_new = y + h K`` with ``K = F(t + h/2, y + h/2 K)`` in the model's
    coordinates: symplectic for every Hamiltonian field, second order, A-stable.

    The implicit stages are solved with optimistix (``integrator.implicit_solver``) to
    :func:`implicit_tolerance` from an extrapolated guess and differentiated implicitly.

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
    method = integrator.method
    count = jnp.zeros((), jnp.int32)
    seq = _control_sequence(model, ts, args, controls, integrator, dtype)
    first = args if seq is None else seq[0] if ts.shape[0] > 1 else None

    if seq is not None and ts.shape[0] < 2:
        zs = z0[None]
    elif kind == "discrete":

        def advance(c, t, h, a):
            return (model.step(c[0], h, a).astype(dtype),)

        zs, _ = _scan_intervals(advance, (z0,), ts, m, args, seq)
    elif method == "euler_so":
        zs = _euler_so(model, z0, ts, args, m, seq)
    elif method == "adaptive":
        if ts.shape[0] < 2:
            zs, stats = z0[None], {"nfe": jnp.asarray(0)}
        else:
            zs, stats = _adaptive(model, z0, ts, args, integrator)
    elif method == "leapfrog_explicit" or (method == "leapfrog" and not _canonical(model)):
        zs, count = _leapfrog_velocity(model, z0, ts, args, integrator, seq)
    elif method == "leapfrog":
        zs, count = _leapfrog_canonical(model, z0, ts, args, integrator, seq)
    elif method == "implicit_midpoint":
        zs, count = _implicit_midpoint(model, z0, ts, args, integrator, seq)
    else:
        step = _STEPS[method]

        def advance(c, t, h, a):
            return (step(lambda t_, y_: model.internal_field(t_, y_, a).astype(dtype), t, c[0], h),)

        ys, _ = _scan_intervals(advance, (model.encode(z0, first).astype(dtype),), ts, m, args, seq)
        zs = _decoded(model, z0, ys, args, seq)

    if not return_stats:
        return zs
    if stats is None:
        carried = ("leapfrog", "implicit_midpoint") + (
            ("leapfrog_explicit",) if seq is not None else ()
        )
        if kind == "continuous" and method in carried:
            stats = {"nfe": count}
        else:
            stats = {"nfe": count_evaluations(model, ts, integrator)}
    return zs, stats


def rollout_batch(
    model,
    z0s,
    ts,
    args,
    integrator: Integrator = Integrator(),
    *,
    controls=None,
    return_stats: bool = False,
):
    """``rollout`` vmapped over initial states ``z0s (N, 2d)``, per-trajectory ``args`` and
    per-trajectory ``controls``.

    ``args`` is ``(N, P)`` (or ``None``); ``controls`` is ``(N, len(ts) - 1, n_controls)`` in a
    controlled scene (else ``None``); ``ts`` is shared. Returns ``(N, T, 2d)``.
    """
    _check(model, integrator)
    z0s = jnp.asarray(z0s)
    if z0s.ndim != 2:
        raise ValueError(f"z0s must have shape (N, 2d), got {z0s.shape}")
    n_u = int(getattr(model.scene, "n_controls", 0))
    if controls is not None or n_u:
        expected = (z0s.shape[0], jnp.shape(ts)[0] - 1, n_u)
        shape = None if controls is None else jnp.shape(controls)
        if shape != expected:
            raise ValueError(
                f"controls must have shape (N, len(ts) - 1, n_controls) = {expected}, got "
                f"{'None' if shape is None else shape}"
            )
    args_axis = None if args is None else 0
    controls_axis = None if controls is None else 0

    def one(z0, a, u):
        return rollout(model, z0, ts, a, integrator, controls=u, return_stats=return_stats)

    return jax.vmap(one, in_axes=(0, args_axis, controls_axis))(z0s, args, controls)


def count_evaluations(model, ts, integrator: Integrator = Integrator()) -> Any:
    """Vector-field evaluations per trajectory of a fixed-step rollout over ``ts``.

    Per step: euler and euler_so 1, rk4 and rk4_38 4, leapfrog_explicit 1 (plus one initial
    acceleration, reused afterwards; a controlled rollout re-evaluates it once per interval,
    which ``rollout(..., return_stats=True)`` counts), a discrete model 1 ``step``; with
    ``implicit_iterations = k > 0`` leapfrog k (2k in canonical coordinates) and
    implicit_midpoint k, plus one initial evaluation. For ``adaptive`` and for implicit stages
    solved to tolerance the count is known only after the solve: use
    ``rollout(..., return_stats=True)``.
    """
    kind = _check(model, integrator)
    steps = (len(ts) - 1) * integrator.substeps
    if kind == "discrete":
        return steps
    method = integrator.method
    if method == "adaptive" or (
        method in ("leapfrog", "implicit_midpoint") and integrator.implicit_iterations == 0
    ):
        raise ValueError(
            f"count_evaluations: the cost of {method} is known after the solve; use "
            "rollout(..., return_stats=True) (allowed here: euler, euler_so, rk4, rk4_38, "
            "leapfrog_explicit, or implicit_iterations > 0)"
        )
    first = 1 if steps > 0 else 0
    if method == "leapfrog_explicit":
        return steps + first
    if method == "leapfrog":
        per = 2 if _canonical(model) else 1
        return steps * per * integrator.implicit_iterations + first
    if method == "implicit_midpoint":
        return steps * integrator.implicit_iterations + first
    return steps * {"euler": 1, "euler_so": 1, "rk4": 4, "rk4_38": 4}[method]
