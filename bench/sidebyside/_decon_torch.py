"""The paper's side of ``python -m bench.sidebyside.decon_hnn``: run by a PyTorch interpreter
(never imported by the suite, which has no torch), it imports the paper's code from
``--seed-code`` and works on the arrays of ``--inp`` (an .npz written by the suite's side),
writing its results to ``--out`` (an .npz).

What runs of the paper's code (ngruver/decon-hnn): ``src/systems/chain_pendulum.py``
(``ChainPendulum``: the constrained Cartesian chain, its ``body2globalCoords``,
``to_pos_momentum``, ``dynamics()`` and ``hamiltonian``), ``src/models`` (``MechanicsNN``,
``NonseparableHNN``, ``HNN``, built as ``make_trainer`` builds them: ``torch.manual_seed(net_seed)``
then the class, then ``.float()``) and ``src/train/trainer.py`` (``IntegratedDynamicsTrainer``:
its ``loss``, ``step`` (clipping at 1, AdamW) and ``rel_err``), with olive-oil-ml's ``Trainer``
and ``cosLr`` under it, stepped as oil's ``Trainer.train`` steps them.

Compatibility shims, none of which changes a computation: ``torch.solve(B, A)`` (removed from
PyTorch) is ``torch.linalg.solve(A, B)`` with the old result's ``.solution`` / ``[0]``;
``collections.Iterable`` and friends (removed from Python) alias ``collections.abc``; the
packages ``oil.model_trainers`` and ``oil.datasetup`` are entered without their ``__init__``
(which imports torchvision for image trainers not used here) and ``oil.datasetup.datasets`` is a
stub (``split_dataset`` is only called by ``make_trainer``, not used here); ``wandb`` is a stub
(only ``logStuff`` calls it, not used here).
"""

from __future__ import annotations

import argparse
import collections
import collections.abc
import importlib.util
import shutil
import sys
import tempfile
import time
import types
from pathlib import Path

import numpy as np

CLASSES = {"node_so": "MechanicsNN", "hnn": "NonseparableHNN", "hnn_so": "HNN"}


def shims() -> None:
    import torch

    for name in ("Iterable", "Mapping", "MutableMapping", "Sequence", "Callable"):
        if not hasattr(collections, name):
            setattr(collections, name, getattr(collections.abc, name))
    result = collections.namedtuple("solve", ["solution", "LU"])

    def solve(b, a):  # the removed torch.solve(B, A): a stub that raises in recent PyTorch
        return result(torch.linalg.solve(a, b), a)

    torch.solve = solve
    sys.modules.setdefault("wandb", types.ModuleType("wandb"))
    spec = importlib.util.find_spec("oil")
    if spec is None:
        raise SystemExit("error: olive-oil-ml (import name oil) is not installed")
    oil_root = Path(spec.submodule_search_locations[0])
    for pkg in ("model_trainers", "datasetup"):
        mod = types.ModuleType(f"oil.{pkg}")
        mod.__path__ = [str(oil_root / pkg)]
        sys.modules.setdefault(f"oil.{pkg}", mod)
    datasets = types.ModuleType("oil.datasetup.datasets")

    def split_dataset(*a, **k):
        raise NotImplementedError("split_dataset: make_trainer is not used by the side-by-side")

    datasets.split_dataset = split_dataset
    sys.modules.setdefault("oil.datasetup.datasets", datasets)
    import oil.model_trainers.trainer as base

    sys.modules["oil.model_trainers"].Trainer = base.Trainer


def load_paper(root: Path) -> types.SimpleNamespace:
    shims()
    sys.path.insert(0, str(root))
    import src.models as models
    from oil.utils.utils import cosLr
    from src.systems.chain_pendulum import ChainPendulum
    from src.train.trainer import IntegratedDynamicsTrainer

    return types.SimpleNamespace(
        models=models, ChainPendulum=ChainPendulum, Trainer=IntegratedDynamicsTrainer, cosLr=cosLr
    )


