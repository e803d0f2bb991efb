"""Our side of claim 7's side-by-side (:mod:`bench.sidebyside.lnn_relativistic`): the
``relativistic_seed`` paper-core models from the notebook's parameters, and our trainer's step
on the notebook's batches, with our loss or the notebook's."""

from __future__ import annotations

import dataclasses

import numpy as np

from . import _relativistic_seed as R
from ._seed import seed_to_ours

CELLS = {"lnn": ("lnn", "velocity"), "hnn_naive": ("hnn", "velocity"), "hnn_p": ("hnn", "momentum")}
PROFILE = "paper-core"


def paper_core_config(model: str, seed: int):
    """The ``relativistic_seed`` RunConfig of ``model`` at paper-core, for ``seed``."""
    import bench

    name, coords = CELLS[model]
    (c,) = [
        x
        for x in bench.expand("relativistic_seed", PROFILE, seeds=[seed])
        if (x.model, x.coordinates) == (name, coords)
    ]
    return c


def net_of(model):
    """The one MLP of our model (the HNN's H, the LNN's L)."""
    return model.net if hasattr(model, "net") else model.hamiltonian_part.net


def our_model(config, params, dtype: str):
    """Our untrained model of ``config`` in ``dtype`` (``bench.core.model_of``, as a run makes
    it), with the notebook's stax ``params`` as its MLP's."""
    import equinox as eqx

    import models
    from bench.core import model_of

    scene = models.Scene(
        dof=1, angular=(False,), n_args=1, canonical=config.coordinates == "momentum"
    )
    model = model_of(config, scene, dtype=dtype)
    return eqx.tree_at(net_of, model, seed_to_ours(params, net_of(model)))


@dataclasses.dataclass(frozen=True)
class SeedBatches:
    """The objective of our trainer's step on a notebook batch (B, 5) = (z, args, dz) in our
    model's coordinates: ``bench.core.loss_fn`` with the derivative target."""

    def data(self, model, dataset, config):
        import jax.numpy as jnp

        return jnp.zeros((0,), jnp.dtype(config.dtype))

    def loss(self, model, data, ix, config):
        import jax.numpy as jnp

        from bench.core import loss_fn

        z, args, dz = ix[:, None, :2], ix[:, 2:3], ix[:, None, 3:]
        return loss_fn(model, z, args, jnp.zeros((1,), ix.dtype), config, dz)


@dataclasses.dataclass(frozen=True)
class WeightedSeedBatches(SeedBatches):
    """The notebook's loss on our trainer's batch (the ``ours_weighted`` curve): our model's
    field and the true one in the notebook's form (:func:`seed_form`), L1 weighted by
    1 + 1 / sqrt(1 - qdot^2); qdot is the target's first component in every model's
    coordinates."""

    kind: str = "hnn_p"

    def loss(self, model, data, ix, config):
        import jax
        import jax.numpy as jnp

        z, a, dz = ix[:, :2], ix[:, 2:3], ix[:, 3:]
        v = dz[:, :1]
        field = jax.vmap(lambda zz, aa: model.vector_field(0.0, zz, aa))(z, a)
        pred, target = (R.seed_form(self.kind, f, v, jnp) for f in (field, dz))
        return R.weighted_l1(pred, target, v, jnp)


def ours_batch(model: str, batch, dtype):
    """The notebook's (states, g, targets) as our trainer's (B, 5) array."""
    return np.concatenate(R.to_ours(model, *batch), 1).astype(dtype)


class Ours:
    """Our trainer's step on ``model`` with the training configuration ``tcfg``."""

    def __init__(self, kind, model, tcfg, objective=None):
        import equinox as eqx
        import jax
        import jax.numpy as jnp

        from bench.core import make_step, optimizer

        self.kind, self.tcfg = kind, tcfg
        self.objective = SeedBatches() if objective is None else objective
        params, self.static = eqx.partition(model, eqx.is_inexact_array)
        self.state = (params, optimizer(tcfg).init(params), jnp.asarray(False), params)
        step = make_step(
            self.static, tcfg, self.objective.data(model, None, tcfg), objective=self.objective
        )
        on = lambda idx: jnp.ones(idx.shape[0], bool)
        self._run = jax.jit(lambda state, idx: jax.lax.scan(step, state, (idx, on(idx))))
        field = lambda p, z, a: eqx.combine(p, self.static).vector_field(0.0, z, a)
        self._field = jax.jit(jax.vmap(field, (None, 0, 0)))

    @property
    def model(self):
        import equinox as eqx

        return eqx.combine(self.state[0], self.static)

    def train(self, batches):
        block = np.stack([ours_batch(self.kind, b, self.tcfg.dtype) for b in batches])
        self.state, (losses, failed) = self._run(self.state, block)
        return np.asarray(losses, float), bool(np.asarray(failed).any())

    def predict(self, state, g):
        """The field at the notebook's (q, qdot), g, as its loss compares it."""
        z, a, _ = R.to_ours(self.kind, state, g, np.zeros((len(g), 1)))
        f = np.asarray(
            self._field(self.state[0], z.astype(self.tcfg.dtype), a.astype(self.tcfg.dtype))
        )
        return R.seed_form(self.kind, f, np.asarray(state, float)[:, 1:])


class OursSeedAdam(Ours):
    """Our model on the notebook's loss (:class:`WeightedSeedBatches`), stepped by the notebook's
    own optimiser (the ``ours_seed_adam`` curve): its ``opt_update`` of
    ``jax.example_libraries.optimizers`` (Adam on its one-cycle rate), given the run's fraction
    done as its step count, as ``update_derivative`` gives it. With the model and the loss
    already shown equal, what this curve leaves between ours and the seed's is the optimiser."""

    def __init__(self, kind, model, tcfg, nb):
        import equinox as eqx
        import jax

        super().__init__(kind, model, tcfg, WeightedSeedBatches(kind))
        self.nb, self.done = nb, 0
        self.opt_state = nb.opt_init(self.state[0])
        objective = self.objective

        def step(opt_state, fraction, ix):
            params = nb.get_params(opt_state)
            loss_of = lambda p: objective.loss(eqx.combine(p, self.static), None, ix, tcfg)
            loss, grads = jax.value_and_grad(loss_of)(params)
            return nb.opt_update(fraction, grads, opt_state), loss

        self._step = jax.jit(step)

    def train(self, batches):
        losses = []
        for b in batches:
            ix = ours_batch(self.kind, b, self.tcfg.dtype)
            self.opt_state, loss = self._step(self.opt_state, self.done / self.nb.steps, ix)
            losses.append(float(loss))
            self.done += 1
        self.state = (self.nb.get_params(self.opt_state), *self.state[1:])
        return np.asarray(losses), not np.all(np.isfinite(losses))
