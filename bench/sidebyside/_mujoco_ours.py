"""Our side of :mod:`bench.sidebyside.decon_mujoco`: a controlled run's training step on a
model (the one loop's ``make_step`` with the run's ``ControlledObjective``), its loss and first
gradient on one batch, its test rollouts (the run's evaluation integrator) and the normalised
MSE."""

from __future__ import annotations

import numpy as np

from ._decon_ours import CompiledBlocks


class Ours(CompiledBlocks):
    """The campaign's training step on ``model``: blocks of steps compiled once per block
    length, timed without their compilation; ``predict`` is the run's test rollout."""

    def __init__(self, model, config, tcfg, windows, opt=None):
        import equinox as eqx
        import jax
        import jax.numpy as jnp

        from bench.core import CONTROLLED, controlled_predictor, make_step, optimizer

        self.data = CONTROLLED.data(model, windows, tcfg)
        params, self.static = eqx.partition(model, eqx.is_inexact_array)
        opt_state = (optimizer(tcfg) if opt is None else opt).init(params)
        self.state = (params, opt_state, jnp.asarray(False), params)
        if opt is None:
            step = make_step(self.static, tcfg, self.data, objective=CONTROLLED)
        else:
            step = plain_step(self.static, tcfg, self.data, opt)
        self._run = jax.jit(
            lambda state, idx: jax.lax.scan(step, state, (idx, jnp.ones(idx.shape[0], bool)))
        )
        self._compiled: dict = {}
        self._predict = controlled_predictor(config, model)
        self.dtype = jnp.dtype(tcfg.dtype)
        self.seconds, self.steps = 0.0, 0

    def model(self):
        import equinox as eqx

        return eqx.combine(self.state[0], self.static)

    def predict(self, z, u, dt: float) -> np.ndarray:
        return predict(self.model(), self._predict, z, u, dt, self.dtype)


def paper_optimizer(tcfg, steps_per_epoch: int, epochs: int, eta_min: float = 1e-6):
    """The paper's ``fit_net`` update in optax: ``clip_grad_norm_(1)``, then PyTorch's
    ``Adam(lr, weight_decay)`` (the decay an L2 term added to the clipped gradient), its rate
    ``CosineAnnealingLR(T_max = epochs, eta_min)`` stepped once per epoch."""
    import optax

    return optax.chain(
        optax.clip_by_global_norm(tcfg.clip),
        optax.add_decayed_weights(tcfg.weight_decay),
        optax.adam(epoch_cosine(tcfg.lr, steps_per_epoch, epochs, eta_min)),
    )


def epoch_cosine(lr: float, steps_per_epoch: int, epochs: int, eta_min: float = 1e-6):
    """``CosineAnnealingLR``'s rate at step s, stepped once per epoch: eta_min + (lr - eta_min)
    (1 + cos(pi e / epochs)) / 2 with e = s // steps_per_epoch."""
    import jax.numpy as jnp

    def schedule(count):
        epoch = jnp.floor_divide(count, steps_per_epoch)
        return eta_min + (lr - eta_min) * (1.0 + jnp.cos(jnp.pi * epoch / epochs)) / 2.0

    return schedule


def plain_step(static, tcfg, data, opt):
    """``make_step``'s signature with another update rule ``opt`` (no divergence guard)."""
    import equinox as eqx
    import jax.numpy as jnp

    from bench.core import CONTROLLED

    def step(carry, xs):
        params, opt_state, dead, good = carry
        loss, grads = eqx.filter_value_and_grad(CONTROLLED.loss)(
            eqx.combine(params, static), data, xs[0], tcfg
        )
        updates, opt_state = opt.update(eqx.filter(grads, eqx.is_inexact_array), opt_state, params)
        params = eqx.apply_updates(params, updates)
        return (params, opt_state, dead, good), (loss, jnp.asarray(False))

    return step


def predict(model, predictor, z, u, dt: float, dtype) -> np.ndarray:
    """The rollout of test windows z (N, T, 2d) from z[:, 0] under their controls u[:, :-1]
    (as ``bench.core._controlled.evaluate``)."""
    import jax.numpy as jnp

    ts = jnp.asarray(np.arange(z.shape[1]) * dt, dtype)
    out = predictor(model, jnp.asarray(z[:, 0], dtype), ts, jnp.asarray(u[:, :-1], dtype))
    return np.asarray(out, np.float64)


def loss_and_grad(model, windows, ix, tcfg):
    """The run's training loss (``ControlledObjective.loss``) on the windows ``ix`` and its
    gradient, in ``tcfg.dtype``."""
    import equinox as eqx
    import jax.numpy as jnp

    from bench.core import CONTROLLED

    data = CONTROLLED.data(model, windows, tcfg)
    loss, g = eqx.filter_value_and_grad(lambda m: CONTROLLED.loss(m, data, jnp.asarray(ix), tcfg))(
        model
    )
    return float(loss), g


def normalised_mse(pred, z, scale) -> float:
    """The paper's ``test_mse`` of one batch: mean over windows, times (t = 0 included) and
    components of ((pred - z) / z_std)^2; NaN if a prediction is not finite."""
    from bench.core import controlled_mse as nmse

    return nmse(np.asarray(pred, float), np.asarray(z, float), np.asarray(scale, float))
