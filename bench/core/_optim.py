"""The optimisation of a training run: the update rule (:func:`optimizer`: the suite's AdamW with
clipping, or the papers' Adam with an L2 term, with or without clipping) and its learning-rate
schedule (:func:`lr_schedule`), both read off a training configuration ``config`` (any object with
the fields of :class:`~bench.core._train_config.TrainConfig` they name: steps, lr, lr_floor,
schedule, optimizer, weight_decay, clip).
"""

from __future__ import annotations

import jax.numpy as jnp
import optax

from ._vocab import OPTIMIZERS  # noqa: F401 (the names :func:`optimizer` takes)

SCHEDULES = ("cosine", "onecycle", "constant")  # :func:`lr_schedule`
ONECYCLE_START, ONECYCLE_DIV = 0.2, 1e4  # the LNN seed notebook's OneCycleLR


def lr_schedule(config, lr=None):
    """The learning rate at step s of N = ``config.steps``, from ``lr`` (default ``config.lr``):

    - ``"cosine"``: lr (1 - (1 - a) (1 - cos(pi s / N)) / 2), a = ``config.lr_floor``;
    - ``"onecycle"``: the LNN seed notebook's OneCycleLR, lr / 1e4 + (lr - lr / 1e4)
      (1 - cos(2 pi u)) / 2 with u = 0.2 + 0.8 s / N: from 0.35 lr up to lr at s = 0.375 N and
      down to lr / 1e4;
    - ``"constant"``: lr.
    """
    lr = config.lr if lr is None else lr
    if config.schedule == "constant":
        return lambda step: lr * jnp.ones_like(step, dtype=jnp.result_type(float))
    if config.schedule == "onecycle":
        low, n = lr / ONECYCLE_DIV, config.steps

        def onecycle(step):
            u = ONECYCLE_START + (1.0 - ONECYCLE_START) * step / n
            return low + (lr - low) * (1.0 - jnp.cos(2.0 * jnp.pi * u)) / 2.0

        return onecycle
    return optax.cosine_decay_schedule(lr, config.steps, alpha=config.lr_floor)


def optimizer(config, lr=None) -> optax.GradientTransformation:
    """The update rule, with the learning rate of :func:`lr_schedule`:

    - ``"adamw"`` (the suite's): clip_by_global_norm(clip) -> AdamW(weight_decay, decoupled);
    - ``"adam_l2"`` (the seeds': PyTorch's ``Adam(weight_decay=w)``, and the LNN notebook's
      L2 term): Adam on g + w theta, no clipping;
    - ``"adam_l2_clip"`` (the Deconstructing paper's MuJoCo training, ``mujoco.py``'s
      ``clip_grad_norm_(1)`` then ``Adam(weight_decay=w)``): Adam on clip(g) + w theta, the
      gradient clipped to norm ``clip`` before the L2 term joins it.

    ``lr`` overrides ``config.lr`` (a traced scalar in an ensemble).
    """
    schedule = lr_schedule(config, lr)
    if config.optimizer in ("adam_l2", "adam_l2_clip"):
        l2 = (optax.add_decayed_weights(config.weight_decay), optax.adam(schedule))
        if config.optimizer == "adam_l2":
            return optax.chain(*l2)
        return optax.chain(optax.clip_by_global_norm(config.clip), *l2)
    return optax.chain(
        optax.clip_by_global_norm(config.clip),
        optax.adamw(schedule, weight_decay=config.weight_decay),
    )
