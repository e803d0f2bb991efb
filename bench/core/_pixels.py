"""Runs that learn from pixels (``RunConfig.observation == "pixels"``): rendered frames
of the system, an autoencoder with latent dynamics (``models.LatentModel``), the HNN seed's
three-term loss, rollouts decoded to pixels, and their metrics as one row.

**Data** (``systems.make_pixel_dataset``): ``n_train`` training and ``n_test`` test
trajectories from starts q0 ~ U(-pi/6, pi/6), qdot0 ~ U(-1, 1) (the seed's Pendulum-v0 starts,
kept only below pi/6), frames of :data:`SIZE` x :data:`SIZE` pixels ``dt`` apart; a training
trajectory spans ``duration`` (``round(duration / dt)`` frames), a test trajectory ``chunk *
test_chunks`` frames. An observation is a frame stacked with its successor.

**Loss** (the HNN seed's experiment-pixels/train.py, on windows of ``chunk`` consecutive frames
drawn anywhere in the training trajectories; ``chunk = 3`` is the seed's x, x_next)::

    z_i = enc(x_i);  ae = mean (dec(z_i) - x_i)^2
    dyn = mean (rollout(z_0)_i - z_i)^2          (i >= 1, the run's train integrator)
    cc  = mean (dw_i - (w_{i+1} - w_i))^2         (z = (w, dw): the auxiliary latent loss)
    loss = ae + cc + 0.1 dyn

in latent time units of one frame (the seed's ``z + f(z)``: its step is one unit; ours is an
RK4 step of one unit, where the seed trains with that Euler step and tests with RK4). AdamW with
the suite's cosine decay and clipping, weight decay 1e-5 (the seed's appendix C).

**Metrics** (test trajectories: encode the first observation, roll the latent state out with
the evaluation integrator, decode every state): ``pixel_mse`` (mean over t >= 1, pixels and
trajectories of (x_hat - x)^2; ``pixel_mse_late`` over the last third of the horizon),
``pixel_mse_static`` (the same for holding the first
observation: the trivial predictor), ``recon_mse`` (the autoencoder alone on the test
observations), ``pixel_loss_train`` / ``pixel_loss_test`` (the seed's loss on training / test
windows), ``latent_energy_drift`` (the learned conserved scalar along the latent rollouts:
mean over trajectories of max_t E - min_t E, over the spread (std) of E over the test starts;
NaN for models without one), and, from the angle read off each decoded frame
(``systems.read_state``: q from the first frame, qdot the difference to the second over dt),
``rollout_error``, ``energy_violation``, ``mse`` and ``decoded_energy_mse`` (mean of (H(read
x_hat) - H(read x))^2, H the system's true energy), the read-off truth scored by the same
reader. The row's ``curves`` also hold per-time ``pixel_mse`` and a few decoded frames of the
first test trajectory (``frames_true``, ``frames_pred``, at ``frame_index``) for the figure.
"""

from __future__ import annotations

import math
import os
import time
import traceback
from pathlib import Path

import numpy as np

import systems

from . import _metrics as M
from ._errors import one_line, storage_error
from ._experiments import RunConfig

SIZE = 28  # pixels per side (the HNN seed's 28 x 28)
MAX_ANGLE = math.pi / 6  # the seed's starts: |angle| < pi/6 ...
MAX_SPEED = 1.0  # ... and angular velocity U(-1, 1) (Pendulum-v0's reset)
AE_LOSS, CC_LOSS, DYN_LOSS = 1.0, 1.0, 0.1  # the seed's weights (train.py)
WEIGHT_DECAY = 1e-5  # the seed's (appendix C: "weight decay ... had a significant impact")
LATENT_DT = 1.0  # latent time per frame (the seed's z_next = z + f(z))
BLOCK = 100  # training steps per compiled block
N_FRAMES_KEPT = 8  # decoded frames of the first test trajectory kept in the row (figure)
_LOSS_WINDOWS = 512  # windows at most for the reported train / test losses
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


