"""The evaluate step of a state run: the trained model's test rollouts (with the evaluation
integrator, timed after a compile), their metrics and per-time curves, the perturbed-truth
floor, and the learning curve at the training checkpoints."""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

import systems

from . import _metrics as M
from ._atomic import write_json
from ._config import RunConfig
from ._fit import train_config
from ._params import code_fingerprint

EVAL_MAX_STEPS = 4096  # adaptive steps per test trajectory (100 points): ~40 per interval
# Test states used for the symplectic error (a Jacobian per state: keep it small).
_SYMPLECTIC_STATES = 64


def eval_integrator(config: RunConfig):
    """The test-rollout integrator of a run (adaptive: at most EVAL_MAX_STEPS steps)."""
    import models

    return models.Integrator(
        config.eval_integrator,
        substeps=config.eval_substeps,
        rtol=config.eval_rtol,
        max_steps=EVAL_MAX_STEPS,
    )


def _floor(system, data, config: RunConfig, cache_root: Path) -> float:
    path = Path(cache_root) / "floors" / f"{data.config.hash()}.json"
    try:
        stored = json.loads(path.read_text())
        if stored["code"] == code_fingerprint():
            return float(stored["floor"])
    except (OSError, ValueError, KeyError, TypeError):
        pass
    args = data.args_test if config.random_args else None
    value = M.perturbed_floor(
        system,
        data.z_test,
        data.ts_test,
        args,
        key=config.seed,
        coordinates=config.coordinates,
        sim_points=getattr(data.config, "n_points", None),
    )
    write_json(path, {"floor": value, "code": code_fingerprint()})
    return value


def _true_maps(system):
    """The TRUE system's (q, p) <-> (q, qdot) maps, as the trivial predictors take them
    (args of shape (0,) mean the system's defaults)."""
    import jax.numpy as jnp

    def fix(a):
        return None if a is None or jnp.size(a) == 0 else a

    def velocity(q, p, a):
        return system.velocity(q, p, fix(a))

    def momentum(q, v, a):
        return system.momentum(jnp.concatenate([q, v]), fix(a))

    return velocity, momentum


def to_velocity(system, zs, args=None) -> np.ndarray:
    """States (N, T, 2d) in (q, p) mapped to (q, qdot) with the TRUE ``system.velocity``;
    ``args`` None (the system's defaults) or (N, n_args). Non-finite states stay non-finite."""
    return systems.to_velocity(system, zs, args)


def _predictor(model, system, roll):
    """f(z0s, ts, args) -> (predictions, stats): the model's rollout, or a trivial
    predictor's closed form (compiled once, so the second call times the prediction alone)."""
    import jax

    import models

    if isinstance(model, models.AbstractTrivialModel):
        velocity, momentum = _true_maps(system)
        fn = jax.jit(
            lambda z0s, ts, args: model.predict_batch(
                z0s, ts, args, velocity=velocity, momentum=momentum
            )
        )
        return lambda z0s, ts, args: (fn(z0s, ts, args), {})
    return lambda z0s, ts, args: roll(model, z0s, ts, args)


def _test_inputs(config: RunConfig, data):
    """(initial states, times, args or None) of the test trajectories, in the run's dtype."""
    import jax.numpy as jnp

    dtype = jnp.dtype(config.dtype)
    z0s = jnp.asarray(data.z_test[:, 0], dtype=dtype)
    ts = jnp.asarray(data.ts_test, dtype=dtype)
    args = jnp.asarray(data.args_test, dtype=dtype) if config.random_args else None
    return z0s, ts, args


def _roller(config: RunConfig):
    """``roll(model, z0s, ts, args) -> (predictions, stats)`` with the run's evaluation
    integrator, jitted: one compile serves every model of one structure (checkpoints)."""
    import equinox as eqx

    import models

    integ = eval_integrator(config)

    @eqx.filter_jit
    def roll(m, z0s, ts, args):
        return models.rollout_batch(m, z0s, ts, args, integ, return_stats=True)

    return roll


