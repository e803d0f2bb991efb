"""A template plug-in model for decon-bench (``drag_so``).

``DragSecondOrderODE`` is a second-order field with a bias of its own: the acceleration is a
force that depends on the configuration only, plus a learned linear drag,

    dq/dt = qdot,    dqdot/dt = f(q, args) - softplus(c) * qdot,

f an MLP on (cos q, sin q) for angles (q otherwise) and c one learned number per coordinate
(started at softplus(-4) = 0.018). It satisfies the suite's model contract: it subclasses
``models.AbstractContinuousModel``, implements ``vector_field`` (and ``acceleration``, so that
leapfrog can integrate it), declares ``structure = None`` and ``second_order = True``, and is
built by ``DragSecondOrderODE(scene, width, depth, activation, dtype, key=...)``.

Importing this module registers it; the package's entry point (group ``decon_bench.models``)
makes the suite import it. Without installing: ``python -m bench --model-module
decon_bench_example_model ...`` with this folder on ``PYTHONPATH``.
"""

from __future__ import annotations

from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp

import models

_ACTIVATIONS = {"tanh": jnp.tanh, "softplus": jax.nn.softplus, "relu": jax.nn.relu}


class DragSecondOrderODE(models.AbstractContinuousModel):
    """dqdot/dt = f(q, args) - softplus(c) * qdot (module docstring)."""

    structure: ClassVar[str | None] = None
    second_order: ClassVar[bool] = True
    scene: models.Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    force: eqx.nn.MLP
    drag: jax.Array

    def __init__(self, scene, width, depth, activation, dtype, *, key):
        self.scene, self.dtype = scene, dtype
        n_in = sum(2 if a else 1 for a in scene.angular) + scene.n_args
        self.force = eqx.nn.MLP(
            n_in,
            scene.dof,
            width,
            depth,
            activation=_ACTIVATIONS.get(activation, jnp.tanh),
            key=key,
            dtype=jnp.dtype(dtype),
        )
        self.drag = jnp.full((scene.dof,), -4.0, jnp.dtype(dtype))

    def _features(self, q, args):
        parts = [
            jnp.stack([jnp.cos(q[i]), jnp.sin(q[i])]) if a else q[i : i + 1]
            for i, a in enumerate(self.scene.angular)
        ]
        args = jnp.zeros((0,), q.dtype) if args is None else jnp.atleast_1d(args)
        return jnp.concatenate([*parts, args[: self.scene.n_args].astype(q.dtype)])

    def acceleration(self, q, v, args):
        q, v = jnp.asarray(q, self.dtype), jnp.asarray(v, self.dtype)
        return self.force(self._features(q, args)) - jax.nn.softplus(self.drag) * v

    def vector_field(self, t, z, args):
        z = jnp.asarray(z, self.dtype)
        d = self.scene.dof
        return jnp.concatenate([z[d:], self.acceleration(z[:d], z[d:], args)])


models.register("drag_so", DragSecondOrderODE, coordinates="velocity")
