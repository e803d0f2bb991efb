"""Learned Hamiltonians: the energy-conservation bias in (q, p)."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.random as jr
from jaxtyping import Array

from ._features import Features
from ._linalg import cho_solve, cholesky
from ._mass import CholeskyNet
from ._mlp import MLP

INVERSE_MASS_JITTER = 1e-4


class GeneralHamiltonian(eqx.Module):
    """H(q, p) = MLP(cos q, sin q, p, args): no assumed structure ("HNN without SO")."""

    features: Features
    net: MLP

    def __init__(
        self, features: Features, width, depth, activation, dtype, *, key, init="orthogonal"
    ):
        self.features = features = features.without_controls()  # H(q, p) never sees u
        self.net = MLP(features.size(True), 1, width, depth, activation, dtype, key=key, init=init)

    def __call__(self, q: Array, p: Array, args: Array) -> Array:
        return self.net(self.features(q, p, args))[0]


class SeparableHamiltonian(eqx.Module):
    """H(q, p) = 1/2 p^T M^-1(q) p + V(q), M^-1 = L L^T + floor I ("HNN with SO").

    L(q) lower-triangular with softplus diagonal from an MLP; V an MLP. ``floor`` (default
    1e-4, :data:`INVERSE_MASS_JITTER`) bounds M^-1's spectrum from below, so M <= I / floor.
    ``init``: both networks' initialisation (:class:`~models._mlp.MLP`; the mass network's
    last layer starts without a bias either way).
    """

    inverse_mass: CholeskyNet
    features: Features
    potential: MLP

    def __init__(
        self,
        features: Features,
        width,
        depth,
        activation,
        dtype,
        *,
        key,
        floor: float = INVERSE_MASS_JITTER,
        init: str = "orthogonal",
    ):
        k1, k2 = jr.split(key)
        self.inverse_mass = CholeskyNet(
            features, width, depth, activation, dtype, key=k1, jitter=floor, init=init
        )
        self.features = features = features.without_controls()  # V(q) never sees u
        self.potential = MLP(
            features.size(False), 1, width, depth, activation, dtype, key=k2, init=init
        )

    def kinetic(self, q: Array, p: Array, args: Array) -> Array:
        lt_p = self.inverse_mass.factor(q, args).T @ p
        return 0.5 * (lt_p @ lt_p) + 0.5 * self.inverse_mass.jitter * (p @ p)

    def potential_energy(self, q: Array, args: Array) -> Array:
        return self.potential(self.features(q, None, args))[0]

    def __call__(self, q: Array, p: Array, args: Array) -> Array:
        return self.kinetic(q, p, args) + self.potential_energy(q, args)

    def acceleration(self, q: Array, v: Array, args: Array, force=None) -> Array:
        """qddot of the flow dq/dt = dH/dp = M^-1 p, dp/dt = -dH/dq + force(q, p, qdot),
        pushed forward to qdot = M^-1(q) p:

            dqdot/dt = M^-1(q) dp/dt + (dM^-1/dt) p,

        with p = M qdot a Cholesky solve with M^-1 and (dM^-1/dt) p one jvp along qdot."""
        inverse_mass = lambda q_: self.inverse_mass.matrix(q_, args)
        minv = inverse_mass(q)
        p = cho_solve(cholesky(minv), v)
        pdot = -jax.grad(self, argnums=0)(q, p, args)
        if force is not None:
            pdot = pdot + force(q, p, v)
        _, dminv_p = jax.jvp(lambda q_: inverse_mass(q_) @ p, (q,), (v,))
        return minv @ pdot + dminv_p
