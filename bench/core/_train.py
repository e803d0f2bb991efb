"""The one training loop: a model fitted by backpropagation, ``steps_per_call`` steps at a
time in one compiled ``lax.scan`` (:func:`train`). What is fitted is an *objective*: by default
:class:`StateObjective`, a dataset's chunks of states through the model's rollout (or, with
``target="derivative"``, the true time derivatives; the loss is :func:`loss_fn`); observations of
another kind bring their own (pixels: ``bench.core._pixels.PixelObjective``). The compiled block
is cached per configuration, objective and shapes: seeds and repeats compile once. The update
rule and its learning-rate schedule: :mod:`bench.core._optim`.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optax

from models import Integrator, rollout_batch

from ._optim import OPTIMIZERS, SCHEDULES, optimizer

LOSSES = ("l2", "l1")
DTYPES = ("float32", "float64")
TARGETS = ("rollout", "derivative")  # what the loss compares (:func:`loss_fn`)


@dataclass(frozen=True)
class TrainConfig:
    """Optimisation settings of one training run (the loss: :func:`loss_fn`).

    ``checkpoints`` names training steps at which a copy of the parameters is kept
    (:class:`Snapshot`, taken at the end of the first compiled block that reaches the step, so
    steps that are multiples of ``steps_per_call`` are exact:
    ``bench.core._fit.checkpoint_steps``). Taking a snapshot changes nothing in the training:
    the final parameters are those of the same run without checkpoints, bit for bit (a
    test)."""

    steps: int = 8000
    batch: int = 200
    lr: float = 5e-3
    weight_decay: float = 1e-4
    clip: float = 1.0
    lr_floor: float = 1e-3  # final learning rate as a fraction of lr
    loss: str = "l2"
    integrator: Integrator = Integrator("rk4_38")
    dtype: str = "float32"
    seed: int = 0
    log_every: int = 100  # progress-bar refresh, in steps (rounded up to whole blocks)
    steps_per_call: int = 100  # steps per compiled block (1: one dispatch per step)
    checkpoints: tuple[int, ...] = ()  # steps whose parameters are kept (TrainResult.snapshots)
    target: str = "rollout"  # "rollout" or "derivative" (:func:`loss_fn`)
    optimizer: str = "adamw"  # "adamw" or "adam_l2" (bench.core._optim.optimizer)
    schedule: str = "cosine"  # "cosine", "onecycle" or "constant" (bench.core._optim)

    def __post_init__(self):
        for name in ("steps", "batch", "log_every", "steps_per_call"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"TrainConfig.{name} must be an integer >= 1, got {value!r}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ValueError(f"TrainConfig.seed must be an integer >= 0, got {self.seed!r}")
        for name, low, high in (
            ("lr", 0.0, np.inf),
            ("weight_decay", -1e-300, np.inf),
            ("clip", 0.0, np.inf),
            ("lr_floor", -1e-300, 1.0),
        ):
            value = getattr(self, name)
            ok = isinstance(value, int | float) and not isinstance(value, bool)
            if not (ok and np.isfinite(value) and low < value <= high):
                bounds = (
                    "in [0, 1]"
                    if name == "lr_floor"
                    else (">= 0" if name == "weight_decay" else "> 0")
                )
                raise ValueError(
                    f"TrainConfig.{name} must be a finite number {bounds}, got {value!r}"
                )
        if self.loss not in LOSSES:
            raise ValueError(f"TrainConfig.loss {self.loss!r}: allowed {', '.join(LOSSES)}")
        if self.dtype not in DTYPES:
            raise ValueError(f"TrainConfig.dtype {self.dtype!r}: allowed {', '.join(DTYPES)}")
        if self.target not in TARGETS:
            raise ValueError(f"TrainConfig.target {self.target!r}: allowed {', '.join(TARGETS)}")
        if self.optimizer not in OPTIMIZERS:
            raise ValueError(
                f"TrainConfig.optimizer {self.optimizer!r}: allowed {', '.join(OPTIMIZERS)}"
            )
        if self.schedule not in SCHEDULES:
            raise ValueError(
                f"TrainConfig.schedule {self.schedule!r}: allowed {', '.join(SCHEDULES)}"
            )
        cps = self.checkpoints
        if not isinstance(cps, tuple) or any(
            isinstance(c, bool) or not isinstance(c, int) or not 1 <= c <= self.steps for c in cps
        ):
            raise ValueError(
                f"TrainConfig.checkpoints must be a tuple of integer steps in [1, steps], "
                f"got {cps!r}"
            )
        if not isinstance(self.integrator, Integrator):
            raise ValueError(
                f"TrainConfig.integrator must be a models.Integrator, got {self.integrator!r}"
            )


@dataclass(frozen=True)
class Snapshot:
    """The model after ``step`` updates, and the training wall time spent until then."""

    step: int
    train_seconds: float
    model: Any


@dataclass(frozen=True)
class TrainResult:
    """``losses[i]`` is the loss at step i (before its update); ``steps_done`` updates applied.

    ``status`` is ``"diverged"`` when step ``diverged_step`` produced a non-finite loss or
    gradient; ``model`` is then the last model with finite loss (the one before that step's
    update) and ``losses`` stop before that step. ``flops_per_step``: see :func:`step_flops`.
    ``snapshots``: one :class:`Snapshot` per ``config.checkpoints`` step reached before any
    divergence (the last one, at ``steps``, holds the final model). A training resumed from a
    saved state (``train``'s ``resume``) started at ``resumed_step`` (0: in one go);
    ``train_seconds`` counts both parts, ``resumed_cpu_seconds`` is the CPU time of the
    interrupted part until its save.
    """

    model: Any
    losses: np.ndarray
    status: str
    diverged_step: int | None
    train_seconds: float
    compile_seconds: float
    steps_done: int
    flops_per_step: float = float("nan")
    snapshots: tuple = ()
    resumed_step: int = 0
    resumed_cpu_seconds: float = 0.0


def loss_fn(model, z, args, ts, config: TrainConfig, dz=None, *, controls=None, scale=None):
    """The loss on a batch of B chunks z (B, C, 2d) observed at ts (C,), args (B, P)::

        L = mean_{b, c, i} e((rollout(model, z[b, 0], ts, args[b])[c, i] - z[b, c, i]) / s_i)
            + mean_b model.penalty(rollout states of b, args[b])

    with e(x) = x^2 ("l2") or |x| ("l1") and s = ``scale`` (2d,) (default 1: a controlled run
    divides by the training states' standard deviation per component). In a controlled scene
    ``controls`` (B, C - 1, n_controls) are each chunk's own, held over each interval.
    With ``target="derivative"`` (the HNN and LNN seeds'
    protocol: no rollout) the loss is on the time derivatives instead::

        L = mean_{b, c, i} e(F(z[b, c], args[b])_i - dz[b, c, i]) + mean_b penalty(z[b], args[b])

    with F the model's vector field and ``dz`` (B, C, 2d) the true one at the same states (the
    dataset's ``dz_train``, from :func:`systems.derivatives`); a discrete model has no vector
    field and cannot train so."""
    if config.target == "derivative":
        field = jax.vmap(
            jax.vmap(lambda zz, a: model.vector_field(0.0, zz, a), in_axes=(0, None)), (0, 0)
        )
        pred, target, states = field(z, args), dz, z
    else:
        pred = rollout_batch(model, z[:, 0], ts, args, config.integrator, controls=controls)
        target, states = z, pred
    err = pred - target if scale is None else (pred - target) / scale
    data = jnp.mean(err * err) if config.loss == "l2" else jnp.mean(jnp.abs(err))
    penalty = jnp.mean(jax.vmap(model.penalty)(states, args))
    return data + penalty.astype(data.dtype)


class Batches:
    """Batch indices: per epoch a random permutation of the N chunks, cut into N // B batches."""

    def __init__(self, n: int, batch: int, seed: int):
        self.n, self.batch = n, min(batch, n)
        self.rng = np.random.default_rng(seed)
        self.pending: list[np.ndarray] = []

    def take(self, k: int) -> np.ndarray:
        while len(self.pending) < k:
            perm = self.rng.permutation(self.n)
            per_epoch = self.n // self.batch
            self.pending.extend(perm[: per_epoch * self.batch].reshape(per_epoch, self.batch))
        out, self.pending = self.pending[:k], self.pending[k:]
        return np.stack(out).astype(np.int32)


@dataclass(frozen=True)
class StateObjective:
    """What :func:`train` fits by default: :func:`loss_fn` on a batch of a dataset's chunks of
    states. An objective is a hashable value (it keys the compiled block) with three methods:
    ``data(model, dataset, config)`` the device arrays of the training set, ``batches(data,
    config)`` an object whose ``take(k)`` gives the batch indices of k steps, and
    ``loss(model, data, ix, config)`` the scalar loss of one batch."""

    def data(self, model, dataset, config: TrainConfig):
        return prepare(model, dataset, config)

    def batches(self, data, config: TrainConfig) -> Batches:
        return Batches(data[0].shape[0], config.batch, config.seed)

    def loss(self, model, data, ix, config: TrainConfig):
        z_all, args_all, ts, *targets = data  # targets: (dz_all,) with target="derivative"
        dz = targets[0][ix] if targets else None
        return loss_fn(model, z_all[ix], args_all[ix], ts, config, dz)


STATES = StateObjective()


_TRACES = [0]  # how many times a training block was traced (tests assert one per config)


def make_step(static, config: TrainConfig, data, lr=None, objective=STATES):
    """One training step ``step(carry, (batch indices, active)) -> (carry, (loss, failed))`` of
    ``objective`` (default :data:`STATES`) on ``data``.

    ``carry = (params, opt_state, dead, good)``. ``active`` False makes the step a no-op
    (padding of the tail). After a non-finite loss or gradient, ``dead`` is set and no later
    step changes the parameters; ``good`` holds the last parameters whose loss was finite.
    ``lr`` (default ``config.lr``) may be a traced scalar: ensembles (``bench.core._ensemble``) vmap
    this one step over members with their own data, parameters and learning rate.
    """
    opt = optimizer(config, lr=lr)

    def step(carry, xs):
        params, opt_state, dead, good = carry
        ix, on = xs
        model = eqx.combine(params, static)
        loss, grads = eqx.filter_value_and_grad(objective.loss)(model, data, ix, config)
        grads = eqx.filter(grads, eqx.is_inexact_array)
        ok = jnp.isfinite(loss) & jnp.isfinite(optax.global_norm(grads))
        updates, new_state = opt.update(grads, opt_state, params)
        new_params = eqx.apply_updates(params, updates)
        live = on & ~dead

        def select(flag):
            return lambda new, old: jnp.where(flag, new, old) if eqx.is_array(new) else new

        good = jax.tree.map(select(live & jnp.isfinite(loss)), params, good)
        params = jax.tree.map(select(live & ok), new_params, params)
        opt_state = jax.tree.map(select(live & ok), new_state, opt_state)
        failed = live & ~ok
        dead = dead | failed
        return (params, opt_state, dead, good), (loss, failed)

    return step


def train_block(inputs, params, opt_state, dead, good, *, static, config: TrainConfig, objective):
    """Run ``len(idx)`` steps of :func:`make_step` as one ``lax.scan``."""
    _TRACES[0] += 1
    data, idx, active = inputs
    step = make_step(static, config, data, objective=objective)
    (params, opt_state, dead, good), (losses, failed) = jax.lax.scan(
        step, (params, opt_state, dead, good), (idx, active)
    )
    return params, opt_state, dead, good, losses, failed


_COMPILED: dict = {}


def step_flops(compiled) -> float:
    """XLA's cost-analysis FLOP count of a compiled training block; NaN when unavailable.

    XLA counts the body of a loop once, not once per trip: the block's ``lax.scan`` over steps
    therefore counts one optimiser step, and inside it the rollout's loop over the chunk's
    intervals (and a Newton loop) also counts once. The figure is one step with every loop body
    counted once: comparable between models trained with the same integrator and chunk.
    """
    try:
        inner = getattr(compiled, "compiled", compiled)  # equinox wraps jax's Compiled
        cost = inner.cost_analysis()
        if isinstance(cost, list | tuple):
            cost = cost[0] if cost else None
        value = float(cost["flops"]) if cost and "flops" in cost else float("nan")
    except Exception:
        return float("nan")
    return value if np.isfinite(value) and value >= 0 else float("nan")


def compiled_block(
    params, static, opt_state, dead, good, data, idx, active, config, objective=STATES
):
    """The compiled block for this configuration, objective and shapes (compiled at most once);
    its ``flops`` attribute is :func:`step_flops` of the compiled program."""
    cfg_key = dataclasses.replace(config, seed=0, log_every=1, checkpoints=())
    leaves = jax.tree.leaves((params, opt_state, data, idx))
    key = (
        jax.tree.structure((params, static, opt_state)),
        tuple(jax.tree.leaves(static)),
        tuple((x.shape, x.dtype) for x in leaves),
        cfg_key,
        objective,
    )
    hit = _COMPILED.get(key)
    if hit is not None:
        return hit, 0.0
    # the inputs (data, batch indices) are not donated; the state is replaced by the outputs
    fn = eqx.filter_jit(train_block, donate="all-except-first")
    t0 = time.perf_counter()
    statics = {"static": static, "config": cfg_key, "objective": objective}
    compiled = fn.lower((data, idx, active), params, opt_state, dead, good, **statics).compile()
    seconds = time.perf_counter() - t0

    def run(data, params, opt_state, dead, good, idx, active):
        return compiled((data, idx, active), params, opt_state, dead, good, **statics)

    run.flops = step_flops(compiled)
    _COMPILED[key] = run
    return run, seconds


def _check_dataset(dataset, min_points: int = 2):
    for name in ("ts_train", "z_train", "args_train"):
        if not hasattr(dataset, name):
            raise ValueError(f"dataset must have ts_train, z_train, args_train; missing {name}")
    z = np.asarray(dataset.z_train)
    ts = np.asarray(dataset.ts_train)
    args = np.asarray(dataset.args_train)
    if z.ndim != 3 or ts.shape != (z.shape[1],) or args.ndim != 2 or args.shape[0] != z.shape[0]:
        raise ValueError(
            f"dataset shapes must be ts_train (C,), z_train (N, C, 2d), args_train (N, P); got "
            f"{ts.shape}, {z.shape}, {args.shape}"
        )
    if z.shape[1] < min_points:
        raise ValueError(f"training chunks need at least {min_points} points, got {z.shape[1]}")
    return ts, z, args


def _check_targets(dataset, z) -> np.ndarray:
    dz = getattr(dataset, "dz_train", None)
    if dz is None:
        raise ValueError(
            'target="derivative" needs dataset.dz_train, the true time derivatives at z_train '
            "(systems.derivatives)"
        )
    dz = np.asarray(dz)
    if dz.shape != z.shape:
        raise ValueError(f"dz_train must have z_train's shape {z.shape}; got {dz.shape}")
    return dz


def prepare(model, dataset, config: TrainConfig):
    """Device arrays of the training set in the configured dtype, and the model checked."""
    if not isinstance(config, TrainConfig):
        raise ValueError(f"config must be a bench.TrainConfig, got {type(config).__name__}")
    model_dtype = getattr(model, "dtype", config.dtype)
    if model_dtype != config.dtype:
        raise ValueError(
            f"model dtype {model_dtype} differs from TrainConfig.dtype {config.dtype}: "
            f"make the model with dtype={config.dtype!r}"
        )
    if config.dtype == "float64" and not jax.config.jax_enable_x64:
        raise ValueError(
            "float64 training needs jax's 64-bit mode: call systems.enable_x64() or "
            'jax.config.update("jax_enable_x64", True) first'
        )
    # a derivative target needs no interval: chunks of one state are the seeds' random states
    ts, z, args = _check_dataset(dataset, 1 if config.target == "derivative" else 2)
    scene = getattr(model, "scene", None)
    if scene is not None and scene.n_args < args.shape[1]:
        # the data carry the system's parameters (e.g. the relativistic particle's default g);
        # a model whose scene takes none must see args of shape (0,), as at evaluation
        args = args[:, : scene.n_args]
    dtype = jnp.dtype(config.dtype)
    data = (jnp.asarray(z, dtype), jnp.asarray(args, dtype), jnp.asarray(ts, dtype))
    if config.target == "derivative":
        if not hasattr(model, "vector_field"):
            raise ValueError(
                f'target="derivative" needs a model with a vector field; '
                f"{type(model).__name__} is a discrete map"
            )
        data += (jnp.asarray(_check_targets(dataset, z), dtype),)
    return data


def train(
    model,
    dataset,
    config: TrainConfig = TrainConfig(),
    progress: bool = False,
    objective=STATES,
    resume=None,
):
    """Fit ``model`` to ``dataset`` (by default its training chunks of states: ``objective``
    :data:`STATES`); never raises on divergence.

    Returns a :class:`TrainResult`. ``compile_seconds`` is the ahead-of-time compile of the
    training block (0 when this configuration was compiled before in this process);
    ``train_seconds`` is the wall time of the steps alone; ``flops_per_step`` comes from the
    same compiled block (no extra compile).

    ``resume`` (a :class:`bench.core._resume.ResumePoint`) keeps the training's state there
    every so often and starts from a state saved there by an interrupted training of the same
    configuration: the result is the uninterrupted training's, bit for bit, with
    ``resumed_step`` the step it started from and the wall and CPU seconds of both parts.
    """
    cpu_start = time.process_time()
    data = objective.data(model, dataset, config)
    params, static = eqx.partition(model, eqx.is_inexact_array)
    # the blocks donate their state buffers: copy so that the caller's model stays valid
    params = jax.tree.map(jnp.copy, params)
    opt_state = optimizer(config).init(params)
    k = min(config.steps_per_call, config.steps)
    batches = objective.batches(data, config)
    dead = jnp.asarray(False)

    def block_inputs(start):
        idx = batches.take(k)
        active = np.arange(start, start + k) < config.steps
        return jnp.asarray(idx), jnp.asarray(active)

    idx, active = block_inputs(0)
    good = jax.tree.map(jnp.copy, params)  # a distinct buffer: both are donated
    compiled, compile_seconds = compiled_block(
        params, static, opt_state, dead, good, data, idx, active, config, objective
    )

    losses: list[np.ndarray] = []
    snapshots: list[Snapshot] = []
    pending = list(config.checkpoints)
    diverged_step = None
    train_seconds = cpu_before = 0.0
    done = 0
    saved = None if resume is None else resume.load(params, opt_state, good, k)
    if saved is not None and saved.done < config.steps:
        done, train_seconds, cpu_before = saved.done, saved.train_seconds, saved.cpu_seconds
        params, opt_state, good = saved.params, saved.opt_state, saved.good
        losses.append(saved.losses)
        snapshots = [Snapshot(a, b, eqx.combine(m, static)) for a, b, m in saved.snapshots]
        pending = [c for c in pending if c > done]
        for _ in range(done // k - 1):  # the stream's draws up to here: block_inputs(0) made one
            batches.take(k)
    resumed_step = done

    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=config.steps, initial=done, desc="train", unit="step", mininterval=0.5)
    last_log = done
    while done < config.steps:
        if done > 0:
            idx, active = block_inputs(done)
        t0 = time.perf_counter()
        params, opt_state, dead, good, block_losses, failed = compiled(
            data, params, opt_state, dead, good, idx, active
        )
        block_losses = np.asarray(block_losses)  # waits for the block
        train_seconds += time.perf_counter() - t0
        block_losses = block_losses[: config.steps - done]
        failed = np.flatnonzero(np.asarray(failed))
        if failed.size:
            bad = int(failed[0])
            losses.append(block_losses[:bad])
            diverged_step = done + bad
            done += bad
            break
        losses.append(block_losses)
        done += len(block_losses)
        if pending and done >= pending[0]:  # a copy: the next block donates these buffers
            kept = params if done >= config.steps else jax.tree.map(jnp.copy, params)
            snapshots.append(Snapshot(done, train_seconds, eqx.combine(kept, static)))
            while pending and done >= pending[0]:
                pending.pop(0)
        if bar is not None:
            bar.update(len(block_losses))
            if done - last_log >= config.log_every or done >= config.steps:
                bar.set_postfix(loss=f"{block_losses[-1]:.3e}")
                last_log = done
        if resume is not None and done < config.steps and resume.due():
            cpu = cpu_before + time.process_time() - cpu_start
            resume.save(done, k, params, opt_state, good, snapshots, losses, train_seconds, cpu)
    if bar is not None:
        bar.close()
    return TrainResult(
        model=eqx.combine(params if diverged_step is None else good, static),
        losses=np.concatenate(losses) if losses else np.zeros(0),
        status="ok" if diverged_step is None else "diverged",
        diverged_step=diverged_step,
        train_seconds=train_seconds,
        compile_seconds=compile_seconds,
        steps_done=done,
        flops_per_step=getattr(compiled, "flops", float("nan")),
        snapshots=tuple(snapshots),
        resumed_step=resumed_step,
        resumed_cpu_seconds=cpu_before,
    )
