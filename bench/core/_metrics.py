"""Metrics of a predicted rollout ``zhat`` against the truth ``z`` (arrays (..., T, 2d)).

Conventions shared by every metric here:

- Angles. ``angular`` marks which of the d coordinates q are angles. A difference of angles is
  wrapped to (-pi, pi], and the norm of a state uses its angles wrapped to (-pi, pi], so adding
  2 pi k to any predicted or true angle changes nothing. (The reference unwrapped angles across
  trajectories, which added 2 pi k offsets to the norms and shrank its errors.)
- Time. Summaries exclude t = 0 (the shared initial state, error exactly 0) unless
  ``reference_compatible=True``, which includes t = 0 and does no wrapping, "for comparison
  with the paper's numbers only".
- Non-finite predictions. From the first time a predicted state has a non-finite entry, the
  relative error and the energy violation are 1 (the maximum of a ratio |a - b| / (|a| + |b|)),
  so a diverged rollout scores as the worst possible prediction, not as NaN.
- Geometric means clamp below at 1e-7: exp(mean(log(max(err, 1e-7)))).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

CLAMP = 1e-7


def wrap(x):
    """Angles mapped to (-pi, pi]: pi - ((pi - x) mod 2 pi)."""
    return np.pi - np.mod(np.pi - np.asarray(x, dtype=np.float64), 2 * np.pi)


def _angular_mask(angular, width: int) -> np.ndarray:
    """Mask over the 2d state entries: True on q entries that are angles (never on rates)."""
    a = np.asarray(tuple(angular) if angular is not None else (), dtype=bool)
    mask = np.zeros(width, dtype=bool)
    mask[: a.size] = a
    return mask


def _nonfinite_from_first(zhat: np.ndarray) -> np.ndarray:
    """(..., T) bool: True from the first time any entry of zhat is non-finite."""
    bad = ~np.all(np.isfinite(zhat), axis=-1)
    return np.cumsum(bad, axis=-1) > 0


def state_difference(zhat, z, angular=(), wrap_angles: bool = True) -> np.ndarray:
    """zhat - z with angle entries wrapped to (-pi, pi]."""
    zhat = np.asarray(zhat, dtype=np.float64)
    z = np.asarray(z, dtype=np.float64)
    d = zhat - z
    if wrap_angles:
        mask = _angular_mask(angular, d.shape[-1])
        d = np.where(mask, wrap(d), d)
    return d


def relative_error(zhat, z, angular=(), reference_compatible: bool = False) -> np.ndarray:
    """Per-time relative state error, shape (..., T).

    err(t) = ||zhat(t) - z(t)|| / (||zhat(t)|| + ||z(t)||), with wrapped angle differences and
    wrapped angles inside the norms (see module doc); 1 from the first non-finite prediction
    on; 0 where both states are zero.
    """
    zhat = np.asarray(zhat, dtype=np.float64)
    z = np.asarray(z, dtype=np.float64)
    wrap_angles = not reference_compatible
    bad = _nonfinite_from_first(zhat)
    zh = np.where(np.isfinite(zhat), zhat, 0.0)
    num = np.linalg.norm(state_difference(zh, z, angular, wrap_angles), axis=-1)
    if wrap_angles:
        mask = _angular_mask(angular, z.shape[-1])
        zh, zt = np.where(mask, wrap(zh), zh), np.where(mask, wrap(z), z)
    else:
        zt = z
    den = np.linalg.norm(zh, axis=-1) + np.linalg.norm(zt, axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        err = np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0)
    return np.where(bad, 1.0, err)


def geometric_mean(x, clamp: float = CLAMP, axis=None):
    """exp(mean(log(max(x, clamp)))); NaN entries are ignored, all-NaN gives NaN."""
    x = np.asarray(x, dtype=np.float64)
    with np.errstate(invalid="ignore", divide="ignore"):
        logs = np.log(np.maximum(x, clamp))
    logs = np.where(np.isnan(x), np.nan, logs)
    if np.all(np.isnan(logs)):
        return np.float64(np.nan) if axis is None else np.exp(np.nanmean(logs, axis=axis))
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.exp(np.nanmean(logs, axis=axis))


def _from(curves: np.ndarray, reference_compatible: bool) -> np.ndarray:
    return curves if reference_compatible else curves[..., 1:]


def rollout_error(zhat, z, angular=(), reference_compatible: bool = False) -> float:
    """Geometric mean of :func:`relative_error` over t >= 1 and over trajectories.

    With ``reference_compatible`` t = 0 enters the mean and angles are not wrapped.
    """
    err = relative_error(zhat, z, angular, reference_compatible)
    return float(geometric_mean(_from(err, reference_compatible)))


def energies(system, zs, args=None, coordinates: str = "velocity") -> np.ndarray:
    """The system's TRUE energy H at every state of ``zs`` (..., 2d) -> (...).

    In momentum coordinates z = (q, p), qdot = system.velocity(q, p, args) first. Non-finite
    states give NaN. ``args``: None, (n_args,), or one row per leading trajectory (N, n_args).
    """
    zs = np.asarray(zs, dtype=np.float64)
    shape = zs.shape[:-1]
    if args is None:
        a = np.asarray(system.default_args(), dtype=np.float64)
    else:
        a = np.asarray(args, dtype=np.float64)
    p = a.shape[-1]
    if a.ndim == 1:
        a = np.broadcast_to(a, (*shape, p))
    else:  # (N, P) per trajectory: repeat over time
        a = np.broadcast_to(a.reshape(a.shape[0], *([1] * (len(shape) - 1)), p), (*shape, p))
    flat_z = zs.reshape(-1, zs.shape[-1])
    flat_a = np.ascontiguousarray(a).reshape(flat_z.shape[0], -1)
    finite = np.all(np.isfinite(flat_z), axis=-1)
    safe = np.where(finite[:, None], flat_z, 0.0)

    h = np.asarray(_energy_batch(system, jnp.asarray(safe), jnp.asarray(flat_a), coordinates))
    return np.where(finite, h, np.nan).reshape(shape)


@eqx.filter_jit
def _energy_batch(system, zs, args, coordinates):
    # One compiled program per system type and shapes: the system is a pytree argument.
    d = zs.shape[-1] // 2

    def one(zz, aa):
        if coordinates == "momentum":
            q, p = zz[:d], zz[d:]
            zz = jnp.concatenate([q, system.velocity(q, p, aa)])
        return system.energy(zz, aa)

    return jax.vmap(one)(zs, args)


def energy_violation_curve(h_pred, h_true) -> np.ndarray:
    """|H(zhat) - H(z)| / (|H(zhat)| + |H(z)|) per time, 1 from the first non-finite H(zhat).

    0 where both energies are 0.
    """
    h_pred = np.asarray(h_pred, dtype=np.float64)
    h_true = np.asarray(h_true, dtype=np.float64)
    bad = np.cumsum(~np.isfinite(h_pred), axis=-1) > 0
    hp = np.where(np.isfinite(h_pred), h_pred, 0.0)
    den = np.abs(hp) + np.abs(h_true)
    with np.errstate(invalid="ignore", divide="ignore"):
        v = np.where(den > 0, np.abs(hp - h_true) / np.where(den > 0, den, 1.0), 0.0)
    return np.where(bad, 1.0, v)


def energy_violation(h_pred, h_true, reference_compatible: bool = False) -> float:
    """Geometric mean over t >= 1 and trajectories of :func:`energy_violation_curve`."""
    return float(
        geometric_mean(_from(energy_violation_curve(h_pred, h_true), reference_compatible))
    )


def energy_pct_max_pe(h_pred, h_true, potential_range: float) -> float:
    """100 * mean |H(zhat) - H(z)| / (max V - min V) over t >= 1 (the LNN seed's metric).

    NaN when the potential is unbounded (``potential_range`` nan) or the prediction is
    non-finite.
    """
    pr = float(potential_range)
    if not np.isfinite(pr) or pr <= 0:
        return float("nan")
    diff = np.abs(np.asarray(h_pred, dtype=np.float64) - np.asarray(h_true, dtype=np.float64))
    return float(100.0 * np.mean(diff[..., 1:]) / pr)


def energy_pct_max_pe_last(h_pred, h_true, potential_range: float) -> float:
    """100 * mean over trajectories of |H(zhat) - H(z)| at the LAST time / (max V - min V): the
    LNN seed's notebook's version of :func:`energy_pct_max_pe` (its text: the mean over time).
    NaN as there."""
    h_pred, h_true = np.asarray(h_pred, dtype=np.float64), np.asarray(h_true, dtype=np.float64)
    return energy_pct_max_pe(h_pred[..., -2:], h_true[..., -2:], potential_range)


def energy_mse(h_pred, h_true) -> float:
    """mean over trajectories and every time (t = 0 included) of (H(zhat) - H(z))^2, H the true
    energy: the HNN seed's "energy MSE" along rollouts. NaN if a prediction is non-finite."""
    d = np.asarray(h_pred, dtype=np.float64) - np.asarray(h_true, dtype=np.float64)
    return float(np.mean(d**2)) if np.all(np.isfinite(d)) else float("nan")


def mse(zhat, z, angular=()) -> float:
    """mean over t >= 1, trajectories and entries of (zhat - z)^2, angle differences wrapped.

    NaN if any prediction is non-finite.
    """
    zhat = np.asarray(zhat, dtype=np.float64)
    if not np.all(np.isfinite(zhat)):
        return float("nan")
    d = state_difference(zhat, z, angular)[..., 1:, :]
    return float(np.mean(d**2))


def valid_prediction_time(err, ts, threshold: float = 0.025) -> np.ndarray:
    """Per trajectory: ts[first t with err(t) > threshold] - ts[0]; full horizon if never.

    ``err`` (..., T) per-time relative errors (non-finite already counted as 1).
    """
    err = np.asarray(err, dtype=np.float64)
    ts = np.asarray(ts, dtype=np.float64)
    rel = ts - ts[0]
    over = err > threshold
    first = np.argmax(over, axis=-1)
    return np.where(np.any(over, axis=-1), rel[first], rel[-1])


def perturbed_floor(
    system,
    z_test,
    ts,
    args=None,
    key: int = 0,
    scale: float = 1e-4,
    coordinates="velocity",
    sim_points: int | None = None,
) -> float:
    """Rollout error of the TRUE system started from z0 + scale * N(0, 1) (same metric).

    The floor that no learned model can beat at the data's float precision and chaos.
    ``sim_points``: simulate that many points of the (uniform) grid of ``ts`` and keep the first
    len(ts) (lets the solve reuse the compiled program of the dataset's own simulations).
    """
    z_test = np.asarray(z_test, dtype=np.float64)
    rng = np.random.default_rng(key)
    z0 = z_test[:, 0] + scale * rng.standard_normal(z_test[:, 0].shape)
    n_t = len(ts)
    ts = np.asarray(ts, dtype=np.float64)
    if sim_points is not None and sim_points > n_t:
        ts = ts[0] + np.arange(sim_points) * (ts[1] - ts[0])
    a = None if args is None or np.asarray(args).size == 0 else np.asarray(args)
    if coordinates == "momentum":
        from systems import to_momentum, to_velocity

        aa = a if a is not None else np.zeros((z0.shape[0], 0))
        if aa.ndim == 1:
            aa = np.broadcast_to(aa, (z0.shape[0], aa.shape[0]))
        z0 = to_velocity(system, z0, aa)
        zs = to_momentum(system, np.asarray(system.simulate_batch(z0, ts - ts[0], a)), aa)
    else:
        zs = np.asarray(system.simulate_batch(z0, ts - ts[0], a))
    zs = zs[:, :n_t]
    return rollout_error(zs, z_test, getattr(system, "angular", ()))


def n_params(model) -> int:
    """Number of scalars in the model's inexact arrays (eqx.filter(model, eqx.is_inexact_array))."""

    leaves = jax.tree_util.tree_leaves(eqx.filter(model, eqx.is_inexact_array))
    return int(sum(int(np.size(x)) for x in leaves))


def symplectic_error(model, zs, args=None) -> float:
    """mean ||J DF - (J DF)^T||_F^2 of a continuous model's field F over states ``zs`` (N, 2d).

    ``models.symplectic_error``; NaN for discrete models or when unavailable.
    """
    try:
        import models
    except ImportError:  # pragma: no cover
        return float("nan")
    fn = getattr(models, "symplectic_error", None)
    if fn is None or not hasattr(model, "vector_field"):
        return float("nan")
    try:
        return float(fn(model, zs, args))
    except Exception:
        return float("nan")
