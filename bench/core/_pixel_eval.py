"""The evaluate step of a pixel run: encode the first observation of each test trajectory,
roll the latent state out with the evaluation integrator, decode every state, and score the
frames against the truth, the states read off them, and the states the HNN seed's linear map
reads off their encodings (:func:`evaluate_pixels`, :func:`latent_map`)."""

from __future__ import annotations

import time

import numpy as np

from . import _metrics as M
from ._config import RunConfig
from ._evaluate import eval_integrator
from ._pixels import LATENT_DT, _gather, _jit, _windows, seed_loss

N_FRAMES_KEPT = 8  # decoded frames of the first test trajectory kept in the row (figure)
_LOSS_WINDOWS = 512  # windows at most for the reported train / test losses


def _loss_on(model, frames, chunk: int, integ, seed: int) -> float:
    """The seed's loss on up to :data:`_LOSS_WINDOWS` windows of ``frames`` (N, T, S, S)."""
    import jax.numpy as jnp

    w = _windows(*frames.shape[:2], chunk)
    if len(w) > _LOSS_WINDOWS:
        w = w[np.random.default_rng(seed).choice(len(w), _LOSS_WINDOWS, replace=False)]
    f = _gather(jnp.asarray(frames, jnp.dtype(model.autoencoder.dtype)), w, chunk)
    return float(_loss_jit(model, f, integ))


@_jit
def _loss_jit(model, frames, integ):
    return seed_loss(model, frames, integ)[0]


@_jit
def _encode(m, x):
    """Encodings (..., 2 latent_dof) of observations x (..., 2, S, S)."""
    import jax

    flat = x.reshape(-1, *x.shape[-3:])
    return jax.vmap(m.encode)(flat).reshape(*x.shape[:-3], -1)


def latent_map(model, frames, states, dtype) -> np.ndarray:
    """The HNN seed's map from a latent to the state (its analysis notebook's
    ``learn_z2canonical``): an affine map fitted by least squares from the encodings of the
    training observations to the true state at each one's first frame. ``frames`` (N, T, S, S),
    ``states`` (N, T, 2 dof); returns W (2 latent_dof + 1, 2 dof), state = [z, 1] @ W.

    The seed fits a ``torch.nn.Linear(2, 2)`` by Adam (4000 steps of 400) to (theta, 0.25
    theta_dot); this is that fit's optimum, and a scale on a target column scales its column of
    W alone, so fitting (q, qdot) or (q, p = m l^2 qdot) reads the same energy."""
    import jax.numpy as jnp

    import systems

    obs = systems.PixelDataset.observations(np.asarray(frames))  # (N, T-1, 2, S, S)
    z = np.asarray(_encode(model, jnp.asarray(obs, dtype)), np.float64)
    z = z.reshape(-1, z.shape[-1])
    y = np.asarray(states, np.float64)[:, : obs.shape[1]].reshape(len(z), -1)
    a = np.concatenate([z, np.ones((len(z), 1))], axis=-1)
    w, *_ = np.linalg.lstsq(a, y, rcond=None)
    return w


def _mapped(z, w) -> np.ndarray:
    """States [z, 1] @ w of latents z (..., 2 latent_dof)."""
    z = np.asarray(z, np.float64)
    return np.concatenate([z, np.ones((*z.shape[:-1], 1))], axis=-1) @ w


@_jit
def _roll(m, x0, n_t: int, integ):
    """Latent rollouts of n_t frame steps from observations x0 and their decoded frames."""
    import jax
    import jax.numpy as jnp

    ts = jnp.arange(n_t, dtype=x0.dtype) * LATENT_DT
    zs = jax.vmap(lambda x: m.rollout(m.encode(x), ts, integ))(x0)
    return zs, jax.vmap(jax.vmap(m.decode))(zs)


