"""The train step of a state run: its :class:`bench.TrainConfig`, and training through the
parameter cache (:mod:`bench.core._params`) with the one training loop (:func:`bench.train`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._config import RunConfig
from ._params import cached_training

TRAIN_BLOCK = 100  # training steps per compiled block; checkpoints fall on block ends

# The meta of a model without parameters (a trivial predictor): nothing trained, nothing cached.
UNTRAINED = {
    "status": "ok",
    "diverged_step": None,
    "train_seconds": 0.0,
    "compile_seconds": 0.0,
    "steps_done": 0,
    "final_loss": None,
    "loss_rise": None,
    "flops_per_step": 0.0,
    "train_cached": False,
}


def checkpoint_steps(steps: int, n: int, block: int = 100) -> tuple[int, ...]:
    """``n`` checkpoints on the halving grid ``steps * 2**-(n-1), ..., steps / 2, steps``, each
    rounded to the nearest multiple of ``block`` (at least one block; the last is ``steps``),
    duplicates dropped: ``checkpoint_steps(8000, 4) == (1000, 2000, 4000, 8000)``,
    ``checkpoint_steps(1000, 4) == (100, 300, 500, 1000)``. ``n = 0`` gives ``()``."""
    if isinstance(n, bool) or not isinstance(n, int) or n < 0:
        raise ValueError(f"the number of checkpoints must be an integer >= 0, got {n!r}")
    block = max(1, min(block, steps))
    out = []
    for i in range(n):
        target = steps * 2.0 ** (i - n + 1)
        snapped = min(steps, max(block, int(np.floor(target / block + 0.5)) * block))
        out.append(steps if i == n - 1 else snapped)
    return tuple(sorted(set(out)))


def train_config(config: RunConfig, *, block: int | None = None, weight_decay=None):
    """The :class:`bench.TrainConfig` of a run: its optimiser, schedule, loss, target and
    checkpoints, ``block`` (default :data:`TRAIN_BLOCK`) steps per compiled block.
    ``weight_decay``: the observation's default, taken where the run sets none (None: the
    TrainConfig's, 1e-4)."""
    import models

    from ._train_config import TrainConfig

    decay = config.weight_decay if config.weight_decay is not None else weight_decay
    block = TRAIN_BLOCK if block is None else block
    return TrainConfig(
        steps=config.steps,
        batch=config.batch,
        lr=config.lr,
        loss=config.loss,
        integrator=models.Integrator(config.train_integrator, substeps=config.train_substeps),
        dtype=config.dtype,
        seed=config.seed,
        steps_per_call=block,
        checkpoints=checkpoint_steps(config.steps, config.eval_checkpoints, block),
        target=config.train_target,
        optimizer=config.optimizer,
        schedule=config.lr_schedule,
        **({} if decay is None else {"weight_decay": decay}),
    )


def objective(config: RunConfig):
    """What a state run fits: its dataset's chunks, or fresh states from its ``train_box``."""
    from ._box import BoxObjective
    from ._objective import STATES

    if not config.train_box:
        return STATES
    return BoxObjective(
        config.system, tuple(sorted(config.system_kwargs().items())), config.train_box
    )


def train_cached(config: RunConfig, model, data, cache_root: Path, progress):
    """``(model, meta)``: ``model`` trained on ``data``, or its parameters loaded from the
    cache (:func:`bench.core._params.cached_training`)."""
    import models

    from ._train import train

    if isinstance(model, models.AbstractTrivialModel):  # no parameters: nothing to train
        return model, dict(UNTRAINED)
    tcfg = train_config(config)
    return cached_training(
        config,
        model,
        cache_root,
        lambda resume: train(
            model, data, tcfg, progress=progress, objective=objective(config), resume=resume
        ),
        checkpoints=tcfg.checkpoints,
    )
