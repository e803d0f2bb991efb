"""The LNN seed's relativistic-particle notebooks, loaded beside the suite: each notebook's own
definitions (its equation of motion, loss, data sampler, schedule and Adam), its initial
parameters and its printed training log, and the maps between its states and our models'
(:mod:`bench.sidebyside.lnn_relativistic` runs them)."""

from __future__ import annotations

import ast
import json
import re
import sys
import types
from functools import partial
from pathlib import Path

import numpy as np

from ._seed import SeedCodeError, _last_definitions, _module, _shim, check_checkout

# model -> (notebook, its equation of motion)
NOTEBOOKS = {
    "lnn": ("notebooks/SpecialRelativity.ipynb", "lagrangian_eom"),
    "hnn_naive": ("notebooks/SpecialRelativity-HNN.ipynb", "hamiltonian_eom"),
    "hnn_p": ("notebooks/SpecialRelativity-HNN-CorrectP.ipynb", "hamiltonian_eom"),
}
MODELS = tuple(NOTEBOOKS)
EXPECTED = ("lnn.py", "hyperopt/HyperparameterSearch.py", *(nb for nb, _ in NOTEBOOKS.values()))
N_INPUT = 3  # the notebooks' network input: (q, qdot or p, g)
_LOG = re.compile(r"epoch=(\d+) lr=\S+ loss=([0-9.eE+-]+)")


def check_seed_code(path) -> Path:
    """``path`` as a Path when it holds every file of :data:`EXPECTED`; else SeedCodeError."""
    return check_checkout(path, "MilesCranmer/lagrangian_nns", EXPECTED)


def _cells(nb: dict) -> list[str]:
    return [
        "".join(c["source"]) if isinstance(c["source"], list) else c["source"]
        for c in nb.get("cells", [])
        if c.get("cell_type") == "code"
    ]


def printed_log(nb: dict) -> list[tuple[int, float]]:
    """The (epoch, loss) lines the notebook's training loop printed (empty if none)."""
    out = []
    for c in nb.get("cells", []):
        for o in c.get("outputs", []):
            text = o.get("text", "")
            text = "".join(text) if isinstance(text, list) else text
            out += [(int(e), float(x)) for e, x in _LOG.findall(text)]
    return out


_BATCH = re.compile(r"cstate, cconditionals, ctarget = gen_data_batch\((?:epoch|0), (\d+)\)")
_VALUE = re.compile(r"DeviceArray\(([0-9.eE+-]+)")


def printed_init_loss(nb: dict) -> tuple[int, float] | None:
    """``(n, loss)``: the loss the notebook printed at its initial parameters on its batch
    ``gen_data_batch(0, n)`` (the cells ``cstate, cconditionals, ctarget = gen_data_batch(epoch,
    n)`` at epoch 0, then ``loss(get_params(opt_state), ...)``); None when it printed none."""
    n = None
    for c in nb.get("cells", []):
        src = "".join(c["source"]) if isinstance(c.get("source"), list) else c.get("source", "")
        m = _BATCH.search(src)
        if m and c.get("cell_type") == "code":
            n = int(m.group(1))
        if n and src.strip().startswith("loss(get_params(opt_state)"):
            for o in c.get("outputs", []):
                text = o.get("data", {}).get("text/plain", "")
                v = _VALUE.search("".join(text) if isinstance(text, list) else text)
                if v:
                    return n, float(v.group(1))
    return None


def _parse(cells):
    for src in cells:
        try:
            yield ast.parse(src)
        except SyntaxError:  # a cell with IPython magics: none of ours
            continue


def loop_batch(cells: list[str]) -> int:
    """The minibatch size the notebook's training loop sets (``batch = 512`` in its loop)."""
    value = None
    for tree in _parse(cells):
        for loop in (n for n in tree.body if isinstance(n, ast.For)):
            for node in ast.walk(loop):
                if (
                    isinstance(node, ast.Assign)
                    and [getattr(t, "id", None) for t in node.targets] == ["batch"]
                    and isinstance(node.value, ast.Constant)
                ):
                    value = int(node.value.value)
    if value is None:
        raise SeedCodeError("the notebook's training loop sets no batch size")
    return value


