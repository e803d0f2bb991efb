"""Runs that learn from single frames (``RunConfig.observation == "frames"``): the VIN seed's
pixel task (Saemundsson et al. 2020, as its authors' code runs it). Build, train and evaluate.

The data are rendered frames of a one-link pendulum (``systems.make_pixel_dataset``) from the
seed's starts far from rest (``RunConfig.pixel_dataset_config``). The model is a
:class:`models.PositionLatentModel`: every frame is encoded to a position, the dynamics carry
the velocity, positions are decoded. ``model_options`` holds its ``latent`` geometry ("so2" or
"r2"); the rest goes to the dynamics model. The loss is the seed's negative ELBO on a window of
``chunk`` frames (:func:`seed_elbo`), trained by the one training loop with
:class:`FrameObjective`; evaluation is :func:`evaluate_frames`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

import systems

from ._config import PIXEL_SIZE, RunConfig
from ._params import cached_training, result_meta

BLOCK = 100  # training steps per compiled block
FRAME_METRICS = (
    "pixel_mse",
    "pixel_mse_late",
    "pixel_mse_static",
    "recon_mse",
    "frame_mse_mean",
    "embedding_trust",
    "embedding_jumps",
    "embedding_defect",
)
N_FRAMES_KEPT = 8  # forecast frames of the first test trajectory kept in the row (figure)
N_EMBEDDED = 3  # test trajectories whose embedding is kept in the row (figure)


def latent_options(c: RunConfig) -> tuple[str, dict]:
    """(latent geometry, the dynamics model's options) of a run's ``model_options``."""
    opts = dict(c.model_options)
    latent = opts.pop("latent", "so2")
    return latent, opts


def check_frame_model(c: RunConfig) -> None:
    """One-line ValueError when the registered models cannot make ``c``'s latent model."""
    import jax

    import models

    system = systems.make(c.system, **c.system_kwargs())
    if system.dof != 1:
        raise ValueError(f"frames runs need a one-link pendulum (dof 1); got {c.system!r}")
    s = models.spec(c.model)
    if not (s.discrete or c.model == "at_rest"):
        allowed = [m for m in models.available() if models.spec(m).discrete] + ["at_rest"]
        raise ValueError(f"frames runs need a discrete model or at_rest; allowed: {allowed}")
    latent, opts = latent_options(c)
    models.PositionLatentModel(
        c.model, (8, 8), key=jax.random.PRNGKey(0), latent=latent, width=2, ae_width=2,
        dtype=c.dtype, **opts,
    )  # fmt: skip


def build(c: RunConfig):
    """(system, pixel dataset, untrained PositionLatentModel) of a run."""
    import jax

    import models

    system = systems.make(c.system, **c.system_kwargs())
    data = systems.make_pixel_dataset(c.pixel_dataset_config())
    latent, opts = latent_options(c)
    model = models.PositionLatentModel(
        c.model,
        (PIXEL_SIZE, PIXEL_SIZE),
        key=jax.random.PRNGKey(c.seed),
        latent=latent,
        width=c.width,
        depth=c.depth,
        ae_width=c.width,
        activation=c.activation,
        dtype=c.dtype,
        **opts,
    )
    return system, data, model


def _kl_normal(mu, scale, mu0, scale0):
    """KL(N(mu, scale^2) || N(mu0, scale0^2)), elementwise."""
    import jax.numpy as jnp

    return jnp.log(scale0 / scale) + (scale**2 + (mu - mu0) ** 2) / (2 * scale0**2) - 0.5


def seed_elbo(model, frames, eps):
    """The seed's loss (its ``PixelLDDN.loss``) on a batch of windows ``frames`` (B, C, S, S),
    with ``eps`` (B, C, dof) standard normal draws for the reparameterised samples::

        (m_t, s_t) = enc(x_t);  q_t = m_t + s_t eps_t                      (t < C)
        dynamics:    qhat = positions(initial_state(q_0, q_1)), C of them
        no dynamics: qhat_t = q_t
        nll = sum_{t, pixels} BCE(logits dec(qhat_t), x_t)
        kl  = with dynamics: KL(N(m_t, s_t) || N(0, 1)) for t < 2, and for t >= 2
              KL(N(m_t - m_{t-1}, s_t + s_{t-1}) || N(0, h^2)) (the steps, scale h the latent
              step, as the seed's code adds the scales); without: KL(N(m_t, s_t) || N(0, 1))
        loss = mean_B (nll + sum_t kl)

    (differences of angles wrapped on so2). The seed infers from the first 10 of its 11 frames;
    ours from all ``chunk``."""
    import jax
    import jax.numpy as jnp

    mean, scale = jax.vmap(jax.vmap(model.encode))(frames)  # (B, C, dof)
    q = mean + scale * eps
    c = frames.shape[1]
    if model.static:
        qhat = q
        kl = _kl_normal(mean, scale, 0.0, 1.0)
    else:
        z0 = jax.vmap(model.initial_state)(q[:, 0], q[:, 1])
        qhat = jax.vmap(lambda z: model.positions(z, c))(z0)
        head = _kl_normal(mean[:, :2], scale[:, :2], 0.0, 1.0)
        d = jax.vmap(jax.vmap(model.difference))(mean[:, 1:-1], mean[:, 2:])
        steps = _kl_normal(d, scale[:, 2:] + scale[:, 1:-1], 0.0, model.step)
        kl = jnp.concatenate([head, steps], axis=1)
    logits = jax.vmap(jax.vmap(model.decode))(qhat)
    nll = jnp.sum(jax.nn.softplus(logits) - frames * logits, axis=(1, 2, 3))
    return jnp.mean(nll + jnp.sum(kl, axis=(1, 2)))


class WindowDraws:
    """Per step ``batch`` windows of the training frames, without replacement within a step
    (all of them when there are fewer: the seed's full batches), each with a noise seed:
    ``take(k)`` -> (k, batch, 3) int32 of (trajectory, start, noise seed)."""

    def __init__(self, n_traj: int, points: int, chunk: int, batch: int, seed: int):
        t, s = np.meshgrid(np.arange(n_traj), np.arange(points - chunk + 1), indexing="ij")
        self.windows = np.stack([t.ravel(), s.ravel()], axis=-1)
        self.batch = min(batch, len(self.windows))
        self.rng = np.random.default_rng(seed)

    def take(self, k: int) -> np.ndarray:
        n = len(self.windows)
        pick = np.stack([self.rng.permutation(n)[: self.batch] for _ in range(k)])
        noise = self.rng.integers(0, 2**31 - 1, size=(k, self.batch, 1))
        return np.concatenate([self.windows[pick], noise], axis=-1).astype(np.int32)


@dataclass(frozen=True)
class FrameObjective:
    """The objective of a frames run for the one training loop (``bench.train``'s
    ``objective``): :func:`seed_elbo` on windows of ``chunk`` frames of
    ``dataset.frames_train``."""

    chunk: int

    def data(self, model, dataset, config):
        import jax.numpy as jnp

        return jnp.asarray(dataset.frames_train, jnp.dtype(config.dtype))

    def batches(self, frames, config) -> WindowDraws:
        n, t = frames.shape[:2]
        return WindowDraws(n, t, self.chunk, config.batch, config.seed)

    def loss(self, model, frames, ix, config):
        import jax
        import jax.numpy as jnp

        from ._pixels import _gather

        windows = _gather(frames, ix[:, :2], self.chunk)
        shape = (self.chunk, model.dof)
        eps = jax.vmap(lambda s: jax.random.normal(jax.random.PRNGKey(s), shape))(ix[:, 2])
        return seed_elbo(model, windows, eps.astype(jnp.dtype(config.dtype)))


def train_config(c: RunConfig):
    """The optimisation of a frames run (:func:`bench.core._fit.train_config`): no weight
    decay unless the run sets one (the seed's Adam is set by the experiment), :data:`BLOCK`
    steps per compiled block."""
    from ._fit import train_config as run_train_config

    return run_train_config(c, block=BLOCK, weight_decay=0.0)


def fit_frames(c: RunConfig, model, data, progress: bool = False, resume=None):
    """Train ``model`` on ``data``'s frames by the one training loop with
    :class:`FrameObjective` (``resume``: ``bench.train``'s); returns its
    :class:`bench.TrainResult`."""
    from ._train import train

    objective = FrameObjective(c.chunk)
    return train(model, data, train_config(c), progress, objective=objective, resume=resume)


def train_frames(c: RunConfig, model, data, progress: bool = False) -> tuple:
    """:func:`fit_frames` as ``(model, meta)``, nothing cached."""
    res = fit_frames(c, model, data, progress)
    return res.model, result_meta(res)


def train_cached_frames(c: RunConfig, model, data, cache_root: Path, progress: bool) -> tuple:
    """The train step of a frames run: trained, or loaded from the parameter cache."""
    return cached_training(
        c, model, cache_root, lambda resume: fit_frames(c, model, data, progress, resume=resume)
    )


def _forecast_jit(model, frames):
    """(positions (N, T, dof) of every frame, probabilities of the forecasts (N, T, S, S) from
    the first two frames)."""
    import jax

    n_t = frames.shape[1]
    means = jax.vmap(jax.vmap(lambda x: model.encode(x)[0]))(frames)
    pred = jax.vmap(lambda f: model.forecast(f[0], f[1], n_t))(frames)
    recon = jax.nn.sigmoid(jax.vmap(jax.vmap(model.decode))(means))
    return means, pred, recon


def evaluate_frames(c: RunConfig, system, data, model) -> tuple[dict, dict]:
    """``(metrics, curves)`` of a trained frames model on the test trajectories.

    Forecasts start from the first two test frames (encoded means) and run the whole test
    trajectory. ``pixel_mse``: mean over t >= 2, pixels and trajectories of (p - x)^2, p the
    forecast's probabilities (``pixel_mse_late`` the last third; ``pixel_mse_static`` holding
    the second frame, the trivial predictor); ``recon_mse`` every test frame through encoder
    mean and decoder; ``frame_mse_mean`` the mean training frame against the test frames (the
    trivial autoencoder); ``embedding_trust``, ``embedding_jumps``, ``embedding_defect``: the
    structure of the encoder's embedding of the test frames against the true angles
    (:func:`bench.core._embedding.structure`); ``rollout_error``: geometric mean over t >= 2 of
    the relative error of the bob's position read off the forecast frames,
    |p_hat - p| / (|p_hat| + |p|). ``curves``: per-time ``pixel_mse`` and ``rel_error``, the
    embedding and true angles of the first :data:`N_EMBEDDED` test trajectories, a few forecast
    frames of the first.
    """
    import time

    import equinox as eqx
    import jax
    import jax.numpy as jnp

    from . import _metrics as M
    from ._embedding import structure

    dtype = jnp.dtype(c.dtype)
    frames = np.asarray(data.frames_test, dtype=np.float64)  # (N, T, S, S)
    n_t = frames.shape[1]
    fn = eqx.filter_jit(_forecast_jit)
    x = jnp.asarray(frames, dtype)
    t0 = time.perf_counter()
    jax.block_until_ready(fn(model, x))
    t1 = time.perf_counter()
    means, pred, recon = jax.block_until_ready(fn(model, x))
    t2 = time.perf_counter()
    means, pred, recon = (np.asarray(a, np.float64) for a in (means, pred, recon))
    finite = bool(np.all(np.isfinite(pred)))
    sq = (pred - frames) ** 2
    pixel_t = sq.mean(axis=(0, 2, 3))
    static = float(np.mean((frames[:, 1:2] - frames[:, 2:]) ** 2))
    mean_frame = np.asarray(data.frames_train, np.float64).mean(axis=(0, 1))
    embedded = np.asarray(jax.vmap(jax.vmap(model.embed))(jnp.asarray(means, dtype)), np.float64)
    angles = np.asarray(data.z_test[..., 0], np.float64)
    s = structure(embedded, angles)

    # the bob's position read off the forecast frames against the truth
    read = np.asarray(systems.read_angle(pred))
    pos = lambda q: np.stack([np.sin(q), -np.cos(q)], axis=-1)  # noqa: E731
    p_hat, p = pos(read), pos(angles)
    err_t = np.linalg.norm(p_hat - p, axis=-1) / (
        np.linalg.norm(p_hat, axis=-1) + np.linalg.norm(p, axis=-1)
    )
    err_t = np.where(np.isfinite(err_t), err_t, 1.0)
    late = slice(-max(1, (n_t - 2) // 3), None)
    metrics = {
        "pixel_mse": float(pixel_t[2:].mean()) if finite else float("nan"),
        "pixel_mse_late": float(pixel_t[late].mean()) if finite else float("nan"),
        "pixel_mse_static": static,
        "recon_mse": float(np.mean((recon - frames) ** 2)),
        "frame_mse_mean": float(np.mean((frames - mean_frame) ** 2)),
        "embedding_trust": s["trust"],
        "embedding_jumps": s["jumps"],
        "embedding_defect": s["defect"],
        "rollout_error": float(M.geometric_mean(err_t[:, 2:])),
        "rollout_finite": finite,
        "eval_compile_seconds": max(0.0, (t1 - t0) - (t2 - t1)),
        "rollout_seconds": t2 - t1,
        "rollout_seconds_per_traj": (t2 - t1) / max(1, len(frames)),
        "n_params": M.n_params(model),
    }
    keep = np.unique(np.linspace(0, n_t - 1, N_FRAMES_KEPT).round().astype(int))
    curves = {
        "t": (np.arange(n_t) * c.dt).tolist(),
        "rel_error": M.geometric_mean(err_t, axis=0).tolist(),
        "pixel_mse": pixel_t.tolist(),
        "embedding": np.round(embedded[:N_EMBEDDED], 4).tolist(),
        "angles": np.round(angles[:N_EMBEDDED], 4).tolist(),
        "frame_index": keep.tolist(),
        "frames_true": np.round(frames[0, keep], 3).tolist(),
        "frames_pred": np.round(pred[0, keep], 3).tolist(),
    }
    return metrics, curves
