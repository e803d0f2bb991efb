"""The neural-ODE family: a free learned field (node, node_symreg), the second-order field
(node_so), and NODE+SO in canonical (q, p) with a learned inverse mass (node_so_symreg).
"""

from __future__ import annotations

from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import jax.random as jr

from ._base import AbstractContinuousModel, as_dtype, split
from ._features import Features
from ._hamiltonian import INVERSE_MASS_JITTER
from ._mass import CholeskyNet
from ._mlp import MLP
from ._scene import Scene
from ._symplectic import symplectic_error


class NeuralODE(AbstractContinuousModel):
    """dz/dt = MLP(cos q, sin q, qdot, args[, u]) (with the scene's standardisation: its
    rate statistics' loc + scale * MLP(...)); with ``weight`` > 0 (node_symreg) the loss gets
    the soft symplectic penalty weight * mean ||J DF - (J DF)^T||_F^2 over the rollout states."""

    takes_controls: ClassVar[bool] = True
    scene: Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    weight: float = eqx.field(static=True)
    features: Features
    net: MLP

    def __init__(
        self, scene, width, depth, activation, dtype, *, key, weight=0.0, init="orthogonal"
    ):
        self.scene, self.dtype, self.weight = scene, dtype, float(weight)
        self.features = Features(scene)
        self.net = MLP(
            self.features.size(True),
            2 * scene.dof,
            width,
            depth,
            activation,
            dtype,
            key=key,
            init=init,
        )

    def vector_field(self, t, z, args):
        q, v = split(as_dtype(z, self.dtype))
        y = self.net(self.features(q, v, as_dtype(args, self.dtype)))
        st = self.scene.standardisation
        return y if st is None else st.rate(y, self.dtype)

    def penalty(self, zs, args):
        if self.weight == 0.0:
            return jnp.zeros((), self.dtype)
        return self.weight * symplectic_error(self, zs, args)


class SecondOrderODE(AbstractContinuousModel):
    """dq/dt = qdot (exactly), dqdot/dt = a(q, qdot, u) = MLP(cos q, sin q, qdot, args[, u])
    (with the scene's standardisation: the dv/dt statistics' loc + scale * MLP(...)).

    The paper's controlled NODE+SO (CoupledNODE) is this field integrated with ``euler_so``."""

    second_order: ClassVar[bool] = True
    takes_controls: ClassVar[bool] = True
    scene: Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    features: Features
    net: MLP

    def __init__(self, scene, width, depth, activation, dtype, *, key):
        self.scene, self.dtype = scene, dtype
        self.features = Features(scene)
        self.net = MLP(
            self.features.size(True), scene.dof, width, depth, activation, dtype, key=key
        )

    def acceleration(self, q, v, args):
        q, v, args = (as_dtype(x, self.dtype) for x in (q, v, args))
        a = self.net(self.features(q, v, args))
        st = self.scene.standardisation
        return a if st is None else st.rate(a, self.dtype, slice(self.scene.dof, None))

    def vector_field(self, t, z, args):
        q, v = split(as_dtype(z, self.dtype))
        return jnp.concatenate([v, self.acceleration(q, v, args)])


class CanonicalSecondOrderODE(AbstractContinuousModel):
    """NODE+SO in canonical coordinates, the reference's symplectic-regularised model.

    On z = (q, p): dq/dt = M^-1(q) p (M^-1 = L L^T + 1e-4 I, the learned inverse mass of
    ``hnn_so``, which never sees u), dp/dt = MLP(cos q, sin q, p, args[, u]). With ``weight``
    > 0 the loss gets the soft symplectic penalty weight * mean ||J DF - (J DF)^T||_F^2 (as
    ``node_symreg``), which is zero for the true dynamics in these coordinates. Needs momentum
    data (Scene.canonical).
    """

    takes_controls: ClassVar[bool] = True
    scene: Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    weight: float = eqx.field(static=True)
    features: Features
    inverse_mass: CholeskyNet
    net: MLP

    def __init__(self, scene, width, depth, activation, dtype, *, key, weight=1.0):
        self.scene, self.dtype, self.weight = scene, dtype, float(weight)
        km, kn = jr.split(key)
        self.features = Features(scene)
        self.inverse_mass = CholeskyNet(
            self.features, width, depth, activation, dtype, key=km, jitter=INVERSE_MASS_JITTER
        )
        self.net = MLP(self.features.size(True), scene.dof, width, depth, activation, dtype, key=kn)

    def vector_field(self, t, z, args):
        q, p = split(as_dtype(z, self.dtype))
        args = as_dtype(args, self.dtype)
        qdot = self.inverse_mass.matrix(q, args) @ p
        return jnp.concatenate([qdot, self.net(self.features(q, p, args))])

    def penalty(self, zs, args):
        if self.weight == 0.0:
            return jnp.zeros((), self.dtype)
        return self.weight * symplectic_error(self, zs, args)
