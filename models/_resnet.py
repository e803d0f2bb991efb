"""The discrete free baseline: a residual map z_{n+1} = z_n + MLP(z_n) (the VIN seed's)."""

from __future__ import annotations

from typing import ClassVar

import equinox as eqx

from ._base import AbstractDiscreteModel, as_dtype, split
from ._features import Features
from ._mlp import MLP
from ._scene import Scene


class ResNet(AbstractDiscreteModel):
    """z_{n+1} = z_n + MLP(cos q_n, sin q_n, qdot_n, args[, u]): the VIN seed's baseline.

    The step is tied to the time step it was trained at (dt is not an input).
    """

    takes_controls: ClassVar[bool] = True
    scene: Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    features: Features
    net: MLP

    def __init__(self, scene, width, depth, activation, dtype, *, key):
        self.scene, self.dtype = scene, dtype
        self.features = Features(scene)
        self.net = MLP(
            self.features.size(True), 2 * scene.dof, width, depth, activation, dtype, key=key
        )

    def step(self, z, dt, args):
        z = as_dtype(z, self.dtype)
        q, v = split(z)
        return z + self.net(self.features(q, v, as_dtype(args, self.dtype)))