def _score(config: RunConfig, system, data, zhat: np.ndarray):
    """The metrics of test predictions ``zhat`` (N, T, 2d) that checkpoints also record
    (:data:`CHECKPOINT_METRICS`), and the per-trajectory, per-time errors and energy
    violations ``err_t``, ``ev_t`` (N, T)."""
    z = data.z_test
    angular = tuple(system.angular)
    h_args = data.args_test if config.random_args else None
    err_t = M.relative_error(zhat, z, angular)
    h_true = M.energies(system, z, h_args, config.coordinates)
    h_pred = M.energies(system, zhat, h_args, config.coordinates)
    ev_t = M.energy_violation_curve(h_pred, h_true)
    # Momentum-coordinate runs are also scored on (q, qdot), decoded with the TRUE velocity map
    # (so models fed (q, p) and (q, qdot) can be compared on one footing).
    err_velocity, mse_velocity = float("nan"), float("nan")
    if config.coordinates == "momentum":
        zv_hat, zv = to_velocity(system, zhat, h_args), to_velocity(system, z, h_args)
        err_velocity = float(M.geometric_mean(M.relative_error(zv_hat, zv, angular)[..., 1:]))
        mse_velocity = M.mse(zv_hat, zv, angular)
    scores = {
        "rollout_error": float(M.geometric_mean(err_t[..., 1:])),
        "energy_violation": float(M.geometric_mean(ev_t[..., 1:])),
        "mse": M.mse(zhat, z, angular),
        "valid_time": float(np.mean(M.valid_prediction_time(err_t, data.ts_test))),
        "rollout_error_velocity": err_velocity,
        "mse_velocity": mse_velocity,
    }
    return scores, err_t, ev_t, h_pred, h_true


# The metrics recorded at every learning-curve checkpoint (row field "checkpoints").
CHECKPOINT_METRICS = (
    "rollout_error",
    "energy_violation",
    "mse",
    "valid_time",
    "rollout_error_velocity",
    "mse_velocity",
)


def _evaluate(config, system, data, model, cache_root, rolled=None, roll=None):
    """Metrics, curves and full curves of a trained model on the test set.

    ``rolled``: ``(pred, stats, rollout_seconds, eval_compile_seconds)`` of test rollouts done
    elsewhere (an ensemble's, vmapped over members: ``bench.core._ensemble``); ``roll``: the
    jitted rollout to use (:func:`_roller`; made here when None).
    """
    import jax
    import jax.numpy as jnp

    # An adaptive evaluation of a stiff learned field can take millions of steps; a test
    # trajectory that needs more than EVAL_MAX_STEPS is recorded as failed from where it stopped
    # (non-finite states) instead of holding the sweep.
    dtype = jnp.dtype(config.dtype)
    z0s, ts, args = _test_inputs(config, data)

    if rolled is None:
        predict = _predictor(model, system, roll or _roller(config))
        t0 = time.perf_counter()
        jax.block_until_ready(predict(z0s, ts, args))  # compile + first run
        t1 = time.perf_counter()
        pred, stats = jax.block_until_ready(predict(z0s, ts, args))
        t2 = time.perf_counter()
        rollout_seconds = t2 - t1
        eval_compile_seconds = max(0.0, (t1 - t0) - rollout_seconds)
    else:
        pred, stats, rollout_seconds, eval_compile_seconds = rolled
    zhat = np.asarray(pred, dtype=np.float64)
    z = data.z_test
    angular = tuple(system.angular)
    h_args = data.args_test if config.random_args else None
    scores, err_t, ev_t, h_pred, h_true = _score(config, system, data, zhat)
    finite = bool(np.all(np.isfinite(zhat)))

    states = z.reshape(-1, z.shape[-1])
    pick = np.linspace(0, len(states) - 1, min(_SYMPLECTIC_STATES, len(states))).astype(int)
    s_args = None
    if config.random_args:
        s_args = jnp.asarray(np.repeat(data.args_test, z.shape[1], axis=0)[pick], dtype=dtype)
    try:
        nfe = float(np.mean(np.asarray(stats["nfe"])))
    except Exception:
        nfe = float("nan")
    metrics = {
        "rollout_error": scores["rollout_error"],
        "energy_violation": scores["energy_violation"],
        "mse": scores["mse"],
        "valid_time": scores["valid_time"],
        "rollout_error_ref": M.rollout_error(zhat, z, angular, reference_compatible=True),
        "energy_violation_ref": M.energy_violation(h_pred, h_true, reference_compatible=True),
        "energy_pct_max_pe": M.energy_pct_max_pe(
            h_pred, h_true, system.potential_range(None if h_args is None else h_args[0])
        ),
        "energy_pct_max_pe_last": M.energy_pct_max_pe_last(
            h_pred, h_true, system.potential_range(None if h_args is None else h_args[0])
        ),
        "energy_mse": M.energy_mse(h_pred, h_true),
        **_derivative_mse(config, system, data, model),
        "rollout_error_velocity": scores["rollout_error_velocity"],
        "mse_velocity": scores["mse_velocity"],
        "symplectic_error": M.symplectic_error(
            model, jnp.asarray(states[pick], dtype=dtype), s_args
        ),
        "floor": _floor(system, data, config, cache_root),
        "rollout_finite": finite,
        "eval_compile_seconds": eval_compile_seconds,
        "rollout_seconds": rollout_seconds,
        "rollout_seconds_per_traj": rollout_seconds / max(1, len(zhat)),
        "nfe": nfe,
        "n_params": M.n_params(model),
    }
    curves = {
        "t": (data.ts_test - data.ts_test[0]).tolist(),
        "rel_error": M.geometric_mean(err_t, axis=0).tolist(),
        "energy_violation": M.geometric_mean(ev_t, axis=0).tolist(),
        "z_true": z[0].tolist(),
        "z_pred": zhat[0].tolist(),
    }
    full = {"err": err_t, "energy_violation": ev_t, "z_pred": zhat[:4], "z_true": z[:4]}
    return metrics, curves, full