# ------------------------------------------------------------------------ ground truth
def ground_truth(paper, states: np.ndarray, dtype) -> dict:
    """The paper's chain at angle states (N, 2k): the bobs' Cartesian velocities and
    accelerations (N, k, 2) from its constrained dynamics (``body.dynamics()`` on
    ``to_pos_momentum(body2globalCoords(z))``, accelerations M^-1 dp/dt) and its
    ``hamiltonian``; the suite maps them to angles. In float64 the potential is evaluated in
    the state's dtype (the paper's ``potential`` casts M to float32, which fails on a float64
    state; the formula is unchanged)."""
    import networkx as nx
    import torch

    k = states.shape[1] // 2
    body = paper.ChainPendulum(k)
    if dtype == torch.float64:
        body.potential = lambda x: 9.81 * (body.M.to(x.dtype) @ x)[..., 1].sum(1)
    ao = torch.tensor(states, dtype=dtype).reshape(-1, 2, k)
    xv = body.body2globalCoords(ao)  # (N, 2, k, 2): positions, velocities
    xp = body.to_pos_momentum(xv)
    dxp = body.dynamics()(torch.zeros((), dtype=dtype), xp).reshape(-1, 2, k, 2)
    acc = body.Minv.to(dtype) @ dxp[:, 1]
    h = body.hamiltonian(torch.zeros(()), xp)
    lengths = [float(body.body_graph.nodes[0]["tether"][1])]
    lengths += [float(v) for v in nx.get_edge_attributes(body.body_graph, "l").values()]
    return {
        "vel": dxp[:, 0].detach().double().numpy(),
        "acc": acc.detach().double().numpy(),
        "energy": h.detach().double().numpy(),
        "masses": np.array([body.body_graph.nodes[i]["m"] for i in range(k)], float),
        "lengths": np.array(lengths, float),
    }


def paper_trajectories(paper, z0: np.ndarray, ts: np.ndarray) -> np.ndarray:
    """The paper's data pipeline from angle states z0 (N, 2k): ``body.integrate`` (dopri5,
    rtol 1e-7, in the Cartesian constrained coordinates, in float32 as its sampled states
    are) then ``global2bodyCoords``."""
    import torch

    k = z0.shape[1] // 2
    body = paper.ChainPendulum(k)
    xv0 = body.body2globalCoords(torch.tensor(z0, dtype=torch.float32).reshape(-1, 2, k))
    zt = body.integrate(xv0, torch.tensor(ts, dtype=torch.float32))  # (N, T, 2, k, 2)
    n, t = zt.shape[:2]
    ang = body.global2bodyCoords(zt.reshape(n * t, *zt.shape[2:]).double())
    return ang.reshape(n, t, 2 * k).numpy()


# ------------------------------------------------------------------------ training
def build_model(paper, name: str, k: int, width: int, net_seed: int):
    """``make_trainer``'s model: ``torch.manual_seed(net_seed)``, the class, ``.float()``."""
    import torch

    body = paper.ChainPendulum(k)
    torch.manual_seed(net_seed)
    cls = getattr(paper.models, CLASSES[name])
    model = cls(G=body.body_graph, dof_ndim=k, angular_dims=body.angular_dims, hidden_size=width)
    return model.float(), body


def make_trainer(paper, model, body, lr, weight_decay, num_epochs, log_dir):
    """``IntegratedDynamicsTrainer`` as ``make_trainer`` configures it (AdamW, ``cosLr``, l2)."""
    from torch.optim import AdamW

    loaders = {"train": types.SimpleNamespace(dataset=types.SimpleNamespace(body=body))}
    return paper.Trainer(
        model,
        loaders,
        lambda params: AdamW(params, lr=lr, weight_decay=weight_decay),
        paper.cosLr(num_epochs),
        log_dir=log_dir,
        constrained=False,
        log_args={"timeFrac": 1 / 4, "minPeriod": 0.0},
        loss="l2",
    )


