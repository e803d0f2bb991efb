"""Runs on a measured trajectory (``RunConfig.observation == "measured"``): the HNN seed's real
pendulum (its Task 3). Build, train and evaluate.

``system`` names the data (``systems.real_pendulum.DATASETS``: the user's measured file or the
synthetic stand-in). The states x = (o, v) are taken as the seed takes them, canonical (q, p),
the targets their forward differences; the seed's split (the first 80% train, the next 20%
test, in time order). Training is the one training loop on derivative targets; the test loss is
the field's squared error at the test states, the energy MSE the seed's: one rollout from the
first test state over the test times, scored with the seed's fitted H = 2.4 (1 - cos q) + p^2.
Every row records the data's source and the sha256 of the bytes read (``data_source``,
``data_sha256``). Nothing is cached: the data may change under one configuration.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from ._build import model_of
from ._config import RunConfig
from ._params import result_meta

TRIVIAL = "at_rest"  # the trivial predictor of a field: dz/dt = 0, the state held
METRIC_COLUMNS = ("data_source", "data_sha256", "data_points")


def _scene():
    import models

    return models.Scene(dof=1, angular=(False,), n_args=0, damped=False, canonical=True)


def check_measured_model(c: RunConfig) -> None:
    """One-line ValueError for a model that cannot run on a measured trajectory: one with a
    vector field, or the trivial :data:`TRIVIAL`."""
    import jax

    import models

    allowed = [
        m
        for m in models.available()
        if m == TRIVIAL or not (models.spec(m).discrete or models.spec(m).trivial)
    ]
    if c.model not in allowed:
        raise ValueError(f"measured runs need a model with a vector field; allowed: {allowed}")
    models.make(c.model, _scene(), key=jax.random.PRNGKey(0), width=2, depth=1, dtype=c.dtype)


@dataclasses.dataclass(frozen=True)
class _Data:
    """The training set in the layout of the training loop: chunks of one state."""

    ts_train: np.ndarray
    z_train: np.ndarray
    args_train: np.ndarray
    dz_train: np.ndarray


def build(c: RunConfig):
    """(measured data, training set, untrained model) of a run."""
    from systems import real_pendulum as R

    data = R.load(c.system)
    x, dx = data.x[data.train], data.dx[data.train]
    train = _Data(np.zeros(1), x[:, None], np.zeros((len(x), 0)), dx[:, None])
    return data, train, model_of(c, _scene())


def train(c: RunConfig, built, cache_root, progress: bool):
    """``(model, meta)``: trained (never cached); a trivial predictor untouched."""
    import models

    from ._fit import UNTRAINED, train_config
    from ._train import train as fit

    _, data, model = built
    if isinstance(model, models.AbstractTrivialModel):
        return model, dict(UNTRAINED)
    res = fit(model, data, train_config(c), progress=progress)
    return res.model, {**result_meta(res), "train_cached": False}


def evaluate(c: RunConfig, built, model, meta: dict, cache_root):
    """The row's columns: the seed's losses and energy MSE, the rollout's error, the data's
    source; ``curves`` the test rollout."""
    import jax
    import jax.numpy as jnp

    import models
    from systems import real_pendulum as R

    from . import _metrics as M
    from ._evaluate import eval_integrator

    data = built[0]
    dtype = jnp.dtype(c.dtype)
    trivial = isinstance(model, models.AbstractTrivialModel)
    if trivial:
        field = lambda z: jnp.zeros_like(z)  # noqa: E731
    else:
        field = jax.jit(jax.vmap(lambda z: model.vector_field(0.0, z, None)))
    losses = {}
    for split in ("train", "test"):
        idx = getattr(data, split)
        pred = np.asarray(field(jnp.asarray(data.x[idx], dtype)), np.float64)
        d = pred - data.dx[idx]
        losses[f"derivative_mse_{split}"] = (
            float(np.mean(d**2)) if np.all(np.isfinite(d)) else float("nan")
        )
    z = data.x[data.test]
    ts = data.t[data.test] - data.t[data.test][0]
    t0 = time.perf_counter()
    if trivial:
        zhat = np.repeat(z[:1], len(z), axis=0)
    else:
        integ = eval_integrator(c)
        roll = jax.jit(lambda m, z0, t: models.rollout(m, z0, t, None, integ))
        zhat = np.asarray(roll(model, jnp.asarray(z[0], dtype), jnp.asarray(ts, dtype)))
    rollout_seconds = time.perf_counter() - t0
    zhat = zhat.astype(np.float64)
    finite = bool(np.all(np.isfinite(zhat)))
    h_true, h_pred = np.asarray(R.seed_energy(z)), np.asarray(R.seed_energy(zhat))
    err_t = M.relative_error(zhat[None], z[None], (False,))
    ev_t = M.energy_violation_curve(h_pred[None], h_true[None])
    columns = {
        **losses,
        "energy_mse": float(np.mean((h_pred - h_true) ** 2)) if finite else float("nan"),
        "rollout_error": float(M.geometric_mean(err_t[..., 1:])),
        "energy_violation": float(M.geometric_mean(ev_t[..., 1:])),
        "mse": float(np.mean((zhat[1:] - z[1:]) ** 2)) if finite else float("nan"),
        "rollout_finite": finite,
        "rollout_seconds": rollout_seconds,
        "n_params": M.n_params(model),
        "data_source": data.source,
        "data_sha256": data.sha256,
        "data_points": int(len(data.x)),
        "curves": {
            "t": ts.tolist(),
            "rel_error": err_t[0].tolist(),
            "energy_violation": ev_t[0].tolist(),
            "z_true": z.tolist(),
            "z_pred": zhat.tolist(),
        },
    }
    return columns, {}
