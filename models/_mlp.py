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
INITS = ("orthogonal", "lnn", "lnn_notebook", "hnn_seed", "paper")
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
    ``init="hnn_seed"``: the HNN seed's MLP (greydanus/hamiltonian-nn, nn_models.py) as PyTorch
    builds it: orthogonal weights at gain 1, PyTorch's default biases U(-1/sqrt(fan_in),
    1/sqrt(fan_in)) on the hidden layers, none on the output layer (zero here).
    ``init="paper"``: the Deconstructing paper's networks as its code builds them: the
    orthogonal weights of ``"orthogonal"`` (gain 0.5, the same draw), and PyTorch's default
    biases U(-1/sqrt(fan_in), 1/sqrt(fan_in)) on every layer.
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
        if init not in INITS:
            raise ValueError(f"init must be one of {INITS}, got {init!r}")
        sizes = [in_size] + [width] * depth + [out_size]
        n_layers = len(sizes) - 1
        keys = jr.split(key, n_layers)
        weights = []
        for i, (k, a, b) in enumerate(zip(keys, sizes[:-1], sizes[1:], strict=True)):
            if init in ("orthogonal", "paper"):
                w = jax.nn.initializers.orthogonal(scale=gain)(k, (a, b), dtype)
            elif init == "hnn_seed":
                w = jax.nn.initializers.orthogonal(scale=1.0)(k, (a, b), dtype)
            else:
                w = _lnn_sigma(i, n_layers, width) * jr.normal(k, (a, b), dtype)
                if init == "lnn_notebook":
                    w = w * LNN_NOTEBOOK_SCALE
            weights.append(w)
        self.weights = tuple(weights)
        self.biases = tuple(jnp.zeros((b,), dtype) for b in sizes[1:])
        if init == "hnn_seed":  # the hidden layers' biases; their keys apart from the weights'
            bkeys = jr.split(jr.fold_in(key, 1), n_layers)
            self.biases = tuple(
                jr.uniform(k, (b,), dtype, -1.0 / math.sqrt(a), 1.0 / math.sqrt(a))
                for k, a, b in zip(bkeys[:-1], sizes[:-2], sizes[1:-1], strict=True)
            ) + (self.biases[-1],)
        elif init == "paper":  # every layer's bias; their keys apart from the weights'
            bkeys = jr.split(jr.fold_in(key, 1), n_layers)
            self.biases = tuple(
                jr.uniform(k, (b,), dtype, -1.0 / math.sqrt(a), 1.0 / math.sqrt(a))
                for k, a, b in zip(bkeys, sizes[:-1], sizes[1:], strict=True)
            )
        self.activation = activation

    def __call__(self, x: Array) -> Array:
        act = ACTIVATIONS[self.activation]
        for w, b in zip(self.weights[:-1], self.biases[:-1], strict=True):
            x = act(x @ w + b)
        return x @ self.weights[-1] + self.biases[-1]
