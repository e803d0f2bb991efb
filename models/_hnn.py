"""The Hamiltonian family: the general HNN (hnn), the separable HNN (hnn_so) and the paper's
damped comparator (mixture_hnn).
"""

from __future__ import annotations

import abc
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.random as jr

from ._base import AbstractContinuousModel, as_dtype, split
from ._dissipation import Dissipation
from ._features import Features
from ._hamiltonian import INVERSE_MASS_JITTER, GeneralHamiltonian, SeparableHamiltonian
from ._linalg import cho_solve, cholesky
from ._mass import MASS_EPS, CholeskyNet, InverseMass
from ._mlp import MLP
from ._scalar import hamiltonian_field
from ._scene import Scene


class HNN(AbstractContinuousModel):
    """dz/dt = J grad H(q, p) (+ friction Q on dp/dt), for any learned H.

    In a canonical scene z = (q, p) and the field is J grad H itself; with
    ``momentum_map=False`` too, on z = (q, qdot): H(q, qdot) with qdot standing in for p (the
    LNN seed's naive HNN baseline, no learned momentum map). Otherwise z = (q, qdot)
    and p = M(q) qdot with a learned mass matrix M = C C^T (C lower-triangular from an MLP,
    softplus diagonal + 1e-3), or with ``inverse_mass`` M = (L L^T + 1e-4 I)^-1, L from the
    MLP (:class:`InverseMass`: the Deconstructing paper's parametrisation); the Hamiltonian
    flow is pushed forward to (q, qdot):

        dq/dt = dH/dp,   dp/dt = -dH/dq + Q,   dqdot/dt = M^-1 (dp/dt - (dM/dt) qdot),

    with dM/dt the derivative of M(q) along dq/dt (one jvp), solved with the Cholesky factor.
    With friction Q = -D(q) dH/dp, dH/dt = -(dH/dp)^T D dH/dp <= 0.

    ``rollout`` integrates the same flow in canonical y = (q, p) (``encode``/``decode``,
    ``internal_field`` = J grad H + Q), where the mass network is not evaluated per stage.
    """

    structure: ClassVar[str | None] = "hamiltonian"

    scene: Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    hamiltonian_part: GeneralHamiltonian | SeparableHamiltonian
    mass: CholeskyNet | InverseMass | None
    dissipation: Dissipation | None

    def __init__(
        self,
        scene,
        width,
        depth,
        activation,
        dtype,
        *,
        key,
        separable=False,
        dissipation=False,
        momentum_map=True,
        init="orthogonal",
        inverse_mass=False,
    ):
        self.scene, self.dtype = scene, dtype
        kh, km, kd = jr.split(key, 3)
        features = Features(scene)
        if separable:
            self.hamiltonian_part = SeparableHamiltonian(
                features, width, depth, activation, dtype, key=kh, init=init
            )
        else:  # init: H's network, and the mass network's with "paper" (dissipation: default)
            self.hamiltonian_part = GeneralHamiltonian(
                features, width, depth, activation, dtype, key=kh, init=init
            )
        # init "paper" starts the mass network as the paper's code does too
        mass_init = "paper" if init == "paper" else "orthogonal"
        if scene.canonical or not momentum_map:
            self.mass = None
        elif inverse_mass:
            self.mass = InverseMass(
                CholeskyNet(
                    *(features, width, depth, activation, dtype),
                    key=km,
                    jitter=INVERSE_MASS_JITTER,
                    init=mass_init,
                )
            )
        else:
            self.mass = CholeskyNet(
                *(features, width, depth, activation, dtype), key=km, eps=MASS_EPS, init=mass_init
            )
        self.dissipation = (
            Dissipation(features, width, depth, activation, dtype, key=kd) if dissipation else None
        )

    def momentum(self, q, v, args):
        """p = M(q) qdot (identity in a canonical scene, where the state holds p, and without
        a momentum map)."""
        if self.mass is None:
            return v
        c = self.mass.factor(q, args)
        return c @ (c.T @ v)

    def hamiltonian(self, z, args):
        q, x = split(as_dtype(z, self.dtype))
        args = as_dtype(args, self.dtype)
        return self.hamiltonian_part(q, self.momentum(q, x, args), args)

    def vector_field(self, t, z, args):
        q, x = split(as_dtype(z, self.dtype))
        args = as_dtype(args, self.dtype)
        H = lambda q_, p_: self.hamiltonian_part(q_, p_, args)
        if self.mass is None:
            qdot, pdot = hamiltonian_field(H, q, x)
            if self.dissipation is not None:
                pdot = pdot + self.dissipation.force(q, qdot, args)
            return jnp.concatenate([qdot, pdot])
        # one linearisation of C(q): its value and its derivative along qdot, no second pass
        c, dfactor = jax.linearize(lambda q_: self.mass.factor(q_, args), q)
        ctx = c.T @ x
        p = c @ ctx
        qdot, pdot = hamiltonian_field(H, q, p)
        if self.dissipation is not None:
            pdot = pdot + self.dissipation.force(q, qdot, args)
        dc = dfactor(qdot)
        dm_v = dc @ ctx + c @ (dc.T @ x)  # (dM/dt) qdot, dM = dC C^T + C dC^T
        vdot = cho_solve(c, pdot - dm_v)
        return jnp.concatenate([qdot, vdot])

    def encode(self, z, args):
        """(q, qdot) -> (q, p = M(q) qdot); identity in a canonical scene."""
        if self.mass is None:
            return z
        q, v = split(as_dtype(z, self.dtype))
        return jnp.concatenate([q, self.momentum(q, v, as_dtype(args, self.dtype))])

    def decode(self, y, args):
        """(q, p) -> (q, qdot = M(q)^-1 p), a Cholesky solve; identity in a canonical scene."""
        if self.mass is None:
            return y
        q, p = split(as_dtype(y, self.dtype))
        c = self.mass.factor(q, as_dtype(args, self.dtype))
        return jnp.concatenate([q, cho_solve(c, p)])

    def internal_field(self, t, y, args):
        """In y = (q, p): dq/dt = dH/dp, dp/dt = -dH/dq + Q(q, dH/dp); no mass network."""
        if self.mass is None:
            return self.vector_field(t, y, args)
        q, p = split(as_dtype(y, self.dtype))
        args = as_dtype(args, self.dtype)
        qdot, pdot = hamiltonian_field(lambda q_, p_: self.hamiltonian_part(q_, p_, args), q, p)
        if self.dissipation is not None:
            pdot = pdot + self.dissipation.force(q, qdot, args)
        return jnp.concatenate([qdot, pdot])


