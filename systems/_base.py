"""The abstract system and the Lagrangian machinery shared by every concrete system.

A system is a small ``eqx.Module`` whose physics is one scalar, L(q, qdot) = T - V. The
equations of motion follow from the Euler-Lagrange equations by automatic differentiation,
in one place (here), for every system:

    M(q, qdot) qddot = dL/dq - (d2L/dqdot dq) qdot + Q,      M = d2L/dqdot2,

solved by a linear solve. Q is the generalised friction force of a drag -f m_i v_i on every
body: Q = -f dT/dqdot (for T = 1/2 sum m_i |v_i|^2 with v_i = J_i(q) qdot, sum_i F_i . dx_i/dq
= -f sum_i m_i J_i^T v_i = -f dT/dqdot). When T is quadratic in qdot, M^{-1} Q = -f qdot
exactly, whatever the coordinates.

Ground truth is integrated in float64 by diffrax (8th-order Dormand-Prince, PID step control at
rtol = atol = 1e-11, or the tighter ``ground_truth_tol`` of a system that sets one), saved at
the requested times, in groups of :data:`TRUTH_GROUP` trajectories. A system may integrate
another form of its motion and map it back to (q, qdot) (``_truth_state``, ``_truth_field``,
``_truth_to_z``): the rotor integrates its frame, where its Euler angles are singular. The
batched solver is one module-level ``eqx.filter_jit`` function taking the system as an
argument, so it is traced once per system type, state size and number of save times (array
fields such as masses are traced, not baked in).
"""

from __future__ import annotations

import abc
from typing import ClassVar

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from ._precision import require_x64

RTOL = 1e-11
ATOL = 1e-11
MAX_STEPS = 1_000_000
SOLVERS = ("dopri8", "dopri5", "tsit5", "kvaerno5")


