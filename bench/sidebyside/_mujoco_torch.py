"""The paper's side of ``python -m bench.sidebyside.decon_mujoco``: run by a PyTorch interpreter
(never imported by the suite, which has no torch), it imports the paper's ``mujoco.py`` from
``--seed-code`` and works on the arrays of ``--inp`` (an .npz written by the suite's side),
writing its results to ``--out`` (an .npz).

What runs of the paper's code (ngruver/decon-hnn): ``mujoco.py``'s model classes (``NODE``,
``CoupledNODE``, ``MixtureHNN`` of ``src/models/dynamics_models.py``, with torchdiffeq under
them), built with ``train_mujoco_model``'s ``model_cfg`` after ``torch.manual_seed(seed)``, its
``timestep_table`` and its ``integrate(x[:, 0], ts, u)[:, :-1]`` on ts of C + 1 points. Three
pieces of ``mujoco.py`` are functions' bodies, not functions, and are restated here line for
line: the standardisation buffers of ``train_mujoco_model`` (the mean and std of the windows'
concatenated (x, u); of the finite-difference rates for the NODEs), and ``fit_net``'s step
(``loss = (z_pred - x).div(z_std).pow(2).mean()``, backward, ``clip_grad_norm_(..., 1)``,
``optim.Adam(net.param_groups, lr, weight_decay)``) with its ``CosineAnnealingLR(T_max =
epochs, eta_min = 1e-6)`` stepped once per epoch; the learning rate is read off ``fit_net``'s
source (hard-coded there). The batches are the suite's (``--inp``'s indices), not
``fit_net``'s unshuffled loader. Stubs, none of which changes a computation: ``wandb`` and
``fire`` (imported by ``mujoco.py``, called only by its ``main``).
"""

from __future__ import annotations

import argparse
import importlib.util
import inspect
import re
import sys
import time
import types
from pathlib import Path

import numpy as np

CLASSES = {"node": "NODE", "node_so": "CoupledNODE", "hnn_force_paper": "MixtureHNN"}