class AbstractSeparableHNN(AbstractContinuousModel):
    """The separable HNN in z = (q, qdot): H = 1/2 p^T M^-1(q) p + V(q), p = M(q) qdot, with
    an optional generalised force Q (:meth:`generalized_force`) on dp/dt.

    dH/dp = M^-1 p = qdot, so the model is second order exactly; the momentum equation
    dp/dt = -dH/dq + Q pushed forward to qdot = M^-1 p gives

        dqdot/dt = M^-1(q) dp/dt + (dM^-1/dt) p,

    with (dM^-1/dt) p one jvp of q -> M^-1(q) p along qdot. p = M qdot is a Cholesky solve
    with M^-1. (In a canonical scene ``make`` builds :class:`HNN` with a separable H.)

    ``rollout`` integrates the same flow in y = (q, p) instead (``encode``/``decode``,
    ``internal_field`` = J grad H + Q): one gradient of H per stage instead of M^-1, grad H
    and a jvp of M^-1. Subclasses say what Q is: none, friction (:class:`SeparableHNN`) or a
    free learned force of the controls (``hnn_force``).
    """

    structure: ClassVar[str | None] = "hamiltonian"
    second_order: ClassVar[bool] = True
    hamiltonian_part: eqx.AbstractVar[SeparableHamiltonian]

    @abc.abstractmethod
    def has_force(self) -> bool:
        """Whether :meth:`generalized_force` adds anything (a static property of the model)."""

    @abc.abstractmethod
    def generalized_force(self, q, p, v, args):
        """Q(q, p, qdot, args) on dp/dt (called only where :meth:`has_force`)."""

    def momentum(self, q, v, args):
        """p = M(q) qdot = (M^-1(q))^-1 qdot (independent of controls)."""
        minv = self.hamiltonian_part.inverse_mass.matrix(q, args)
        return cho_solve(cholesky(minv), v)

    def hamiltonian(self, z, args):
        q, v = split(as_dtype(z, self.dtype))
        args = as_dtype(args, self.dtype)
        return self.hamiltonian_part(q, self.momentum(q, v, args), args)

    def acceleration(self, q, v, args):
        q, v, args = (as_dtype(x, self.dtype) for x in (q, v, args))
        force = None
        if self.has_force():
            force = lambda q_, p_, v_: self.generalized_force(q_, p_, v_, args)
        return self.hamiltonian_part.acceleration(q, v, args, force)

    def vector_field(self, t, z, args):
        q, v = split(as_dtype(z, self.dtype))
        return jnp.concatenate([v, self.acceleration(q, v, args)])

    def encode(self, z, args):
        """(q, qdot) -> (q, p = M(q) qdot), a Cholesky solve with M^-1(q)."""
        q, v = split(as_dtype(z, self.dtype))
        return jnp.concatenate([q, self.momentum(q, v, as_dtype(args, self.dtype))])

    def decode(self, y, args):
        """(q, p) -> (q, qdot = M^-1(q) p)."""
        q, p = split(as_dtype(y, self.dtype))
        minv = self.hamiltonian_part.inverse_mass.matrix(q, as_dtype(args, self.dtype))
        return jnp.concatenate([q, minv @ p])

    def internal_field(self, t, y, args):
        """In y = (q, p): dq/dt = dH/dp = M^-1 p, dp/dt = -dH/dq + Q(q, p, dH/dp): one gradient
        of H, so the inverse-mass network runs once forward and once backward per stage."""
        q, p = split(as_dtype(y, self.dtype))
        args = as_dtype(args, self.dtype)
        qdot, pdot = hamiltonian_field(lambda q_, p_: self.hamiltonian_part(q_, p_, args), q, p)
        if self.has_force():
            pdot = pdot + self.generalized_force(q, p, qdot, args)
        return jnp.concatenate([qdot, pdot])


