"""The paper's side of ``python -m bench.sidebyside.decon_rigid``: run by a PyTorch interpreter
(never imported by the suite), it imports the paper's code from ``--seed-code`` and its
predecessor's meshes from ``--meshes``, reads the request in ``--inp`` (an .npz written by the
suite's side) and writes its results to ``--out`` (an .npz).

What runs of the paper's code (ngruver/decon-hnn): ``src/systems/{rotor,gyroscope,
magnet_pendulum}.py`` with ``rigid_body.py`` under them (the constrained Cartesian dynamics,
``integrate``, ``body2globalCoords``), ``src/datasets.py`` (``RigidBodyDataset``: its trajectories,
its random chunk per trajectory, its angles read off the frames and unwrapped), ``src/models``
(``NN``, ``MechanicsNN``, ``HNN``, built as ``make_trainer`` builds them) and
``src/train/trainer.py`` (``IntegratedDynamicsTrainer``: its loss, its step with clipping at 1,
AdamW, oil's ``cosLr`` per epoch). ``make_trainer`` itself is not called (its ``split_dataset``
needs torchvision): its data and loaders are rebuilt as it builds them, the train set the
first 80 % of the chunks (its split is a random 80 % of the same independent chunks), batches
drawn without replacement per epoch as its shuffled loader draws them. The compatibility shims
are ``_decon_torch``'s.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import sys
import tempfile
import time
import types
from pathlib import Path

import numpy as np


def shims() -> None:
    """``_decon_torch``'s shims: that script is loaded from its file (a script, not the
    suite's package, which a torch interpreter does not import)."""
    spec = importlib.util.spec_from_file_location(
        "decon_torch", Path(__file__).with_name("_decon_torch.py")
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    module.shims()


CLASSES = {"node": "NN", "node_so": "MechanicsNN", "hnn_so": "HNN"}
SYSTEMS = {"rotor": "Rotor", "gyroscope": "Gyroscope", "magnet_pendulum": "MagnetPendulum"}


def load(root: Path, meshes: Path) -> types.SimpleNamespace:
    shims()
    sys.path.insert(0, str(root))
    os.chdir(meshes)  # the paper's read_obj opens "rotor.obj" / "gyro.obj" in the working folder
    import src.models as models
    import src.systems as systems
    from oil.utils.utils import cosLr
    from src.datasets import RigidBodyDataset
    from src.train.trainer import IntegratedDynamicsTrainer

    return types.SimpleNamespace(
        models=models,
        systems=systems,
        Dataset=RigidBodyDataset,
        Trainer=IntegratedDynamicsTrainer,
        cosLr=cosLr,
    )


def make_body(paper, system: str, mass_arg: float | None):
    """The paper's system: its class's defaults, or with ``mass_arg`` passed first, as
    ``toy_systems.py`` passes its ``num_bodies`` (the mass of these three classes)."""
    cls = getattr(paper.systems, SYSTEMS[system])
    return cls() if mass_arg is None else cls(mass_arg)


def body_points(paper, body, z0: np.ndarray, ts: np.ndarray) -> np.ndarray:
    """The paper's ground truth from Cartesian starts z0 (N, 2, n, 3), its body points and their
    velocities: the constrained Cartesian body points (N, T, 2, n, 3) of ``integrate`` (dopri5,
    rtol 1e-7), in float32 as it made its data (its potentials cast the mass matrix to float32)."""
    import torch

    x0 = torch.tensor(z0, dtype=torch.float32)
    return body.integrate(x0, torch.tensor(ts, dtype=torch.float32)).double().numpy()


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="_decon_rigid_torch.py")
    for name in ("--seed-code", "--meshes", "--inp", "--out"):
        p.add_argument(name, required=True)
    a = p.parse_args(argv)
    import torch
    from oil.utils.utils import Eval, FixedNumpySeed
    from torch.optim import AdamW

    torch.set_num_threads(1)
    inp_path, out_path = Path(a.inp).resolve(), Path(a.out).resolve()
    paper = load(Path(a.seed_code).resolve(), Path(a.meshes).resolve())
    inp = np.load(inp_path)
    system, cls = str(inp["system"]), CLASSES[str(inp["model"])]
    seed, width, lr = int(inp["seed"]), int(inp["width"]), float(inp["lr"])
    n_systems, tau, chunk = int(inp["n_systems"]), float(inp["tau"]), int(inp["chunk"])
    batch, steps, log_every = int(inp["batch"]), int(inp["steps"]), int(inp["log_every"])
    mass_arg = float(inp["mass_arg"]) if "mass_arg" in inp.files and inp["mass_arg"] else None
    out: dict = {}

    # (0) the ground truth from the suite's starts
    if inp["check_z0"].size:
        body = make_body(paper, system, mass_arg)
        out["check_points"] = body_points(paper, body, inp["check_z0"], inp["check_ts"])

    # (1) the paper's data, as make_trainer makes it (train: one chunk of C per trajectory;
    # test: one chunk of 100 of a fifth as many trajectories, mode "val", the same seed)
    body = make_body(paper, system, mass_arg)
    body.integration_time = tau
    root = tempfile.mkdtemp(prefix="decon_rigid_")
    t0 = time.perf_counter()
    with FixedNumpySeed(seed):
        common = dict(root_dir=root, body=body, angular_coords=True, seed=seed, regen=True)
        train = paper.Dataset(n_systems=n_systems, chunk_len=chunk, **common)
        test = paper.Dataset(n_systems=n_systems // 5, chunk_len=100, mode="val", **common)
    out["data_seconds"] = time.perf_counter() - t0
    n_train = int(0.8 * n_systems)
    z_train, ts_train = train.Zs[:n_train], train.Ts[:n_train]
    z_test, ts_test = test.Zs, test.Ts
    out.update(
        z_train=z_train.double().numpy(),
        ts_train=ts_train[0].double().numpy(),
        z_test=z_test.double().numpy(),
        ts_test=ts_test[0].double().numpy(),
    )
    print(f"paper data: {tuple(z_train.shape)} train, {tuple(z_test.shape)} test", flush=True)

    # (2) its model and trainer
    torch.manual_seed(seed)
    model = getattr(paper.models, cls)(
        G=body.body_graph, dof_ndim=body.D, angular_dims=body.angular_dims, hidden_size=width
    ).float()
    loaders = {"train": types.SimpleNamespace(dataset=types.SimpleNamespace(body=body))}
    per_epoch = n_train // batch
    trainer = paper.Trainer(
        model,
        loaders,
        lambda params: AdamW(params, lr=lr, weight_decay=float(inp["weight_decay"])),
        paper.cosLr(int(inp["num_epochs"])),
        log_dir=tempfile.mkdtemp(prefix="decon_rigid_log_"),
        constrained=False,
        log_args={"timeFrac": 1 / 4, "minPeriod": 0.0},
        loss="l2",
    )

    def predict() -> np.ndarray:
        with Eval(trainer.model), torch.no_grad():
            pred = trainer.model.integrate(z_test[:, 0], ts_test[0], tol=trainer.hypers["tol"])
        return pred.double().numpy()

    g = torch.Generator().manual_seed(seed)
    losses, checkpoints, preds, seconds, s = [], [0], [predict()], 0.0, 0
    diverged = 0  # the step whose update failed or made the loss non-finite; 0: none
    while s < steps and not diverged:
        perm = torch.randperm(n_train, generator=g)
        for b in range(per_epoch):
            idx = perm[b * batch : (b + 1) * batch]
            t1 = time.perf_counter()
            try:  # the paper's HNN raises "NaNs in dH" where its Hamiltonian's gradient fails
                loss = float(trainer.step(((z_train[idx, 0], ts_train[idx]), z_train[idx])))
            except RuntimeError as e:
                print(f"paper step {s + 1}: {e}", flush=True)
                loss = float("nan")
            for sched in trainer.lr_schedulers:
                sched.step(s / per_epoch)
            seconds += time.perf_counter() - t1
            losses.append(loss)
            s += 1
            if not np.isfinite(loss):
                diverged = s
            if s % log_every == 0 or s == steps or diverged:
                checkpoints.append(s)
                preds.append(np.full_like(preds[0], np.nan) if diverged else predict())
                print(f"paper step {s}: loss {np.mean(losses[-log_every:]):.4g}", flush=True)
            if s == steps or diverged:
                break
    out.update(
        losses=np.asarray(losses, float),
        checkpoints=np.asarray(checkpoints, int),
        preds=np.stack(preds),
        diverged=diverged,
        train_seconds=seconds,
    )
    np.savez(out_path, **out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
