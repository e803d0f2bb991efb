"""The paper's MuJoCo code beside the suite: which of its files are needed, which of its
classes is which of our controlled models, how its PyTorch parameters map onto them, and the
per-layer comparison of first gradients (:mod:`bench.sidebyside.decon_mujoco` runs them).

| ours | the paper's code (``mujoco.py``, ``dynamics_models.py``) | its networks |
| --- | --- | --- |
| ``node`` | ``NODE`` | ``net`` |
| ``node_so`` | ``CoupledNODE`` | ``net`` |
| ``hnn_force_paper`` | ``MixtureHNN`` | ``potential_net``, ``force_net`` (``mass_net`` unused) |

A MuJoCo scene has no angular coordinate, so our networks' features are the standardised raw
(q, qdot, u), the paper's input: the mapping is exact with our registered classes, and the
mapped model is the suite's own model with the paper's weights put in (no class of its own).
``MixtureHNN``'s ``mass_net`` has no counterpart: its output is multiplied by 0 (M = I), so it
never changes a prediction and its gradient is exactly 0.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._decon import set_mlp
from ._seed import SeedCodeError, check_checkout  # noqa: F401 (raised through check_checkout)

EXPECTED = (
    "mujoco.py",
    "src/models/dynamics_models.py",
    "src/models/utils.py",
    "src/models/hnn.py",
    "src/dynamics/hamiltonian.py",
)
PAPER_CLASSES = {"node": "NODE", "node_so": "CoupledNODE", "hnn_force_paper": "MixtureHNN"}
# Per model: (the paper's state-dict prefix, our model's attribute holding the same MLP)
NETWORKS = {
    "node": (("net", "net"),),
    "node_so": (("net", "net"),),
    "hnn_force_paper": (("potential_net", "potential"), ("force_net", "force")),
}
UNUSED = {"hnn_force_paper": ("mass_net",)}  # the paper's networks that never reach a loss


def check_paper_code(path) -> Path:
    """``path`` as a Path when it holds every file of :data:`EXPECTED`; else SeedCodeError."""
    return check_checkout(path, "ngruver/decon-hnn", EXPECTED, whose="the paper's")


def torch_mlp(state: dict, prefix: str) -> tuple[list, list]:
    """(weights, biases) of our MLP from the paper's ``prefix`` network in ``state`` (numpy
    arrays): an ``nn.Sequential`` of Linear, Tanh, ..., Linear (``prefix.0``, ``prefix.2``,
    ...; a trailing ``Reshape`` has no parameter), torch's (out, in) weights transposed to
    our (in, out)."""
    ws, bs, i = [], [], 0
    while f"{prefix}.{i}.weight" in state:
        ws.append(np.asarray(state[f"{prefix}.{i}.weight"]).T)
        bs.append(np.asarray(state[f"{prefix}.{i}.bias"]))
        i += 2
    if not ws:
        raise KeyError(f"no layer {prefix}.0.weight in the state dict")
    return ws, bs


def mlp_to_torch(weights, biases, prefix: str) -> dict:
    """The inverse of :func:`torch_mlp`."""
    out = {}
    for i, (w, b) in enumerate(zip(weights, biases, strict=True)):
        out[f"{prefix}.{2 * i}.weight"] = np.asarray(w).T
        out[f"{prefix}.{2 * i}.bias"] = np.asarray(b)
    return out


def with_paper_weights(name: str, model, state: dict):
    """Our ``model`` of ``name`` with every network of :data:`NETWORKS` replaced by the
    paper's (``state``: its state dict as numpy arrays)."""
    import equinox as eqx

    for prefix, attr in NETWORKS[name]:
        ws, bs = torch_mlp(state, prefix)
        mlp = set_mlp(getattr(model, attr), ws, bs)
        model = eqx.tree_at(lambda m, a=attr: getattr(m, a), model, mlp)
    return model


def model_to_torch(name: str, model) -> dict:
    """The paper's state dict (its networks of :data:`NETWORKS`) of our ``model``."""
    out = {}
    for prefix, attr in NETWORKS[name]:
        mlp = getattr(model, attr)
        out.update(mlp_to_torch(mlp.weights, mlp.biases, prefix))
    return out