def custom_init_seed(cells: list[str]) -> int | None:
    """The ``seed`` of the notebook's ``init_params = custom_init(init_params, seed=...)`` (the
    LNN's appendix-B initialisation), or None when the notebook keeps stax's initialisation."""
    value = None
    for tree in _parse(cells):
        for node in tree.body:
            call = getattr(node, "value", None)
            if (
                isinstance(node, ast.Assign)
                and isinstance(call, ast.Call)
                and getattr(call.func, "id", None) == "custom_init"
            ):
                kw = {k.arg: k.value for k in call.keywords}
                seed = kw.get("seed")
                value = int(seed.value) if isinstance(seed, ast.Constant) else 0
    return value


def load_notebook(root, model: str) -> types.SimpleNamespace:
    """One relativistic notebook's code as a namespace: ``init(seed)`` its initial parameters
    (stax's init at PRNGKey(seed), then ``custom_init`` where the notebook calls it), ``loss``,
    ``update_derivative``, ``OneCycleLR``, ``opt_init``, ``opt_update``, ``get_params``,
    ``gen_data_batch``, ``qdotdot``, ``eom(params, states, g)`` its predictions as its loss
    compares them, ``args``, ``batch`` (its loop's), ``minibatch_per``, ``steps`` (epochs x
    minibatches), ``lr``, ``log`` (its printed (epoch, loss) lines) and ``printed_init`` (its
    printed loss at initialisation, :func:`printed_init_loss`)."""
    import jax
    import jax.numpy as jnp

    root = check_seed_code(root)
    if model not in NOTEBOOKS:
        raise ValueError(f"model {model!r}: one of {', '.join(MODELS)}")
    nb_path, eom_name = NOTEBOOKS[model]
    _shim()
    sys.path.insert(0, str(root))
    try:
        lnn = _module(root / "lnn.py", "_seed_lnn")
    finally:
        sys.path.remove(str(root))
    from jax.example_libraries import optimizers, stax

    ns = {"jax": jax, "jnp": jnp, "np": np, "jit": jax.jit, "partial": partial}
    ns |= {"stax": stax, "optimizers": optimizers}
    hs = (root / "hyperopt" / "HyperparameterSearch.py").read_text()
    imports = [
        n
        for n in ast.parse(hs).body
        if isinstance(n, ast.ImportFrom) and (n.module or "").startswith("jax")
    ]
    hs_defs = _last_definitions([hs], {"swish", "relu3", "Swish", "Relu3", "extended_mlp"})
    try:
        nb = json.loads((root / nb_path).read_text())
    except json.JSONDecodeError as e:
        raise SeedCodeError(f"{nb_path}: not a notebook ({e})") from None
    cells = _cells(nb)
    order = ("ObjectView", "args", eom_name, "learned_dynamics", "qdotdot", "gen_data_batch")
    order += ("total_epochs", "minibatch_per", "lr", "final_div_factor", "OneCycleLR")
    order += ("opt_init", "loss", "update_derivative")
    nb_defs = _last_definitions(cells, set(order))
    body, seen = [], set()
    for node in [*imports, *(hs_defs[n] for n in ("swish", "relu3", "Swish", "Relu3"))] + [
        hs_defs["extended_mlp"],
        *(nb_defs[n] for n in order),
    ]:
        if id(node) not in seen:  # one statement may define several names
            seen.add(id(node))
            body.append(node)
    code = compile(ast.Module(body=body, type_ignores=[]), f"<the seed's {nb_path}>", "exec")
    with jax.enable_x64(False):
        exec(code, ns)  # noqa: S102 - the seed's code, by the user's --seed-code
        init_random_params, ns["nn_forward_fn"] = ns["extended_mlp"](ns["args"])
    cinit = custom_init_seed(cells)

    def init(seed: int = 0):
        """The notebook's: stax's init at PRNGKey(seed) (+ ``custom_init`` where it calls it)."""
        with jax.enable_x64(False):
            _, params = init_random_params(jax.random.PRNGKey(seed), (-1, N_INPUT))
            return params if cinit is None else lnn.custom_init(params, seed=seed)

    def eom(params, states, g):
        runner = jax.vmap(
            partial(ns[eom_name], ns["learned_dynamics"](params, ns["nn_forward_fn"]))
        )
        field = runner(states, g)
        return field[:, 1:] if model == "lnn" else field  # what the notebook's loss compares

    return types.SimpleNamespace(
        model=model,
        notebook=nb_path,
        init=init,
        custom_init=cinit,
        loss=ns["loss"],
        update_derivative=ns["update_derivative"],
        OneCycleLR=ns["OneCycleLR"],
        opt_init=ns["opt_init"],
        opt_update=ns["opt_update"],
        get_params=ns["get_params"],
        gen_data_batch=ns["gen_data_batch"],
        qdotdot=ns["qdotdot"],
        eom=jax.jit(eom),
        args=ns["args"],
        batch=loop_batch(cells),
        minibatch_per=int(ns["minibatch_per"]),
        steps=int(ns["total_epochs"]) * int(ns["minibatch_per"]),
        lr=float(ns["lr"]),
        log=printed_log(nb),
        printed_init=printed_init_loss(nb),
    )