def dataset_config(c: RunConfig) -> systems.PixelDatasetConfig:
    """The pixel dataset of a run."""
    return systems.PixelDatasetConfig(
        system=c.system,
        system_params=tuple(sorted(c.system_kwargs().items())),
        size=SIZE,
        n_train=c.n_train,
        n_test=c.n_test,
        train_points=max(c.chunk, round(c.duration / c.dt)),
        test_points=c.chunk * c.test_chunks,
        dt=c.dt,
        max_angle=MAX_ANGLE,
        max_speed=MAX_SPEED,
        seed=c.seed,
    )


def check_pixels(c: RunConfig) -> RunConfig:
    """One-line ValueError for a pixel run that can never run (before any training)."""
    import jax

    import models

    c.validate()
    if c.chunk < 3:
        raise ValueError(
            f"pixel runs need chunk >= 3 frames (two observations); got chunk={c.chunk}"
        )
    for name, bad in (
        ("noise", c.noise != 0),
        ("random_args", c.random_args),
        ("train_target 'derivative'", c.train_target != "rollout"),
        ("friction", c.friction != 0),
    ):
        if bad:
            raise ValueError(f"pixel runs support no {name}; allowed: the default")
    system = systems.make(c.system, **c.system_kwargs())
    systems._render.reach(system)  # the renderable systems (ValueError naming them)
    dataset_config(c)
    if models.spec(c.model).trivial:
        allowed = [m for m in models.available() if not models.spec(m).trivial]
        raise ValueError(f"pixel runs need a learned model; allowed: {', '.join(allowed)}")
    models.LatentModel(
        c.model, (2, 8, 8), key=jax.random.PRNGKey(0), width=2, ae_width=2, dtype=c.dtype
    )
    return c