def load_paper(root: Path):
    """The paper's ``mujoco.py`` as a module (wandb and fire stubbed)."""
    sys.modules.setdefault("wandb", types.ModuleType("wandb"))
    fire = types.ModuleType("fire")
    fire.Fire = None
    sys.modules.setdefault("fire", fire)
    sys.path.insert(0, str(root))
    spec = importlib.util.spec_from_file_location("paper_mujoco", root / "mujoco.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def paper_lr(paper) -> float:
    """``fit_net``'s Adam rate, read off its source (``optim.Adam(..., lr=5e-3, ...)``)."""
    found = re.search(r"optim\.Adam\([^)]*lr=([0-9.eE+-]+)", inspect.getsource(paper.fit_net))
    if not found:
        raise SystemExit("error: no optim.Adam(..., lr=...) in the paper's fit_net")
    return float(found.group(1))


def build(paper, name, x_size, u_size, width, depth, wd, env_dt, int_steps, seed):
    """``train_mujoco_model``'s ``model_cfg`` and class, after ``torch.manual_seed(seed)``."""
    import torch

    torch.manual_seed(seed)
    cls = CLASSES[name]
    cfg = dict(input_size=x_size + u_size, hidden_size=width, num_layers=depth, weight_decay=wd)
    if cls == "NODE":
        cfg.update(output_size=x_size, method="euler", step_size=env_dt / int_steps)
    elif cls == "CoupledNODE":
        cfg.update(output_size=x_size // 2, method="euler", step_size=env_dt / int_steps)
    else:  # MixtureHNN: one Euler step of env_dt
        cfg.update(output_size=x_size, method="euler", step_size=env_dt)
    return getattr(paper, cls)(**cfg)


def set_buffers(net, name, train_x, train_u, env_dt):
    """``train_mujoco_model``'s standardisation of ``net`` (its lines, restated)."""
    import torch

    x_size = train_x.shape[-1]
    xu = np.concatenate((train_x, train_u), axis=-1).reshape(-1, x_size + train_u.shape[-1])
    net.input_loc = torch.tensor(xu.mean(0)).to(net.input_loc)
    net.input_scale = torch.tensor(xu.std(0)).to(net.input_scale)
    q_dot_fd = (train_x[:, 1:, : x_size // 2] - train_x[:, :-1, : x_size // 2]) / env_dt
    v_dot_fd = (train_x[:, 1:, x_size // 2 :] - train_x[:, :-1, x_size // 2 :]) / env_dt
    if name == "node":
        fd = np.concatenate((q_dot_fd, v_dot_fd), axis=-1).reshape(-1, x_size)
    elif name == "node_so":
        fd = v_dot_fd.reshape(-1, x_size // 2)
    else:
        return
    net.output_loc = torch.tensor(fd.mean(0)).to(net.output_loc)
    net.output_scale = torch.tensor(fd.std(0)).to(net.output_scale)


def time_grid(n_points: int, env_dt: float, dtype):
    """``mujoco.py``'s ``train_ts``/``test_ts`` for windows of ``n_points`` states."""
    import torch

    return torch.tensor(np.linspace(0, env_dt * n_points, n_points + 1)).to(dtype)


def control_schedule(net, name, x, u, ts) -> np.ndarray:
    """The index of the control each call of ``net.forward`` reads during one
    ``integrate``, found by the forward's own rule (the latest of its ``ts`` not after t)."""
    scale = 1000.0 if name == "hnn_force_paper" else 1.0
    seen, forward = [], net.forward

    def spy(t, z):
        mask = net.ts <= scale * t
        diff = (net.ts - scale * t).pow(2)[mask]
        seen.append(int(mask.nonzero().flatten()[diff.argmin()]))
        return forward(t, z)

    net.forward = spy
    try:
        net.integrate(x[:, 0], ts, u)
    finally:
        del net.forward
    return np.asarray(seen)


def loss_of(net, x, u, ts, z_std):
    """``fit_net``'s loss on a batch (x, u)."""
    z_pred = net.integrate(x[:, 0], ts, u)[:, :-1]
    return (z_pred - x).div(z_std).pow(2).mean()


def predict(net, z, u, env_dt) -> np.ndarray:
    """``fit_net``'s test rollout: ``net.integrate(x[:, 0], test_ts, u)[:, :-1]``, eval mode."""
    import torch

    net.eval()
    with torch.no_grad():
        x = torch.tensor(z).float()
        uu = torch.tensor(u).float()
        pred = net.integrate(x[:, 0], time_grid(z.shape[1], env_dt, torch.float32), uu)[:, :-1]
    net.train()
    return pred.double().numpy()


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="_mujoco_torch.py")
    p.add_argument("--seed-code", required=True)
    p.add_argument("--inp", required=True)
    p.add_argument("--out", required=True)
    a = p.parse_args(argv)
    import torch
    from torch.nn.utils import clip_grad_norm_

    torch.set_num_threads(1)
    paper = load_paper(Path(a.seed_code))
    inp = np.load(a.inp)
    name, task = str(inp["model"]), str(inp["task"])
    z, u = inp["z_train"], inp["u_train"]
    x_size, u_size = z.shape[-1], u.shape[-1]
    env_dt = float(paper.timestep_table[task])
    width, depth, wd = int(inp["width"]), int(inp["depth"]), float(inp["weight_decay"])
    int_steps, seed = int(inp["num_int_steps"]), int(inp["net_seed"])
    lr = paper_lr(paper)
    out: dict = {"env_dt": env_dt, "lr": lr}

    def make(dtype):  # the buffers set in the model's dtype (the paper's float32, or float64)
        net = build(paper, name, x_size, u_size, width, depth, wd, env_dt, int_steps, seed)
        net = net.to(dtype)
        set_buffers(net, name, z, u, env_dt)
        return net

    net = make(torch.float32)
    out.update({f"w:{k}": v.detach().numpy().copy() for k, v in net.state_dict().items()})
    z_std = torch.tensor(np.clip(z.reshape(-1, x_size).std(0), 1e-6, None))  # float64

    # (a), (b) at initialisation, float32 (as it ran) and float64
    first = inp["batches"][0]
    for tag, dtype in (("32", torch.float32), ("64", torch.float64)):
        m = net if dtype == torch.float32 else make(dtype)  # the same draw
        x, uu = torch.tensor(z[first]).to(dtype), torch.tensor(u[first]).to(dtype)
        ts = time_grid(z.shape[1], env_dt, dtype)
        m.zero_grad()
        loss = loss_of(m, x, uu, ts, z_std)
        loss.backward()
        out[f"loss0_{tag}"] = float(loss)
        for k, prm in m.named_parameters():
            g = np.zeros(tuple(prm.shape)) if prm.grad is None else prm.grad.double().numpy()
            out[f"g{tag}:{k}"] = g.copy()
        m.zero_grad()
        out[f"sched_train_{tag}"] = control_schedule(m, name, x[:2], uu[:2], ts)
        ze, ue = inp["z_eval"][:2], inp["u_eval"][:2]
        out[f"sched_test_{tag}"] = control_schedule(
            m,
            name,
            torch.tensor(ze).to(dtype),
            torch.tensor(ue).to(dtype),
            time_grid(ze.shape[1], env_dt, dtype),
        )

    # (c) the curve: fit_net's step, its schedule stepped once per epoch
    steps, log_every = int(inp["steps"]), int(inp["log_every"])
    per_epoch, epochs = int(inp["steps_per_epoch"]), int(inp["num_epochs"])
    optimizer = torch.optim.Adam(net.param_groups, lr=lr, weight_decay=wd)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(optimizer, T_max=epochs, eta_min=1e-6)
    ts = time_grid(z.shape[1], env_dt, torch.float32)
    losses, logged, seconds = [], [0], 0.0
    preds = [predict(net, inp["z_eval"], inp["u_eval"], env_dt)]
    for s in range(steps):
        ix = inp["batches"][s]
        x, uu = torch.tensor(z[ix]).float(), torch.tensor(u[ix]).float()
        t0 = time.perf_counter()
        z_pred = net.integrate(x[:, 0], ts, uu)[:, :-1]
        optimizer.zero_grad()
        loss = (z_pred - x).div(z_std).pow(2).mean()
        loss.backward()
        clip_grad_norm_(net.parameters(), 1)
        optimizer.step()
        losses.append(loss.item())
        if (s + 1) % per_epoch == 0:
            sched.step()
        seconds += time.perf_counter() - t0
        if (s + 1) % log_every == 0 or s + 1 == steps:
            preds.append(predict(net, inp["z_eval"], inp["u_eval"], env_dt))
            logged.append(s + 1)
            print(f"paper step {s + 1}: loss {losses[-1]:.4g}", flush=True)
    out["losses"] = np.asarray(losses, float)
    out["logged"] = np.asarray(logged)
    out["preds"] = np.stack(preds)
    out["lr_final"] = float(optimizer.param_groups[0]["lr"])
    out["seconds"] = seconds
    np.savez(a.out, **out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