_DERIVATIVE_STATES = 2048  # states per split at most for the derivative MSEs


def _derivative_mse(config, system, data, model) -> dict:
    """The HNN seed's train and test losses, whatever the run trained on: the mean squared
    difference between the model's field and the true dz/dt (:func:`systems.derivatives`, in
    the run's coordinates) at up to :data:`_DERIVATIVE_STATES` training states (noisy where the
    data are) and test states (noise-free). Computed for derivative-target runs only (the
    seeds' protocol; it costs a compile per run); NaN otherwise and for a model without a
    vector field."""
    import jax
    import jax.numpy as jnp

    import models

    if (
        config.train_target != "derivative"
        or isinstance(model, models.AbstractDiscreteModel)
        or not hasattr(model, "vector_field")
    ):
        return {"derivative_mse_train": float("nan"), "derivative_mse_test": float("nan")}
    out = {}
    dtype = jnp.dtype(config.dtype)
    canonical = config.coordinates == "momentum"
    field = jax.jit(jax.vmap(lambda zz, a: model.vector_field(0.0, zz, a)))
    for split in ("train", "test"):
        z, args = getattr(data, f"z_{split}"), np.asarray(getattr(data, f"args_{split}"))
        # targets at the clean states (training: the noise-free twin, as in training)
        clean = getattr(data, "z_train_clean", z) if split == "train" else z
        states = z.reshape(-1, z.shape[-1])
        clean = clean.reshape(-1, z.shape[-1])
        a = np.repeat(args, z.shape[1], axis=0)
        pick = np.linspace(0, len(states) - 1, min(_DERIVATIVE_STATES, len(states))).astype(int)
        states, clean, a = states[pick], clean[pick], a[pick]
        true = systems.derivatives(system, clean, a if a.shape[-1] else None, canonical)
        pred = np.asarray(
            field(jnp.asarray(states, dtype), jnp.asarray(a, dtype)), dtype=np.float64
        )
        d = pred - np.asarray(true, dtype=np.float64)
        out[f"derivative_mse_{split}"] = (
            float(np.mean(d**2)) if np.all(np.isfinite(d)) else float("nan")
        )
    return out


