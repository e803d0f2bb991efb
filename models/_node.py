"""The neural-ODE family: a free learned field (node, node_symreg), the second-order field
(node_so), NODE+SO in canonical (q, p) with a learned inverse mass (node_so_symreg), and the
same field reached from (q, qdot) through that inverse mass (node_so_pq: the Deconstructing
paper's own NODE+SO).
"""

from __future__ import annotations

from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.random as jr

from ._base import AbstractContinuousModel, as_dtype, split
from ._features import Features
from ._hamiltonian import INVERSE_MASS_JITTER
from ._linalg import cho_solve, cholesky
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

    def __init__(
        self, scene, width, depth, activation, dtype, *, key, weight=1.0, init="orthogonal"
    ):
        self.scene, self.dtype, self.weight = scene, dtype, float(weight)
        km, kn = jr.split(key)
        self.features = Features(scene)
        self.inverse_mass = CholeskyNet(
            self.features,
            width,
            depth,
            activation,
            dtype,
            key=km,
            jitter=INVERSE_MASS_JITTER,
            init=init,
        )
        self.net = MLP(
            self.features.size(True), scene.dof, width, depth, activation, dtype, key=kn, init=init
        )

    def vector_field(self, t, z, args):
        q, p = split(as_dtype(z, self.dtype))
        args = as_dtype(args, self.dtype)
        qdot = self.inverse_mass.matrix(q, args) @ p
        return jnp.concatenate([qdot, self.net(self.features(q, p, args))])

    def penalty(self, zs, args):
        if self.weight == 0.0:
            return jnp.zeros((), self.dtype)
        return self.weight * symplectic_error(self, zs, args)


class MomentumSecondOrderODE(AbstractContinuousModel):
    """NODE+SO as the Deconstructing paper's code builds it (its ``MechanicsNN``), on a scene
    in (q, qdot): the state is carried as y = (q, p) with p = M(q) qdot, through a learned
    inverse mass M^-1 = L L^T + 1e-4 I, and

        dq/dt = M^-1(q) p,   dp/dt = MLP(cos q, sin q, p, args[, u])

    (:class:`CanonicalSecondOrderODE` without its penalty). ``rollout`` integrates y itself
    (``encode``/``internal_field``/``decode``); ``vector_field`` is the same flow pushed
    forward to z = (q, qdot): dqdot/dt = M^-1 dp/dt + (dM^-1/dt) p, one jvp. The model is
    second order exactly, because the maps both ways use the one M^-1 (the paper's code
    uses 1e-6 on the way in and 1e-4 on the way out, a difference of order 1e-8 at its
    initialisation). Unlike :class:`SecondOrderODE`, whose network gives the acceleration
    from qdot, the free network here gives the force from p, and the mass is a second
    network. ``init``: the networks' initialisation, by default the paper's (``MLP``'s
    ``"paper"``: its biases start uniform, ours elsewhere at zero), since both the form and
    the start move how far it learns in the paper's budget (docs/sidebyside.md).
    """

    second_order: ClassVar[bool] = True
    takes_controls: ClassVar[bool] = True
    scene: Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    inner: CanonicalSecondOrderODE

    def __init__(self, scene, width, depth, activation, dtype, *, key, init="paper"):
        self.scene, self.dtype = scene, dtype
        self.inner = CanonicalSecondOrderODE(
            scene, width, depth, activation, dtype, key=key, weight=0.0, init=init
        )

    def encode(self, z, args):
        """(q, qdot) -> (q, p = (M^-1)^-1 qdot), a Cholesky solve."""
        q, v = split(as_dtype(z, self.dtype))
        minv = self.inner.inverse_mass.matrix(q, as_dtype(args, self.dtype))
        return jnp.concatenate([q, cho_solve(cholesky(minv), v)])

    def decode(self, y, args):
        """(q, p) -> (q, qdot = M^-1(q) p)."""
        q, p = split(as_dtype(y, self.dtype))
        return jnp.concatenate(
            [q, self.inner.inverse_mass.matrix(q, as_dtype(args, self.dtype)) @ p]
        )

    def internal_field(self, t, y, args):
        return self.inner.vector_field(t, y, args)

    def acceleration(self, q, v, args):
        """dqdot/dt = M^-1 dp/dt + (dM^-1/dt) p: decode's derivative along the flow in y."""
        z = jnp.concatenate([as_dtype(q, self.dtype), as_dtype(v, self.dtype)])
        y = self.encode(z, args)
        dy = self.internal_field(0.0, y, args)
        return jax.jvp(lambda y_: self.decode(y_, args), (y,), (dy,))[1][self.scene.dof :]

    def vector_field(self, t, z, args):
        q, v = split(as_dtype(z, self.dtype))
        return jnp.concatenate([v, self.acceleration(q, v, args)])
