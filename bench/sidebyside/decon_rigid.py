"""Fig. 9's rigid bodies (claim 13) run by the paper's own code beside ours: does its model learn
where ours does not?

    python -m bench.sidebyside.decon_rigid --seed-code /path/to/decon-hnn \\
        --meshes /path/to/constrained-hamiltonian-neural-networks \\
        [--system rotor] [--model node] [--steps 8000] [--out DIR]

``--seed-code`` is a checkout of the paper's public code (``git clone
https://github.com/ngruver/decon-hnn``); ``--meshes`` a checkout of its predecessor
(``git clone https://github.com/mfinzi/constrained-hamiltonian-neural-networks``), whose
``rotor.obj`` and ``gyro.obj`` the paper's systems read and do not ship. Both are read and run,
never copied. The paper's side runs in a PyTorch interpreter (``--torch-python``, as for
:mod:`bench.sidebyside.decon_hnn`, plus ``pywavefront``), the script ``_decon_rigid_torch.py``.

On the paper-core cell of ``rigid_bodies`` (``--system``, ``--model``, the paper's rate 5e-3,
seed ``--seed``), checks with one-line verdicts:

- (0) the ground truth: the paper's constrained Cartesian integration (in float32, as it made
  its data) from our test windows' starts (our ``positions`` and their velocities) against our
  windows' body points, over the window; on the magnet pendulum the paper's dipole term has
  the opposite sign (a departure, docs/studies/rigid_bodies.md), so there they differ by design;
- (1) the paper's pipeline end to end: its data (``RigidBodyDataset``: 1000 trajectories of
  10 time units, one chunk of 5 per trajectory, angles read off the frames and unwrapped), its
  model and trainer for ``--steps`` steps; every ``--log-every`` steps its held-out rollout
  error against constant velocity's on the same windows, in the suite's metric (angles wrapped,
  from t = 1) and in the paper's (angles as stored, t = 0 included); a step that fails (its HNN
  raises on a non-finite dH/dz) or makes the loss non-finite ends the curve, scored as error 1;
- (2) our model and step (the cell's) trained on the paper's arrays and batches of the same size,
  scored alike;
- (d) the training windows' rates, the paper's and ours: where Euler angles pass near their
  pole, a few windows' rates dominate an L2 loss;
- (3) our stored runs of the cell (``--results``): the geometric mean over seeds of constant
  velocity's rollout error over the model's.

With ``--toy-defaults`` both sides take the paper's command-line defaults instead of the widths
its text reports: ``toy_systems.py`` without options builds width-128 networks and calls the
system's class with its ``num_bodies`` (2) as the first argument, which these three classes
read as the mass (the magnet pendulum's 3 becomes 2; the free rotor and the gyroscope move
alike at any mass). Our stored runs stay at the cell's width.

A model *learns* where it beats constant velocity by the claim's learning margin (2x). The
verdict asks whether the paper's code learns where ours does not: (1) against (3), agree where
both learn or neither does; (2) tells a difference of model and step from one of data.
Writes ``checks.csv``, ``curves.csv`` and ``verdicts.txt`` under ``--out``/system/model;
docs/sidebyside.md has the measured numbers.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
from pathlib import Path

import numpy as np

from ._decon import check_paper_code
from ._learn import constant_velocity, learns, scores, stored_ratio, verdict
from ._seed import SeedCodeError, check_checkout, run_side, torch_error, write_table

SYSTEMS = ("rotor", "gyroscope", "magnet_pendulum")
MODELS = ("node", "node_so", "hnn_so")
MESHES = ("rotor.obj", "gyro.obj")
TOL_TRUTH = 1e-4  # (0) max |x_paper - x_ours| / max |x| over the windows (paper: float32)
PAPER_DATA = {"n_systems": 1000, "tau": 10.0, "chunk": 5}  # toy_systems.py's defaults
DEPARTURES = {"magnet_pendulum": "the paper's dipole term has the opposite sign"}
TOY_DEFAULTS = {"width": 128, "mass_arg": 2.0}  # its hidden_size and num_bodies without options
TORCH_SCRIPT = Path(__file__).with_name("_decon_rigid_torch.py")


def run_config(system: str, model: str, seed: int, lr: float = 5e-3):
    """The paper-core cell of ``model`` on ``system`` in ``rigid_bodies`` at ``lr``."""
    import bench

    cells = [
        c
        for c in bench.expand("rigid_bodies", "paper-core", seeds=[seed])
        if c.system == system and c.model == model and c.lr == lr
    ]
    if len(cells) != 1:
        raise ValueError(f"{len(cells)} paper-core cells of {model} on {system} at lr {lr:g}")
    return cells[0]


def cartesian_starts(system, z0: np.ndarray) -> np.ndarray:
    """Our states z0 (N, 2d) as the paper's Cartesian body points and their velocities
    (N, 2, n, 3): ``system.positions`` and its derivative along qdot."""
    import jax
    import jax.numpy as jnp

    d = z0.shape[1] // 2

    def points(z):
        x, v = jax.jvp(lambda q: system.positions(jnp.concatenate([q, z[d:]])), (z[:d],), (z[d:],))
        return jnp.stack([x, v])

    return np.asarray(jax.vmap(points)(jnp.asarray(z0)))


def rates(z: np.ndarray) -> tuple[float, float]:
    """The 99th percentile and the largest |qdot| of windows z (N, C, 2d): the Euler-angle
    systems' rates grow as 1/sin(beta) near the pole, and a few such windows dominate an L2
    loss."""
    v = np.abs(z[..., z.shape[-1] // 2 :])
    return float(np.percentile(v, 99)), float(v.max())


def checkpoint(curve: str, step, pred, true, angular, cv: dict) -> dict:
    """One row of ``curves.csv``: both metrics and constant velocity's error over the model's
    (a failed prediction scores error 1)."""
    s = scores(pred, true, angular)
    return {"curve": curve, "step": int(step), **s, "cv_ratio": cv["error"] / s["error"]}


def side_by_side(name: str, a, root: Path, meshes: Path, out: Path) -> list[str]:
    """Every check of model ``name`` on ``a.system``; returns the verdict lines."""
    from types import SimpleNamespace

    from bench.core import Batches, build_run, prepare, train_config
    from systems import cache_root

    from ._decon_ours import Ours

    config = run_config(a.system, name, a.seed)
    cell_width = config.width
    if a.toy_defaults:
        config = dataclasses.replace(config, width=TOY_DEFAULTS["width"])
    system, data, _, suite_model = build_run(config, cache_root())
    tcfg = train_config(config)
    angular = tuple(system.angular)
    out.mkdir(parents=True, exist_ok=True)
    z_check = np.asarray(data.z_test)[: a.n_check]
    ts_check = np.asarray(data.ts_test) - float(np.asarray(data.ts_test)[0])
    per_epoch = int(0.8 * PAPER_DATA["n_systems"]) // tcfg.batch
    steps = tcfg.steps if a.steps is None else a.steps
    inp = out / "exchange_in.npz"
    np.savez(
        inp,
        system=a.system,
        model=name,
        seed=a.seed,
        width=config.width,
        lr=tcfg.lr,
        weight_decay=tcfg.weight_decay,
        batch=tcfg.batch,
        num_epochs=tcfg.steps // per_epoch,
        steps=steps,
        log_every=a.log_every,
        check_z0=cartesian_starts(system, z_check[:, 0]) if a.n_check else np.zeros(0),
        check_ts=ts_check,
        mass_arg=TOY_DEFAULTS["mass_arg"] if a.toy_defaults else 0.0,
        **PAPER_DATA,
    )
    toy = ", toy_systems.py's defaults" if a.toy_defaults else ""
    print(
        f"{name} on {a.system} ({config.config_hash}): {steps} steps, lr {tcfg.lr:g}, width "
        f"{config.width}{toy}",
        flush=True,
    )
    args = ("--seed-code", root, "--meshes", meshes, "--inp", inp)
    paper = run_side(a.torch_python, TORCH_SCRIPT, out, *args)
    rows, lines = [], []

    # (0) the ground truth
    if a.n_check:
        ours_x = np.asarray(
            [[system.positions(z) for z in window] for window in z_check], dtype=np.float64
        )
        theirs = paper["check_points"][:, :, 0]  # (N, T, n, 3) positions
        rel = float(np.max(np.abs(theirs - ours_x)) / np.max(np.abs(ours_x)))
        ok = rel <= TOL_TRUTH
        rows.append({"check": "0", "quantity": "body points over the window", "value": rel})
        why = f" ({DEPARTURES[a.system]}: a departure)" if a.system in DEPARTURES else ""
        lines.append(
            f"(0) {'agree' if ok else 'DIFFER'} within {TOL_TRUTH:g}: the paper's integration "
            f"from our {a.n_check} window starts, max |diff| / max |x| {rel:.2e}{why}"
        )

    # (1) the paper's pipeline, (2) ours on its arrays
    z_train = paper["z_train"].reshape(*paper["z_train"].shape[:2], -1)
    z_test = paper["z_test"].reshape(*paper["z_test"].shape[:2], -1)
    ts_train, ts_test = paper["ts_train"], paper["ts_test"]
    cv = scores(constant_velocity(z_test, ts_test), z_test, angular)
    ours_rates, paper_rates = rates(np.asarray(data.z_train)), rates(z_train)
    ratio = paper_rates[1] / ours_rates[1]
    rows.append({"check": "d", "quantity": "largest training rate, paper / ours", "value": ratio})
    lines.append(
        f"(d) the training windows' |qdot|: the paper's 99th percentile {paper_rates[0]:.3g}, "
        f"largest {paper_rates[1]:.3g}; ours {ours_rates[0]:.3g}, {ours_rates[1]:.3g}"
    )
    curves = [
        checkpoint("paper", step, pred.reshape(z_test.shape), z_test, angular, cv)
        for step, pred in zip(paper["checkpoints"], paper["preds"], strict=True)
    ]
    dataset = SimpleNamespace(
        z_train=z_train, ts_train=ts_train - ts_train[0], args_train=np.zeros((len(z_train), 0))
    )
    ours = Ours(suite_model, tcfg, prepare(suite_model, dataset, tcfg))
    batches = Batches(len(z_train), tcfg.batch, tcfg.seed).take(max(steps, 1))
    done = 0
    for step in sorted({0, steps, *range(a.log_every, steps + 1, a.log_every)}):
        if step > done:
            ours.train(batches[done:step])
            done = step
        pred = ours.predict(z_test[:, 0], ts_test - ts_test[0])
        curves.append(checkpoint("ours", step, pred, z_test, angular, cv))
    write_table(out / "curves.csv", curves)
    final = {c["curve"]: c for c in curves}  # the last checkpoint of each curve
    diverged = {"paper": int(paper["diverged"]), "ours": 0}
    stored, n_seeds = stored_ratio(
        Path(a.results), {"experiment": "rigid_bodies", "system": a.system}, name, lr=tcfg.lr
    )
    for key, text in (
        ("paper", "the paper's code on its own data"),
        ("ours", "our model and step on the paper's data"),
    ):
        f = final[key]
        rows.append({"check": "12"[key == "ours"], "quantity": text, "value": f["cv_ratio"]})
        when = f"diverged at step {f['step']}" if diverged[key] else f"step {f['step']}"
        lines.append(
            f"({rows[-1]['check']}) {text}, {when}: rollout error {f['error']:.4g} "
            f"(constant velocity {cv['error']:.4g}; paper's metric {f['paper_gerr']:.4g} "
            f"against {cv['paper_gerr']:.4g}): {learns(f['cv_ratio'])}"
        )
    rows.append({"check": "3", "quantity": f"our stored runs ({n_seeds} seeds)", "value": stored})
    lines.append(
        f"(3) our stored runs on our data ({n_seeds} seeds, width {cell_width}): {learns(stored)}"
    )
    lines.append(verdict(name, a.system, final["paper"]["cv_ratio"], stored))
    write_table(out / "checks.csv", rows)
    (out / "verdicts.txt").write_text("\n".join(lines) + "\n")
    return lines


def parse(argv):
    p = argparse.ArgumentParser(
        prog="python -m bench.sidebyside.decon_rigid",
        description="Fig. 9's rigid bodies by the paper's own code beside ours.",
    )
    p.add_argument("--seed-code", required=True, help="a checkout of ngruver/decon-hnn")
    p.add_argument(
        "--meshes",
        required=True,
        help="a checkout of mfinzi/constrained-hamiltonian-neural-networks",
    )
    p.add_argument("--system", default="rotor", help=f"of {', '.join(SYSTEMS)}")
    p.add_argument("--model", default="node", help=f"comma-separated, of {', '.join(MODELS)}")
    p.add_argument("--steps", type=int, default=None, help="default: the cell's (8000)")
    p.add_argument("--log-every", type=int, default=1000)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--n-check", type=int, default=20, help="windows for the ground-truth check")
    p.add_argument("--results", default="results/reference/paper", help="our stored runs")
    p.add_argument(
        "--toy-defaults",
        action="store_true",
        help="toy_systems.py's defaults without options: width 128, num_bodies 2 as the mass",
    )
    p.add_argument("--torch-python", default=os.environ.get("DECON_TORCH_PYTHON", "python3"))
    p.add_argument("--out", default="results/own/sidebyside/decon_rigid")
    return p.parse_args(argv)


def argument_error(a) -> str | None:
    """One line naming a bad argument, or None."""
    a.models = [m.strip() for m in a.model.split(",") if m.strip()]
    if a.system not in SYSTEMS:
        return f"--system {a.system!r}: of {', '.join(SYSTEMS)}"
    if not a.models or any(m not in MODELS for m in a.models):
        return f"--model {a.model!r}: of {', '.join(MODELS)}"
    if (a.steps is not None and a.steps < 1) or a.log_every < 1 or a.n_check < 0:
        return "--steps >= 1, --log-every >= 1, --n-check >= 0"
    return None


def main(argv=None) -> int:
    a = parse(argv)
    try:
        root = check_paper_code(a.seed_code)
        meshes = check_checkout(
            a.meshes,
            "mfinzi/constrained-hamiltonian-neural-networks",
            MESHES,
            "the predecessor's",
            option="--meshes",
        )
    except SeedCodeError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    msg = argument_error(a)
    if msg:
        print(f"error: {msg}", file=sys.stderr)
        return 2
    msg = torch_error(a.torch_python, ("torch", "torchdiffeq", "oil", "pywavefront"))
    if msg:
        print(f"error: {msg}", file=sys.stderr)
        return 2

    from bench.core import setup_process

    setup_process(n=1)
    for name in a.models:
        folder = Path(a.out) / a.system / (name + ("_toy_defaults" if a.toy_defaults else ""))
        print("\n".join(side_by_side(name, a, root, meshes, folder)))
    print(f"wrote {a.out}/{a.system}/<model>/checks.csv, curves.csv, verdicts.txt")
    return 0


if __name__ == "__main__":
    sys.exit(main())
