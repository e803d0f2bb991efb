"""The paper's code beside the suite on the chain pendulum: which of its files are needed, how
its PyTorch parameters map onto our MLPs, the models that its parametrisations make out of our
parts, and the ground-truth comparison (:mod:`bench.sidebyside.decon_hnn` runs them).

Which paper class is which of ours (its plotting notebook, ``bar_plots.ipynb``, labels
``NN``/``MechanicsNN`` "without/with SO bias" among the NODEs and ``NonseparableHNN``/``HNN``
among the HNNs):

| ours | the paper's code | what differs in the model |
| --- | --- | --- |
| ``node_so`` | ``MechanicsNN`` | the paper's state is (q, p), p = M(q) qdot with a learned M^-1 |
| ``hnn`` | ``NonseparableHNN`` | the paper learns M^-1 = L L^T + 1e-4 I, ours M = C C^T |
| ``hnn_so`` | ``HNN`` | nothing (the last layer's bias shift of our Cholesky diagonal) |
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ._seed import SeedCodeError, check_checkout  # noqa: F401 (raised through check_checkout)

EXPECTED = (
    "toy_systems.py",
    "src/models/reduced_hnns.py",
    "src/models/hnn.py",
    "src/models/utils.py",
    "src/systems/chain_pendulum.py",
    "src/systems/rigid_body.py",
    "src/dynamics/hamiltonian.py",
    "src/train/trainer.py",
)
PAPER_CLASSES = {"node_so": "MechanicsNN", "hnn": "NonseparableHNN", "hnn_so": "HNN"}
# The paper's networks of each model: (state-dict prefix, whether it is the mass network)
NETWORKS = {
    "node_so": (("mass_net", True), ("dynamics_net", False)),
    "hnn": (("h_net", False), ("mass_net", True)),
    "hnn_so": (("potential_net", False), ("mass_net", True)),
}
SHIFT = math.log(math.e - 1.0)  # our Cholesky diagonal is softplus(raw + SHIFT) (models._mass)
PAPER_M_EPS = {"node_so": 1e-6, "hnn": 1e-4, "hnn_so": 1e-4}  # eps of the paper's M(q) solve
PAPER_MINV_EPS = 1e-4  # M^-1 = L L^T + 1e-4 I in every paper class


def check_paper_code(path) -> Path:
    """``path`` as a Path when it holds every file of :data:`EXPECTED`; else SeedCodeError."""
    return check_checkout(path, "ngruver/decon-hnn", EXPECTED, whose="the paper's")


# ------------------------------------------------------------------------ parameter mapping
def mass_rows(dof: int) -> tuple[np.ndarray, np.ndarray]:
    """For each of our raw Cholesky entries (``np.tril_indices(dof)`` order, L[i, j], i >= j)
    the output of the paper's mass network that makes it, and whether it is diagonal.

    The paper reshapes its dof^2 outputs row-major into A and takes L = (triu(A, 1) +
    diag(softplus(diag A)))^T, so L[i, j] = A[j, i] (output j dof + i) below the diagonal and
    L[i, i] = softplus(A[i, i]); the outputs A[i, j], i > j, are unused."""
    rows, cols = np.tril_indices(dof)
    return cols * dof + rows, rows == cols


def torch_mlp(state: dict, prefix: str, mass: bool = False, dof: int | None = None):
    """(weights, biases) of our MLP from the paper's ``prefix`` network in ``state`` (a
    state dict of numpy arrays: ``prefix.i.0.weight`` for hidden layer i = 1.., then
    ``prefix.n.weight``); torch's (out, in) weights transposed to our (in, out). A mass
    network's last layer keeps the outputs of :func:`mass_rows`, the diagonal's bias less
    :data:`SHIFT`."""
    ws, bs = [], []
    i = 1
    while f"{prefix}.{i}.0.weight" in state:
        ws.append(np.asarray(state[f"{prefix}.{i}.0.weight"]).T)
        bs.append(np.asarray(state[f"{prefix}.{i}.0.bias"]))
        i += 1
    w, b = np.asarray(state[f"{prefix}.{i}.weight"]).T, np.asarray(state[f"{prefix}.{i}.bias"])
    if mass:
        dof = dof if dof is not None else math.isqrt(w.shape[1])
        idx, diag = mass_rows(dof)
        w, b = w[:, idx], b[idx] - SHIFT * diag
    ws.append(w)
    bs.append(b)
    return ws, bs


def mlp_to_torch(weights, biases, prefix: str, mass: bool = False) -> dict:
    """The inverse of :func:`torch_mlp` (a mass network's unused outputs are zero)."""
    out, n = {}, len(weights)
    for i, (w, b) in enumerate(zip(weights, biases, strict=True)):
        w, b = np.asarray(w), np.asarray(b)
        if i == n - 1 and mass:
            dof = int(round((math.sqrt(8 * w.shape[1] + 1) - 1) / 2))
            idx, diag = mass_rows(dof)
            full_w = np.zeros((w.shape[0], dof * dof), w.dtype)
            full_b = np.zeros(dof * dof, b.dtype)
            full_w[:, idx], full_b[idx] = w, b + SHIFT * diag
            w, b = full_w, full_b
        key = f"{prefix}.{i + 1}.0" if i < n - 1 else f"{prefix}.{n}"
        out[f"{key}.weight"], out[f"{key}.bias"] = w.T, b
    return out


def paper_minv(state: dict, prefix: str, features: np.ndarray, eps: float = PAPER_MINV_EPS):
    """The paper's M^-1 = L L^T + eps I at network inputs ``features`` (N, n_in), in numpy
    (tanh hidden layers): a reference for tests of the mapping."""
    ws, bs = [], []
    i = 1
    while f"{prefix}.{i}.0.weight" in state:
        ws.append(state[f"{prefix}.{i}.0.weight"])
        bs.append(state[f"{prefix}.{i}.0.bias"])
        i += 1
    x = features
    for w, b in zip(ws, bs, strict=True):
        x = np.tanh(x @ w.T + b)
    a = x @ state[f"{prefix}.{i}.weight"].T + state[f"{prefix}.{i}.bias"]
    dof = math.isqrt(a.shape[1])
    a = a.reshape(-1, dof, dof)
    diag = np.log1p(np.exp(np.diagonal(a, axis1=1, axis2=2)))
    upper = np.triu(a, 1) + diag[:, :, None] * np.eye(dof)
    lower = np.swapaxes(upper, 1, 2)
    return lower @ np.swapaxes(lower, 1, 2) + eps * np.eye(dof)


def set_mlp(mlp, weights, biases):
    """``mlp`` (our MLP) with the given arrays, cast to its dtype; shapes must agree."""
    import equinox as eqx
    import jax.numpy as jnp

    if len(weights) != len(mlp.weights):
        raise ValueError(f"{len(weights)} layers against {len(mlp.weights)}")
    ws, bs = [], []
    for w, b, w0, b0 in zip(weights, biases, mlp.weights, mlp.biases, strict=True):
        if tuple(np.shape(w)) != tuple(w0.shape) or tuple(np.shape(b)) != tuple(b0.shape):
            raise ValueError(f"shapes {np.shape(w)}, {np.shape(b)} against {w0.shape}, {b0.shape}")
        ws.append(jnp.asarray(w, w0.dtype))
        bs.append(jnp.asarray(b, b0.dtype))
    return eqx.tree_at(lambda m: (m.weights, m.biases), mlp, (tuple(ws), tuple(bs)))


# ------------------------------------------------------------------------ ground truth
def cartesian_to_angular(q, vel, acc, lengths):
    """(qdot, qddot) (N, k) of a planar chain from its bobs' Cartesian velocities and
    accelerations (N, k, 2): link j's vector r_j = l_j (sin q_j, -cos q_j) has
    r_j' = l_j qdot_j u_j and r_j'' . u_j = l_j qddot_j with u_j = (cos q_j, sin q_j)."""
    q, vel, acc = (np.asarray(x, np.float64) for x in (q, vel, acc))
    u = np.stack([np.cos(q), np.sin(q)], axis=-1)
    rel_v = np.diff(vel, axis=1, prepend=np.zeros_like(vel[:, :1]))
    rel_a = np.diff(acc, axis=1, prepend=np.zeros_like(acc[:, :1]))
    lengths = np.asarray(lengths, np.float64)
    return (rel_v * u).sum(-1) / lengths, (rel_a * u).sum(-1) / lengths


def relative_max(a, b) -> float:
    """max |a - b| / max |b|."""
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


def field_difference(system, states, qdot, qddot, energy=None) -> dict:
    """The paper's (or any) chain field (qdot, qddot) and energy at ``states`` (N, 2k) against
    ``system``'s: max relative differences of qdot, qddot and the energy (the last relative to
    the largest |E|)."""
    import jax

    import systems

    states = np.asarray(states, np.float64)
    ours = systems.derivatives(system, states)
    k = states.shape[1] // 2
    out = {
        "qdot": relative_max(qdot, ours[:, :k]),
        "qddot": relative_max(qddot, ours[:, k:]),
    }
    if energy is not None:
        e = np.asarray(jax.vmap(lambda z: system.energy(z))(states), np.float64)
        out["energy"] = relative_max(energy, e)
    return out


def wrapped_difference(a, b, k: int) -> np.ndarray:
    """a - b of (..., 2k) states with the angle entries wrapped to (-pi, pi]."""
    d = np.asarray(a, np.float64) - np.asarray(b, np.float64)
    d[..., :k] = np.pi - np.mod(np.pi - d[..., :k], 2 * np.pi)
    return d


# ------------------------------------------------------------------------ paper-form models
def paper_node_so_class():
    """The paper's ``MechanicsNN`` made of our parts (a class, built lazily: equinox)."""
    import equinox as eqx
    import jax
    import jax.numpy as jnp

    from models import AbstractContinuousModel, CanonicalSecondOrderODE, cho_solve, cholesky

    class PaperNodeSO(AbstractContinuousModel):
        """In y = (q, p): dq/dt = M^-1(q) p (M^-1 = L L^T + 1e-4 I, our ``CholeskyNet``),
        dp/dt = MLP(cos q, sin q, p) (``node_so_symreg``'s field without its penalty); from
        (q, qdot) by p = (L L^T + 1e-6 I)^-1 qdot and back by qdot = M^-1 p, the paper's two
        epsilons."""

        scene: object = eqx.field(static=True)
        dtype: str = eqx.field(static=True)
        inner: CanonicalSecondOrderODE

        def __init__(self, scene, width, depth, activation, dtype, *, key):
            self.scene, self.dtype = scene, dtype
            self.inner = CanonicalSecondOrderODE(
                scene, width, depth, activation, dtype, key=key, weight=0.0
            )

        def encode(self, z, args):
            q, v = z[: self.scene.dof], z[self.scene.dof :]
            c = self.inner.inverse_mass.factor(q, args)
            minv = c @ c.T + PAPER_M_EPS["node_so"] * jnp.eye(self.scene.dof, dtype=c.dtype)
            return jnp.concatenate([q, cho_solve(cholesky(minv), v)])

        def decode(self, y, args):
            q, p = y[: self.scene.dof], y[self.scene.dof :]
            return jnp.concatenate([q, self.inner.inverse_mass.matrix(q, args) @ p])

        def internal_field(self, t, y, args):
            return self.inner.vector_field(t, y, args)

        def vector_field(self, t, z, args):
            y = self.encode(z, args)
            dy = self.internal_field(t, y, args)
            return jax.jvp(lambda y_: self.decode(y_, args), (y,), (dy,))[1]

    return PaperNodeSO


def paper_mass_class():
    """The paper's momentum map for our ``HNN``: a ``factor(q, args)`` C with C C^T = M =
    (L L^T + 1e-4 I)^-1, L from our ``CholeskyNet`` (a class, built lazily)."""
    import equinox as eqx
    import jax.numpy as jnp

    from models import CholeskyNet, cholesky

    class PaperMass(eqx.Module):
        inverse: CholeskyNet

        def factor(self, q, args):
            return cholesky(jnp.linalg.inv(self.inverse.matrix(q, args)))

    return PaperMass


def build_mapped(name: str, scene, config, dtype: str, state: dict | None, key):
    """Our model in the paper's parametrisation of ``name`` (:data:`PAPER_CLASSES`), with the
    paper's parameters ``state`` (None: our own draw). ``node_so``: :func:`paper_node_so_class`;
    ``hnn``: our HNN with :func:`paper_mass_class`; ``hnn_so``: our hnn_so itself."""
    import equinox as eqx

    import models
    from models import INVERSE_MASS_JITTER, CholeskyNet

    width, depth, act = config.width, config.depth, config.activation or "tanh"
    if name == "node_so":
        model = paper_node_so_class()(scene, width, depth, act, dtype, key=key)
    elif name == "hnn":
        model = models.make("hnn", scene, key=key, width=width, depth=depth, dtype=dtype)
        feats = models.Features(scene)
        inv = CholeskyNet(feats, width, depth, act, dtype, key=key, jitter=INVERSE_MASS_JITTER)
        model = eqx.tree_at(lambda m: m.mass, model, paper_mass_class()(inv))
    elif name == "hnn_so":
        model = models.make("hnn_so", scene, key=key, width=width, depth=depth, dtype=dtype)
    else:
        raise ValueError(f"model {name!r}: one of {', '.join(PAPER_CLASSES)}")
    if state is None:
        return model
    for prefix, mass in NETWORKS[name]:
        ws, bs = torch_mlp(state, prefix, mass, scene.dof)
        new = set_mlp(network(name, model, prefix), ws, bs)
        model = eqx.tree_at(lambda m, p=prefix: network(name, m, p), model, new)
    return model


def first_point_term(model, z0, n_points: int):
    """What the paper's rollout adds to the loss at t = 0 and ours does not: its prediction at
    t = 0 is decode(encode(z0)), ours z0 itself, so the paper's mean over (B, C, 2k) has the
    extra mean((decode(encode(z0)) - z0)^2) / C (a jax scalar; zero up to rounding unless the
    two maps disagree, as ``MechanicsNN``'s 1e-6 and 1e-4 do)."""
    import jax
    import jax.numpy as jnp

    args = jnp.zeros((0,), z0.dtype)
    back = jax.vmap(lambda z: model.decode(model.encode(z, args), args))(z0)
    return jnp.mean((back - z0) ** 2) / n_points


# The paper's network that has a place in the suite's own model of the same name (the rest of
# the suite's model keeps its own draw): NODE+SO's force network is our acceleration network
# (its input p, ours qdot), NonseparableHNN's H network is our H network.
SUITE_PLACES = {
    "node_so": ("dynamics_net", lambda m: m.net),
    "hnn": ("h_net", lambda m: m.hamiltonian_part.net),
}


def suite_with_paper(name: str, suite_model, state: dict):
    """The suite's own model of ``name`` with the paper's network of :data:`SUITE_PLACES`
    copied in; None where there is no partial map (``hnn_so`` maps whole: ``mapped``)."""
    import equinox as eqx

    if name not in SUITE_PLACES:
        return None
    prefix, where = SUITE_PLACES[name]
    ws, bs = torch_mlp(state, prefix)
    return eqx.tree_at(where, suite_model, set_mlp(where(suite_model), ws, bs))


def network(name: str, model, prefix: str):
    """Our MLP that the paper's network ``prefix`` of model ``name`` maps to."""
    paths = {
        ("node_so", "mass_net"): lambda m: m.inner.inverse_mass.net,
        ("node_so", "dynamics_net"): lambda m: m.inner.net,
        ("hnn", "h_net"): lambda m: m.hamiltonian_part.net,
        ("hnn", "mass_net"): lambda m: m.mass.inverse.net,
        ("hnn_so", "potential_net"): lambda m: m.hamiltonian_part.potential,
        ("hnn_so", "mass_net"): lambda m: m.hamiltonian_part.inverse_mass.net,
    }
    return paths[(name, prefix)](model)


def gradient_rows(name: str, grads_ours, grads_paper: dict, dof: int) -> list[tuple]:
    """Per layer (network, layer, kind, ||g_paper||, ||g_ours||, relative difference) of the
    first gradient: the paper's (a state dict of numpy arrays) mapped by :func:`torch_mlp`
    (no bias shift: a constant) against ours (a gradient pytree of our mapped model)."""
    rows = []
    for prefix, mass in NETWORKS[name]:
        ws, bs = torch_mlp(grads_paper, prefix, mass, dof)
        if mass:  # the shift is a constant: the gradient of the bias is the paper's own
            idx, _ = mass_rows(dof)
            i = len(ws)
            bs[-1] = np.asarray(grads_paper[f"{prefix}.{i}.bias"])[idx]
        net = network(name, grads_ours, prefix)
        for layer, (wp, bp, wo, bo) in enumerate(zip(ws, bs, net.weights, net.biases, strict=True)):
            for kind, xp, xo in (("W", wp, wo), ("b", bp, bo)):
                xp, xo = np.asarray(xp, np.float64), np.asarray(xo, np.float64)
                nrm = float(np.linalg.norm(xo))
                rel = float(np.linalg.norm(xp - xo) / max(nrm, 1e-300))
                rows.append((prefix, layer, kind, float(np.linalg.norm(xp)), nrm, rel))
    return rows
