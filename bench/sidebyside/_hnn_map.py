"""The HNN seed's pixel model against ours, parameter by parameter: which files of its code the
side-by-side needs (:func:`check_seed_code`) and the mapping of its PyTorch ``state_dict`` onto
our ``models.LatentModel`` (:func:`seed_to_ours`, :func:`ours_to_seed`), numpy arrays only.

The seed's ``PixelHNN`` (hnn.py, nn_models.py) and ours, layer by layer (PyTorch's ``Linear``
computes x W^T + b, ours x W + b, so every weight is transposed):

- autoencoder: ``autoencoder.linear1..4`` (encoder: in -> h, h + relu(W h) twice, h -> 2) and
  ``linear5..8`` (decoder, the mirror) are our ``autoencoder.encoder.layers[0..3]`` and
  ``autoencoder.decoder.layers[0..3]``, one to one;
- the HNN: ``hnn.differentiable_model`` is an MLP 2 -> 200 -> 200 -> 2 with no bias on its last
  layer; ``HNN(field_type='solenoidal')`` uses its second output F2 alone (dz/dt = J grad F2),
  the first output's row of ``linear3.weight`` reaches no loss. Ours
  (``dynamics.hamiltonian_part.net``) is 2 -> 200 -> 200 -> 1 with an output bias: its
  output weight is the F2 row, its output bias (a constant added to H) is zero and stays zero;
- the baseline: the same MLP, its two outputs dz/dt; ours (``dynamics.net``) has an output bias
  the seed's lacks: zero at the start, trained (its gradient is the mean residual of the
  dynamics term; :func:`ours_to_seed` returns it apart).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._seed import SeedCodeError, check_checkout  # noqa: F401 (raised through check_checkout)

EXPECTED = ("nn_models.py", "hnn.py", "utils.py", "experiment-pixels/train.py")
REPO = "greydanus/hamiltonian-nn"
ENCODER = tuple(f"autoencoder.linear{i}" for i in (1, 2, 3, 4))
DECODER = tuple(f"autoencoder.linear{i}" for i in (5, 6, 7, 8))
DYNAMICS = tuple(f"hnn.differentiable_model.linear{i}" for i in (1, 2, 3))
OUTPUT_BIAS = "dynamics output bias (ours only)"


def check_seed_code(path) -> Path:
    """``path`` as a Path when it holds every file of :data:`EXPECTED`; else SeedCodeError."""
    return check_checkout(path, REPO, EXPECTED)


def _net(model):
    """Our dynamics MLP: the HNN's H network or the baseline's field network."""
    dyn = model.dynamics
    part = getattr(dyn, "hamiltonian_part", None)
    return (part.net, True) if part is not None else (dyn.net, False)


def ours_to_seed(model) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """(our arrays in the seed's ``state_dict`` layout, ours the seed has no place for). Works
    on a model or on a gradient of one (the same tree). The HNN's unused F1 row is zero."""
    net, is_hnn = _net(model)
    out = {}
    for names, stack in (
        (ENCODER, model.autoencoder.encoder),
        (DECODER, model.autoencoder.decoder),
    ):
        for n, (w, b) in zip(names, stack.layers, strict=True):
            out[f"{n}.weight"] = np.asarray(w).T
            out[f"{n}.bias"] = np.asarray(b)
    ws, bs = net.weights, net.biases
    if len(ws) != len(DYNAMICS):
        raise ValueError(f"our dynamics network has {len(ws)} layers, the seed's {len(DYNAMICS)}")
    for n, w, b in zip(DYNAMICS[:-1], ws[:-1], bs[:-1], strict=True):
        out[f"{n}.weight"] = np.asarray(w).T
        out[f"{n}.bias"] = np.asarray(b)
    w_out = np.asarray(ws[-1]).T  # (out, width)
    if is_hnn:  # F1 (row 0) unused by the solenoidal field; F2 (row 1) is our H
        w_out = np.concatenate([np.zeros_like(w_out), w_out])
    out[f"{DYNAMICS[-1]}.weight"] = w_out
    return out, {OUTPUT_BIAS: np.asarray(bs[-1])}


def seed_to_ours(state, model):
    """``model`` (a LatentModel of the same sizes) with the seed's parameters ``state`` (name
    -> array, its ``state_dict`` layout); our dynamics output bias set to zero."""
    import equinox as eqx
    import jax.numpy as jnp

    net, is_hnn = _net(model)

    def arr(name, like, transpose=False):
        a = np.asarray(state[name])
        a = a.T if transpose else a
        if is_hnn and name == f"{DYNAMICS[-1]}.weight":
            a = np.asarray(state[name])[1:2].T  # the F2 row
        if a.shape != tuple(like.shape):
            raise ValueError(f"{name}: shape {a.shape} against ours {tuple(like.shape)}")
        return jnp.asarray(a, like.dtype)

    def stack_layers(names, stack):
        return tuple(
            (arr(f"{n}.weight", w, True), arr(f"{n}.bias", b))
            for n, (w, b) in zip(names, stack.layers, strict=True)
        )

    enc = stack_layers(ENCODER, model.autoencoder.encoder)
    dec = stack_layers(DECODER, model.autoencoder.decoder)
    if len(net.weights) != len(DYNAMICS):
        raise ValueError(f"our dynamics network has {len(net.weights)} layers, the seed's 3")
    ws = tuple(arr(f"{n}.weight", w, True) for n, w in zip(DYNAMICS, net.weights, strict=True))
    bs = tuple(arr(f"{n}.bias", b) for n, b in zip(DYNAMICS[:-1], net.biases[:-1], strict=True))
    bs = (*bs, jnp.zeros_like(net.biases[-1]))
    model = eqx.tree_at(
        lambda m: (m.autoencoder.encoder.layers, m.autoencoder.decoder.layers), model, (enc, dec)
    )
    net_of = (lambda m: m.dynamics.hamiltonian_part.net) if is_hnn else (lambda m: m.dynamics.net)
    return eqx.tree_at(lambda m: (net_of(m).weights, net_of(m).biases), model, (ws, bs))


def layer_diffs(seed: dict, ours: dict) -> list[tuple[str, float, float, float]]:
    """(name, ||seed||, ||ours||, ||seed - ours|| / ||ours||) per parameter of the seed."""
    out = []
    for name, a in seed.items():
        a, b = np.asarray(a, np.float64), np.asarray(ours[name], np.float64)
        nb = float(np.linalg.norm(b))
        rel = float(np.linalg.norm(a - b) / nb) if nb > 0 else float(np.linalg.norm(a - b))
        out.append((name, float(np.linalg.norm(a)), nb, rel))
    return out
