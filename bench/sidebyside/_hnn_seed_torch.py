"""The HNN seed's side of ``python -m bench.sidebyside.hnn_seed``: its pixel model and training
step, run by a PyTorch interpreter (the suite's environment has no torch).

    TORCH_PYTHON _hnn_seed_torch.py REQUEST.npz RESULT.npz

This file imports only the standard library, numpy, torch and the seed's own code (never the
suite). From ``--seed-code`` it imports ``nn_models.py`` (``MLPAutoencoder``, ``MLP``) and
``hnn.py`` (``HNN``, ``PixelHNN``); from ``experiment-pixels/train.py``, which cannot be
imported (it needs gym and autograd), it takes by name with Python's ``ast``: ``get_args``'s
defaults, ``pixelhnn_loss`` (run as the seed wrote it, its global ``args`` supplied) and the
statements of ``train`` that seed torch and build the model and the optimiser (run as they
stand); its data loading and its ``randperm`` batches are replaced by the shared arrays of the
request. ``utils.py`` (imported by ``hnn.py`` for its ``rk4``) imports ``imageio`` at the top,
for gifs: an empty stand-in module is put in its place when imageio is absent.

The request (numpy arrays and a JSON ``meta``): ``frames`` (N, T, S, S) training frames,
``idx`` (steps, B, 2) the (trajectory, start) windows of every step, ``held_frames`` and
``held_idx`` the held-out windows, ``first`` (B, 2) the windows of the checks at
initialisation. ``meta``: seed_code, baseline, seed, log_every, snapshots (steps), threads. The
result: ``meta`` (the seed's settings, the loss terms at initialisation in float32 and float64,
per-step training terms, held-out terms at every logged step, seconds) and arrays
``init/<name>``, ``step<k>/<name>`` (parameters after k steps), ``grad<tag>/<name>``.
"""

from __future__ import annotations

import ast
import copy
import json
import sys
import time
import types
from pathlib import Path

import numpy as np

try:
    import torch
except ImportError:  # the suite's environment: only the readers of train.py are used there
    torch = None


def _import_seed(root: Path):
    try:
        import imageio  # noqa: F401
    except ImportError:  # utils.py imports it for gifs only
        sys.modules["imageio"] = types.ModuleType("imageio")
    sys.path.insert(0, str(root))
    import hnn
    import nn_models

    return nn_models, hnn


def _defaults(tree: ast.Module) -> dict:
    """``get_args``'s ``add_argument('--name', default=...)`` values that evaluate alone."""
    out = {}
    for node in ast.walk(tree):
        if not (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute)
            and node.func.attr == "add_argument"
            and node.args
            and isinstance(node.args[0], ast.Constant)
        ):
            continue
        name = str(node.args[0].value).lstrip("-")
        for kw in node.keywords:
            if kw.arg == "default":
                try:
                    code = compile(ast.Expression(kw.value), "<default>", "eval")
                    out[name] = eval(code, {"__builtins__": {}})  # noqa: S307 - a literal
                except Exception:  # a default naming a variable (save_dir): not needed
                    pass
    return out


def _function(tree: ast.Module, name: str) -> ast.FunctionDef:
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and node.name == name:
            return node
    raise SystemExit(f"experiment-pixels/train.py defines no {name}")


def _build_statements(train: ast.FunctionDef) -> list[ast.stmt]:
    """``train``'s statements before its dataset is loaded: the seeding, the autoencoder, the
    model and the optimiser."""
    out = []
    for node in train.body:
        if isinstance(node, ast.Assign) and any(
            isinstance(t, ast.Name) and t.id == "data" for t in node.targets
        ):
            return out
        out.append(node)
    raise SystemExit("experiment-pixels/train.py: train() loads no dataset")


def _weight_decay(train: ast.FunctionDef) -> float | None:
    for node in ast.walk(train):
        if isinstance(node, ast.Call) and getattr(node.func, "attr", "") == "Adam":
            for kw in node.keywords:
                if kw.arg == "weight_decay" and isinstance(kw.value, ast.Constant):
                    return float(kw.value.value)
    return None


def load(root: Path, baseline: bool, seed: int):
    """(model, optimiser, pixelhnn_loss, settings) as the seed's ``train`` builds them."""
    nn_models, hnn = _import_seed(root)
    tree = ast.parse((root / "experiment-pixels" / "train.py").read_text())
    defaults = _defaults(tree)
    args = types.SimpleNamespace(**defaults)
    args.baseline, args.seed, args.verbose = bool(baseline), int(seed), False
    train = _function(tree, "train")
    ns = {
        "torch": torch,
        "np": np,
        "args": args,
        "MLPAutoencoder": nn_models.MLPAutoencoder,
        "MLP": nn_models.MLP,
        "PixelHNN": hnn.PixelHNN,
        "HNN": hnn.HNN,
    }
    loss_def = ast.Module(body=[_function(tree, "pixelhnn_loss")], type_ignores=[])
    exec(compile(loss_def, "<the seed's pixelhnn_loss>", "exec"), ns)  # noqa: S102
    body = ast.Module(body=_build_statements(train), type_ignores=[])
    exec(compile(body, "<the seed's train()>", "exec"), ns)  # noqa: S102
    settings = {k: v for k, v in defaults.items() if isinstance(v, int | float | str | bool)}
    settings["weight_decay"] = _weight_decay(train)
    settings["adam"] = {k: v for k, v in ns["optim"].defaults.items() if k in ("betas", "eps")}
    return ns["model"], ns["optim"], ns["pixelhnn_loss"], settings


