"""Runs that learn from pixels (``RunConfig.observation == "pixels"``): the build and train
steps. Rendered frames of the system (``systems.make_pixel_dataset``; an observation is a frame
stacked with its successor), an autoencoder with latent dynamics (``models.LatentModel``), and
the HNN seed's three-term loss (:func:`seed_loss`), trained with AdamW, the suite's cosine decay
and clipping and the seed's weight decay. The evaluate step is :mod:`bench.core._pixel_eval`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

import systems

from ._config import PIXEL_SIZE, RunConfig
from ._params import cached_training, result_meta

AE_LOSS, CC_LOSS, DYN_LOSS = 1.0, 1.0, 0.1  # the seed's weights (train.py)
WEIGHT_DECAY = 1e-5  # the seed's (appendix C: "weight decay ... had a significant impact")
LATENT_DT = 1.0  # latent time per frame (the seed's z_next = z + f(z))
BLOCK = 100  # training steps per compiled block
PIXEL_METRICS = (
    "pixel_mse",
    "pixel_mse_late",
    "pixel_mse_static",
    "recon_mse",
    "pixel_loss_train",
    "pixel_loss_test",
    "latent_energy_drift",
    "decoded_energy_mse",
    "seed_energy_mse",
    "seed_energy_mse_floor",
    "frame_mse_mean",
)


def check_pixel_model(c: RunConfig) -> None:
    """One-line ValueError when the registered models cannot make ``c``'s latent model (the
    configuration itself was checked when it was built)."""
    import jax

    import models

    if models.spec(c.model).trivial:
        allowed = [m for m in models.available() if not models.spec(m).trivial]
        raise ValueError(f"pixel runs need a learned model; allowed: {', '.join(allowed)}")
    models.LatentModel(
        c.model,
        (2, 8, 8),
        key=jax.random.PRNGKey(0),
        width=2,
        ae_width=2,
        dtype=c.dtype,
        options=dict(c.model_options),
    )


def build(c: RunConfig):
    """(system, pixel dataset, untrained LatentModel) of a run."""
    import jax

    import models

    system = systems.make(c.system, **c.system_kwargs())
    data = systems.make_pixel_dataset(c.pixel_dataset_config())
    model = models.LatentModel(
        c.model,
        (2, PIXEL_SIZE, PIXEL_SIZE),
        key=jax.random.PRNGKey(c.seed),
        latent_dof=system.dof,
        width=c.width,
        depth=c.depth,
        ae_width=c.width,
        activation=c.activation,
        dtype=c.dtype,
        options=dict(c.model_options),
    )
    return system, data, model


def _observations(frames):
    """(..., C, S, S) frames -> (..., C - 1, 2, S, S) observations."""
    import jax.numpy as jnp

    return jnp.stack([frames[..., :-1, :, :], frames[..., 1:, :, :]], axis=-3)


def seed_loss(model, frames, integrator, aux_weight: float = CC_LOSS):
    """The HNN seed's loss (its experiment-pixels/train.py) on a batch of windows ``frames``
    (B, C, S, S) of ``chunk`` consecutive frames: ``(loss, (ae, cc, dyn))`` with::

        z_i = enc(x_i);  ae = mean (dec(z_i) - x_i)^2
        dyn = mean (rollout(z_0)_i - z_i)^2          (i >= 1, the run's train integrator)
        cc  = mean (dw_i - (w_{i+1} - w_i))^2         (z = (w, dw): the auxiliary latent loss)
        loss = ae + aux_weight * cc + 0.1 dyn

    in latent time units of one frame (the seed's ``z + f(z)`` steps one unit; ours is an
    integrator step of one unit). ``aux_weight``: the seed's 1; the VIN diagnosis,
    ``python -m bench diagnose-vin``, also trains with 0."""
    import jax
    import jax.numpy as jnp

    obs = _observations(frames)  # (B, C-1, 2, S, S)
    z = jax.vmap(jax.vmap(model.encode))(obs)
    x_hat = jax.vmap(jax.vmap(model.decode))(z)
    ae = jnp.mean((x_hat - obs) ** 2)
    ts = jnp.arange(obs.shape[1], dtype=z.dtype) * LATENT_DT
    zr = jax.vmap(lambda z0: model.rollout(z0, ts, integrator))(z[:, 0])
    dyn = jnp.mean((zr[:, 1:] - z[:, 1:]) ** 2)
    d = z.shape[-1] // 2
    w, dw = z[..., :d], z[..., d:]
    cc = jnp.mean((dw[:, :-1] - (w[:, 1:] - w[:, :-1]) / LATENT_DT) ** 2)
    return AE_LOSS * ae + aux_weight * cc + DYN_LOSS * dyn, (ae, cc, dyn)


def _windows(n_traj: int, points: int, chunk: int) -> np.ndarray:
    """Every (trajectory, start) of a window of ``chunk`` frames."""
    t, s = np.meshgrid(np.arange(n_traj), np.arange(points - chunk + 1), indexing="ij")
    return np.stack([t.ravel(), s.ravel()], axis=-1)


def _gather(frames, idx, chunk: int):
    """Windows (B, chunk, S, S) of ``frames`` (N, T, S, S) at ``idx`` (B, 2) = (traj, start)."""
    import jax
    import jax.numpy as jnp

    def one(i):
        return jax.lax.dynamic_slice_in_dim(frames[i[0]], i[1], chunk, axis=0)

    return jax.vmap(one)(jnp.asarray(idx))


def _jit(fn):
    import equinox as eqx

    return eqx.filter_jit(fn)


class Windows:
    """Batch indices of pixel training: ``take(k)`` draws k batches of ``batch`` (trajectory,
    start) windows uniformly with replacement (``windows[rng.integers(...)]``, (k, batch, 2))."""

    def __init__(self, windows: np.ndarray, batch: int, seed: int):
        self.windows, self.batch = windows, min(batch, len(windows))
        self.rng = np.random.default_rng(seed)

    def take(self, k: int) -> np.ndarray:
        return self.windows[self.rng.integers(0, len(self.windows), size=(k, self.batch))]


@dataclass(frozen=True)
class PixelObjective:
    """The objective of a pixel run for the one training loop (``bench.train``'s
    ``objective``): :func:`seed_loss` (its cc term weighed by ``aux_weight``) on windows of
    ``chunk`` frames of ``dataset.frames_train``, rolled out with ``config.integrator``."""

    chunk: int
    aux_weight: float = CC_LOSS

    def data(self, model, dataset, config):
        import jax.numpy as jnp

        return jnp.asarray(dataset.frames_train, jnp.dtype(config.dtype))

    def batches(self, frames, config) -> Windows:
        return Windows(_windows(*frames.shape[:2], self.chunk), config.batch, config.seed)

    def loss(self, model, frames, ix, config):
        return seed_loss(
            model, _gather(frames, ix, self.chunk), config.integrator, self.aux_weight
        )[0]


def train_config(c: RunConfig):
    """The optimisation of a pixel run (:func:`bench.core._fit.train_config`): the seed's
    weight decay unless the run sets one, :data:`BLOCK` steps per compiled block."""
    from ._fit import train_config as run_train_config

    return run_train_config(c, block=BLOCK, weight_decay=WEIGHT_DECAY)


def fit_pixels(
    c: RunConfig, model, data, progress: bool = False, aux_weight: float | None = None, resume=None
):
    """Train ``model`` on ``data``'s frames by the one training loop (``bench.train``) with
    :class:`PixelObjective`, its auxiliary weight ``aux_weight`` (None: the run's,
    ``c.aux_weight``; ``resume``: ``bench.train``'s); returns its :class:`bench.TrainResult`."""
    from ._train import train

    weight = c.aux_weight if aux_weight is None else aux_weight
    objective = PixelObjective(chunk=c.chunk, aux_weight=weight)
    return train(model, data, train_config(c), progress, objective=objective, resume=resume)


def train_pixels(
    c: RunConfig, model, data, progress: bool = False, aux_weight: float | None = None
) -> tuple:
    """:func:`fit_pixels` as ``(model, meta)``, meta the row's training fields
    (:func:`bench.core._params.result_meta`), nothing cached."""
    res = fit_pixels(c, model, data, progress, aux_weight)
    return res.model, result_meta(res)


def train_cached_pixels(c: RunConfig, model, data, cache_root: Path, progress: bool) -> tuple:
    """The train step of a pixel run: ``(model, meta)``, trained by :func:`fit_pixels` or
    loaded from the parameter cache (:func:`bench.core._params.cached_training`)."""
    return cached_training(
        c, model, cache_root, lambda resume: fit_pixels(c, model, data, progress, resume=resume)
    )
