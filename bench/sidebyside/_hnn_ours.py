"""Our side of ``python -m bench.sidebyside.hnn_seed``: the claim's run configuration, its
dataset and batches, our model, its loss terms and gradient on given windows, our training step
and the claim's test metric."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._hnn_map import ours_to_seed

TERMS = ("ae0", "ae1", "cc", "dyn")
EXPERIMENT, PROFILE = "pixel_pendulum_hnn_seed", "paper-core"


def seed_total(t: dict) -> float:
    """The seed's loss from its terms: ae0 + cc + 0.1 dyn."""
    return t["ae0"] + t["cc"] + 0.1 * t["dyn"]


def run_config(model: str, seed: int):
    import bench

    (c,) = [x for x in bench.expand(EXPERIMENT, PROFILE, seeds=[seed]) if x.model == model]
    return c


_FIELDS = ("frames_train", "z_train", "frames_test", "z_test", "ts_test")


def dataset(c, cache: Path):
    """The run's ``systems.PixelDataset`` (rendered once, then read from ``cache``)."""
    import systems

    cfg = c.pixel_dataset_config()
    if cache.is_file():
        z = np.load(cache)
        if str(z["config"]) == repr(cfg):
            return systems.PixelDataset(cfg, *(z[k] for k in _FIELDS))
    data = systems.make_pixel_dataset(cfg)
    np.savez(cache, config=repr(cfg), **{k: getattr(data, k) for k in _FIELDS})
    return data


def our_model(c, system, dtype: str | None = None):
    """The run's untrained ``LatentModel`` (as ``bench.core._pixels.build`` makes it)."""
    import jax

    import models
    from bench.core import PIXEL_SIZE

    return models.LatentModel(
        c.model,
        (2, PIXEL_SIZE, PIXEL_SIZE),
        key=jax.random.PRNGKey(c.seed),
        latent_dof=system.dof,
        width=c.width,
        depth=c.depth,
        ae_width=c.width,
        activation=c.activation,
        dtype=dtype or c.dtype,
        options=dict(c.model_options),
    )


def batch_stream(objective, frames, tcfg, steps: int) -> np.ndarray:
    """(steps, B, 2): the run's batches in its order (drawn in its blocks of
    ``steps_per_call``)."""
    stream = objective.batches(frames, tcfg)
    k = min(tcfg.steps_per_call, tcfg.steps)
    blocks = [stream.take(k) for _ in range(-(-steps // k))]
    return np.concatenate(blocks)[:steps] if blocks else np.zeros((0, tcfg.batch, 2), int)


def all_windows(frames: np.ndarray, chunk: int) -> np.ndarray:
    """Every (trajectory, start) of a window of ``chunk`` frames of ``frames`` (N, T, ...)."""
    n, t = frames.shape[:2]
    a, b = np.meshgrid(np.arange(n), np.arange(t - chunk + 1), indexing="ij")
    return np.stack([a.ravel(), b.ravel()], axis=-1)


def gather(frames: np.ndarray, idx: np.ndarray, chunk: int) -> np.ndarray:
    """Windows (M, chunk, S, S) of ``frames`` at ``idx`` (M, 2)."""
    return frames[idx[:, :1], idx[:, 1:] + np.arange(chunk)]


def _terms_fn():
    import equinox as eqx
    import jax
    import jax.numpy as jnp

    from bench.core import seed_loss

    @eqx.filter_jit
    def terms(model, windows, integ):
        loss, (ae, cc, dyn) = seed_loss(model, windows, integ)
        obs0 = jnp.stack([windows[:, 0], windows[:, 1]], axis=1)
        rec = jax.vmap(lambda x: model.decode(model.encode(x)))(obs0)
        ae0 = jnp.mean((rec - obs0) ** 2)
        return loss, ae0, 2.0 * ae - ae0, cc, dyn

    return terms


_TERMS = []


def our_terms(model, windows, integ) -> dict:
    """ae0, ae1, cc, dyn (and ``loss``, ours) of ``model`` on ``windows`` (M, 3, S, S)."""
    import jax.numpy as jnp

    if not _TERMS:
        _TERMS.append(_terms_fn())
    w = jnp.asarray(windows, model.autoencoder.dtype)
    loss, *t = _TERMS[0](model, w, integ)
    return {"loss": float(loss), **{k: float(v) for k, v in zip(TERMS, t, strict=True)}}


def our_grad(model, windows, integ):
    """The gradient of our loss on ``windows``, in the seed's layout (and ours-only arrays)."""
    import equinox as eqx
    import jax.numpy as jnp

    from bench.core import seed_loss

    w = jnp.asarray(windows, model.autoencoder.dtype)
    g = eqx.filter_grad(lambda m: seed_loss(m, w, integ)[0])(model)
    return ours_to_seed(g)


class Ours:
    """Our training step (``bench.core._train.make_step`` with ``PixelObjective``, the
    campaign's) on ``model`` with the run's training configuration ``tcfg``."""

    def __init__(self, model, tcfg, frames, chunk: int):
        import equinox as eqx
        import jax
        import jax.numpy as jnp

        from bench.core import PixelObjective, make_step, optimizer

        self.objective = PixelObjective(chunk=chunk)
        params, self.static = eqx.partition(model, eqx.is_inexact_array)
        data = jnp.asarray(frames, jnp.dtype(tcfg.dtype))
        self.state = (params, optimizer(tcfg).init(params), jnp.asarray(False), params)
        step = make_step(self.static, tcfg, data, objective=self.objective)

        @jax.jit
        def run(state, idx):
            return jax.lax.scan(step, state, (idx, jnp.ones(idx.shape[0], bool)))

        self._run = run

    @property
    def model(self):
        import equinox as eqx

        return eqx.combine(self.state[0], self.static)

    def train(self, block) -> tuple[np.ndarray, bool]:
        import jax.numpy as jnp

        self.state, (losses, failed) = self._run(self.state, jnp.asarray(block))
        return np.asarray(losses, float), bool(np.asarray(failed).any())


def claim_metric(c, system, data, model) -> dict:
    """The claim's test metrics (``evaluate_pixels`` of the committed rows)."""
    from bench.core import evaluate_pixels

    m, _ = evaluate_pixels(c, system, data, model)
    keys = ("pixel_mse", "pixel_mse_static", "recon_mse", "seed_energy_mse")
    return {k: float(m[k]) for k in keys}