def build(c: RunConfig):
    """(system, pixel dataset, untrained LatentModel) of a run."""
    import jax

    import models

    system = systems.make(c.system, **c.system_kwargs())
    data = systems.make_pixel_dataset(dataset_config(c))
    model = models.LatentModel(
        c.model,
        (2, SIZE, SIZE),
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
    """The HNN seed's loss on a batch of windows ``frames`` (B, C, S, S): (loss, (ae, cc, dyn))
    (module docstring). ``aux_weight`` weighs the auxiliary latent loss cc (the seed's 1; the
    VIN diagnosis, ``python -m bench diagnose-vin``, also trains with 0)."""
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


def train_pixels(
    c: RunConfig, model, data, progress: bool = False, aux_weight: float = CC_LOSS
) -> tuple:
    """Train ``model`` with :func:`seed_loss` (its cc term weighed by ``aux_weight``); returns
    (model, meta) as the store keeps them.

    A non-finite loss or gradient stops training at that block (``status`` diverged) and
    keeps the last finite parameters."""
    import equinox as eqx
    import jax.numpy as jnp

    from ._train import optimizer

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
    losses = np.asarray(losses, dtype=np.float64)
    meta = {
        "status": status,
        "diverged_step": diverged_step,
        "train_seconds": float(total - compile_seconds),
        "compile_seconds": float(compile_seconds),
        "steps_done": int(done),
        "flops_per_step": float("nan"),
        "final_loss": float(losses[-1]) if len(losses) else None,
    }
    return eqx.combine(params, static), meta


def _train_cached(c: RunConfig, model, data, cache_root: Path, progress: bool):
    """Train, or load the parameters cached under ``train_hash`` when their checksum and code
    hold (:func:`bench.core._rows.cached_params_meta`)."""
    import equinox as eqx

    from ._rows import cached_params_meta, code_fingerprint, sha256_file
    from ._rows import write_json as _write_json

    pdir = Path(cache_root) / "params" / c.train_hash
    pfile, meta_file = pdir / "model.eqx", pdir / "train.json"
    meta = cached_params_meta(pdir)
    if meta is not None:
        try:
            meta["train_cached"] = True
            return eqx.tree_deserialise_leaves(pfile, like=model), meta
        except Exception:  # a damaged cache entry: retrain
            pass
    trained, meta = train_pixels(c, model, data, progress)
    pdir.mkdir(parents=True, exist_ok=True)
    tmp = pdir / f".tmp-{os.getpid()}.eqx"
    eqx.tree_serialise_leaves(tmp, trained)
    os.replace(tmp, pfile)
    meta["sha256"] = sha256_file(pfile)
    meta["code"] = code_fingerprint()
    _write_json(meta_file, meta)
    meta["train_cached"] = False
    return trained, meta


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
def _roll(m, x0, n_t: int, integ):
    """Latent rollouts of n_t frame steps from observations x0 and their decoded frames."""
    import jax
    import jax.numpy as jnp

    ts = jnp.arange(n_t, dtype=x0.dtype) * LATENT_DT
    zs = jax.vmap(lambda x: m.rollout(m.encode(x), ts, integ))(x0)
    return zs, jax.vmap(jax.vmap(m.decode))(zs)


def evaluate_pixels(c: RunConfig, system, data, model) -> tuple[dict, dict]:
    """(metrics, curves) of a trained latent model on the test trajectories (module
    docstring)."""
    import jax
    import jax.numpy as jnp

    import models

    from ._rows import eval_integrator

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
    recon = jax.vmap(jax.vmap(lambda x: model.decode(model.encode(x))))(jnp.asarray(obs, dtype))
    recon_mse = float(np.mean((np.asarray(recon, np.float64) - obs) ** 2))
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

    train_integ = models.Integrator(c.train_integrator, substeps=c.train_substeps)
    metrics = {
        "pixel_mse": float(pixel_t[1:].mean()) if finite else float("nan"),
        "pixel_mse_late": float(pixel_t[-max(1, n_t // 3) :].mean()) if finite else float("nan"),
        "pixel_mse_static": static,
        "recon_mse": recon_mse,
        "pixel_loss_train": _loss_on(model, data.frames_train, c.chunk, train_integ, c.seed),
        "pixel_loss_test": _loss_on(model, data.frames_test, c.chunk, train_integ, c.seed),
        "latent_energy_drift": drift,
        "decoded_energy_mse": decoded_energy_mse,
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


def execute_pixels(c: RunConfig, cache_root=None, progress: bool = False) -> dict:
    """One pixel run end to end: its row, as ``bench.core._execute.execute_run`` writes rows
    (never raises, except for a storage error)."""
    from ._provenance import provenance
    from ._rows import artifact_dir, base_row
    from ._rows import write_json as _write_json

    cache_root = Path(cache_root or systems.cache_root())
    row = base_row(c)
    art = artifact_dir(c.config_hash, cache_root)
    t_start, c_start = time.perf_counter(), time.process_time()
    try:
        art.mkdir(parents=True, exist_ok=True)
        _write_json(art / "config.json", c.to_dict())
        (art / "traceback.txt").unlink(missing_ok=True)
        check_pixels(c)
        system, data, model = build(c)
        model, meta = _train_cached(c, model, data, cache_root, progress)
        row.update(
            status=meta["status"],
            diverged_step=meta.get("diverged_step"),
            train_seconds=meta["train_seconds"],
            compile_seconds=meta["compile_seconds"],
            steps_done=meta.get("steps_done"),
            final_loss=meta.get("final_loss"),
            flops_per_step=float("nan"),
            train_cached=meta["train_cached"],
        )
        metrics, curves = evaluate_pixels(c, system, data, model)
        row.update(metrics)
        row["curves"] = curves
    except Exception as e:  # one run never stops the sweep, a full disk does
        if storage_error(e):
            raise
        row["status"] = "failed"
        row["error"] = one_line(e, 500)
        (art / "traceback.txt").write_text(traceback.format_exc())
    row["wall_seconds"] = time.perf_counter() - t_start
    row["cpu_seconds"] = time.process_time() - c_start  # every thread of the process
    row.update(provenance())
    _write_json(art / "metrics.json", {a: b for a, b in row.items() if a != "curves"})
    return row
