"""What a training fits by default: a dataset's chunks of states (:class:`StateObjective`,
:data:`STATES`), through the model's rollout or, with ``target="derivative"``, against the true
time derivatives (the loss: :func:`loss_fn`), in batches of chunks (:class:`Batches`) of the
device arrays that :func:`prepare` makes. An objective is any hashable value with the three
methods of :class:`StateObjective`; observations of another kind bring their own (pixels:
``bench.core._pixels.PixelObjective``) to the one training loop (:mod:`bench.core._train`).
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from models import rollout_batch

from ._train_config import TrainConfig


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
    """What :func:`bench.train` fits by default: :func:`loss_fn` on a batch of a dataset's
    chunks of states. An objective is a hashable value (it keys the compiled block) with three
    methods: ``data(model, dataset, config)`` the training set as device arrays (a pytree of
    them: the members of an ensemble stack theirs), ``batches(data, config)`` an object whose
    ``take(k)`` gives an array of the batches of k steps (batch indices, or the batches
    themselves), and ``loss(model, data, ix, config)`` the scalar loss of one batch, ``config``
    there being the members' shared one (seed 0, lr 1:
    :func:`bench.core._train_config.shared_config`)."""

    def data(self, model, dataset, config: TrainConfig):
        return prepare(model, dataset, config)

    def batches(self, data, config: TrainConfig) -> Batches:
        return Batches(data[0].shape[0], config.batch, config.seed)

    def loss(self, model, data, ix, config: TrainConfig):
        z_all, args_all, ts, *targets = data  # targets: (dz_all,) with target="derivative"
        dz = targets[0][ix] if targets else None
        return loss_fn(model, z_all[ix], args_all[ix], ts, config, dz)


STATES = StateObjective()


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