class AbstractSystem(eqx.Module):
    """A mechanical system with Lagrangian L(q, qdot, args) = T(q, qdot) - V(q, args).

    State z = concat(q, qdot) of length 2 * dof. ``args`` holds the per-trajectory parameters
    (shape ``(n_args,)``); ``None`` means :meth:`default_args`.
    """

    name: eqx.AbstractVar[str]
    angular: eqx.AbstractVar[tuple[bool, ...]]
    # rtol = atol of the ground truth (a class constant): 1e-11, or tighter where a system's
    # conservation test needs it (two_body: 1e-13, energy to < 1e-9 over ten orbits)
    ground_truth_tol: ClassVar[float] = RTOL
    friction: eqx.AbstractVar[float]
    n_args: eqx.AbstractVar[int]

    # ----------------------------------------------------------------------------- physics
    @property
    def dof(self) -> int:
        """Number of generalised coordinates."""
        return len(self.angular)

    def default_args(self) -> Array:
        """The parameters used when ``args`` is None (empty for parameter-free systems)."""
        return jnp.zeros((0,), dtype=jnp.float64)

    @abc.abstractmethod
    def kinetic_energy(self, q, qdot, args=None):
        """T(q, qdot); also defines the friction force Q = -f dT/dqdot."""

    @abc.abstractmethod
    def potential_energy(self, q, args=None):
        """V(q)."""

    @abc.abstractmethod
    def positions(self, z) -> Array:
        """Cartesian positions of the bodies at state z."""

    @abc.abstractmethod
    def sample_initial(self, key, n: int) -> Array:
        """``n`` random initial states z0."""

    def sample_args(self, key, n: int) -> Array:
        """``n`` random per-trajectory parameter vectors (shape (n, 0) when there are none)."""
        del key
        return jnp.zeros((n, 0), dtype=jnp.float64)

    def potential_range(self, args=None) -> float:
        """max V - min V over configuration space, or nan where V is unbounded."""
        del args
        return float("nan")

    def _args(self, args):
        return self.default_args() if args is None else jnp.asarray(args)

    def lagrangian(self, q, qdot, args=None):
        """L = T(q, qdot) - V(q)."""
        args = self._args(args)
        return self.kinetic_energy(q, qdot, args) - self.potential_energy(q, args)

    def momentum(self, z, args=None):
        """Canonical momentum p = dL/dqdot at z = (q, qdot)."""
        args = self._args(args)
        q, qdot = self._split(z)
        return jax.grad(self.lagrangian, argnums=1)(q, qdot, args)

    def velocity(self, q, p, args=None):
        """Inverse of :meth:`momentum` for T quadratic in qdot: qdot = M(q)^{-1} p."""
        args = self._args(args)
        mass = jax.hessian(self.lagrangian, argnums=1)(q, jnp.zeros_like(q), args)
        return jnp.linalg.solve(mass, p)

    def energy(self, z, args=None):
        """Total energy H = p . qdot - L (the Legendre transform; T + V when T is quadratic)."""
        args = self._args(args)
        q, qdot = self._split(z)
        return jnp.dot(self.momentum(z, args), qdot) - self.lagrangian(q, qdot, args)

    def friction_force(self, q, qdot, args):
        """Generalised force of a drag -f m_i v_i on every body: Q = -f dT/dqdot."""
        return -self.friction * jax.grad(self.kinetic_energy, argnums=1)(q, qdot, args)

    def acceleration(self, q, qdot, args=None):
        """qddot = M^{-1} (dL/dq - (d2L/dqdot dq) qdot + Q), M = d2L/dqdot2 (Euler-Lagrange)."""
        args = self._args(args)
        dl_dqdot = lambda q_, v_: jax.grad(self.lagrangian, argnums=1)(q_, v_, args)
        dl_dq = jax.grad(self.lagrangian, argnums=0)(q, qdot, args)
        mass = jax.jacfwd(dl_dqdot, argnums=1)(q, qdot)
        # d/dq (dL/dqdot) . qdot as a single forward-mode product, not a full Jacobian.
        _, mixed = jax.jvp(lambda q_: dl_dqdot(q_, qdot), (q,), (qdot,))
        rhs = dl_dq - mixed
        if self.friction != 0.0:
            rhs = rhs + self.friction_force(q, qdot, args)
        return jnp.linalg.solve(mass, rhs)

    def vector_field(self, t, z, args):
        """dz/dt = (qdot, qddot). Pure; ``diffrax.ODETerm(system.vector_field)`` works."""
        del t
        q, qdot = self._split(z)
        return jnp.concatenate([qdot, self.acceleration(q, qdot, args)])

    def _split(self, z):
        return z[..., : self.dof], z[..., self.dof :]

    # The form the ground truth integrates: z and :meth:`vector_field` themselves by default. A
    # system whose coordinates are singular somewhere a trajectory may pass close by (ZXZ Euler
    # angles at sin(beta) = 0) integrates a regular form instead and maps its samples back to z.
    _truth_substeps: ClassVar[int] = 1  # saves per interval of the requested times

    def _truth_state(self, z0, args):
        """The integrated state at the start, from z0 (one trajectory)."""
        del args
        return z0

    def _truth_field(self, t, y, args):
        """d/dt of the integrated state."""
        return self.vector_field(t, y, args)

    def _truth_to_z(self, ys, z0, args):
        """The integrated states at the save times (leading axis: time) as z, shape (T, 2 dof):
        the requested times, each interval cut into ``_truth_substeps``."""
        del z0, args
        return ys

    # -------------------------------------------------------------------------- simulation
    def check_states(self, z: np.ndarray) -> None:
        """Raise ValueError for states outside the system's domain (hook; none by default)."""

    def simulate(
        self, z0, ts, args=None, *, rtol=None, atol=None, solver="dopri8", stats=False
    ) -> Array:
        """Ground-truth trajectory z(ts) from z(ts[0]) = z0, float64, shape (len(ts), 2*dof).

        ``rtol``, ``atol``, ``solver`` and ``stats``: as in :meth:`simulate_batch`.
        """
        require_x64("simulate")
        z0 = _as_float_array(z0, "z0")
        if z0.shape != (2 * self.dof,):
            raise ValueError(
                f"z0 must have shape ({2 * self.dof},) for {self.name}; got {z0.shape}"
            )
        if args is not None:
            args = _as_float_array(args, "args")
            if args.shape != (self.n_args,):
                raise ValueError(f"args must have shape ({self.n_args},); got {args.shape}")
            args = args[None]
        out = self.simulate_batch(
            z0[None], ts, args, rtol=rtol, atol=atol, solver=solver, stats=stats
        )
        if stats:
            return out[0][0], {k: v[0] for k, v in out[1].items()}
        return out[0]

    def simulate_batch(
        self, z0s, ts, args=None, *, rtol=None, atol=None, solver="dopri8", stats=False
    ) -> Array:
        """Ground-truth trajectories for a batch of initial states, shape (N, len(ts), 2*dof).

        ``args``: None (default parameters), shape (n_args,) (shared) or (N, n_args).
        ``rtol``, ``atol``: the PID controller's tolerances (default: the ground truth's,
        ``ground_truth_tol``, 1e-11 unless the system sets it tighter);
        ``solver``: ``dopri8`` (default) | ``dopri5`` | ``tsit5`` | ``kvaerno5`` (implicit, for
        stiff systems). The solve runs in float64 with ``max_steps`` = 10^6 and does not raise:
        a solve that fails (out of steps) is not finite from where it stopped. With
        ``stats=True`` returns ``(zs, stats)``, stats per trajectory: ``num_steps``,
        ``num_rejected_steps``, ``nfe`` (vector-field evaluations: stages per step less the
        first-same-as-last one; for ``kvaerno5`` the stages' Newton iterations are not counted,
        so it is a lower bound) and ``ok`` (the solve succeeded).
        """
        require_x64("simulate")
        if any(x.dtype != jnp.float64 for x in jax.tree_util.tree_leaves(self) if eqx.is_array(x)):
            raise ValueError(
                f"this {self.name} was made while jax's 64-bit mode was off (float32 "
                "parameters): make it again after systems.enable_x64()"
            )
        if solver not in SOLVERS:
            raise ValueError(f"solver {solver!r}: allowed {', '.join(SOLVERS)}")
        rtol = self.ground_truth_tol if rtol is None else rtol
        atol = self.ground_truth_tol if atol is None else atol
        for name, tol in (("rtol", rtol), ("atol", atol)):
            if not (isinstance(tol, int | float) and 0 < tol < 1):
                raise ValueError(f"{name} must be a number in (0, 1), got {tol!r}")
        z0s = _as_float_array(z0s, "z0s")
        if z0s.ndim != 2 or z0s.shape[1] != 2 * self.dof or z0s.shape[0] < 1:
            raise ValueError(
                f"z0s must have shape (N >= 1, {2 * self.dof}) for {self.name}; got {z0s.shape}"
            )
        self.check_states(z0s)
        ts = _as_float_array(ts, "ts")
        if ts.ndim != 1 or ts.shape[0] < 2:
            raise ValueError(f"ts must be a 1-D array of at least 2 times; got shape {ts.shape}")
        if not np.all(np.diff(ts) > 0):
            raise ValueError("ts must be strictly increasing")
        n = z0s.shape[0]
        if args is None:
            args = np.broadcast_to(np.asarray(self.default_args()), (n, self.n_args))
        else:
            args = _as_float_array(args, "args")
            if args.shape == (self.n_args,):
                args = np.broadcast_to(args, (n, self.n_args))
            if args.shape != (n, self.n_args):
                raise ValueError(
                    f"args must have shape ({self.n_args},) or ({n}, {self.n_args}); "
                    f"got {args.shape}"
                )
        default = (rtol, atol, solver) == (self.ground_truth_tol,) * 2 + ("dopri8",)
        if default and not stats:
            return _solve_batch(self, jnp.asarray(z0s), jnp.asarray(ts), jnp.asarray(args))
        zs, info = _solve_batch_with(
            self,
            jnp.asarray(z0s),
            jnp.asarray(ts),
            jnp.asarray(args),
            jnp.asarray(rtol, jnp.float64),
            jnp.asarray(atol, jnp.float64),
            solver,
        )
        return (zs, info) if stats else zs


