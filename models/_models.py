"""The registered models, each assembled from the bias parts of the sibling modules.

| name         | biases                                                                   |
| ------------ | ------------------------------------------------------------------------ |
| node         | ODE: dz/dt = MLP(z)                                                      |
| node_so      | ODE + second order: dq/dt = qdot, dqdot/dt = MLP(q, qdot)               |
| hnn          | ODE + energy + exact symplectic: J grad H, general H(q, p)               |
| hnn_so       | hnn + second order: separable H = 1/2 p^T M^-1(q) p + V(q)               |
| mixture_hnn  | the paper's damped comparator: hnn_so field + a free MLP field in (q, p) |
| node_symreg  | node + soft symplectic penalty weight * mean ||J DF - (J DF)^T||^2       |
| node_so_symreg | canonical NODE+SO: dq/dt = M^-1(q) p, dp/dt = MLP(q, p), + the penalty |
| lnn          | ODE + second order + energy: Euler-Lagrange of a learned L(q, qdot)      |
| vin          | discrete + variational: Verlet step of L = 1/2 v^T M v - U(q)            |
| vin_implicit | discrete + variational: midpoint DEL step of a general learned L(q, v)   |
| resnet       | discrete, free: z_{n+1} = z_n + MLP(z_n)                                 |
| constant_velocity | trivial, no parameters: q(t) = q0 + t qdot0 (see ``_trivial``)      |
| at_rest      | trivial, no parameters: q(t) = q0, qdot(t) = 0                           |

``hnn`` takes ``momentum_map`` (default True: p = M(q) qdot with a learned M in a velocity
scene); ``momentum_map=False`` is the LNN seed's naive baseline, H(q, qdot) with qdot standing
in for p and dz/dt = J grad H on (q, qdot).

The structured models (hnn, hnn_so, lnn, vin, vin_implicit) add the :class:`Dissipation`
part when the scene is damped (or ``dissipation=True``).
"""

from __future__ import annotations

import difflib
from collections.abc import Callable
from typing import ClassVar, NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.random as jr
from jaxtyping import Array

from ._base import AbstractContinuousModel, AbstractDiscreteModel, as_dtype
from ._dissipation import Dissipation
from ._features import Features
from ._hamiltonian import INVERSE_MASS_JITTER, GeneralHamiltonian, SeparableHamiltonian
from ._linalg import cho_solve, cholesky
from ._mass import CholeskyNet
from ._mlp import ACTIVATIONS, DTYPES, INITS, MLP
from ._scalar import SOLVES, acceleration_from_lagrangian, hamiltonian_field, lagrangian_energy
from ._scene import Scene
from ._symplectic import symplectic_error
from ._trivial import AtRest, ConstantVelocity
from ._variational import midpoint_variational_step, verlet_step

MASS_EPS = 1e-3  # floor on the diagonal of a learned mass factor: M stays invertible


def _split(z: Array) -> tuple[Array, Array]:
    d = z.shape[-1] // 2
    return z[..., :d], z[..., d:]


# --------------------------------------------------------------------------- free models


class NeuralODE(AbstractContinuousModel):
    """dz/dt = MLP(cos q, sin q, qdot, args); with ``weight`` > 0 (node_symreg) the loss gets
    the soft symplectic penalty weight * mean ||J DF - (J DF)^T||_F^2 over the rollout states."""

    scene: Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    weight: float = eqx.field(static=True)
    features: Features
    net: MLP

    def __init__(self, scene, width, depth, activation, dtype, *, key, weight=0.0):
        self.scene, self.dtype, self.weight = scene, dtype, float(weight)
        self.features = Features(scene)
        self.net = MLP(
            self.features.size(True), 2 * scene.dof, width, depth, activation, dtype, key=key
        )

    def vector_field(self, t, z, args):
        q, v = _split(as_dtype(z, self.dtype))
        return self.net(self.features(q, v, as_dtype(args, self.dtype)))

    def penalty(self, zs, args):
        if self.weight == 0.0:
            return jnp.zeros((), self.dtype)
        return self.weight * symplectic_error(self, zs, args)


class SecondOrderODE(AbstractContinuousModel):
    """dq/dt = qdot (exactly), dqdot/dt = MLP(cos q, sin q, qdot, args)."""

    second_order: ClassVar[bool] = True
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
        return self.net(self.features(q, v, args))

    def vector_field(self, t, z, args):
        q, v = _split(as_dtype(z, self.dtype))
        return jnp.concatenate([v, self.acceleration(q, v, args)])