def pairs(frames: torch.Tensor, idx: np.ndarray):
    """The seed's (x, x_next) rows of windows ``idx`` (B, 2): x = [f_s, f_s+1] flattened,
    x_next = [f_s+1, f_s+2] (its ``make_gym_dataset``: two stacked frames, one frame on)."""
    t, s = torch.as_tensor(idx[:, 0]), torch.as_tensor(idx[:, 1])
    f0, f1, f2 = frames[t, s], frames[t, s + 1], frames[t, s + 2]
    b = f0.shape[0]
    x = torch.cat([f0.reshape(b, -1), f1.reshape(b, -1)], dim=1)
    x_next = torch.cat([f1.reshape(b, -1), f2.reshape(b, -1)], dim=1)
    return x, x_next


def terms(model, x, x_next):
    """The terms of ``pixelhnn_loss`` (batch means), with the second observation's
    reconstruction beside the first's: ae0, ae1, cc, dyn."""
    z, z_next = model.encode(x), model.encode(x_next)
    ae0 = ((x - model.decode(z)) ** 2).mean()
    ae1 = ((x_next - model.decode(z_next)) ** 2).mean()
    dyn = ((z_next - (z + model.time_derivative(z))) ** 2).mean()
    w, dw = z.split(1, 1)
    w_next, _ = z_next.split(1, 1)
    cc = ((dw - (w_next - w)) ** 2).mean()
    return ae0, ae1, cc, dyn


def _arrays(prefix: str, named) -> dict:
    return {f"{prefix}/{k}": v.detach().cpu().numpy().copy() for k, v in named}


def checks(model, loss_fn, frames, first, dtype) -> tuple[dict, dict]:
    """The loss terms and gradients at the current parameters on windows ``first``: the seed's
    loss (``pixelhnn_loss``) and ours (its first-observation reconstruction replaced by the
    mean over both observations), in ``dtype``."""
    m = copy.deepcopy(model).to(dtype)
    if hasattr(m.hnn, "M"):  # a plain tensor attribute, not moved by .to()
        m.hnn.M = m.hnn.M.to(dtype)
    x, x_next = pairs(frames.to(dtype), first)
    tag = "64" if dtype == torch.float64 else "32"
    out, arrays = {}, {}
    ae0, ae1, cc, dyn = terms(m, x, x_next)
    seed_loss = loss_fn(x, x_next, m)
    out.update(ae0=ae0.item(), ae1=ae1.item(), cc=cc.item(), dyn=dyn.item())
    out["seed_loss"] = seed_loss.item()
    m.zero_grad()
    seed_loss.backward()
    arrays.update(_arrays(f"grad_seed{tag}", ((k, p.grad) for k, p in m.named_parameters())))
    m.zero_grad()
    ae0, ae1, cc, dyn = terms(m, x, x_next)
    ours = loss_fn(x, x_next, m) + 0.5 * (ae1 - ae0)
    out["ours_loss"] = ours.item()
    ours.backward()
    arrays.update(_arrays(f"grad_ours{tag}", ((k, p.grad) for k, p in m.named_parameters())))
    return out, arrays


def held_out(model, frames, idx, size: int = 1000) -> dict:
    """Mean ae0, ae1, cc, dyn over the windows ``idx`` (chunks of ``size``)."""
    sums, n = np.zeros(4), 0
    for i in range(0, len(idx), size):
        x, x_next = pairs(frames, idx[i : i + size])
        t = terms(model, x, x_next)
        sums += len(x) * np.array([v.item() for v in t])
        n += len(x)
    return dict(zip(("ae0", "ae1", "cc", "dyn"), (sums / n).tolist(), strict=True))


def main(request: str, result: str) -> int:
    req = np.load(request)
    meta = json.loads(str(req["meta"]))
    torch.set_num_threads(int(meta.get("threads", 1)))
    model, optim, loss_fn, settings = load(Path(meta["seed_code"]), meta["baseline"], meta["seed"])
    frames = torch.as_tensor(req["frames"], dtype=torch.float32)
    held_frames = torch.as_tensor(req["held_frames"], dtype=torch.float32)
    idx, held_idx, first = req["idx"], req["held_idx"], req["first"]
    arrays = _arrays("init", model.named_parameters())
    init = {}
    for dtype in (torch.float32, torch.float64):
        got, a = checks(model, loss_fn, frames, first, dtype)
        init["64" if dtype == torch.float64 else "32"] = got
        arrays.update(a)
    log_every, snapshots = int(meta["log_every"]), set(meta["snapshots"])
    steps = len(idx)
    train, held, seconds = [], [], 0.0
    for step in range(steps + 1):
        if step % log_every == 0 or step == steps:
            held.append(
                {"step": step, "seconds": seconds, **held_out(model, held_frames, held_idx)}
            )
        if step in snapshots or step == steps:
            arrays.update(_arrays(f"step{step}", model.named_parameters()))
        if step == steps:
            break
        t0 = time.perf_counter()
        x, x_next = pairs(frames, idx[step])
        # the seed's training step (train.py): loss, backward, Adam step, zero the gradients
        loss = loss_fn(x, x_next, model)
        loss.backward()
        optim.step()
        optim.zero_grad()
        seconds += time.perf_counter() - t0
        train.append(loss.item())
    out = {
        "settings": settings,
        "init": init,
        "train_loss": train,
        "held": held,
        "threads": torch.get_num_threads(),
        "torch": torch.__version__,
    }
    np.savez(result, meta=json.dumps(out), **arrays)
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 3:
        print("usage: _hnn_seed_torch.py REQUEST.npz RESULT.npz", file=sys.stderr)
        sys.exit(2)
    sys.exit(main(sys.argv[1], sys.argv[2]))
