"""A training's settings and outcome: :class:`TrainConfig` (checked when made) and the
settings that trainings run together share (:func:`shared_config`), the :class:`TrainResult`
that the one training loop (:mod:`bench.core._train`) returns, and the :class:`Snapshot` of the
model that it keeps at each checkpoint."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from models import Integrator

from ._optim import OPTIMIZERS, SCHEDULES

LOSSES = ("l2", "l1")
DTYPES = ("float32", "float64")
TARGETS = ("rollout", "derivative")  # what the loss compares (bench.core._objective.loss_fn)


@dataclass(frozen=True)
class TrainConfig:
    """Optimisation settings of one training run (the loss: :func:`bench.core._objective.loss_fn`).

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
    target: str = "rollout"  # "rollout" or "derivative" (bench.core._objective.loss_fn)
    optimizer: str = "adamw"  # "adamw", "adam_l2", "adam_l2_clip" (bench.core._optim)
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
    update) and ``losses`` stop before that step. ``snapshots``: one :class:`Snapshot` per
    ``config.checkpoints`` step reached before any divergence (the last one, at ``steps``,
    holds the final model). ``compile_seconds`` (0 when the program was compiled before in this
    process), ``train_seconds`` (the wall time of the steps alone) and ``flops_per_step``
    (:func:`bench.core._train.step_flops`) are those of the compiled program: a member of an
    ensemble of M gets 1/M of each. A training resumed from a saved state (``train``'s
    ``resume``) started at ``resumed_step`` (0: in one go); ``train_seconds`` counts both
    parts, ``resumed_cpu_seconds`` is the CPU time of the interrupted part until its save.
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


def shared_config(configs) -> TrainConfig:
    """The configuration that trainings of ``configs`` share, so that they run as one program:
    the first with seed 0, lr 1 and log_every 1; ValueError when they differ in more than seed
    and lr (or one is not a :class:`TrainConfig`)."""
    if not configs:
        raise ValueError("a training needs at least one member")
    keys = []
    for c in configs:
        if not isinstance(c, TrainConfig):
            raise ValueError(f"config must be a bench.TrainConfig, got {type(c).__name__}")
        keys.append(dataclasses.replace(c, seed=0, lr=1.0, log_every=1))
    for k in keys[1:]:
        if k != keys[0]:
            raise ValueError("ensemble members may differ only in seed and lr (TrainConfig)")
    return keys[0]
