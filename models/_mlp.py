"""The multilayer perceptron that every learned part is made of."""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.random as jr
from jaxtyping import Array

ACTIVATIONS = {
    "tanh": jnp.tanh,
    "softplus": jax.nn.softplus,
    "relu": jax.nn.relu,
    "gelu": jax.nn.gelu,
    "silu": jax.nn.silu,
    "sigmoid": jax.nn.sigmoid,
}
INITS = ("orthogonal", "lnn", "lnn_notebook")
# The LNN seed's notebook (DoublePendulum.ipynb) divides every appendix-B parameter by 200
LNN_NOTEBOOK_SCALE = 1.0 / 200.0
DTYPES = ("float32", "float64")


def _lnn_sigma(layer: int, n_layers: int, width: int) -> float:
    """LNN seed, appendix B, eq. 3: sigma = (1/sqrt(n)) x {2.2 first, 0.58 i hidden i, n output}."""
    if layer == 0:
        return 2.2 / math.sqrt(width)
    if layer == n_layers - 1:
        return width / math.sqrt(width)
    return 0.58 * layer / math.sqrt(width)


class MLP(eqx.Module):
    """y = W_D s(... s(W_1 x + b_1) ...) + b_D with ``depth`` hidden layers of ``width`` units.

    ``init="orthogonal"``: orthogonal weights with gain ``gain`` (0.5 in the paper), zero
    biases. ``init="lnn"``: Gaussian weights with the LNN seed's per-layer sigma, zero biases;
    ``init="lnn_notebook"``: the same divided by 200 (an optimiser state the seed's notebook
    built and then replaced before training; an ablation).
    """

    weights: tuple[Array, ...]
    biases: tuple[Array, ...]
    activation: str = eqx.field(static=True)

    def __init__(
        self,
        in_size: int,
        out_size: int,
        width: int,
        depth: int,
        activation: str,
        dtype: str,
        *,
        key,
        init: str = "orthogonal",
        gain: float = 0.5,
    ):
        sizes = [in_size] + [width] * depth + [out_size]
        n_layers = len(sizes) - 1
        keys = jr.split(key, n_layers)
        weights = []
        for i, (k, a, b) in enumerate(zip(keys, sizes[:-1], sizes[1:], strict=True)):
            if init == "orthogonal":
                w = jax.nn.initializers.orthogonal(scale=gain)(k, (a, b), dtype)
            else:
                w = _lnn_sigma(i, n_layers, width) * jr.normal(k, (a, b), dtype)
                if init == "lnn_notebook":
                    w = w * LNN_NOTEBOOK_SCALE
            weights.append(w)
        self.weights = tuple(weights)
        self.biases = tuple(jnp.zeros((b,), dtype) for b in sizes[1:])
        self.activation = activation

    def __call__(self, x: Array) -> Array:
        act = ACTIVATIONS[self.activation]
        for w, b in zip(self.weights[:-1], self.biases[:-1], strict=True):
            x = act(x @ w + b)
        return x @ self.weights[-1] + self.biases[-1]
