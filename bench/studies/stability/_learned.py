"""Stability cases of small learned models: long horizons, high energy, float32 vs float64."""

from __future__ import annotations

import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

import systems

from ...core import one_line
from ._core import (
    METHOD_NOTES,
    Row,
    StabilitySize,
    _size,
    bound,
    energy_drift,
    first_bad_step,
    grid,
    guard,
    relative_error,
    valid_time,
    velocity_mask,
)
from ._truth import high_energy_states

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
        from ...core import TrainConfig, train

        ds = systems.make_dataset(
            systems.DatasetConfig(
                system="chain_pendulum",
                system_params=(("k", 2),),
                n_generated=size.n_train,
                n_train=size.n_train,
                n_test=2,
            )
        )
        res = train(model, ds, TrainConfig(steps=size.train_steps, batch=64))
        model = res.model
        info = f"trained {res.steps_done} steps ({res.status})"
    _MODEL_CACHE[key] = (model, info)
    return model, info


def _applies(model, method: str) -> bool:
    from models import AbstractDiscreteModel

    if isinstance(model, AbstractDiscreteModel):
        return method == "rk4"  # a discrete model has one integrator: itself (label it once)
    return method not in ("leapfrog", "leapfrog_explicit") or bool(model.second_order)


def case_long_horizon(size) -> list[Row]:
    """Small trained models rolled out ``size.long_steps`` steps of dt = 0.03 (10^4 at quick).

    Per model and integrator: divergence rate (fraction of trajectories non-finite or beyond
    the bound), median final energy drift (true H) of the surviving ones, for Hamiltonian
    models the median final drift of their own learned H (what a symplectic method keeps
    bounded), median valid prediction time (``bench.core._metrics.valid_prediction_time``: seconds
    until the wrapped relative error first exceeds its threshold) and the rollout seconds.
    """
    import models

    size = _size(size)
    sysm = systems.make("chain_pendulum", k=2)
    ts = grid(size.long_steps)
    z0 = np.asarray(sysm.sample_initial(jax.random.PRNGKey(4), size.n_traj))
    truth = np.asarray(sysm.simulate_batch(z0, ts))
    limit = bound(sysm, truth)
    mask = velocity_mask(sysm)
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
                    model, info, name, label, method, sysm, z0, ts, truth, limit, mask, models
                )
            return out

        rows += guard("long_horizon", one, f"{name}/*")
    return rows


def _long_rollout(model, info, name, label, method, sysm, z0, ts, truth, bound, mask, models):
    variant = f"{name}/{label}"
    common = dict(system="chain_pendulum", method=label, param=float(len(ts) - 1), dtype="float32")
    info = f"{info}; {METHOD_NOTES.get(label, label)}"
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
    if hasattr(model, "hamiltonian"):
        h = np.asarray(
            jax.vmap(jax.vmap(lambda z: model.hamiltonian(z, None)))(jnp.asarray(zs[good]))
        ).astype(np.float64)
        dh = np.abs(h[:, -1] - h[:, 0]) / np.maximum(np.abs(h[:, -1]) + np.abs(h[:, 0]), 1e-300)
        rows.append(
            Row(
                "long_horizon",
                variant,
                "learned_energy_drift",
                "ok",
                float(np.median(dh)),
                message=info,
                **common,
            )
        )
    drift = energy_drift(sysm, zs[good])[:, -1]
    valid_t = valid_time(sysm, zs[good], truth[good], ts)
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
    ts = grid(size.high_energy_steps)
    truth = np.asarray(sysm.simulate_batch(z0, ts))
    limit, mask = bound(sysm, truth), velocity_mask(sysm)
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
                bad = first_bad_step(zs[i], limit, mask)
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
                err = float(relative_error(sysm, zs[i, -1:], truth[i, -1:])[0])
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
    ts = grid(n)
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
            diff = relative_error(sysm, z32, z64)
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
