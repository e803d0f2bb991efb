"""The LNN seed's own code, loaded beside the suite: its modules and notebook definitions, and
the mapping of its stax parameters onto our MLP (:mod:`bench.sidebyside.lnn_seed` runs them)."""

from __future__ import annotations

import ast
import importlib.util
import json
import sys
import types
from functools import partial
from pathlib import Path

import numpy as np

EXPECTED = (
    "lnn.py",
    "utils.py",
    "experiment_dblpend/physics.py",
    "hyperopt/HyperparameterSearch.py",
    "notebooks/DoublePendulum.ipynb",
)


class SeedCodeError(ValueError):
    """--seed-code does not point at a usable checkout of the seed's code."""


def check_checkout(
    path, repo: str, expected, whose: str = "the seed's", option: str = "--seed-code"
) -> Path:
    """``path`` as a Path when it holds every file of ``expected`` (a checkout of ``repo``);
    else SeedCodeError with a one-line message naming the ``option`` and what is missing."""
    root = Path(path).expanduser()
    if not root.is_dir():
        raise SeedCodeError(
            f"{option} {path}: not a directory; clone {whose} code first: "
            f"git clone https://github.com/{repo}"
        )
    missing = [f for f in expected if not (root / f).is_file()]
    if missing:
        raise SeedCodeError(
            f"{option} {path}: not a checkout of {repo} (missing {', '.join(missing)})"
        )
    return root


def verdict_line(name, ok, detail, tol) -> str:
    """One check's line of ``verdicts.txt``: ``(name) agree within tol: detail`` (or DIFFER)."""
    return f"({name}) {'agree' if ok else 'DIFFER'} within {tol}: {detail}"


def write_table(path: Path, rows: list[dict], fieldnames=None) -> None:
    """``rows`` as a CSV file with a header (``fieldnames``, default the first row's keys): the
    side-by-side scripts' ``curves.csv`` and ``checks.csv``."""
    import csv

    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(fieldnames or rows[0]))
        w.writeheader()
        w.writerows(rows)


def torch_error(python: str, modules) -> str | None:
    """None when the interpreter ``python`` imports every module of ``modules``; else the
    one-line error naming them (``--torch-python``: the other framework's environment)."""
    import subprocess

    try:
        r = subprocess.run(
            [python, "-c", "import " + ", ".join(modules)], capture_output=True, timeout=120
        )
        ok = r.returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        ok = False
    return None if ok else f"--torch-python {python}: cannot import {', '.join(modules)}"


def run_side(python, script, folder: Path, *args, whose: str = "the paper's") -> dict:
    """Run the other framework's side, ``python script *args --out folder/paper_out.npz``
    (stdout and stderr to ``folder/paper_log.txt``), and load the .npz it wrote; a failure
    raises RuntimeError naming the log and its last lines."""
    import subprocess

    out, log = Path(folder) / "paper_out.npz", Path(folder) / "paper_log.txt"
    cmd = [str(c) for c in (python, script, *args, "--out", out)]
    with open(log, "w") as f:
        proc = subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT)
    if proc.returncode != 0:
        tail = log.read_text().strip().splitlines()[-5:]
        raise RuntimeError(f"{whose} side failed ({log}): " + " | ".join(tail))
    return dict(np.load(out))


def check_seed_code(path) -> Path:
    """``path`` as a Path when it holds every file of :data:`EXPECTED`; else SeedCodeError."""
    return check_checkout(path, "MilesCranmer/lagrangian_nns", EXPECTED)


# ------------------------------------------------------------------------ the seed's code
def _shim() -> None:
    """The seed's ``jax.experimental.stax`` / ``optimizers`` are ``jax.example_libraries``'s."""
    import jax.example_libraries.optimizers as optimizers
    import jax.example_libraries.stax as stax

    sys.modules.setdefault("jax.experimental.stax", stax)
    sys.modules.setdefault("jax.experimental.optimizers", optimizers)
    try:
        import jax.experimental.ode  # noqa: F401  (lnn.py imports odeint at the top)
    except ImportError:  # a jax without it: lnn.py's odeint is not used here
        stub = types.ModuleType("jax.experimental.ode")
        stub.odeint = None
        sys.modules["jax.experimental.ode"] = stub