# ------------------------------------------------------------------------ the state maps
def momentum(v):
    """The canonical momentum p = qdot (1 - qdot^2)^(-3/2) (c = 1, unit mass)."""
    return v / (1.0 - v**2) ** 1.5


def pdot_to_qddot(pdot, v):
    """qddot = pdot (1 - qdot^2)^(5/2) / (1 + 2 qdot^2), the notebook's map back."""
    return pdot * (1.0 - v**2) ** 2.5 / (1.0 + 2.0 * v**2)


def to_ours(model: str, state, g, target):
    """The notebook's batch (states (N, 2) = (q, qdot), g (N, 1), its targets, qddot last) in
    the coordinates our model of ``model`` reads and predicts, so that it computes what the
    notebook's does: ``(z (N, 2), args (N, 1), dz (N, 2))``.

    - lnn, hnn_naive: z = (q / 10, qdot), args = g / 10 (the notebooks divide q and g by 10
      before their networks and differentiate in q / 10); dz = (qdot, qddot);
    - hnn_p: z = (q, p), args = g / 10 (the notebook leaves q raw); dz = (qdot, dp/dt = g).
    """
    state, g, target = (np.asarray(x, float) for x in (state, g, target))
    q, v = state[:, :1], state[:, 1:]
    if model == "hnn_p":
        return np.concatenate([q, momentum(v)], 1), g / 10.0, np.concatenate([v, g], 1)
    return np.concatenate([q / 10.0, v], 1), g / 10.0, np.concatenate([v, target[:, -1:]], 1)


def seed_form(model: str, field, v, xp=np):
    """Our model's dz/dt in its coordinates as the notebook's loss compares it: qddot alone
    (lnn), (qdot, qddot) (hnn_naive), (qdot, pdot mapped to qddot) (hnn_p)."""
    if model == "lnn":
        return field[:, 1:]
    if model == "hnn_p":
        return xp.concatenate([field[:, :1], pdot_to_qddot(field[:, 1:], v)], 1)
    return field


def seed_targets(model: str, state, g):
    """The notebook's targets at (q, qdot) = ``state`` and ``g``, from the true field:
    qddot (lnn), (qdot, qddot) (the HNNs)."""
    state, g = np.asarray(state, float), np.asarray(g, float)
    v = state[:, 1:]
    qddot = pdot_to_qddot(g, v)
    return qddot if model == "lnn" else np.concatenate([v, qddot], 1)