def _checkpoints(config, system, data, meta, final_metrics, final_curves, roll) -> dict | None:
    """The learning curve of a run: :data:`CHECKPOINT_METRICS` at each of its training
    checkpoints (``bench.core._fit.checkpoint_steps``), on the whole test set with the
    evaluation integrator, as columns (lists, one entry per checkpoint) plus the per-time
    curves ``rel_error_t``, ``energy_violation_t`` (geometric mean over trajectories).

    The checkpoint at the full budget of a run that trained to the end IS the final model: it
    takes the final metrics (so the curve ends on the row's numbers exactly). A checkpoint at or
    after a divergence is ``status`` ``diverged`` with the final (last finite) model's metrics,
    as the row of a diverged run. None when the run has no checkpoints (or nothing trained).
    """
    import jax

    targets = train_config(config).checkpoints
    snaps = {s.step: s for s in meta.get("_snapshots") or ()}
    if not targets or meta.get("steps_done") is None or "_snapshots" not in meta:
        return None
    z0s, ts, args = _test_inputs(config, data)
    out: dict = {"step": [], "fraction": [], "train_seconds": [], "status": []}
    for key in (*CHECKPOINT_METRICS, "rel_error_t", "energy_violation_t"):
        out[key] = []
    for target in targets:
        snap = next((snaps[k] for k in sorted(snaps) if k >= target), None)
        final = snap is None or (snap.step >= config.steps and meta["status"] == "ok")
        if final:
            scores = {k: final_metrics[k] for k in CHECKPOINT_METRICS}
            rel, ev = final_curves["rel_error"], final_curves["energy_violation"]
            status = meta["status"] if snap is None else "ok"
            seconds = meta["train_seconds"] if snap is None else snap.train_seconds
        else:
            pred, _ = jax.block_until_ready(roll(snap.model, z0s, ts, args))
            scores, err_t, ev_t, _, _ = _score(config, system, data, np.asarray(pred, np.float64))
            rel = M.geometric_mean(err_t, axis=0).tolist()
            ev = M.geometric_mean(ev_t, axis=0).tolist()
            status, seconds = "ok", snap.train_seconds
        out["step"].append(int(target))
        out["fraction"].append(target / config.steps)
        out["train_seconds"].append(float(seconds))
        out["status"].append(status)
        for k in CHECKPOINT_METRICS:
            out[k].append(float(scores[k]))
        out["rel_error_t"].append(list(rel))
        out["energy_violation_t"].append(list(ev))
    return out


NAN_METRICS = (
    "rollout_error",
    "rollout_error_velocity",
    "energy_violation",
    "mse",
    "mse_velocity",
    "valid_time",
    "rollout_error_ref",
    "energy_violation_ref",
    "energy_pct_max_pe",
    "energy_pct_max_pe_last",
    "symplectic_error",
)


def evaluate_state(config: RunConfig, built, model, meta: dict, cache_root, rolled=None):
    """The evaluate step of a state run: ``(columns, arrays)``, the row's metric columns,
    ``curves`` and, with checkpoints, ``checkpoints`` and ``checkpoint_seconds``
    (:func:`_checkpoints`); ``arrays`` the full per-trajectory curves of ``curves.npz``.

    ``built``: the build step's ``(system, data, scene, model)``; ``meta``: the train step's;
    ``rolled``: test rollouts done elsewhere (an ensemble's, see :func:`_evaluate`).
    """
    system, data = built[0], built[1]
    roll = _roller(config)
    metrics, curves, full = _evaluate(config, system, data, model, cache_root, rolled, roll)
    if meta["status"] == "diverged" and not metrics["rollout_finite"]:
        # A model that went non-finite in training has no meaningful prediction.
        metrics.update(dict.fromkeys(NAN_METRICS, float("nan")))
    columns = {**metrics, "curves": curves}
    t_check = time.perf_counter()
    checkpoints = _checkpoints(config, system, data, meta, metrics, curves, roll)
    if checkpoints is not None:
        columns["checkpoints"] = checkpoints
        columns["checkpoint_seconds"] = time.perf_counter() - t_check
    return columns, full
