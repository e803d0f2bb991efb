"""Runs that learn from pixels (``RunConfig.observation == "pixels"``): the build and train
steps. Rendered frames of the system (``systems.make_pixel_dataset``; an observation is a frame
stacked with its successor), an autoencoder with latent dynamics (``models.LatentModel``), and
the HNN seed's three-term loss (:func:`seed_loss`), trained with AdamW, the suite's cosine decay
and clipping and the seed's weight decay. The evaluate step is :mod:`bench.core._pixel_eval`.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

import systems

from ._experiments import PIXEL_SIZE, RunConfig
from ._params import cached_training

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
        c.model, (2, 8, 8), key=jax.random.PRNGKey(0), width=2, ae_width=2, dtype=c.dtype
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


def _train_config(steps, batch, lr):
    from ._train import TrainConfig

    return TrainConfig(steps=steps, batch=batch, lr=lr, weight_decay=WEIGHT_DECAY)


def _jit(fn):
    import equinox as eqx

    return eqx.filter_jit(fn)


@_jit
def _block(params, opt_state, frames, idx, static, hp):
    """A block of training steps (one compile per model structure, shapes and ``hp``, shared
    by the seeds of a sweep in one process)."""
    import equinox as eqx
    import jax
    import jax.numpy as jnp
    import optax

    import models

    from ._train import optimizer

    steps, batch, lr, chunk, method, substeps, aux_weight = hp
    integ = models.Integrator(method, substeps=substeps)
    opt = optimizer(_train_config(steps, batch, lr))

    def step(carry, i):
        p, s = carry
        f = _gather(frames, i, chunk)
        loss, grads = jax.value_and_grad(
            lambda p_: seed_loss(eqx.combine(p_, static), f, integ, aux_weight)[0]
        )(p)
        ok = jnp.isfinite(loss) & jnp.isfinite(optax.global_norm(grads))
        updates, s2 = opt.update(grads, s, p)
        p2 = eqx.apply_updates(p, updates)
        keep = lambda a, b: jax.tree_util.tree_map(lambda x, y: jnp.where(ok, x, y), a, b)
        return (keep(p2, p), keep(s2, s)), jnp.where(ok, loss, jnp.nan)

    (params, opt_state), losses = jax.lax.scan(step, (params, opt_state), idx)
    return params, opt_state, losses


def fit_pixels(c: RunConfig, model, data, progress: bool = False, aux_weight: float = CC_LOSS):
    """Train ``model`` with :func:`seed_loss` (its cc term weighed by ``aux_weight``); returns
    a :class:`bench.TrainResult` (``flops_per_step`` NaN, no snapshots).

    A non-finite loss or gradient stops training at that block (``status`` diverged) and
    keeps the parameters from before the block."""
    import equinox as eqx
    import jax.numpy as jnp

    from ._train import TrainResult, optimizer

    dtype = jnp.dtype(c.dtype)
    tcfg = _train_config(c.steps, c.batch, c.lr)
    hp = (c.steps, c.batch, c.lr, c.chunk, c.train_integrator, c.train_substeps, aux_weight)
    opt = optimizer(tcfg)
    frames = jnp.asarray(data.frames_train, dtype)
    windows = _windows(*frames.shape[:2], c.chunk)
    batch = min(c.batch, len(windows))
    params, static = eqx.partition(model, eqx.is_inexact_array)
    opt_state = opt.init(params)

    rng = np.random.default_rng(c.seed)
    losses, status, diverged_step, done = [], "ok", None, 0
    compile_seconds, t_start = 0.0, time.perf_counter()
    while done < c.steps:
        k = min(BLOCK, c.steps - done)
        idx = windows[rng.integers(0, len(windows), size=(k, batch))]
        t0 = time.perf_counter()
        new_params, new_state, block_losses = _block(
            params, opt_state, frames, jnp.asarray(idx), static, hp
        )
        block_losses = np.asarray(block_losses, dtype=np.float64)
        if done == 0:  # the first block includes the compile: time a second call of it
            compile_seconds = time.perf_counter() - t0
        bad = ~np.isfinite(block_losses)
        if bad.any():
            first = int(np.argmax(bad))
            losses.extend(block_losses[:first])
            status, diverged_step, done = "diverged", done + first, done + first
            break
        params, opt_state = new_params, new_state
        losses.extend(block_losses)
        done += k
        if progress:
            print(f"  step {done}/{c.steps} loss {block_losses[-1]:.4g}", flush=True)
    total = time.perf_counter() - t_start
    # the first block's time is mostly its compile; its steps are charged at the mean rate
    per_step = (total - compile_seconds) / max(1, done - min(done, BLOCK))
    compile_seconds = max(0.0, compile_seconds - per_step * min(done, BLOCK))
    return TrainResult(
        model=eqx.combine(params, static),
        losses=np.asarray(losses, dtype=np.float64),
        status=status,
        diverged_step=diverged_step,
        train_seconds=float(total - compile_seconds),
        compile_seconds=float(compile_seconds),
        steps_done=int(done),
    )


def train_pixels(
    c: RunConfig, model, data, progress: bool = False, aux_weight: float = CC_LOSS
) -> tuple:
    """:func:`fit_pixels` as ``(model, meta)``: meta with the training's outcome, costs and
    ``final_loss`` (the last loss; None without one)."""
    res = fit_pixels(c, model, data, progress, aux_weight)
    meta = {
        "status": res.status,
        "diverged_step": res.diverged_step,
        "train_seconds": res.train_seconds,
        "compile_seconds": res.compile_seconds,
        "steps_done": res.steps_done,
        "flops_per_step": float("nan"),
        "final_loss": float(res.losses[-1]) if len(res.losses) else None,
    }
    return res.model, meta


def train_cached_pixels(c: RunConfig, model, data, cache_root: Path, progress: bool) -> tuple:
    """The train step of a pixel run: ``(model, meta)``, trained by :func:`fit_pixels` or
    loaded from the parameter cache (:func:`bench.core._params.cached_training`)."""
    return cached_training(c, model, cache_root, lambda: fit_pixels(c, model, data, progress))