class ResNet(AbstractDiscreteModel):
    """z_{n+1} = z_n + MLP(cos q_n, sin q_n, qdot_n, args): the VIN seed's baseline.

    The step is tied to the time step it was trained at (dt is not an input).
    """

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
        q, v = _split(z)
        return z + self.net(self.features(q, v, as_dtype(args, self.dtype)))


# --------------------------------------------------------------------------- Hamiltonian


class HNN(AbstractContinuousModel):
    """dz/dt = J grad H(q, p) (+ friction Q on dp/dt), for any learned H.

    In a canonical scene z = (q, p) and the field is J grad H itself; with
    ``momentum_map=False`` too, on z = (q, qdot): H(q, qdot) with qdot standing in for p (the
    LNN seed's naive HNN baseline, no learned momentum map). Otherwise z = (q, qdot)
    and p = M(q) qdot with a learned mass matrix M = C C^T (C lower-triangular from an MLP,
    softplus diagonal + 1e-3); the Hamiltonian flow is pushed forward to (q, qdot):

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
    mass: CholeskyNet | None
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
    ):
        self.scene, self.dtype = scene, dtype
        kh, km, kd = jr.split(key, 3)
        features = Features(scene)
        part = SeparableHamiltonian if separable else GeneralHamiltonian
        self.hamiltonian_part = part(features, width, depth, activation, dtype, key=kh)
        self.mass = (
            None
            if scene.canonical or not momentum_map
            else CholeskyNet(features, width, depth, activation, dtype, key=km, eps=MASS_EPS)
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
        q, x = _split(as_dtype(z, self.dtype))
        args = as_dtype(args, self.dtype)
        return self.hamiltonian_part(q, self.momentum(q, x, args), args)

    def vector_field(self, t, z, args):
        q, x = _split(as_dtype(z, self.dtype))
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
        q, v = _split(as_dtype(z, self.dtype))
        return jnp.concatenate([q, self.momentum(q, v, as_dtype(args, self.dtype))])

    def decode(self, y, args):
        """(q, p) -> (q, qdot = M(q)^-1 p), a Cholesky solve; identity in a canonical scene."""
        if self.mass is None:
            return y
        q, p = _split(as_dtype(y, self.dtype))
        c = self.mass.factor(q, as_dtype(args, self.dtype))
        return jnp.concatenate([q, cho_solve(c, p)])

    def internal_field(self, t, y, args):
        """In y = (q, p): dq/dt = dH/dp, dp/dt = -dH/dq + Q(q, dH/dp); no mass network."""
        if self.mass is None:
            return self.vector_field(t, y, args)
        q, p = _split(as_dtype(y, self.dtype))
        args = as_dtype(args, self.dtype)
        qdot, pdot = hamiltonian_field(lambda q_, p_: self.hamiltonian_part(q_, p_, args), q, p)
        if self.dissipation is not None:
            pdot = pdot + self.dissipation.force(q, qdot, args)
        return jnp.concatenate([qdot, pdot])


class SeparableHNN(AbstractContinuousModel):
    """The separable HNN in z = (q, qdot): H = 1/2 p^T M^-1(q) p + V(q), p = M(q) qdot.

    dH/dp = M^-1 p = qdot, so the model is second order exactly; the momentum equation
    dp/dt = -dH/dq + Q pushed forward to qdot = M^-1 p gives

        dqdot/dt = M^-1(q) dp/dt + (dM^-1/dt) p,

    with (dM^-1/dt) p one jvp of q -> M^-1(q) p along qdot. p = M qdot is a Cholesky solve
    with M^-1. (In a canonical scene ``make`` builds :class:`HNN` with a separable H.)

    ``rollout`` integrates the same flow in y = (q, p) instead (``encode``/``decode``,
    ``internal_field`` = J grad H + Q): one gradient of H per stage instead of M^-1, grad H
    and a jvp of M^-1.
    """

    structure: ClassVar[str | None] = "hamiltonian"

    second_order: ClassVar[bool] = True
    scene: Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    hamiltonian_part: SeparableHamiltonian
    dissipation: Dissipation | None

    def __init__(self, scene, width, depth, activation, dtype, *, key, dissipation=False):
        self.scene, self.dtype = scene, dtype
        kh, kd = jr.split(key)
        features = Features(scene)
        self.hamiltonian_part = SeparableHamiltonian(
            features, width, depth, activation, dtype, key=kh
        )
        self.dissipation = (
            Dissipation(features, width, depth, activation, dtype, key=kd) if dissipation else None
        )

    def momentum(self, q, v, args):
        """p = M(q) qdot = (M^-1(q))^-1 qdot."""
        minv = self.hamiltonian_part.inverse_mass.matrix(q, args)
        return cho_solve(cholesky(minv), v)

    def hamiltonian(self, z, args):
        q, v = _split(as_dtype(z, self.dtype))
        args = as_dtype(args, self.dtype)
        return self.hamiltonian_part(q, self.momentum(q, v, args), args)

    def acceleration(self, q, v, args):
        q, v, args = (as_dtype(x, self.dtype) for x in (q, v, args))
        inverse_mass = lambda q_: self.hamiltonian_part.inverse_mass.matrix(q_, args)
        minv = inverse_mass(q)
        p = cho_solve(cholesky(minv), v)
        pdot = -jax.grad(self.hamiltonian_part, argnums=0)(q, p, args)
        if self.dissipation is not None:
            pdot = pdot + self.dissipation.force(q, v, args)
        _, dminv_p = jax.jvp(lambda q_: inverse_mass(q_) @ p, (q,), (v,))
        return minv @ pdot + dminv_p

    def vector_field(self, t, z, args):
        q, v = _split(as_dtype(z, self.dtype))
        return jnp.concatenate([v, self.acceleration(q, v, args)])

    def encode(self, z, args):
        """(q, qdot) -> (q, p = M(q) qdot), a Cholesky solve with M^-1(q)."""
        q, v = _split(as_dtype(z, self.dtype))
        return jnp.concatenate([q, self.momentum(q, v, as_dtype(args, self.dtype))])

    def decode(self, y, args):
        """(q, p) -> (q, qdot = M^-1(q) p)."""
        q, p = _split(as_dtype(y, self.dtype))
        minv = self.hamiltonian_part.inverse_mass.matrix(q, as_dtype(args, self.dtype))
        return jnp.concatenate([q, minv @ p])

    def internal_field(self, t, y, args):
        """In y = (q, p): dq/dt = dH/dp = M^-1 p, dp/dt = -dH/dq + Q(q, dH/dp): one gradient
        of H, so the inverse-mass network runs once forward and once backward per stage."""
        q, p = _split(as_dtype(y, self.dtype))
        args = as_dtype(args, self.dtype)
        qdot, pdot = hamiltonian_field(lambda q_, p_: self.hamiltonian_part(q_, p_, args), q, p)
        if self.dissipation is not None:
            pdot = pdot + self.dissipation.force(q, qdot, args)
        return jnp.concatenate([qdot, pdot])


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
        q, p = _split(y)
        return self.hamiltonian_part(q, p, as_dtype(args, self.dtype))

    def internal_field(self, t, y, args):
        """dy/dt = J grad H(q, p) + MLP(q, p) in y = (q, p)."""
        q, p = _split(as_dtype(y, self.dtype))
        args = as_dtype(args, self.dtype)
        qdot, pdot = hamiltonian_field(lambda q_, p_: self.hamiltonian_part(q_, p_, args), q, p)
        return jnp.concatenate([qdot, pdot]) + self.free(self.features(q, p, args))

    def encode(self, z, args):
        """(q, qdot) -> (q, p = M(q) qdot); identity in a canonical scene."""
        if self.scene.canonical:
            return as_dtype(z, self.dtype)
        q, v = _split(as_dtype(z, self.dtype))
        minv = self._inverse_mass(q, as_dtype(args, self.dtype))
        return jnp.concatenate([q, cho_solve(cholesky(minv), v)])

    def decode(self, y, args):
        """(q, p) -> (q, qdot = M^-1(q) p); identity in a canonical scene."""
        if self.scene.canonical:
            return as_dtype(y, self.dtype)
        q, p = _split(as_dtype(y, self.dtype))
        return jnp.concatenate([q, self._inverse_mass(q, as_dtype(args, self.dtype)) @ p])

    def vector_field(self, t, z, args):
        if self.scene.canonical:
            return self.internal_field(t, z, args)
        y = self.encode(z, args)
        dy = self.internal_field(t, y, args)
        return jax.jvp(lambda y_: self.decode(y_, args), (y,), (dy,))[1]


class CanonicalSecondOrderODE(AbstractContinuousModel):
    """NODE+SO in canonical coordinates, the reference's symplectic-regularised model.

    On z = (q, p): dq/dt = M^-1(q) p (M^-1 = L L^T + 1e-4 I, the learned inverse mass of
    ``hnn_so``), dp/dt = MLP(cos q, sin q, p, args). With ``weight`` > 0 the loss gets the soft
    symplectic penalty weight * mean ||J DF - (J DF)^T||_F^2 (as ``node_symreg``), which is
    zero for the true dynamics in these coordinates. Needs momentum data (Scene.canonical).
    """

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
        q, p = _split(as_dtype(z, self.dtype))
        args = as_dtype(args, self.dtype)
        qdot = self.inverse_mass.matrix(q, args) @ p
        return jnp.concatenate([qdot, self.net(self.features(q, p, args))])

    def penalty(self, zs, args):
        if self.weight == 0.0:
            return jnp.zeros((), self.dtype)
        return self.weight * symplectic_error(self, zs, args)


# --------------------------------------------------------------------------- Lagrangian


class LNN(AbstractContinuousModel):
    """dq/dt = qdot, qddot = (d2L/dqdot2)^-1 (dL/dq - (d2L/dqdot dq) qdot + Q) for a learned
    L(q, qdot) = MLP(cos q, sin q, qdot, args) + c |qdot|^2 (softplus, the LNN seed's
    initialisation).

    c = ``kinetic_prior`` (default 0.1, the constrained-HNN reference's term; 0 is the LNN
    seed's pure form). Without it a freshly initialised MLP has d2L/dqdot2 close to singular,
    so a few training trajectories reach accelerations of 1e3 and non-finite losses at step 0
    (measured on the quick profile: 3 of 9 LNN runs diverged); with it the Hessian starts near
    2c I and the network learns the rest. Measured again for the relativistic particle (quick,
    float32, seed 0): kinetic_prior=0 gives one training chunk of 200 with a non-finite step-0
    loss (max |qddot| 2e3 at init), so the run diverges at step 0, with the default g range and
    with the slow test set alike; seeds 1 and 2 have none (smoke sizes: none in 3 seeds).

    With friction Q = -D(q) qdot the energy E = qdot . dL/dqdot - L has dE/dt = qdot . Q <= 0.
    """

    structure: ClassVar[str | None] = "lagrangian"

    second_order: ClassVar[bool] = True
    scene: Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    solve: str = eqx.field(static=True)
    eps: float = eqx.field(static=True)
    kinetic_prior: float = eqx.field(static=True)
    features: Features
    net: MLP
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
        dissipation=False,
        solve="solve",
        eps=1e-3,
        init="lnn",
        kinetic_prior=0.1,
    ):
        self.scene, self.dtype, self.solve, self.eps = scene, dtype, solve, float(eps)
        self.kinetic_prior = float(kinetic_prior)
        kl, kd = jr.split(key)
        self.features = Features(scene)
        self.net = MLP(
            self.features.size(True), 1, width, depth, activation, dtype, key=kl, init=init
        )
        self.dissipation = (
            Dissipation(self.features, width, depth, activation, dtype, key=kd)
            if dissipation
            else None
        )

    def _lagrangian(self, q, v, args):
        return self.net(self.features(q, v, args))[0] + self.kinetic_prior * (v @ v)

    def lagrangian(self, q, v, args):
        q, v, args = (as_dtype(x, self.dtype) for x in (q, v, args))
        return self._lagrangian(q, v, args)

    def energy(self, z, args):
        q, v = _split(as_dtype(z, self.dtype))
        return lagrangian_energy(lambda q_, v_: self.lagrangian(q_, v_, args), q, v)

    def acceleration(self, q, v, args):
        q, v, args = (as_dtype(x, self.dtype) for x in (q, v, args))
        force = None if self.dissipation is None else self.dissipation.force(q, v, args)
        return acceleration_from_lagrangian(
            lambda q_, v_: self._lagrangian(q_, v_, args),
            q,
            v,
            force=force,
            solve=self.solve,
            eps=self.eps,
        )

    def vector_field(self, t, z, args):
        q, v = _split(as_dtype(z, self.dtype))
        return jnp.concatenate([v, self.acceleration(q, v, args)])


# --------------------------------------------------------------------------- variational


class VIN(AbstractDiscreteModel):
    """Variational integrator network: velocity Verlet of L = 1/2 v^T M v - U(q).

    M = C C^T a learned constant positive-definite matrix (C starts at the identity), U an
    MLP. With dissipation a learned constant PSD friction D enters as a trapezoidal discrete
    Lagrange-d'Alembert force (see :func:`verlet_step`).
    """

    structure: ClassVar[str | None] = "lagrangian"

    scene: Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    features: Features
    potential: MLP
    mass: CholeskyNet
    dissipation: Dissipation | None

    def __init__(self, scene, width, depth, activation, dtype, *, key, dissipation=False):
        self.scene, self.dtype = scene, dtype
        self.features = Features(scene)
        self.potential = MLP(self.features.size(False), 1, width, depth, activation, dtype, key=key)
        self.mass = CholeskyNet(
            self.features,
            width,
            depth,
            activation,
            dtype,
            key=key,
            state_dependent=False,
            eps=MASS_EPS,
        )
        self.dissipation = (
            Dissipation(
                self.features, width, depth, activation, dtype, key=key, state_dependent=False
            )
            if dissipation
            else None
        )

    def potential_energy(self, q, args):
        return self.potential(self.features(q, None, args))[0]

    def lagrangian(self, q, v, args):
        q, v, args = (as_dtype(x, self.dtype) for x in (q, v, args))
        m = self.mass.matrix(q, args)
        return 0.5 * v @ (m @ v) - self.potential_energy(q, args)

    def energy(self, z, args):
        q, v = _split(as_dtype(z, self.dtype))
        args = as_dtype(args, self.dtype)
        m = self.mass.matrix(q, args)
        return 0.5 * v @ (m @ v) + self.potential_energy(q, args)

    def step(self, z, dt, args):
        q, v = _split(as_dtype(z, self.dtype))
        args, dt = as_dtype(args, self.dtype), as_dtype(dt, self.dtype)
        grad_U = jax.grad(lambda q_: self.potential_energy(q_, args))
        damping = None if self.dissipation is None else self.dissipation.matrix(q, args)
        q1, v1 = verlet_step(grad_U, self.mass.factor(q, args), q, v, dt, damping)
        return jnp.concatenate([q1, v1])


class ImplicitVIN(AbstractDiscreteModel):
    """Variational integrator network for a general L(q, v) = 1/2 |v|^2 + MLP(q, v, args).

    One step is the midpoint-rule discrete Euler-Lagrange equation, solved by Newton with
    implicit differentiation (:func:`midpoint_variational_step`); the state velocity is mapped
    to and from the discrete momenta with the continuous Legendre map. The 1/2 |v|^2 prior
    keeps d2L/dv2 near the identity at initialisation, so both Newton solves are well posed;
    the MLP can learn any correction. With dissipation, Q = -D(q) v (learned PSD D(q)).
    """

    structure: ClassVar[str | None] = "lagrangian"

    scene: Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    newton_steps: int = eqx.field(static=True)
    features: Features
    net: MLP
    dissipation: Dissipation | None

    def __init__(
        self, scene, width, depth, activation, dtype, *, key, dissipation=False, newton_steps=20
    ):
        self.scene, self.dtype, self.newton_steps = scene, dtype, int(newton_steps)
        kl, kd = jr.split(key)
        self.features = Features(scene)
        self.net = MLP(self.features.size(True), 1, width, depth, activation, dtype, key=kl)
        self.dissipation = (
            Dissipation(self.features, width, depth, activation, dtype, key=kd)
            if dissipation
            else None
        )

    def lagrangian(self, q, v, args):
        q, v, args = (as_dtype(x, self.dtype) for x in (q, v, args))
        return 0.5 * (v @ v) + self.net(self.features(q, v, args))[0]

    def step_with_status(self, z, dt, args):
        """(z_{n+1}, converged): the step and whether both Newton solves converged."""
        q, v = _split(as_dtype(z, self.dtype))
        args, dt = as_dtype(args, self.dtype), as_dtype(dt, self.dtype)
        L = lambda q_, v_: 0.5 * (v_ @ v_) + self.net(self.features(q_, v_, args))[0]
        force = None
        if self.dissipation is not None:
            force = lambda q_, v_: self.dissipation.force(q_, v_, args)
        q1, v1, ok = midpoint_variational_step(L, q, v, dt, force, self.newton_steps)
        return jnp.concatenate([q1, v1]), ok

    def step(self, z, dt, args):
        return self.step_with_status(z, dt, args)[0]


# --------------------------------------------------------------------------- registry


def _positive_float(name):
    def check(x):
        if isinstance(x, bool) or not isinstance(x, int | float) or not x >= 0:
            raise ValueError(f"option {name} must be a number >= 0, got {x!r}")
        return float(x)

    return check


def _choice(name, allowed):
    def check(x):
        if x not in allowed:
            raise ValueError(f"option {name} must be one of {allowed}, got {x!r}")
        return x

    return check


def _positive_int(name):
    def check(x):
        if isinstance(x, bool) or not isinstance(x, int) or x < 1:
            raise ValueError(f"option {name} must be an int >= 1, got {x!r}")
        return x

    return check


def _boolean(name):
    def check(x):
        if not isinstance(x, bool):
            raise ValueError(f"option {name} must be True or False, got {x!r}")
        return x

    return check


def _build_hnn(scene, *a, key, dissipation, separable=False, momentum_map=True):
    if separable and not scene.canonical:
        return SeparableHNN(scene, *a, key=key, dissipation=dissipation)
    return HNN(
        scene, *a, key=key, separable=separable, dissipation=dissipation, momentum_map=momentum_map
    )


def _trivial(cls):
    def build(s, width, depth, activation, dtype, *, key, dissipation):
        return cls(s, dtype)

    return build


class _Entry(NamedTuple):
    """A registered model: its class (whose markers the spec reads), how to build it, its
    options (name -> validator), whether it takes a dissipation term (the structured models),
    the coordinates it needs (None: either) and its default activation."""

    cls: type
    build: Callable
    options: dict = {}
    structured: bool = False
    needs: str | None = None
    activation: str = "tanh"


def _plain(cls):
    """The builder of a model class that takes no dissipation term."""

    def build(s, *a, key, dissipation, **options):
        return cls(s, *a, key=key, **options)

    return build


_V, _P = "velocity", "momentum"
_REGISTRY = {
    "node": _Entry(NeuralODE, _plain(NeuralODE)),
    "node_so": _Entry(SecondOrderODE, _plain(SecondOrderODE)),
    "hnn": _Entry(HNN, _build_hnn, {"momentum_map": _boolean("momentum_map")}, True),
    "hnn_so": _Entry(
        SeparableHNN,
        lambda s, *a, key, dissipation: _build_hnn(
            s, *a, key=key, separable=True, dissipation=dissipation
        ),
        structured=True,
    ),
    "mixture_hnn": _Entry(MixtureHNN, _plain(MixtureHNN)),
    "node_symreg": _Entry(
        NeuralODE,
        lambda s, *a, key, dissipation, weight=1.0: NeuralODE(s, *a, key=key, weight=weight),
        {"weight": _positive_float("weight")},
    ),
    "node_so_symreg": _Entry(
        CanonicalSecondOrderODE,
        lambda s, *a, key, dissipation, weight=1.0: CanonicalSecondOrderODE(
            s, *a, key=key, weight=weight
        ),
        {"weight": _positive_float("weight")},
        needs=_P,
    ),
    "lnn": _Entry(
        LNN,
        LNN,
        {
            "solve": _choice("solve", SOLVES),
            "eps": _positive_float("eps"),
            "init": _choice("init", INITS),
            "kinetic_prior": _positive_float("kinetic_prior"),
        },
        True,
        _V,
        "softplus",
    ),
    "vin": _Entry(VIN, VIN, {}, True, _V),
    "vin_implicit": _Entry(
        ImplicitVIN, ImplicitVIN, {"newton_steps": _positive_int("newton_steps")}, True, _V
    ),
    "resnet": _Entry(ResNet, _plain(ResNet)),
    "constant_velocity": _Entry(ConstantVelocity, _trivial(ConstantVelocity)),
    "at_rest": _Entry(AtRest, _trivial(AtRest)),
}


BUILT_IN = tuple(_REGISTRY)
ENTRY_POINT_GROUP = "decon_bench.models"
MODULES_ENV = "DECON_MODEL_MODULES"  # comma-separated plug-in modules (--model-module)
_PLUGINS: set[str] = set()  # plug-in sources already loaded ("ep:<name>", "module:<name>")


def register(
    name: str,
    cls: type,
    *,
    build: Callable | None = None,
    options: dict | None = None,
    takes_dissipation: bool = False,
    coordinates: str | None = None,
    activation: str = "tanh",
) -> str:
    """Register a model from outside the suite under ``name``; returns ``name``.

    The contract (checked here, a one-line ValueError naming what is missing): ``cls`` is a
    subclass of :class:`AbstractContinuousModel` (a learned field ``vector_field(t, z, args)``)
    or :class:`AbstractDiscreteModel` (a learned map ``step(z, dt, args)``), with every
    abstract method implemented and a class attribute ``structure`` in (None, "hamiltonian",
    "lagrangian"); ``build(scene, width, depth, activation, dtype, *, key, dissipation,
    **options)`` returns an instance (default: ``cls(scene, width, depth, activation, dtype,
    key=key, **options)``); ``options`` maps each option name to a validator returning the
    value; ``takes_dissipation``: the model adds a dissipation term in damped scenes (then
    ``build`` receives ``dissipation``); ``coordinates``: None (either), "velocity" or
    "momentum". :func:`spec` reads its capabilities like a built-in's. Re-registering the
    same plug-in name replaces it; a built-in name cannot be taken.
    """
    import inspect

    def bad(what: str):
        raise ValueError(f"model plug-in {name!r}: {what}")

    if not isinstance(name, str) or not name.isidentifier():
        bad("the name must be a Python identifier")
    if name in BUILT_IN:
        bad(f"the name is a built-in model; built-ins: {', '.join(BUILT_IN)}")
    if not isinstance(cls, type) or not issubclass(
        cls, AbstractContinuousModel | AbstractDiscreteModel
    ):
        bad(
            "the class must subclass models.AbstractContinuousModel (a vector field) or "
            "models.AbstractDiscreteModel (a map); got "
            f"{getattr(cls, '__name__', cls)!r}"
        )
    missing = sorted(getattr(cls, "__abstractmethods__", ()) or ())
    if missing:
        bad(f"{cls.__name__} does not implement {', '.join(missing)}")
    if getattr(cls, "structure", "?") not in (None, "hamiltonian", "lagrangian"):
        bad(f"{cls.__name__}.structure must be None, 'hamiltonian' or 'lagrangian'")
    if coordinates not in (None, _V, _P):
        bad(f"coordinates must be None, {_V!r} or {_P!r}; got {coordinates!r}")
    if activation not in ACTIVATIONS:
        bad(f"activation must be one of {sorted(ACTIVATIONS)}; got {activation!r}")
    options = dict(options or {})
    if not all(isinstance(k, str) and callable(v) for k, v in options.items()):
        bad("options must map option names to validator callables")
    if build is None:
        build = _plain(cls)
        target = cls
        probe = ("scene", 1, 1, "tanh", "float32")
        kwargs = {"key": None}
    else:
        target, probe, kwargs = (
            build,
            ("scene", 1, 1, "tanh", "float32"),
            {
                "key": None,
                "dissipation": False,
            },
        )
    if not callable(build):
        bad("build must be callable")
    try:
        inspect.signature(target).bind(*probe, **kwargs)
    except TypeError as e:
        bad(
            "build (or the class) must accept (scene, width, depth, activation, dtype, *, key"
            f"{', dissipation' if target is build else ''}, **options): {e}"
        )
    except ValueError:  # no signature available: trust it
        pass
    _REGISTRY[name] = _Entry(cls, build, options, bool(takes_dissipation), coordinates, activation)
    from ._spec import spec

    spec.cache_clear()
    return name


_ENTRY_POINTS: list = []  # [the entry points of ENTRY_POINT_GROUP], once scanned


def load_plugins(modules: str | None = None) -> None:
    """Import the plug-in models, once each: the entry points of :data:`ENTRY_POINT_GROUP` and
    the modules named in ``$DECON_MODEL_MODULES`` (or ``modules``), comma-separated. A module
    registers its models on import (:func:`register`); an entry point that loads a callable
    is called. A plug-in that fails to import is a one-line ValueError naming it."""
    import importlib
    import os
    from importlib import metadata

    names = modules if modules is not None else os.environ.get(MODULES_ENV, "")
    todo = [("module:" + m.strip(), m.strip()) for m in names.split(",") if m.strip()]
    if not _ENTRY_POINTS:  # scanned once a process: a scan reads every installed package's
        # metadata (~7 ms), and available() is asked for every configuration of a sweep
        try:
            _ENTRY_POINTS.append(list(metadata.entry_points(group=ENTRY_POINT_GROUP)))
        except Exception:  # noqa: BLE001 - a broken environment must not stop the built-ins
            _ENTRY_POINTS.append([])
    todo += [("ep:" + ep.name, ep) for ep in _ENTRY_POINTS[0]]
    for key, what in todo:
        if key in _PLUGINS:
            continue
        _PLUGINS.add(key)
        try:
            obj = importlib.import_module(what) if isinstance(what, str) else what.load()
            if callable(obj) and not isinstance(obj, type):
                obj()
        except ValueError:
            raise
        except Exception as e:  # noqa: BLE001 - one line naming the plug-in
            source = (
                "DECON_MODEL_MODULES/--model-module"
                if isinstance(what, str)
                else (f"entry point {ENTRY_POINT_GROUP}")
            )
            raise ValueError(
                f"model plug-in {key.split(':', 1)[1]!r} ({source}) failed to load: "
                f"{type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}"
            ) from None


def available() -> list[str]:
    """Names of the registered models (built-ins, then plug-ins)."""
    load_plugins()
    return list(_REGISTRY)


def trivial_models() -> list[str]:
    """Names of the registered trivial predictors (no parameters, nothing to train)."""
    load_plugins()
    return [n for n, entry in _REGISTRY.items() if entry.cls.trivial]


def coordinates(name: str) -> tuple[str, ...]:
    """The coordinate settings ("velocity", "momentum") that model ``name`` accepts."""
    load_plugins()
    if name not in _REGISTRY:
        raise ValueError(f"unknown model {name!r}; allowed: {available()}")
    needs = _REGISTRY[name].needs
    return (_V, _P) if needs is None else (needs,)


def make(
    name: str,
    scene: Scene,
    *,
    key,
    width: int = 256,
    depth: int = 2,
    activation: str | None = None,
    dtype: str = "float32",
    dissipation: bool | None = None,
    **options,
):
    """Build the model ``name`` for ``scene``.

    ``activation`` None takes the model's default (softplus for lnn, as in the LNN seed; tanh
    otherwise). ``dissipation`` None follows ``scene.damped`` for the structured models (hnn,
    hnn_so, lnn, vin, vin_implicit); False forces the plain variant; free models ignore it.
    """
    load_plugins()
    if name not in _REGISTRY:
        close = difflib.get_close_matches(str(name), list(_REGISTRY), n=1)
        hint = f" (closest: {close[0]!r})" if close else ""
        raise ValueError(f"unknown model {name!r}{hint}; allowed: {available()}")
    builder, allowed, structured, needs, default_activation = _REGISTRY[name][1:]
    if not isinstance(scene, Scene):
        raise ValueError(f"scene must be a models.Scene, got {type(scene).__name__}")
    for field, value in (("width", width), ("depth", depth)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ValueError(f"{field} must be an int >= 1, got {value!r}")
    activation = default_activation if activation is None else activation
    if activation not in ACTIVATIONS:
        raise ValueError(f"activation must be one of {sorted(ACTIVATIONS)}, got {activation!r}")
    if dtype not in DTYPES:
        raise ValueError(f"dtype must be one of {DTYPES}, got {dtype!r}")
    unknown = sorted(set(options) - set(allowed))
    if unknown:
        raise ValueError(
            f"unknown option(s) {unknown} for model {name!r}; allowed: {sorted(allowed)}"
        )
    options = {k: allowed[k](v) for k, v in options.items()}
    if dissipation is not None and not isinstance(dissipation, bool):
        raise ValueError(f"dissipation must be None, True or False, got {dissipation!r}")
    if needs == _V and scene.canonical:
        raise ValueError(f"model {name!r} needs velocity coordinates (Scene.canonical=False)")
    if needs == _P and not scene.canonical:
        raise ValueError(f"model {name!r} needs momentum coordinates (Scene.canonical=True)")
    dissipation = (scene.damped if dissipation is None else dissipation) and structured
    return builder(
        scene, width, depth, activation, dtype, key=key, dissipation=dissipation, **options
    )


def n_parameters(model) -> int:
    """The number of trainable scalars of a model."""
    leaves = jax.tree_util.tree_leaves(eqx.filter(model, eqx.is_inexact_array))
    return int(sum(x.size for x in leaves))