def minibatch(z: np.ndarray, ts: np.ndarray, dtype):
    """``RigidBodyDataset``'s minibatch ((z0, ts), zs) of chunks z (B, C, 2k) at times ts."""
    import torch

    b, c, n = z.shape
    zs = torch.tensor(z, dtype=dtype).reshape(b, c, 2, n // 2)
    tt = torch.tensor(np.broadcast_to(ts, (b, c)).copy(), dtype=dtype)
    return (zs[:, 0], tt), zs


def loss_and_grads(trainer, mb) -> tuple[float, dict]:
    trainer.optimizer.zero_grad()
    loss = trainer.loss(mb)
    loss.backward()
    grads = {  # None: a parameter the loss does not reach (an H network's last bias)
        n: np.zeros(tuple(p.shape)) if p.grad is None else p.grad.detach().double().numpy().copy()
        for n, p in trainer.model.named_parameters()
    }
    trainer.optimizer.zero_grad()
    return float(loss), grads


def predict(trainer, z0: np.ndarray, ts: np.ndarray) -> np.ndarray:
    """The trainer's test rollout (``model.integrate(z0, ts, tol)`` in eval mode)."""
    import torch
    from oil.utils.utils import Eval

    k = z0.shape[1] // 2
    with Eval(trainer.model), torch.no_grad():
        x0 = torch.tensor(z0, dtype=torch.float32).reshape(-1, 2, k)
        t = torch.tensor(ts, dtype=torch.float32)
        pred = trainer.model.integrate(x0, t, tol=trainer.hypers["tol"])
    return pred.reshape(pred.shape[0], pred.shape[1], 2 * k).double().numpy()


def paper_gerr(trainer, pred: np.ndarray, true: np.ndarray) -> tuple[float, float]:
    """The trainer's ``gerr``: exp of the mean of its ``rel_err`` (log, clamped at 1e-7) over
    windows and times, t = 0 included (as it reports it) and from t = 1 on."""
    import torch

    k = true.shape[-1] // 2
    p = torch.tensor(pred, dtype=torch.float32).reshape(*pred.shape[:2], 2, k)
    t = torch.tensor(true, dtype=torch.float32).reshape(*true.shape[:2], 2, k)
    log_err = trainer.rel_err(p, t, None)
    return float(np.exp(log_err.mean().item())), float(np.exp(log_err[:, 1:].mean().item()))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="_decon_torch.py")
    p.add_argument("--seed-code", required=True)
    p.add_argument("--inp", required=True)
    p.add_argument("--out", required=True)
    a = p.parse_args(argv)
    import torch

    torch.set_num_threads(1)
    paper = load_paper(Path(a.seed_code))
    inp = np.load(a.inp)
    name = str(inp["model"])
    k, width = int(inp["k"]), int(inp["width"])
    out: dict = {}

    # (0) ground truth, float32 (as the paper made its data) and float64
    for tag, dtype in (("32", torch.float32), ("64", torch.float64)):
        gt = ground_truth(paper, inp["gt_states"], dtype)
        out.update({f"gt{tag}_{key}": v for key, v in gt.items()})
    if inp["traj_z0"].size:
        out["traj"] = paper_trajectories(paper, inp["traj_z0"], inp["traj_ts"])

    # (a), (b) at initialisation, float32 (as it ran) and float64
    model, body = build_model(paper, name, k, width, int(inp["net_seed"]))
    out.update({f"w:{n}": v.detach().numpy().copy() for n, v in model.state_dict().items()})
    steps_per_epoch = int(inp["steps_per_epoch"])
    lr, wd, epochs = float(inp["lr"]), float(inp["weight_decay"]), int(inp["num_epochs"])
    log_dir = tempfile.mkdtemp(prefix="decon_torch_")
    trainer = make_trainer(paper, model, body, lr, wd, epochs, log_dir)
    first = inp["z_train"][inp["batches"][0]]
    ts_train = inp["ts_train"]
    for tag, dtype in (("32", torch.float32), ("64", torch.float64)):
        tr = trainer
        if dtype == torch.float64:
            twin, _ = build_model(paper, name, k, width, int(inp["net_seed"]))  # the same draw
            tr = make_trainer(paper, twin.double(), body, lr, wd, epochs, log_dir)
        loss, grads = loss_and_grads(tr, minibatch(first, ts_train, dtype))
        out[f"loss0_{tag}"] = loss
        out.update({f"g{tag}:{n}": g for n, g in grads.items()})

    # (c) the curve: the trainer's step and oil's schedule step, as Trainer.train runs them
    steps, log_every = int(inp["steps"]), int(inp["log_every"])
    z_eval, ts_eval = inp["z_eval"], inp["ts_eval"]
    losses, evals, seconds = [], [], 0.0
    sched = trainer.lr_schedulers

    def evaluate(step):
        pred = predict(trainer, z_eval[:, 0], ts_eval)
        mse = float(np.mean((pred - z_eval) ** 2))
        evals.append((step, *paper_gerr(trainer, pred, z_eval), mse, seconds))
        return pred

    pred = evaluate(0)
    for s in range(steps):
        mb = minibatch(inp["z_train"][inp["batches"][s]], ts_train, torch.float32)
        t0 = time.perf_counter()
        losses.append(float(trainer.step(mb)))
        [sc.step(s / steps_per_epoch) for sc in sched]
        seconds += time.perf_counter() - t0
        if (s + 1) % log_every == 0 or s + 1 == steps:
            pred = evaluate(s + 1)
            print(f"paper step {s + 1}: loss {losses[-1]:.4g}, gerr {evals[-1][2]:.4g}", flush=True)
    out["losses"] = np.asarray(losses, float)
    out["evals"] = np.asarray(evals, float).reshape(-1, 5)
    out["pred_final"] = pred
    out["lr_final"] = float(trainer.optimizer.param_groups[0]["lr"])
    out["seconds"] = seconds
    np.savez(a.out, **out)
    shutil.rmtree(log_dir, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
