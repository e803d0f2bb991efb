"""The HNN of the paper's controlled (MuJoCo) experiment: a separable Hamiltonian plus a free
learned force F(q, p, u) on dp/dt (hnn_force), and the same model as the paper's code runs it
(hnn_force_paper)."""

from __future__ import annotations

from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.random as jr

from ._base import AbstractContinuousModel, as_dtype, split
from ._features import Features
from ._hamiltonian import INVERSE_MASS_JITTER, SeparableHamiltonian
from ._hnn import AbstractSeparableHNN
from ._mlp import MLP
from ._scene import Scene


class ForcedHNN(AbstractSeparableHNN):
    """A separable HNN with a non-conservative learned force, in z = (q, qdot):

        dq/dt = dH/dp = M^-1(q) p,   dp/dt = -dH/dq + F(q, p, u),
        H = 1/2 p^T M^-1(q) p + V(q),   M^-1 = L L^T + floor I,   p = M(q) qdot,

    F = MLP(cos q, sin q, p, args, u). H, M and V never see u (their features leave it out);
    F enters dp/dt only, so dq/dt = qdot exactly (second order) and
    dH/dt = qdot . F(q, p, u): H is conserved only where F = 0. ``rollout`` integrates the
    flow in y = (q, p) (``encode``/``decode``/``internal_field``) like ``hnn_so``.

    The paper's code (ngruver/decon-hnn, ``src/models/dynamics_models.py``, ``MixtureHNN``)
    has the same field with F = force_net(q, p, u); there the learned Cholesky factor of
    M^-1 is multiplied by 0, so M = I and p = qdot. Ours keeps the suite's learned M^-1(q) (the
    ``hnn_so`` Hamiltonian, which can represent M = I): MuJoCo's generalised coordinates have
    configuration-dependent inertia. Angles enter through (cos q, sin q) as everywhere here.

    ``inverse_mass_floor`` (default 1e-4, ``hnn_so``'s jitter) is the floor under M^-1's
    spectrum, so M <= I / floor. Integrated by explicit Euler, a learned M^-1 that turns
    near-singular makes the flow stiff and training blows up with a finite loss
    (docs/studies/mujoco.md); a floor of 0.1 keeps it trainable and still lets M vary tenfold.
    """

    takes_controls: ClassVar[bool] = True
    forced: ClassVar[bool] = True

    scene: Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    hamiltonian_part: SeparableHamiltonian
    features: Features
    force: MLP

    def __init__(
        self,
        scene,
        width,
        depth,
        activation,
        dtype,
        *,
        key,
        inverse_mass_floor: float = INVERSE_MASS_JITTER,
    ):
        self.scene, self.dtype = scene, dtype
        kh, kf = jr.split(key)
        self.features = Features(scene)  # F's input: (q, p, args, u)
        self.hamiltonian_part = SeparableHamiltonian(  # leaves u out of M^-1 and V
            self.features, width, depth, activation, dtype, key=kh, floor=inverse_mass_floor
        )
        self.force = MLP(
            self.features.size(True), scene.dof, width, depth, activation, dtype, key=kf
        )

    def force_term(self, q, p, args):
        """F(q, p, u): the generalised force added to dp/dt."""
        return self.force(self.features(q, p, args))

    def has_force(self) -> bool:
        return True

    def generalized_force(self, q, p, v, args):
        return self.force_term(q, p, args)


class ReferenceForcedHNN(AbstractContinuousModel):
    """The controlled HNN as the Deconstructing paper's code runs it (``MixtureHNN`` of
    ngruver/decon-hnn, ``src/models/dynamics_models.py``), beside ``hnn_force`` to measure what
    that construction costs Fig. 7's HNN. In z = (q, qdot), with the scene's standardisation
    (loc, scale of q and of qdot):

        H(q_s, p_s) = 1/2 |p_s|^2 + V(q),   p = qdot (M = I: the code multiplies its learned
        factor of M^-1 by 0),   q_s = (q - q_loc) / q_scale,   p_s = (qdot - v_loc) / v_scale,

        dq/dt = dH/dp_s = (qdot - v_loc) / v_scale,   dqdot/dt = -dH/dq_s + F(q, qdot, u),

    the gradient taken in the standardised state and used as the rate of the raw one, as the
    code does (so dH/dq_s = q_scale * dV/dq). Its position update is thus fixed, with no
    trainable parameter: one Euler step of dt per transition (the code's) has a floor on the
    training error wherever v_scale is not 1 (``examples/mujoco/reference_hnn_floor.py``).
    Without a standardisation it is an HNN with M = I and a free force. V and F are the
    suite's MLPs on its features (angles as (cos q, sin q), where the code standardises them).
    Not a model to learn dynamics with: a record of what the paper's HNN was.
    """

    takes_controls: ClassVar[bool] = True
    forced: ClassVar[bool] = True

    scene: Scene = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    features: Features
    potential: MLP
    force: MLP

    def __init__(self, scene, width, depth, activation, dtype, *, key):
        self.scene, self.dtype = scene, dtype
        kv, kf = jr.split(key)
        self.features = Features(scene)  # F's input: (q, qdot, args, u)
        v_features = self.features.without_controls()  # V(q) never sees u
        self.potential = MLP(v_features.size(False), 1, width, depth, activation, dtype, key=kv)
        self.force = MLP(
            self.features.size(True), scene.dof, width, depth, activation, dtype, key=kf
        )

    def potential_energy(self, q, args):
        return self.potential(self.features.without_controls()(q, None, args))[0]

    def vector_field(self, t, z, args):
        q, v = split(as_dtype(z, self.dtype))
        args = as_dtype(args, self.dtype)
        st = self.scene.standardisation
        q_scale = jnp.ones_like(q) if st is None else jnp.asarray(st.q_scale, self.dtype)
        v_loc = jnp.zeros_like(v) if st is None else jnp.asarray(st.v_loc, self.dtype)
        v_scale = jnp.ones_like(v) if st is None else jnp.asarray(st.v_scale, self.dtype)
        dv_dq = jax.grad(self.potential_energy)(q, args)
        qdot = (v - v_loc) / v_scale
        vdot = -q_scale * dv_dq + self.force(self.features(q, v, args))
        return jnp.concatenate([qdot, vdot])