def _module(path: Path, name: str):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _names(node) -> set[str]:
    """The names a top-level statement defines."""
    if isinstance(node, ast.FunctionDef | ast.ClassDef):
        return {node.name}
    if isinstance(node, ast.Assign):
        out = set()
        for t in node.targets:
            elts = t.elts if isinstance(t, ast.Tuple) else [t]
            out |= {e.id for e in elts if isinstance(e, ast.Name)}
        return out
    return set()


def _last_definitions(sources: list[str], names: set[str]) -> dict[str, ast.stmt]:
    """The last top-level statement of ``sources`` (in order) defining each of ``names``."""
    found: dict[str, ast.stmt] = {}
    for src in sources:
        try:
            tree = ast.parse(src)
        except SyntaxError:  # a cell with IPython magics: none of ours
            continue
        for node in tree.body:
            for n in _names(node) & names:
                found[n] = node
    missing = names - set(found)
    if missing:
        raise SeedCodeError(f"the seed's code defines no {', '.join(sorted(missing))}")
    return found


def _training_l2reg(cells: list[str]) -> float:
    """The L2 weight the notebook's training loop passes to ``update_derivative`` (its last
    argument, a literal, in the loop over epochs)."""
    value = None
    for src in cells:
        try:
            tree = ast.parse(src)
        except SyntaxError:
            continue
        for node in tree.body:
            if not isinstance(node, ast.For):
                continue
            for call in ast.walk(node):
                if (
                    isinstance(call, ast.Call)
                    and isinstance(call.func, ast.Name)
                    and call.func.id == "update_derivative"
                    and isinstance(call.args[-1], ast.Constant)
                ):
                    value = float(call.args[-1].value)
    if value is None:
        raise SeedCodeError("the notebook's training loop calls no update_derivative")
    return value


def load_seed(root, **overrides) -> types.SimpleNamespace:
    """The seed's code of the double-pendulum LNN, as a namespace: ``init(seed)`` the
    notebook's initial parameters, ``loss``, ``update_derivative``, ``OneCycleLR``, ``opt_init``,
    ``get_params``, ``eom(params, states)`` the learned dz/dt, ``field(states, g)`` the analytic
    one, ``args``, ``l2reg``, ``steps`` (epochs x minibatches) and ``lr`` (the notebook's).
    ``overrides`` replace entries of the notebook's ``args`` (``hidden_dim``, ``batch_size``)."""
    import jax
    import jax.numpy as jnp
    from jax.tree_util import tree_flatten

    root = check_seed_code(root)
    _shim()
    sys.path.insert(0, str(root))  # lnn.py's own imports
    try:
        lnn = _module(root / "lnn.py", "_seed_lnn")
        utils = _module(root / "utils.py", "_seed_utils")
        physics = _module(root / "experiment_dblpend" / "physics.py", "_seed_physics")
    finally:
        sys.path.remove(str(root))
    from jax.example_libraries import optimizers, stax

    ns = {
        "jax": jax,
        "jnp": jnp,
        "np": np,
        "jit": jax.jit,
        "partial": partial,
        "stax": stax,
        "optimizers": optimizers,
        "tree_flatten": tree_flatten,
        "wrap_coords": utils.wrap_coords,
        "raw_lagrangian_eom": lnn.raw_lagrangian_eom,
        "custom_init": lnn.custom_init,
    }
    hs = (root / "hyperopt" / "HyperparameterSearch.py").read_text()
    tree = ast.parse(hs)
    imports = [
        n for n in tree.body if isinstance(n, ast.ImportFrom) and (n.module or "").startswith("jax")
    ]
    hs_defs = _last_definitions(
        [hs], {"swish", "relu3", "Swish", "Relu3", "extended_mlp", "learned_dynamics"}
    )
    nb = json.loads((root / "notebooks" / "DoublePendulum.ipynb").read_text())
    cells = [
        "".join(c["source"]) if isinstance(c["source"], list) else c["source"]
        for c in nb["cells"]
        if c.get("cell_type") == "code"
    ]
    nb_names = {
        "ObjectView",
        "args",
        "lr",
        "final_div_factor",
        "total_epochs",
        "minibatch_per",
        "loss",
        "OneCycleLR",
        "update_derivative",
        "opt_init",
    }
    nb_defs = _last_definitions(cells, nb_names)
    order = [
        *imports,
        *(hs_defs[n] for n in ("swish", "relu3", "Swish", "Relu3")),
        hs_defs["extended_mlp"],
        hs_defs["learned_dynamics"],
        *(nb_defs[n] for n in ("ObjectView", "args", "lr", "final_div_factor")),
        *(nb_defs[n] for n in ("total_epochs", "minibatch_per")),
        *(nb_defs[n] for n in ("loss", "OneCycleLR", "update_derivative", "opt_init")),
    ]
    seen, body = set(), []
    for node in order:  # one statement may define several names
        if id(node) not in seen:
            seen.add(id(node))
            body.append(node)
    code = compile(ast.Module(body=body, type_ignores=[]), "<the seed's code>", "exec")
    with jax.enable_x64(False):
        exec(code, ns)  # noqa: S102 - the seed's code, by the user's --seed-code
        ns["args"].__dict__.update(overrides)
        init_random_params, ns["nn_forward_fn"] = ns["extended_mlp"](ns["args"])

    def init(seed: int = 0):
        """The notebook's: stax's init at PRNGKey(seed) + 1, then ``custom_init(seed=seed)``."""
        with jax.enable_x64(False):
            rng = jax.random.PRNGKey(seed)
            _, params = init_random_params(rng + 1, (-1, 4))
            return ns["custom_init"](params, seed=seed)

    @jax.jit
    def eom(params, states):
        return jax.vmap(partial(ns["raw_lagrangian_eom"], ns["learned_dynamics"](params)))(states)

    field = jax.jit(
        jax.vmap(lambda s, g: physics.analytical_fn(s, g=g), (0, None)),
    )
    return types.SimpleNamespace(
        ns=ns,
        init=init,
        loss=ns["loss"],
        update_derivative=ns["update_derivative"],
        OneCycleLR=ns["OneCycleLR"],
        opt_init=ns["opt_init"],
        get_params=ns["get_params"],
        eom=eom,
        field=field,
        args=ns["args"],
        l2reg=_training_l2reg(cells),
        steps=int(ns["total_epochs"]) * int(ns["minibatch_per"]),
        lr=float(ns["lr"]),
    )


