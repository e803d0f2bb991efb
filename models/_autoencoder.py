"""The HNN seed's pixel autoencoder: fully connected, residual, a small latent vector.

Greydanus et al. (2019), section 5.1: "Both the encoder and decoder were composed of four
fully-connected layers with relu activations and residual connections ... 200 hidden units on
all layers except the latent vector z, where we used two units." Its public code
(nn_models.MLPAutoencoder) writes the same shape: in -> h, h + s(W h) twice, h -> latent, and
the mirror image for the decoder, the output linear (no squashing).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.random as jr
from jaxtyping import Array

from ._mlp import ACTIVATIONS, DTYPES


def _linear(key, a: int, b: int, dtype) -> tuple[Array, Array]:
    w = jax.nn.initializers.orthogonal()(key, (a, b), dtype)
    return w, jnp.zeros((b,), dtype)


class _ResidualStack(eqx.Module):
    """x -> h = s(W0 x + b0); h <- h + s(W_i h + b_i) for each residual layer; -> W_out h + b."""

    layers: tuple[tuple[Array, Array], ...]
    activation: str = eqx.field(static=True)

    def __init__(self, in_size, out_size, width, residual, activation, dtype, *, key):
        keys = jr.split(key, residual + 2)
        sizes = [(in_size, width)] + [(width, width)] * residual + [(width, out_size)]
        self.layers = tuple(_linear(k, a, b, dtype) for k, (a, b) in zip(keys, sizes, strict=True))
        self.activation = activation

    def __call__(self, x):
        act = ACTIVATIONS[self.activation]
        (w, b), *mid, (wo, bo) = self.layers
        h = act(x @ w + b)
        for w, b in mid:
            h = h + act(h @ w + b)
        return h @ wo + bo


class Autoencoder(eqx.Module):
    """Observations x of shape ``obs_shape`` (e.g. (2, 28, 28): two stacked frames) <-> latent
    vectors of ``latent`` numbers: ``encode(x)``, ``decode(z)`` (unbatched; vmap for batches).

    Four layers each way (``residual`` = 2 residual layers between the first and the last), as
    in the HNN seed; ``activation`` relu by default (its text)."""

    obs_shape: tuple[int, ...] = eqx.field(static=True)
    latent: int = eqx.field(static=True)
    dtype: str = eqx.field(static=True)
    encoder: _ResidualStack
    decoder: _ResidualStack

    def __init__(
        self,
        obs_shape,
        latent: int = 2,
        width: int = 200,
        residual: int = 2,
        activation: str = "relu",
        dtype: str = "float32",
        *,
        key,
    ):
        obs_shape = tuple(int(s) for s in obs_shape)
        if not obs_shape or any(s < 1 for s in obs_shape):
            raise ValueError(f"obs_shape must be positive sizes; got {obs_shape!r}")
        for name, v, low in (("latent", latent, 1), ("width", width, 1), ("residual", residual, 0)):
            if isinstance(v, bool) or not isinstance(v, int) or v < low:
                raise ValueError(f"{name} must be an int >= {low}; got {v!r}")
        if activation not in ACTIVATIONS:
            raise ValueError(f"activation must be one of {sorted(ACTIVATIONS)}, got {activation!r}")
        if dtype not in DTYPES:
            raise ValueError(f"dtype must be one of {DTYPES}, got {dtype!r}")
        self.obs_shape, self.latent, self.dtype = obs_shape, latent, dtype
        size = 1
        for s in obs_shape:
            size *= s
        ke, kd = jr.split(key)
        self.encoder = _ResidualStack(size, latent, width, residual, activation, dtype, key=ke)
        self.decoder = _ResidualStack(latent, size, width, residual, activation, dtype, key=kd)

    def encode(self, x) -> Array:
        """z = encoder(flatten(x)), shape (latent,)."""
        return self.encoder(jnp.asarray(x, self.dtype).reshape(-1))

    def decode(self, z) -> Array:
        """x_hat = decoder(z), shape ``obs_shape``."""
        return self.decoder(jnp.asarray(z, self.dtype)).reshape(self.obs_shape)

    def __call__(self, x) -> Array:
        return self.decode(self.encode(x))
