"""The one training loop: models fitted by backpropagation, ``steps_per_call`` steps at a time
in one compiled ``lax.scan`` over the one step (:func:`make_step`). M >= 1 trainings that differ
only in seed and learning rate advance together as one program (:class:`Training`, driven by
:func:`drive`): the step mapped over the members, each with its own batches, divergence flag
and last good parameters. A single run (:func:`train`) is the one-member case, an ensemble
(:func:`bench.core._ensemble.train_ensemble`) the M-member one. The compiled block is cached per
configuration up to seed and rate, objective, member count and shapes: seeds, rates and repeats
compile once.

What is fitted: an objective (:mod:`bench.core._objective`; by default a dataset's chunks of
states). The settings and the result: :mod:`bench.core._train_config`; the update rule and its
learning-rate schedule: :mod:`bench.core._optim`.
"""

from __future__ import annotations

import dataclasses
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optax

# Batches, loss_fn and prepare: the observation kinds' objectives import them from here
from ._objective import STATES, Batches, loss_fn, prepare  # noqa: F401
from ._optim import optimizer
from ._train_config import Snapshot, TrainConfig, TrainResult, shared_config

_TRACES = [0]  # how many times a training block was traced (tests assert one per config)


def make_step(static, config: TrainConfig, data, lr=None, objective=STATES):
    """One training step ``step(carry, (batch indices, active)) -> (carry, (loss, failed))`` of
    ``objective`` (default :data:`bench.core._objective.STATES`) on ``data``.

    ``carry = (params, opt_state, dead, good)``. ``active`` False makes the step a no-op
    (padding of the tail). After a non-finite loss or gradient, ``dead`` is set and no later
    step changes the parameters; ``good`` holds the last parameters whose loss was finite.
    ``lr`` (default ``config.lr``) may be a traced scalar: :func:`train_block` maps this one
    step over members with their own data, parameters and learning rate.
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


def _on_members(step, members: int):
    """``step(carry, xs, data, lr)`` of one member, applied to ``members`` of them: the member
    axis leads ``carry``, ``data``, ``lr`` and the batch part of ``xs = (batch, active)``
    (``active`` is shared). ``jax.vmap`` for several; for one, ``step`` on the member itself:
    the same values, and XLA's CPU code for a vmap of one runs a few percent slower."""
    if members > 1:
        return jax.vmap(step, in_axes=(0, (0, None), 0, 0))

    def first(tree):
        return jax.tree.map(lambda x: x[0], tree)

    def one(carry, xs, data, lr):
        out = step(first(carry), (first(xs[0]), xs[1]), first(data), lr[0])
        return jax.tree.map(lambda x: x[None], out)

    return one


def train_block(inputs, params, opt_state, dead, good, *, static, config: TrainConfig, objective):
    """``len(active)`` steps of :func:`make_step` for M members as one ``lax.scan``.

    ``inputs = (data, lr, batches, active)``: the members' data and learning rates (M, ...),
    their batches (steps, M, ...) and whether each step is on (steps,); ``params``,
    ``opt_state``, ``dead`` and ``good`` carry the members' state (M, ...). Returns the new
    state and the losses and failure flags of every step and member (steps, M)."""
    _TRACES[0] += 1
    data, lr, batches, active = inputs

    def member_step(carry, xs, data, lr):
        return make_step(static, config, data, lr, objective=objective)(carry, xs)

    step = _on_members(member_step, lr.shape[0])
    (params, opt_state, dead, good), (losses, failed) = jax.lax.scan(
        lambda carry, xs: step(carry, xs, data, lr),
        (params, opt_state, dead, good),
        (batches, active),
    )
    return params, opt_state, dead, good, losses, failed


_COMPILED: dict = {}


