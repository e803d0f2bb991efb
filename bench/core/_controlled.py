"""Runs on a MuJoCo task's transitions under recorded controls (``observation ==
"controlled"``, the paper's Fig. 7): build (the task's file checked against its card, or the
random-control stand-in; a split by episode), train (the one loop on 3-step windows, each under
its own controls, the error divided by the training std per component) and evaluate (test
rollouts under their controls; the reference's normalised MSE). Unlike the reference, the HNN
too takes 8 Euler steps per transition (it takes one, a defect not copied). The protocol and
the other differences: docs/studies/mujoco.md.
"""

from __future__ import annotations

import dataclasses
import functools
import time
from pathlib import Path

import numpy as np

from ._build import model_of
from ._config import RunConfig

SPLIT_SEED = 2021  # the reference converter's split seed; one split per task for all runs
STAND_IN_SEED = 0  # the stand-in's collection seed
LR_END = 1e-6  # the cosine schedule's final learning rate (App. C)
STD_FLOOR = 1e-6  # the reference's clip of the per-component std
TRIVIAL = "constant_velocity"  # q0 + t v0: zero acceleration, the controls ignored
METRIC_COLUMNS = ("data_source", "data_sha256", "data_points", "test_mse", "train_mse")


def scene(task_name: str, standardisation=None):
    """The models' scene of a task: dof = nq, no angular flags, n_controls = nu, and the
    training data's ``standardisation`` (``models.Standardisation``) or None."""
    import models
    import systems

    t = systems.mujoco_task(task_name)
    if t.nq != t.nv:
        raise ValueError(f"{t.name}: nq {t.nq} != nv {t.nv}; z = [q, v] needs equal sizes")
    return models.Scene(
        dof=t.nq, angular=(False,) * t.nq, n_controls=t.nu, standardisation=standardisation
    )


def _model(c: RunConfig, width: int, depth: int, standardisation=None):
    return model_of(c, scene(c.system, standardisation), width=width, depth=depth)


def check_controlled_model(c: RunConfig) -> None:
    """One-line ValueError for a model that cannot run a controlled task: one that reads no
    control (the registry's refusal) or an integrator its rollout refuses."""
    import equinox as eqx
    import jax
    import jax.numpy as jnp

    import models

    model = _model(c, 2, 1)
    if isinstance(model, models.AbstractTrivialModel):
        return
    s, dtype = model.scene, jnp.dtype(c.dtype)
    z0 = jax.ShapeDtypeStruct((s.state_size,), dtype)
    ts = jax.ShapeDtypeStruct((2,), dtype)
    u = jax.ShapeDtypeStruct((1, s.n_controls), dtype)
    for what in ("train_integrator", "eval_integrator"):
        integ = models.Integrator(getattr(c, what))
        try:
            eqx.filter_eval_shape(
                lambda m, z, t, uu, i=integ: models.rollout(m, z, t, None, i, controls=uu),
                model,
                z0,
                ts,
                u,
            )
        except ValueError as e:
            first = str(e).splitlines()[0] if str(e) else type(e).__name__
            method = getattr(c, what)
            raise ValueError(f"{what} {method!r} cannot run {c.model!r}: {first}") from None


@dataclasses.dataclass(frozen=True)
class Windows:
    """The training set in the layout of the training loop, with each window's controls
    ``u_train`` (N, C, nu) and the per-component ``scale`` (2d,) of the loss."""

    ts_train: np.ndarray
    z_train: np.ndarray
    args_train: np.ndarray
    u_train: np.ndarray
    scale: np.ndarray


@dataclasses.dataclass(frozen=True)
class Built:
    split: object  # systems' Split: train_z/u (N, C, .), test_z/u (M, T, .)
    windows: Windows
    source: str
    sha256: str
    transitions: int
    model: object


