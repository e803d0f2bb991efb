"""A neural ODE in PyTorch on an exported decon-bench dataset: export, predict, score.

The suite's plug-in models are JAX/equinox (``--model-module``); a model in any other framework
goes through an export instead: it reads the exported folder with the folder's own
``decon_data.py`` (NumPy; its ``TorchDataset`` for torch), predicts the test rollouts from
their initial states, and the suite scores the predictions with its own metrics and sets them
beside its reference models (docs/any_framework.md). This script needs torch and NumPy only::

    python -m bench data export chain_pendulum --k 2 --seeds 0-4 --out /tmp/export
    python examples/pytorch_node.py /tmp/export --datasets 'velocity_n200_seed*' \\
        --out /tmp/torch_node.npz
    python -m bench score /tmp/torch_node.npz --data /tmp/export --model torch_node \\
        --out /tmp/scores.csv
    python -m bench compare --scores /tmp/scores.csv

The model is dz/dt = f(z) with f an MLP (two hidden layers of 128, tanh; angles enter as their
sine and cosine), trained as the suite trains its NODE at the quick profile: each training
chunk rolled out from its first state with Kutta's 3/8 RK4 rule, one step per dt, the mean
squared error on the chunk's states, Adam at learning rate 5e-3, batches of 100 chunks, 1000
steps, float64. One model per dataset (its seed seeds torch). The predictions file holds one
array per dataset, named by it and shaped as its ``z_test``: what ``bench score`` reads.
"""

from __future__ import annotations

import argparse
import fnmatch
import importlib.util
import sys
import time
from pathlib import Path

import numpy as np
import torch


def loader(folder: Path):
    """The exported folder's own ``decon_data.py``, imported from the folder."""
    spec = importlib.util.spec_from_file_location("decon_data", folder / "decon_data.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["decon_data"] = module  # TorchDataset's pickling finds it by name
    spec.loader.exec_module(module)
    return module


class Field(torch.nn.Module):
    """dz/dt = f(z): an MLP on (sin q, cos q) for the angles, q otherwise, and the rates."""

    def __init__(self, angular: list[bool], width: int = 128):
        super().__init__()
        d = len(angular)
        self.angular = torch.tensor(angular + [False] * d)
        n_in = 2 * d + int(sum(angular))
        self.net = torch.nn.Sequential(
            torch.nn.Linear(n_in, width),
            torch.nn.Tanh(),
            torch.nn.Linear(width, width),
            torch.nn.Tanh(),
            torch.nn.Linear(width, 2 * d),
        )

    def forward(self, z: torch.Tensor) -> torch.Tensor:
        a = z[..., self.angular]
        x = torch.cat([torch.sin(a), torch.cos(a), z[..., ~self.angular]], dim=-1)
        return self.net(x)


def rk4_38(f, z: torch.Tensor, h: float) -> torch.Tensor:
    """One step of Kutta's 3/8 rule (the suite's rk4_38)."""
    k1 = f(z)
    k2 = f(z + h * k1 / 3)
    k3 = f(z + h * (k2 - k1 / 3))
    k4 = f(z + h * (k1 - k2 + k3))
    return z + h * (k1 + 3 * k2 + 3 * k3 + k4) / 8


def rollout(f, z0: torch.Tensor, n: int, h: float) -> torch.Tensor:
    """States (B, n, 2d) from z0 (B, 2d), one step per interval of h."""
    zs = [z0]
    for _ in range(n - 1):
        zs.append(rk4_38(f, zs[-1], h))
    return torch.stack(zs, dim=1)


def fit_and_predict(dd, folder: Path, name: str, steps: int, lr: float, batch: int):
    """Train on dataset ``name``'s training chunks; predict its test windows (M, T, 2d)."""
    card = dd.read_card(folder)["datasets"][name]
    torch.manual_seed(card["seed"])
    train = dd.TorchDataset(folder, name, split="train", dtype="float64")
    h = float(train.ts[1] - train.ts[0])
    model = Field(card["angular"]).double()
    opt = torch.optim.Adam(model.parameters(), lr=lr)
    batches = torch.utils.data.DataLoader(train, batch_size=batch, shuffle=True, drop_last=True)
    step = 0
    while step < steps:
        for z, _ in batches:
            pred = rollout(model, z[:, 0], z.shape[1], h)
            loss = torch.mean((pred - z) ** 2)
            opt.zero_grad()
            loss.backward()
            opt.step()
            step += 1
            if step == steps:
                break
    test = dd.load(folder, name)
    with torch.no_grad():
        z0 = torch.from_numpy(test["z_test"][:, 0])
        zhat = rollout(model, z0, test["z_test"].shape[1], h).numpy()
    return zhat, loss.item()


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("export", type=Path, help="a folder written by python -m bench data export")
    p.add_argument("--datasets", required=True, help="dataset names or patterns, comma-separated")
    p.add_argument("--out", type=Path, required=True, help="the predictions file (.npz)")
    p.add_argument("--steps", type=int, default=1000)
    p.add_argument("--lr", type=float, default=5e-3)
    p.add_argument("--batch", type=int, default=100)
    args = p.parse_args(argv)
    torch.set_num_threads(1)
    dd = loader(args.export)
    names = dd.datasets(args.export)
    chosen = [n for n in names if any(fnmatch.fnmatch(n, g) for g in args.datasets.split(","))]
    if not chosen:
        p.error(f"--datasets {args.datasets} matches none of {', '.join(names)}")
    predictions = {}
    for name in chosen:
        t0 = time.perf_counter()
        predictions[name], loss = fit_and_predict(
            dd, args.export, name, args.steps, args.lr, args.batch
        )
        print(
            f"{name}: trained {args.steps} steps, final loss {loss:.3g}, "
            f"{time.perf_counter() - t0:.0f} s"
        )
    np.savez(args.out, **predictions)
    print(f"predictions: {args.out}")
    for row in dd.score(args.export, args.out):  # the suite's metrics, NumPy only
        print(
            f"{row['dataset']}: rollout error {row['rollout_error']:.4g}, energy violation "
            f"{row['energy_violation']:.4g}, MSE {row['mse']:.4g} (decon_data.score)"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
