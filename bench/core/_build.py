"""The build step of a state run: its system, dataset (with the true time derivatives for a
derivative target) and untrained model, from the run's configuration alone."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

import systems

from ._config import RunConfig


def model_of(config: RunConfig, scene, *, width=None, depth=None, dtype=None):
    """The untrained model of a run's configuration on ``scene``: ``models.make`` of its model
    with its seed as the key, its width, depth, activation, dtype, dissipation and options
    (``width``, ``depth``, ``dtype``: other values where a caller needs them)."""
    import jax

    import models

    return models.make(
        config.model,
        scene,
        key=jax.random.PRNGKey(config.seed),
        width=config.width if width is None else width,
        depth=config.depth if depth is None else depth,
        activation=config.activation,
        dtype=config.dtype if dtype is None else dtype,
        dissipation=config.dissipation,
        **dict(config.model_options),
    )


def build_run(config: RunConfig, cache_root: Path):
    """``(system, data, scene, model)`` of a state run; the model untrained."""
    import models

    system = systems.make(config.system, **config.system_kwargs())
    dcfg = config.dataset_config()
    scene = models.Scene(
        dof=system.dof,
        angular=tuple(system.angular),
        n_args=system.n_args if config.random_args else 0,
        damped=config.friction > 0,
        canonical=config.coordinates == "momentum",
    )
    model = model_of(config, scene)
    data = systems.make_dataset(dcfg, cache_dir=cache_root)
    if config.train_target == "derivative":
        clean = None
        if dcfg.noise > 0:  # the same trajectories and windows without the observation noise
            clean = systems.make_dataset(dataclasses.replace(dcfg, noise=0.0), cache_root)
        data = WithDerivatives(data, system, canonical=scene.canonical, clean=clean)
    return system, data, scene, model


class WithDerivatives:
    """A dataset plus ``dz_train``: the true dz/dt of its training states, in the run's
    coordinates (:func:`systems.derivatives`; for ``train_target="derivative"``).

    With observation noise (``clean``: the same dataset without it) the seeds' protocol: the
    inputs are the noisy states and the targets the true field at the clean ones (the HNN
    seed's data.py: noise added to q and p after dz/dt is computed), so a model is asked for
    the field at where the system really was, from a noisy reading of it."""

    def __init__(self, data, system, canonical: bool, clean=None):
        self._data = data
        args = np.asarray(data.args_train)
        self.z_train_clean = data.z_train if clean is None else clean.z_train
        self.dz_train = systems.derivatives(
            system, self.z_train_clean, args if args.shape[-1] else None, canonical=canonical
        )

    def __getattr__(self, name):
        return getattr(self._data, name)