def gradient_rows(name: str, grads_ours, grads_paper: dict) -> list[tuple]:
    """Per layer (network, layer, kind, ||g_paper||, ||g_ours||, relative difference) of the
    first gradient: the paper's (a state dict of numpy arrays) against ours (the gradient
    pytree of our mapped model), and the paper's unused networks' norms (ours 0)."""
    rows = []
    for prefix, attr in NETWORKS[name]:
        ws, bs = torch_mlp(grads_paper, prefix)
        net = getattr(grads_ours, attr)
        for layer, (wp, bp, wo, bo) in enumerate(zip(ws, bs, net.weights, net.biases, strict=True)):
            for kind, xp, xo in (("W", wp, wo), ("b", bp, bo)):
                xp, xo = np.asarray(xp, np.float64), np.asarray(xo, np.float64)
                nrm = float(np.linalg.norm(xo))
                rel = float(np.linalg.norm(xp - xo) / max(nrm, 1e-300))
                rows.append((prefix, layer, kind, float(np.linalg.norm(xp)), nrm, rel))
    for prefix in UNUSED.get(name, ()):
        keys = [k for k in grads_paper if k.startswith(prefix + ".")]
        nrm = float(np.sqrt(sum(np.sum(np.square(grads_paper[k])) for k in keys)))
        rows.append((prefix, "all", "W, b", nrm, 0.0, nrm))
    return rows


def paper_statistics(z: np.ndarray, u: np.ndarray, dt: float, name: str) -> dict:
    """The standardisation the paper's ``train_mujoco_model`` computes from training windows
    z (N, C, 2d) and controls u (N, C, nu), as its lines do it (numpy, float64): ``z_std``
    (the loss's scale, the std clipped at 1e-6), ``input_loc``/``input_scale`` (mean, std of
    the concatenated (x, u), no floor) and for the NODEs ``output_loc``/``output_scale`` (of the
    finite-difference rates: both halves for ``node``, the velocity's for ``node_so``)."""
    d = z.shape[-1] // 2
    xu = np.concatenate((z, u), axis=-1).reshape(-1, 2 * d + u.shape[-1])
    out = {
        "z_std": np.clip(z.reshape(-1, 2 * d).std(0), 1e-6, None),
        "input_loc": xu.mean(0),
        "input_scale": xu.std(0),
    }
    q_fd = (z[:, 1:, :d] - z[:, :-1, :d]) / dt
    v_fd = (z[:, 1:, d:] - z[:, :-1, d:]) / dt
    if name == "node":
        rates = np.concatenate((q_fd, v_fd), axis=-1).reshape(-1, 2 * d)
    elif name == "node_so":
        rates = v_fd.reshape(-1, d)
    else:
        return out
    out["output_loc"], out["output_scale"] = rates.mean(0), rates.std(0)
    return out


def our_statistics(model, scale: np.ndarray, name: str) -> dict:
    """The same quantities from our model's scene standardisation and the run's loss scale."""
    st = model.scene.standardisation
    d = model.scene.dof
    out = {
        "z_std": np.asarray(scale, float),
        "input_loc": np.concatenate([st.q_loc, st.v_loc, st.u_loc]),
        "input_scale": np.concatenate([st.q_scale, st.v_scale, st.u_scale]),
    }
    if name == "node":
        out["output_loc"], out["output_scale"] = np.asarray(st.rate_loc), np.asarray(st.rate_scale)
    elif name == "node_so":
        out["output_loc"] = np.asarray(st.rate_loc[d:])
        out["output_scale"] = np.asarray(st.rate_scale[d:])
    return out


def held_schedule(n_intervals: int, substeps: int) -> np.ndarray:
    """Our controls' schedule: substep s of a rollout holds u_{s // substeps}."""
    return np.arange(n_intervals * substeps) // substeps


def late(values, steps_logged, steps: int) -> float:
    """The geometric mean of ``values`` at the checkpoints ``steps_logged`` in the second half
    of ``steps`` (the last one alone when there is none); NaN if any is not finite."""
    v = np.asarray(values, float)
    s = np.asarray(steps_logged)
    pick = v[s > steps // 2] if np.any(s > steps // 2) else v[-1:]
    if not np.all(np.isfinite(pick)) or np.any(pick <= 0):
        return float("nan")
    return float(np.exp(np.mean(np.log(pick))))


def relative_max(a, b) -> float:
    """max |a - b| / max |b|."""
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    return float(np.max(np.abs(a - b)) / max(float(np.max(np.abs(b))), 1e-300))


def l2_to_gradient(state: dict, grads: dict, prefix: str, weight_decay: float) -> float:
    """||weight_decay theta|| / ||g|| over the paper's ``prefix`` network: how much of the first
    step of its ``Adam(weight_decay=...)`` (an L2 term added to the gradient, then normalised
    per entry) is the decay rather than the data; AdamW's decoupled decay does not enter Adam's
    normalisation."""
    keys = [k for k in grads if k.startswith(prefix + ".")]
    theta = np.sqrt(sum(np.sum(np.square(np.asarray(state[k], float))) for k in keys))
    g = np.sqrt(sum(np.sum(np.square(np.asarray(grads[k], float))) for k in keys))
    return float(weight_decay * theta / max(g, 1e-300))