class SeparableHNN(AbstractSeparableHNN):
    """The separable HNN (hnn_so), with friction Q = -D(q) qdot when ``dissipation``
    (:class:`AbstractSeparableHNN` for the field). ``init="paper"`` starts H's networks as
    the Deconstructing paper's ``HNN`` does (PyTorch's default biases; the friction network
    keeps the default)."""

    scene: Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    hamiltonian_part: SeparableHamiltonian
    dissipation: Dissipation | None

    def __init__(
        self, scene, width, depth, activation, dtype, *, key, dissipation=False, init="orthogonal"
    ):
        self.scene, self.dtype = scene, dtype
        kh, kd = jr.split(key)
        features = Features(scene)
        self.hamiltonian_part = SeparableHamiltonian(
            features, width, depth, activation, dtype, key=kh, init=init
        )
        self.dissipation = (
            Dissipation(features, width, depth, activation, dtype, key=kd) if dissipation else None
        )

    def has_force(self) -> bool:
        return self.dissipation is not None

    def generalized_force(self, q, p, v, args):
        return self.dissipation.force(q, v, args)


class MixtureHNN(AbstractContinuousModel):
    """The paper's damped comparator ("MixtureHNN", labelled SymODEN in the paper's Fig. 6).

    In canonical y = (q, p):

        dy/dt = J grad H(q, p) + MLP(cos q, sin q, p, args),
        H = 1/2 p^T M^-1(q) p + V(q),   M^-1 = L L^T + 1e-4 I,

    a separable HNN (the ``hnn_so`` Hamiltonian) plus a free MLP field on the whole state, added
    to both dq/dt and dp/dt; the MLP absorbs the friction (and anything else). In a velocity
    scene the state is mapped with the learned mass, p = M(q) qdot (``encode``), integrated in
    (q, p) and mapped back with qdot = M^-1(q) p (``decode``), as the reference does;
    ``vector_field`` on (q, qdot) is the same flow pushed forward (one jvp of ``decode``).

    The paper's code (ngruver/decon-hnn, ``src/models/mixture_hnn.py``): ``forward`` returns
    ``hnn(t, z) + nn(t, z)`` with the reference's separable HNN (learned M^-1(q) by a Cholesky
    factor with softplus diagonal + 1e-4 I, potential MLP) and a free NN on z = (q, p), both
    integrated in (q, p) from p0 = M(q0) qdot0. Ours differs only in the shared conventions of
    this package: angles enter every network as (cos q, sin q) (the NN's input too), the
    Cholesky diagonal is softplus(. + shift) + 1e-3, orthogonal init with gain 0.5 for both
    networks; the reference's optional layer tying and spectral norm (off by default) are not
    built. It is not dissipative by construction: the MLP may add or remove energy. The
    Rayleigh variant ``hnn_so`` + ``Dissipation`` (Q = -D(q) qdot on dp/dt) is the correctly
    specified, stronger model for the benchmark's damped systems.
    """

    structure: ClassVar[str | None] = "hamiltonian"
    takes_controls: ClassVar[bool] = True  # the free MLP reads u; H does not
    forced: ClassVar[bool] = True

    scene: Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    hamiltonian_part: SeparableHamiltonian
    features: Features
    free: MLP

    def __init__(self, scene, width, depth, activation, dtype, *, key):
        self.scene, self.dtype = scene, dtype
        kh, kf = jr.split(key)
        self.features = Features(scene)
        self.hamiltonian_part = SeparableHamiltonian(
            self.features, width, depth, activation, dtype, key=kh
        )
        self.free = MLP(
            self.features.size(True), 2 * scene.dof, width, depth, activation, dtype, key=kf
        )

    def _inverse_mass(self, q, args):
        return self.hamiltonian_part.inverse_mass.matrix(q, args)

    def hamiltonian(self, z, args):
        """The learned H of the conservative part, at z in the scene's coordinates."""
        y = self.encode(z, args)
        q, p = split(y)
        return self.hamiltonian_part(q, p, as_dtype(args, self.dtype))

    def internal_field(self, t, y, args):
        """dy/dt = J grad H(q, p) + MLP(q, p) in y = (q, p)."""
        q, p = split(as_dtype(y, self.dtype))
        args = as_dtype(args, self.dtype)
        qdot, pdot = hamiltonian_field(lambda q_, p_: self.hamiltonian_part(q_, p_, args), q, p)
        return jnp.concatenate([qdot, pdot]) + self.free(self.features(q, p, args))

    def encode(self, z, args):
        """(q, qdot) -> (q, p = M(q) qdot); identity in a canonical scene."""
        if self.scene.canonical:
            return as_dtype(z, self.dtype)
        q, v = split(as_dtype(z, self.dtype))
        minv = self._inverse_mass(q, as_dtype(args, self.dtype))
        return jnp.concatenate([q, cho_solve(cholesky(minv), v)])

    def decode(self, y, args):
        """(q, p) -> (q, qdot = M^-1(q) p); identity in a canonical scene."""
        if self.scene.canonical:
            return as_dtype(y, self.dtype)
        q, p = split(as_dtype(y, self.dtype))
        return jnp.concatenate([q, self._inverse_mass(q, as_dtype(args, self.dtype)) @ p])

    def vector_field(self, t, z, args):
        if self.scene.canonical:
            return self.internal_field(t, z, args)
        y = self.encode(z, args)
        dy = self.internal_field(t, y, args)
        return jax.jvp(lambda y_: self.decode(y_, args), (y,), (dy,))[1]