def weighted_l1(pred, target, v, xp=np):
    """The notebook's printed loss (its ``loss`` / len(batch)): sum over the compared
    components of |error| (1 + 1 / sqrt(1 - qdot^2)), over the batch's sum of the weights
    (``xp``: numpy, or jax.numpy to differentiate it)."""
    w = 1.0 + 1.0 / xp.sqrt(1.0 - xp.reshape(v, (-1, 1)) ** 2)
    return xp.sum(xp.abs(pred - target) * w) / xp.sum(w)


# ------------------------------------------------------------------------ the notebook's side
class Sampler:
    """The notebook's batches: per epoch ``gen_data_batch(epoch, minibatch_per * batch)``,
    cut in order (``take(k, start)``: those of steps start .. start + k - 1; the notebook's
    ``gen_data_batch`` draws qdot from PRNGKey(1) whatever the epoch, so every epoch has the
    same speeds, with new q and g)."""

    def __init__(self, nb, batch: int):
        self.nb, self.batch, self._epoch = nb, batch, (None, None)

    def epoch_arrays(self, e: int):
        """``gen_data_batch(e, minibatch_per * batch)`` as numpy arrays (the last one kept)."""
        import jax

        if self._epoch[0] != e:
            with jax.enable_x64(False):
                arrays = self.nb.gen_data_batch(e, self.nb.minibatch_per * self.batch)
            self._epoch = (e, [np.asarray(x) for x in arrays])
        return self._epoch[1]

    def take(self, k: int, start: int):
        out = []
        for s in range(start, start + k):
            e, mb = divmod(s, self.nb.minibatch_per)
            sl = slice(mb * self.batch, (mb + 1) * self.batch)
            out.append(tuple(x[sl] for x in self.epoch_arrays(e)))
        return out


class Seed:
    """The notebook's training loop on its own Adam state."""

    def __init__(self, nb, params):
        import jax

        self.nb, self.done = nb, 0
        with jax.enable_x64(False):
            self.opt_state = nb.opt_init(params)

    @property
    def params(self):
        return self.nb.get_params(self.opt_state)

    def train(self, batches):
        import jax

        losses = []
        with jax.enable_x64(False):
            for cs, cc, ct in batches:
                fraction = self.done / self.nb.steps  # the notebook's (epoch + mb / mbs) / E
                self.opt_state, params = self.nb.update_derivative(
                    fraction, self.opt_state, cs, cc, ct
                )
                losses.append(float(self.nb.loss(params, cs, cc, ct)) / len(cs))  # its cur_loss
                self.done += 1
        return np.asarray(losses), not np.all(np.isfinite(losses))

    def predict(self, state, g):
        import jax

        with jax.enable_x64(False):
            return np.asarray(
                self.nb.eom(self.params, state.astype("float32"), g.astype("float32")), float
            )


def seed_loss_and_grad(nb, params, batch, x64: bool):
    """The notebook's loss / len(batch), its ``update_derivative``'s gradient and its
    predictions, in float32 or (``x64``) float64."""
    import jax
    import jax.numpy as jnp

    dtype = jnp.float64 if x64 else jnp.float32
    with jax.enable_x64(x64):
        p = jax.tree.map(lambda x: jnp.asarray(x, dtype), params)
        cs, cc, ct = (jnp.asarray(x, dtype) for x in batch)
        g = jax.grad(lambda *a: nb.loss(*a) / len(cs), 0)(p, cs, cc, ct)
        pred = np.asarray(nb.eom(p, cs, cc), float)
        return float(nb.loss(p, cs, cc, ct)) / len(cs), g, pred


def held_out(n: int, seed: int):
    """``n`` states of the notebooks' distribution (q ~ U(-10, 10), qdot = 0.99999 tanh(2 N(0,
    1)), g ~ 10 N(0, 1)), float32 as they train, drawn apart from their sampler."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(-10, 10, (n, 1))
    v = np.tanh(2 * rng.standard_normal((n, 1))) * 0.99999
    g = 10 * rng.standard_normal((n, 1))
    return np.concatenate([q, v], 1).astype("float32"), g.astype("float32")