def load_episodes(c: RunConfig):
    """(Episodes, source label, sha256) of a run's data: the task's file (its first
    ``n_generated`` transitions) or the stand-in."""
    from systems import mujoco_data as D

    if dict(c.system_params)["data"] == "stand-in":
        ep, card = D.stand_in(c.system, c.n_generated, seed=STAND_IN_SEED)
        return ep, f"{D.STAND_IN}, {c.n_generated} steps", card["episodes_sha256"]
    ep, card = D.load_data(c.system)
    n = len(ep.episode)
    if n < c.n_generated:
        raise ValueError(f"{c.system}: the file holds {n} transitions, n_generated {c.n_generated}")
    keep = {k: v[: c.n_generated] for k, v in ep.arrays().items()}
    label = f"file {D.data_path(c.system).name}: {card.get('policy_budget', card.get('policy'))}"
    return dataclasses.replace(ep, **keep), label, card["episodes_sha256"]


def build(c: RunConfig) -> Built:
    """The run's data (split by episode), its training windows and its untrained model."""
    import systems

    ep, source, sha = load_episodes(c)
    split = systems.split_episodes(
        ep,
        seed=SPLIT_SEED,
        n_train=c.n_train,
        train_len=c.chunk,
        n_test=c.n_test,
        test_len=c.chunk * c.test_chunks,
    )
    z = split.train_z
    std = np.maximum(z.reshape(-1, z.shape[-1]).std(0), STD_FLOOR)
    windows = Windows(
        ts_train=np.arange(c.chunk) * c.dt,
        z_train=z,
        args_train=np.zeros((len(z), 0)),
        u_train=split.train_u,
        scale=std,
    )
    st = None
    if c.standardise:  # the training windows' statistics, controls included (the reference's)
        import models

        st = models.Standardisation.from_windows(z, split.train_u, c.dt)
    model = _model(c, c.width, c.depth, st)
    return Built(split, windows, source, sha, len(ep.episode), model)


@dataclasses.dataclass(frozen=True)
class ControlledObjective:
    """The objective of a controlled run for the one training loop: ``loss_fn`` on a batch of
    windows, each rolled out under its own controls u_0..u_{C-2}, the error divided by the
    training std per component."""

    def data(self, model, dataset: Windows, config):
        import jax.numpy as jnp

        from ._train import prepare

        z, args, ts = prepare(model, dataset, config)
        u = jnp.asarray(dataset.u_train[:, :-1], z.dtype)
        return z, args, ts, u, jnp.asarray(dataset.scale, z.dtype)

    def batches(self, data, config):
        from ._train import Batches

        return Batches(data[0].shape[0], config.batch, config.seed)

    def loss(self, model, data, ix, config):
        from ._train import loss_fn

        z, args, ts, u, scale = data
        return loss_fn(model, z[ix], args[ix], ts, config, controls=u[ix], scale=scale)


CONTROLLED = ControlledObjective()


def train_config(c: RunConfig):
    """The run's :class:`bench.TrainConfig`, its cosine ending at :data:`LR_END`."""
    from ._fit import train_config as run_train_config

    tc = run_train_config(c)
    return dataclasses.replace(tc, lr_floor=min(1.0, LR_END / c.lr))


def member_inputs(c: RunConfig, built: Built):
    """``(model, dataset, objective)``: what the one training loop fits for the run, alone or
    as an ensemble's member (:class:`bench.core._execute.Member`)."""
    return built.model, built.windows, CONTROLLED


def record(c: RunConfig, res, cache_root) -> dict:
    """The train step's meta of a :class:`bench.TrainResult` (never cached)."""
    from ._params import result_meta

    return {**result_meta(res), "train_cached": False}


def train(c: RunConfig, built: Built, cache_root, progress: bool):
    """``(model, meta)``: trained (never cached, but a killed training resumes from its last
    saved state, for the same code and data file); a trivial predictor untouched."""
    import models

    from ._fit import UNTRAINED
    from ._params import resumable_training
    from ._train import train as fit

    model, windows, objective = member_inputs(c, built)
    if isinstance(model, models.AbstractTrivialModel):
        return model, dict(UNTRAINED)
    tc = train_config(c)

    def fit_from(resume):
        return fit(model, windows, tc, progress=progress, objective=objective, resume=resume)

    res = resumable_training(c, Path(cache_root), fit_from, data=built.sha256)
    return res.model, record(c, res, cache_root)


