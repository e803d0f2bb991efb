"""Training on fresh states drawn uniformly from a box (``RunConfig.train_box``): the LNN seed
notebook's protocol, whose data are "instantaneous accelerations" at random states, new ones
every epoch, rather than states along simulated trajectories.

Every batch draws its states independently: q uniform in [q_low, q_high) and qdot uniform in
[qdot_low, qdot_high) for every coordinate, with the true vector field (qdot, qddot) of the run's
system at them in float64 as the targets. The notebook draws 2000 batches at a time per epoch;
independent draws per batch have the same distribution.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


class BoxStates:
    """``take(k)`` -> (k, batch, 2, 2d): per step a batch of states (``[..., 0, :]``) and the
    true dz/dt at them (``[..., 1, :]``), in ``dtype``, from a generator seeded by ``seed``."""

    def __init__(self, system, box: tuple, batch: int, seed: int, dtype: str):
        import jax
        import jax.numpy as jnp

        import systems

        systems.require_x64("training on a train_box (its targets)")
        self.d = system.dof
        self.low = np.array([box[0]] * self.d + [box[2]] * self.d)
        self.high = np.array([box[1]] * self.d + [box[3]] * self.d)
        self.batch, self.dtype = batch, np.dtype(dtype)
        self.rng = np.random.default_rng(seed)
        self._field = jax.jit(jax.vmap(lambda z: system.vector_field(0.0, z, None)))
        self._jnp = jnp

    def take(self, k: int) -> np.ndarray:
        z = self.rng.uniform(self.low, self.high, size=(k * self.batch, 2 * self.d))
        dz = np.asarray(self._field(self._jnp.asarray(z, dtype=self._jnp.float64)))
        out = np.stack([z, dz], axis=1).reshape(k, self.batch, 2, 2 * self.d)
        return out.astype(self.dtype)


@dataclass(frozen=True)
class BoxObjective:
    """The objective (``bench.train``'s ``objective``) of a run with a ``train_box``: the
    derivative loss (:func:`bench.core._objective.loss_fn`, ``target="derivative"``) on batches of
    :class:`BoxStates` of the system ``system`` with ``system_params``."""

    system: str
    system_params: tuple
    box: tuple

    def data(self, model, dataset, config):
        import jax.numpy as jnp

        return jnp.zeros((0,), jnp.dtype(config.dtype))  # every batch brings its own states

    def batches(self, data, config) -> BoxStates:
        import systems

        system = systems.make(self.system, **dict(self.system_params))
        return BoxStates(system, self.box, config.batch, config.seed, config.dtype)

    def loss(self, model, data, ix, config):
        import jax.numpy as jnp

        from ._objective import loss_fn

        z, dz = ix[:, None, 0], ix[:, None, 1]  # (B, 1, 2d): one state per "chunk"
        args = jnp.zeros((z.shape[0], 0), z.dtype)
        ts = jnp.zeros((1,), z.dtype)
        return loss_fn(model, z, args, ts, config, dz)