def evaluate_pixels(c: RunConfig, system, data, model) -> tuple[dict, dict]:
    """``(metrics, curves)`` of a trained latent model on the test trajectories.

    ``pixel_mse``: mean over t >= 1, pixels and trajectories of (x_hat - x)^2
    (``pixel_mse_late`` over the last third of the horizon; ``pixel_mse_static`` the same for
    holding the first observation, the trivial predictor); ``recon_mse``: the autoencoder
    alone on the test observations (``frame_mse_mean``: the mean training observation against
    them, the trivial autoencoder); ``pixel_loss_train`` / ``pixel_loss_test``: the seed's
    loss on training / test windows; ``latent_energy_drift``: the learned conserved scalar
    along the latent rollouts, mean over trajectories of max_t E - min_t E over the spread
    (std) of E over the test starts (NaN for models without one). From the angle read off each
    decoded frame (``systems.read_state``: q from the first frame, qdot the difference to the
    second over dt): ``rollout_error``, ``energy_violation``, ``mse`` and
    ``decoded_energy_mse`` (mean of (H(read x_hat) - H(read x))^2, H the true energy), the
    read-off truth scored by the same reader. The HNN seed's energy metric (its analysis
    notebook): each decoded frame pair encoded again and mapped to the state by
    :func:`latent_map`, ``seed_energy_mse`` the mean over t >= 1 and trajectories of
    (H(mapped) - H(true state))^2 against the true states of the test set (not read off
    frames); ``seed_energy_mse_floor`` the same map applied to the encoded true observations
    (every t), what the map alone costs. ``curves`` also hold per-time ``pixel_mse`` and
    a few decoded frames of the first test trajectory (``frames_true``, ``frames_pred``, at
    ``frame_index``) for the figure.
    """
    import jax
    import jax.numpy as jnp

    import models

    dtype = jnp.dtype(c.dtype)
    integ = eval_integrator(c)
    obs = np.asarray(data.observations(data.frames_test), dtype=np.float64)  # (N, T-1, 2, S, S)
    n_t = obs.shape[1]

    def roll(m, x0):
        return _roll(m, x0, n_t, integ)

    x0 = jnp.asarray(obs[:, 0], dtype)
    t0 = time.perf_counter()
    jax.block_until_ready(roll(model, x0))
    t1 = time.perf_counter()
    zs, pred = jax.block_until_ready(roll(model, x0))
    t2 = time.perf_counter()
    zs, pred = np.asarray(zs, np.float64), np.asarray(pred, np.float64)
    finite = bool(np.all(np.isfinite(pred)))
    sq = (pred - obs) ** 2
    pixel_t = sq.mean(axis=(0, 2, 3, 4))
    x_all = jnp.asarray(obs, dtype)
    recon = jax.vmap(jax.vmap(lambda x: model.decode(model.encode(x))))(x_all)
    recon_mse = float(np.mean((np.asarray(recon, np.float64) - obs) ** 2))
    mean_obs = np.asarray(data.observations(data.frames_train)).mean(axis=(0, 1), dtype=np.float64)
    frame_mse_mean = float(np.mean((obs - mean_obs) ** 2))
    static = float(np.mean((obs[:, :1] - obs[:, 1:]) ** 2))

    # the learned conserved scalar along the latent rollouts
    drift = float("nan")
    energy_first = [float("nan")] * n_t
    if model.has_energy:
        e = np.asarray(
            jax.vmap(jax.vmap(model.latent_energy))(jnp.asarray(zs, dtype)), dtype=np.float64
        )
        spread = float(np.std(e[:, 0]))
        if np.all(np.isfinite(e)) and spread > 0:
            drift = float(np.mean(e.max(axis=1) - e.min(axis=1)) / spread)
        energy_first = e[0].tolist()

    # states and true energies read off the decoded and the true frames
    z_hat, z_true = data.read_states(pred), data.read_states(obs)
    energy = jax.jit(jax.vmap(jax.vmap(system.energy)))
    h_hat, h_true = np.asarray(energy(z_hat)), np.asarray(energy(z_true))
    angular = tuple(system.angular)
    err_t = M.relative_error(z_hat, z_true, angular)
    ev_t = M.energy_violation_curve(h_hat, h_true)
    d_h = (h_hat - h_true) ** 2
    decoded_energy_mse = float(np.mean(d_h)) if np.all(np.isfinite(d_h)) else float("nan")

    # the seed's energy: decoded frames encoded again, mapped linearly to the state, true H
    w = latent_map(model, data.frames_train, data.z_train, dtype)
    h_state = np.asarray(energy(jnp.asarray(data.z_test[:, :n_t])), np.float64)
    seed_energy_mse = seed_energy_floor = float("nan")
    if finite:
        z_re = _encode(model, jnp.asarray(pred, dtype))
        h_seed = np.asarray(energy(jnp.asarray(_mapped(z_re, w))), np.float64)
        d_seed = (h_seed - h_state)[:, 1:] ** 2
        if np.all(np.isfinite(d_seed)):
            seed_energy_mse = float(np.mean(d_seed))
    h_floor = np.asarray(energy(jnp.asarray(_mapped(_encode(model, x_all), w))), np.float64)
    d_floor = (h_floor - h_state) ** 2
    if np.all(np.isfinite(d_floor)):
        seed_energy_floor = float(np.mean(d_floor))

    train_integ = models.Integrator(c.train_integrator, substeps=c.train_substeps)
    metrics = {
        "pixel_mse": float(pixel_t[1:].mean()) if finite else float("nan"),
        "pixel_mse_late": float(pixel_t[-max(1, n_t // 3) :].mean()) if finite else float("nan"),
        "pixel_mse_static": static,
        "recon_mse": recon_mse,
        "frame_mse_mean": frame_mse_mean,
        "pixel_loss_train": _loss_on(model, data.frames_train, c.chunk, train_integ, c.seed),
        "pixel_loss_test": _loss_on(model, data.frames_test, c.chunk, train_integ, c.seed),
        "latent_energy_drift": drift,
        "decoded_energy_mse": decoded_energy_mse,
        "seed_energy_mse": seed_energy_mse,
        "seed_energy_mse_floor": seed_energy_floor,
        "rollout_error": float(M.geometric_mean(err_t[..., 1:])),
        "energy_violation": float(M.geometric_mean(ev_t[..., 1:])),
        "mse": M.mse(z_hat, z_true, angular),
        "rollout_finite": finite,
        "eval_compile_seconds": max(0.0, (t1 - t0) - (t2 - t1)),
        "rollout_seconds": t2 - t1,
        "rollout_seconds_per_traj": (t2 - t1) / max(1, len(obs)),
        "n_params": M.n_params(model),
    }
    keep = np.unique(np.linspace(0, n_t - 1, N_FRAMES_KEPT).round().astype(int))
    curves = {
        "t": (np.arange(n_t) * c.dt).tolist(),
        "rel_error": M.geometric_mean(err_t, axis=0).tolist(),
        "energy_violation": M.geometric_mean(ev_t, axis=0).tolist(),
        "z_true": z_true[0].tolist(),
        "z_pred": z_hat[0].tolist(),
        "pixel_mse": pixel_t.tolist(),
        "latent_energy": energy_first,
        "frame_index": keep.tolist(),
        "frames_true": np.round(obs[0, keep, 0], 3).tolist(),
        "frames_pred": np.round(pred[0, keep, 0], 3).tolist(),
    }
    return metrics, curves