@functools.cache
def _rollouts(trivial: bool):
    """The compiled f(m, z0s, ts, u, integ), one per process, so that runs of one architecture
    (an ensemble's members, a worker's runs) compile their test rollouts once."""
    import equinox as eqx

    import models

    if trivial:
        return eqx.filter_jit(lambda m, z0s, ts, u, integ: m.predict_batch(z0s, ts))
    return eqx.filter_jit(
        lambda m, z0s, ts, u, integ: models.rollout_batch(m, z0s, ts, None, integ, controls=u)
    )


def predictor(c: RunConfig, model):
    """f(m, z0s, ts, u) -> states (N, T, 2d): the rollout under controls u (N, T - 1, nu) with
    the run's evaluation integrator, or a trivial predictor's closed form."""
    import models

    from ._evaluate import eval_integrator

    trivial = isinstance(model, models.AbstractTrivialModel)
    return functools.partial(_rollouts(trivial), integ=None if trivial else eval_integrator(c))


def normalised_mse(zhat: np.ndarray, z: np.ndarray, scale: np.ndarray) -> float:
    """mean over trajectories, times (t0 included) and components of ((zhat - z) / std)^2:
    the reference's ``train_mse`` / ``test_mse``; NaN if a prediction is non-finite."""
    if not np.all(np.isfinite(zhat)):
        return float("nan")
    return float(np.mean(((zhat - z) / scale) ** 2))


def evaluate(c: RunConfig, built: Built, model, meta: dict, cache_root):
    """The row's columns: the suite's rollout error and MSE on the test trajectories, the
    reference's normalised test and train MSE, the data's source and sha256; ``curves`` the
    per-time relative error and the first test trajectory."""
    import jax
    import jax.numpy as jnp

    from . import _metrics as M

    split, w = built.split, built.windows
    dtype = jnp.dtype(c.dtype)
    predict = predictor(c, model)

    def run(z, u):
        ts = jnp.asarray(np.arange(z.shape[1]) * c.dt, dtype)
        args = (jnp.asarray(z[:, 0], dtype), ts, jnp.asarray(u[:, :-1], dtype))
        return predict(model, *args), args

    pred, args = run(split.test_z, split.test_u)
    jax.block_until_ready(pred)  # compiled; the second call is timed
    t0 = time.perf_counter()
    zhat = np.asarray(jax.block_until_ready(predict(model, *args)), np.float64)
    rollout_seconds = time.perf_counter() - t0
    z = split.test_z
    angular = tuple(model.scene.angular)
    err_t = M.relative_error(zhat, z, angular)
    train_hat = np.asarray(run(w.z_train, w.u_train)[0], np.float64)
    finite = bool(np.all(np.isfinite(zhat)))
    columns = {
        "rollout_error": float(M.geometric_mean(err_t[..., 1:])),
        "energy_violation": float("nan"),  # no true energy of a controlled task
        "mse": M.mse(zhat, z, angular),
        "test_mse": normalised_mse(zhat, z, w.scale),
        "train_mse": normalised_mse(train_hat, w.z_train, w.scale),
        "rollout_finite": finite,
        "rollout_seconds": rollout_seconds,
        "n_params": M.n_params(model),
        "data_source": built.source,
        "data_sha256": built.sha256,
        "data_points": built.transitions,
        "curves": {
            "t": (np.arange(z.shape[1]) * c.dt).tolist(),
            "rel_error": M.geometric_mean(err_t, axis=0).tolist(),
            "z_true": z[0].tolist(),
            "z_pred": zhat[0].tolist(),
        },
    }
    return columns, {"err": err_t, "z_pred": zhat[:4], "z_true": z[:4]}