def step_flops(compiled) -> float:
    """XLA's cost-analysis FLOP count of a compiled training block; NaN when unavailable.

    XLA counts the body of a loop once, not once per trip: the block's ``lax.scan`` over steps
    therefore counts one optimiser step (of every member), and inside it the rollout's loop
    over the chunk's intervals (and a Newton loop) also counts once. The figure is one step
    with every loop body counted once: comparable between models trained with the same
    integrator and chunk.
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


def compiled_block(inputs, params, static, opt_state, dead, good, config, objective=STATES):
    """``(run, compile seconds)``: :func:`train_block` compiled for these shapes, ``config``
    and ``objective``, at most once per process (0 seconds when it was compiled before);
    ``run(inputs, params, opt_state, dead, good)`` runs it and ``run.flops`` is its
    :func:`step_flops`. ``config`` is the members' :func:`shared_config` without checkpoints:
    seeds, learning rates and repeats share one program."""
    key = (
        jax.tree.structure((params, static, opt_state)),
        tuple(jax.tree.leaves(static)),
        tuple((x.shape, x.dtype) for x in jax.tree.leaves((inputs, params, opt_state))),
        config,
        objective,
    )
    hit = _COMPILED.get(key)
    if hit is not None:
        return hit, 0.0
    # the inputs (data, rates, batches) are not donated; the state is replaced by the outputs
    fn = eqx.filter_jit(train_block, donate="all-except-first")
    statics = {"static": static, "config": config, "objective": objective}
    t0 = time.perf_counter()
    compiled = fn.lower(inputs, params, opt_state, dead, good, **statics).compile()
    seconds = time.perf_counter() - t0

    def run(inputs, params, opt_state, dead, good):
        return compiled(inputs, params, opt_state, dead, good, **statics)

    run.flops = step_flops(compiled)
    _COMPILED[key] = run
    return run, seconds


def _stack(trees):
    return jax.tree.map(lambda *xs: jnp.stack(xs), *trees)


def _member(tree, i):
    return jax.tree.map(lambda x: x[i] if eqx.is_array(x) else x, tree)


class Training:
    """M >= 1 trainings advanced together, a block of ``block`` steps at a time, by one
    compiled program (:func:`compiled_block`): ``models[m]`` fits ``objective`` on
    ``datasets[m]`` with ``configs[m]``. The configs may differ only in seed and learning
    rate, the models and their data only in values (ValueError otherwise).

    Holds the members' state (``params``, ``opt_state``, ``dead``: diverged, ``good``: the last
    parameters with a finite loss; the member axis leads), their batch streams, the program's
    ``compile_seconds`` and ``flops`` (:func:`step_flops`, all members), ``done`` (steps run)
    and ``train_seconds`` (the wall time of the blocks alone)."""

    def __init__(self, models, datasets, configs, objective=STATES):
        if not (len(models) == len(datasets) == len(configs)):
            raise ValueError("a training needs as many datasets and configs as models")
        self.config = cfg = shared_config(configs)
        data = [objective.data(m, d, c) for m, d, c in zip(models, datasets, configs, strict=True)]
        parts = [eqx.partition(m, eqx.is_inexact_array) for m in models]
        self.static = parts[0][1]
        shapes = [[x.shape for x in jax.tree.leaves(p)] for p, _ in parts]
        for i in range(1, len(models)):
            same = jax.tree.structure(parts[i][0]) == jax.tree.structure(parts[0][0])
            if not (same and shapes[i] == shapes[0] and eqx.tree_equal(parts[i][1], self.static)):
                raise ValueError(f"ensemble member {i}'s model differs in structure from member 0")
            if [x.shape for x in jax.tree.leaves(data[i])] != [
                x.shape for x in jax.tree.leaves(data[0])
            ]:
                raise ValueError(
                    f"ensemble member {i}'s training data differ in shape from member 0"
                )
        self.members, self.steps = len(models), cfg.steps
        self.block = min(cfg.steps_per_call, cfg.steps)
        self.params = _stack([p for p, _ in parts])  # new buffers: the callers' models stay valid
        self.good = jax.tree.map(jnp.copy, self.params)  # a distinct buffer: both are donated
        self.opt_state = jax.vmap(optimizer(cfg).init)(self.params)
        self.dead = jnp.zeros(self.members, bool)
        self._data = _stack(data)
        self._lr = jnp.asarray([c.lr for c in configs], jnp.dtype(cfg.dtype))
        self._streams = [objective.batches(d, c) for d, c in zip(data, configs, strict=True)]
        self.done, self.train_seconds = 0, 0.0
        self._next = self._draw()  # the first block's batches, which shape the program
        self._run, self.compile_seconds = compiled_block(
            self._inputs(self._next),
            self.params,
            self.static,
            self.opt_state,
            self.dead,
            self.good,
            dataclasses.replace(cfg, checkpoints=()),  # snapshots are taken outside it
            objective,
        )
        self.flops = self._run.flops

    def _draw(self) -> np.ndarray:
        return np.stack([s.take(self.block) for s in self._streams], axis=1)  # (block, M, ...)

    def _inputs(self, batches):
        active = np.arange(self.done, self.done + self.block) < self.steps
        return self._data, self._lr, jnp.asarray(batches), jnp.asarray(active)

    def advance(self):
        """Run the next block: ``(losses, failed)`` of its steps up to ``steps``, (steps, M)
        arrays, once the block is done; its wall time adds to ``train_seconds``."""
        batches, self._next = (self._draw() if self._next is None else self._next), None
        inputs = self._inputs(batches)
        t0 = time.perf_counter()
        *state, losses, failed = self._run(
            inputs, self.params, self.opt_state, self.dead, self.good
        )
        losses = np.asarray(losses)  # waits for the block
        self.train_seconds += time.perf_counter() - t0
        self.params, self.opt_state, self.dead, self.good = state
        n = min(self.block, self.steps - self.done)
        self.done += n
        return losses[:n], np.asarray(failed)[:n]

    def model(self, i: int, good: bool = False):
        """Member ``i``'s model now (``good``: its last one with a finite loss), in new
        buffers."""
        return eqx.combine(_member(self.good if good else self.params, i), self.static)

    def member_state(self, i: int) -> tuple:
        """Member ``i``'s ``(params, opt_state, good)``, as a single run saves them."""
        return tuple(_member(x, i) for x in (self.params, self.opt_state, self.good))

    def restore(self, done: int, params, opt_state, good) -> None:
        """Go on from a one-member training's state after ``done`` steps (whole blocks),
        ``params``, ``opt_state`` and ``good`` as :meth:`member_state` gives them; the batch
        stream is replayed to there (its ``take`` called once per block already run)."""
        if self.members != 1 or done % self.block:
            raise ValueError("a saved state restores one member, after whole blocks")
        self.params, self.opt_state, self.good = (_stack([x]) for x in (params, opt_state, good))
        if done:
            self._next = None
            for _ in range(done // self.block - 1):  # the first block's batches are drawn
                self._draw()
        self.done = done


def drive(models, datasets, configs, objective=STATES, *, progress=False, resume=None) -> list:
    """Train ``models[m]`` on ``datasets[m]`` with ``configs[m]`` as one :class:`Training`;
    one :class:`TrainResult` per member, never raising on divergence: a member whose loss or
    gradient turns non-finite is recorded there (its last model with a finite loss) while the
    others go on. Snapshots are taken at the end of the block that reaches each of the
    configs' ``checkpoints``; ``progress`` shows a bar over the steps.

    ``resume`` (one member only: a :class:`bench.core._resume.ResumePoint`) keeps the
    training's state there every so often and starts from a state saved there by an
    interrupted training of the same configuration (see :func:`train`)."""
    cpu_start = time.process_time()
    if resume is not None and len(models) != 1:
        raise ValueError("only a training of one member resumes")
    run = Training(models, datasets, configs, objective)
    cfg, m = run.config, run.members
    losses: list[list[np.ndarray]] = [[] for _ in range(m)]
    snapshots: list[list[Snapshot]] = [[] for _ in range(m)]
    diverged: list[int | None] = [None] * m
    pending = list(cfg.checkpoints)
    cpu_before = 0.0
    saved = None if resume is None else resume.load(*run.member_state(0), run.block)
    if saved is not None and saved.done < cfg.steps:
        run.restore(saved.done, saved.params, saved.opt_state, saved.good)
        run.train_seconds, cpu_before = saved.train_seconds, saved.cpu_seconds
        losses[0].append(saved.losses)
        snapshots[0] = [Snapshot(a, b, eqx.combine(p, run.static)) for a, b, p in saved.snapshots]
        pending = [c for c in pending if c > run.done]
    resumed_step = run.done

    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=cfg.steps, initial=run.done, desc="train", unit="step", mininterval=0.5)
    last_log = run.done
    while run.done < cfg.steps and None in diverged:
        start = run.done
        block_losses, failed = run.advance()
        for i in (i for i in range(m) if diverged[i] is None):
            bad = np.flatnonzero(failed[:, i])
            end = int(bad[0]) if bad.size else len(block_losses)
            losses[i].append(block_losses[:end, i])
            if bad.size:
                diverged[i] = start + end
        live = [i for i in range(m) if diverged[i] is None]
        if pending and run.done >= pending[0]:
            for i in live:
                snapshots[i].append(Snapshot(run.done, run.train_seconds / m, run.model(i)))
            while pending and run.done >= pending[0]:
                pending.pop(0)
        if bar is not None:
            bar.update(len(block_losses))
            if live and (run.done - last_log >= cfg.log_every or run.done >= cfg.steps):
                bar.set_postfix(loss=f"{np.median(block_losses[-1, live]):.3e}")
                last_log = run.done
        if resume is not None and live and run.done < cfg.steps and resume.due():
            cpu = cpu_before + time.process_time() - cpu_start
            state = run.member_state(0)
            resume.save(
                run.done, run.block, *state, snapshots[0], losses[0], run.train_seconds, cpu
            )
    if bar is not None:
        bar.close()
    return [
        TrainResult(
            model=run.model(i, good=diverged[i] is not None),
            losses=np.concatenate(losses[i]) if losses[i] else np.zeros(0),
            status="ok" if diverged[i] is None else "diverged",
            diverged_step=diverged[i],
            train_seconds=run.train_seconds / m,
            compile_seconds=run.compile_seconds / m,
            steps_done=run.done if diverged[i] is None else diverged[i],
            flops_per_step=run.flops / m,
            snapshots=tuple(snapshots[i]),
            resumed_step=resumed_step,
            resumed_cpu_seconds=cpu_before,
        )
        for i in range(m)
    ]


def train(
    model,
    dataset,
    config: TrainConfig = TrainConfig(),
    progress: bool = False,
    objective=STATES,
    resume=None,
):
    """Fit ``model`` to ``dataset`` (by default its training chunks of states: ``objective``
    :data:`bench.core._objective.STATES`); never raises on divergence. The one-member
    training of :func:`drive`.

    Returns a :class:`TrainResult`. ``compile_seconds`` is the ahead-of-time compile of the
    training block (0 when this configuration was compiled before in this process, whatever
    its seed and learning rate); ``train_seconds`` is the wall time of the steps alone;
    ``flops_per_step`` comes from the same compiled block (no extra compile).

    ``resume`` (a :class:`bench.core._resume.ResumePoint`) keeps the training's state there
    every so often and starts from a state saved there by an interrupted training of the same
    configuration: the result is the uninterrupted training's, bit for bit, with
    ``resumed_step`` the step it started from and the wall and CPU seconds of both parts.
    """
    return drive([model], [dataset], [config], objective, progress=progress, resume=resume)[0]
