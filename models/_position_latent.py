"""The VIN seed's latent model of single frames: each frame is encoded to a *position* q (a
Gaussian posterior, mean and scale), the dynamics carry the velocity, and only positions are
decoded (Saemundsson et al. 2020; the authors' code, steindoringi/Variational_Integrator_Networks,
``PixelLDDN``).

Two latent geometries (``latent``): ``"so2"``, one angle q whose frame is decoded from
(cos q, sin q) (the seed's VIN-SO(2) and, without dynamics, its "Lie group VAE" baseline), and
``"r2"``, a position in the plane decoded from q itself (the seed's VAE and dynamic-VAE
baselines). The dynamics is any registered discrete model (``vin``, ``resnet``, ...) on the
latent :class:`Scene` of the positions (angular for so2), stepped ``step`` latent time units
per frame, or the trivial ``at_rest`` for a model without dynamics (a VAE: each frame is decoded
from its own encoding).

The initial state of a rollout is made from the positions of the first two frames. For the
VIN (velocity Verlet of L = 1/2 v^T M v - U(q), M constant) the initial velocity is the one
whose Verlet step lands exactly on the second position,

    v0 = (d - (q1(v=0) - q0)) / h,   d = q1 - q0 (wrapped on SO(2)),

so that the rollout is the seed's Stormer-Verlet recursion q_{n+1} = 2 q_n - q_{n-1} -
h^2 M^-1 grad U(q_n) through the two encoded positions; for any other model v0 = d / h.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.random as jr
from jaxtyping import Array

from ._autoencoder import _ResidualStack
from ._base import AbstractModel
from ._integrators import Integrator, rollout
from ._registry import make
from ._scene import Scene
from ._spec import spec
from ._vin import VIN

LATENTS = ("so2", "r2")
# The seed's latent time per frame: 0.1 for VIN-SO(2) (its pixels_SO2.gin), 1 for the others
# (pixels.gin)
LATENT_STEP = {"so2": 0.1, "r2": 1.0}
SCALE_FLOOR = 1e-4  # added to the softplus posterior scale


def latent_dof(latent: str) -> int:
    """Position coordinates of a latent geometry: 1 angle (so2), 2 (r2)."""
    if latent not in LATENTS:
        raise ValueError(f"latent must be one of {LATENTS}; got {latent!r}")
    return 1 if latent == "so2" else 2


def wrap(x):
    """Angles to (-pi, pi]."""
    return jnp.arctan2(jnp.sin(x), jnp.cos(x))


class PositionLatentModel(eqx.Module):
    """Frames of ``obs_shape`` <-> positions of the ``latent`` geometry, with dynamics ``name``.

    ``encode(x) -> (mean, scale)`` of the position posterior; ``embed(q)`` the decoder's input
    ((cos q, sin q) on so2, q on r2: the embedding the seed plots); ``decode(q)`` the frame's
    logits (a Bernoulli likelihood, probabilities ``sigmoid``); ``initial_state(q0, q1)`` the
    dynamics' state from two positions; ``positions(z0, n)`` the n positions of a rollout (q0
    held without dynamics); ``forecast(x0, x1, n)`` the probabilities of n frames from two.
    Encoder and decoder: two hidden relu layers of ``ae_width`` each way (the second residual).
    """

    obs_shape: tuple[int, ...] = eqx.field(static=True)
    latent: str = eqx.field(static=True)
    step: float = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    encoder: _ResidualStack
    decoder: _ResidualStack
    dynamics: AbstractModel

    def __init__(
        self,
        name: str,
        obs_shape,
        *,
        key,
        latent: str = "so2",
        width: int = 200,
        depth: int = 1,
        ae_width: int = 200,
        activation: str | None = None,
        dtype: str = "float32",
        step: float | None = None,
        **options,
    ):
        dof = latent_dof(latent)
        s = spec(name)
        if not (s.discrete or name == "at_rest"):
            raise ValueError(
                f"a position latent needs a discrete model or at_rest; got {name!r} (continuous)"
            )
        self.obs_shape = tuple(int(n) for n in obs_shape)
        self.latent, self.dtype = latent, dtype
        self.step = float(LATENT_STEP[latent] if step is None else step)
        size = 1
        for n in self.obs_shape:
            size *= n
        ke, kd, km = jr.split(key, 3)
        self.encoder = _ResidualStack(size, 2 * dof, ae_width, 1, "relu", dtype, key=ke)
        self.decoder = _ResidualStack(2, size, ae_width, 1, "relu", dtype, key=kd)
        scene = Scene(dof=dof, angular=(latent == "so2",) * dof)
        self.dynamics = make(
            name, scene, key=km, width=width, depth=depth, activation=activation, dtype=dtype,
            **options,
        )  # fmt: skip

    @property
    def dof(self) -> int:
        return latent_dof(self.latent)

    @property
    def static(self) -> bool:
        """No dynamics: each frame is decoded from its own encoding (a VAE)."""
        return bool(self.dynamics.trivial)

    def encode(self, x) -> tuple[Array, Array]:
        out = self.encoder(jnp.asarray(x, self.dtype).reshape(-1))
        d = self.dof
        return out[:d], jax.nn.softplus(out[d:]) + SCALE_FLOOR

    def embed(self, q) -> Array:
        q = jnp.asarray(q, self.dtype)
        if self.latent == "so2":
            return jnp.concatenate([jnp.cos(q), jnp.sin(q)], axis=-1)
        return q

    def decode(self, q) -> Array:
        """Logits of the frame at position q, shape ``obs_shape``."""
        return self.decoder(self.embed(q)).reshape(self.obs_shape)

    def difference(self, q0, q1) -> Array:
        """q1 - q0, wrapped on so2."""
        d = q1 - q0
        return wrap(d) if self.latent == "so2" else d

    def initial_state(self, q0, q1) -> Array:
        """The dynamics' state (q0, v0) whose first step reaches q1 (VIN: exactly)."""
        d = self.difference(q0, q1)
        if self.static:
            return jnp.concatenate([q0, jnp.zeros_like(q0)])
        v = d / self.step
        if isinstance(self.dynamics, VIN):  # Verlet: q1(v) = q1(0) + h v exactly
            at_rest = self.dynamics.step(jnp.concatenate([q0, jnp.zeros_like(q0)]), self.step, None)
            v = (d - (at_rest[: self.dof] - q0)) / self.step
        return jnp.concatenate([q0, v])

    def positions(self, z0, n: int) -> Array:
        """(n, dof) positions of the latent rollout from z0 (q0 held without dynamics)."""
        if self.static:
            return jnp.broadcast_to(z0[: self.dof], (n, self.dof))
        ts = jnp.arange(n, dtype=z0.dtype) * self.step
        return rollout(self.dynamics, z0, ts, None, Integrator("euler"))[:, : self.dof]

    def forecast(self, x0, x1, n: int) -> Array:
        """Frame probabilities (n, *obs_shape) from the posterior means of two frames."""
        q0, q1 = self.encode(x0)[0], self.encode(x1)[0]
        qs = self.positions(self.initial_state(q0, q1), n)
        return jax.nn.sigmoid(jax.vmap(self.decode)(qs))