# ------------------------------------------------------------------------ the mapping
def ours_to_seed(mlp) -> list:
    """Our ``MLP``'s parameters as stax's ``serial(Dense, act, ..., Dense)`` holds them."""
    out: list = []
    for i, (w, b) in enumerate(zip(mlp.weights, mlp.biases, strict=True)):
        if i:
            out.append(())
        out.append((w, b))
    return out


def seed_to_ours(params, mlp):
    """``mlp`` (an ``MLP`` of the same shapes) with the stax parameters ``params``."""
    import equinox as eqx
    import jax.numpy as jnp

    dense = [p for p in params if len(p)]
    if len(dense) != len(mlp.weights):
        raise ValueError(f"{len(dense)} dense layers against {len(mlp.weights)}")
    ws, bs = [], []
    for (w, b), w0, b0 in zip(dense, mlp.weights, mlp.biases, strict=True):
        if tuple(w.shape) != tuple(w0.shape) or tuple(b.shape) != tuple(b0.shape):
            raise ValueError(f"shapes {w.shape}, {b.shape} against {w0.shape}, {b0.shape}")
        ws.append(jnp.asarray(w, w0.dtype))
        bs.append(jnp.asarray(b, b0.dtype))
    return eqx.tree_at(lambda m: (m.weights, m.biases), mlp, (tuple(ws), tuple(bs)))


def _seed_features_class():
    from models import Features

    class SeedFeatures(Features):
        """The seed's network input: q wrapped into [-pi, pi) (``raw_lagrangian_eom``'s q mod
        2 pi, then ``wrap_coords``), then qdot; no cos/sin."""

        def __call__(self, q, v, args):
            import jax.numpy as jnp

            q = (q % (2 * jnp.pi) + jnp.pi) % (2 * jnp.pi) - jnp.pi
            return jnp.concatenate([q, v])

    return SeedFeatures