def _as_float_array(x, what: str) -> np.ndarray:
    try:
        arr = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{what} must be a real float array; got {type(x).__name__}") from e
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{what} must be finite (no nan or inf)")
    return arr


# Trajectories solved side by side: a vmapped adaptive solve steps until its slowest member
# is done, so a batch is cut into groups of this many (``jax.lax.map``), each paying its own.
TRUTH_GROUP = 128
_METHODS = {
    "dopri8": diffrax.Dopri8,
    "dopri5": diffrax.Dopri5,
    "tsit5": diffrax.Tsit5,
    "kvaerno5": diffrax.Kvaerno5,
}
# stages per step less the first-same-as-last one; kvaerno5's Newton iterations not counted
_STAGES = {"dopri8": 12, "dopri5": 6, "tsit5": 6, "kvaerno5": 6}


def _solve(system: AbstractSystem, z0s, ts, args, rtol, atol, solver: str):
    """Each trajectory's solve (``system``'s integrated form, :meth:`_truth_field`), saved at
    ``ts`` refined ``_truth_substeps`` times for :meth:`_truth_to_z`, returned at ``ts``."""
    term = diffrax.ODETerm(system._truth_field)
    method = _METHODS[solver]()
    controller = diffrax.PIDController(rtol=rtol, atol=atol)
    k = system._truth_substeps
    saved = ts if k == 1 else jnp.append(jnp.linspace(ts[:-1], ts[1:], k, endpoint=False).T, ts[-1])

    def one(z0_a):
        z0, a = z0_a
        sol = diffrax.diffeqsolve(
            term,
            method,
            t0=ts[0],
            t1=ts[-1],
            dt0=None,
            y0=system._truth_state(z0, a),
            args=a,
            saveat=diffrax.SaveAt(ts=saved),
            stepsize_controller=controller,
            max_steps=MAX_STEPS,
            throw=False,
        )
        steps = sol.stats["num_steps"]
        info = {
            "num_steps": steps,
            "num_rejected_steps": sol.stats["num_rejected_steps"],
            "nfe": 1 + _STAGES[solver] * steps,
            "ok": sol.result == diffrax.RESULTS.successful,
        }
        return system._truth_to_z(sol.ys, z0, a)[::k], info

    return jax.lax.map(one, (z0s, args), batch_size=TRUTH_GROUP)


@eqx.filter_jit
def _solve_batch(system: AbstractSystem, z0s, ts, args):
    tol = system.ground_truth_tol
    return _solve(system, z0s, ts, args, tol, tol, "dopri8")[0]


@eqx.filter_jit
def _solve_batch_with(system: AbstractSystem, z0s, ts, args, rtol, atol, solver: str):
    """:func:`_solve_batch` at other tolerances or with another solver, with step counts."""
    return _solve(system, z0s, ts, args, rtol, atol, solver)


def reference_masses_lengths(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The reference masses and lengths of n bodies.

    A legacy ``numpy.random.RandomState(0)`` draws n masses and then n lengths, each uniform on
    [0.6, 1.4]; each list is used in reverse order, as the paper's public code does.
    """
    rng = np.random.RandomState(0)
    masses = rng.uniform(0.6, 1.4, size=n)
    lengths = rng.uniform(0.6, 1.4, size=n)
    return masses[::-1].copy(), lengths[::-1].copy()
