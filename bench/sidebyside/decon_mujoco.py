"""The MuJoCo models (claim 16) side by side with the Deconstructing paper's own code.

    python -m bench.sidebyside.decon_mujoco --seed-code /path/to/decon-hnn \\
        [--task HopperFull-v0] [--model node,node_so,hnn_force_paper] [--steps 2000] [--out DIR]

``--seed-code`` is a checkout of the paper's public code (``git clone
https://github.com/ngruver/decon-hnn``), read and run, never copied. It is PyTorch code: its
side runs in another interpreter (``--torch-python``, default ``$DECON_TORCH_PYTHON`` or
``python3``, with torch, torchdiffeq and pandas installed), the script ``_mujoco_torch.py``
beside this one; the two sides exchange arrays through .npz files in ``--out``.

Our side is the ``paper-core`` cell of the model on ``--task`` (experiment ``mujoco``, seed
``--seed``) at the paper's code's rate 5e-3 (``fit_net`` hard-codes it): its windows (3 states
under their controls, ``bench.core._controlled.build``), the batches of its objective
(``Batches``), its training configuration and step (``make_step`` with ``ControlledObjective``:
the error divided by the training std per component, clipping at 1, AdamW with decay 1e-4,
cosine to 1e-6 per step over 51,200 steps) and its test rollouts (the run's evaluation
integrator). The paper's side runs its model classes on the SAME arrays and batch indices (cast
to float32 as its loader does), with its Adam (an L2 term, not AdamW) and its per-epoch cosine;
``_mujoco_torch.py`` says which of its lines are restated.

Per model (``node``: the paper's ``NODE``; ``node_so``: its ``CoupledNODE``;
``hnn_force_paper``: its ``MixtureHNN``), checks with one-line verdicts:

- (0) the setup: the standardisation (its buffers against our scene's statistics and loss
  scale), the time step and learning rate read off its code, and which control each of its
  solver's steps reads (its torchdiffeq grid, train and test windows) against ours (held per
  interval);
- (a) the loss at initialisation on the first batch and (b) the first gradient per layer, of
  the paper's model against ours with the paper's parameters (``mapped``: our registered
  class, whose features on a MuJoCo scene are the paper's standardised (q, qdot, u), so the
  mapping is exact), float32 and float64; the suite's own draw is reported beside them;
- (c) the curves over ``--steps`` steps of ``paper``, ``mapped`` (the campaign's step),
  ``mapped_paper_opt`` (the mapped model under the paper's update rule in optax:
  :func:`~bench.sidebyside._mujoco_ours.paper_optimizer`, which isolates the optimiser's part
  of a gap) and ``suite`` (the registered model as the campaign builds it and steps it, its own
  initialisation): the training MSE, and
  every ``--log-every`` steps the held-out normalised MSE (the paper's ``test_mse``) on the
  first ``--n-eval`` test trajectories of the run; judged on the checkpoints of the second half.

Writes ``checks.csv``, ``curves.csv`` and ``verdicts.txt`` per model under ``--out``;
docs/sidebyside.md (the MuJoCo section) has the measured numbers.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time
from pathlib import Path

import numpy as np

from . import _mujoco as M
from ._mujoco_ours import Ours, loss_and_grad, normalised_mse, paper_optimizer
from ._seed import SeedCodeError, run_side, torch_error, verdict_line, write_table

CURVES = ("paper", "mapped", "mapped_paper_opt", "suite")
PROFILE = "paper-core"
CODE_LR = 5e-3  # fit_net's hard-coded Adam rate, the paper-core cell taken
PAPER_INT_STEPS = 8  # mujoco.py's num_int_steps (the NODEs' Euler steps per transition)
TORCH_SCRIPT = Path(__file__).with_name("_mujoco_torch.py")
TOL_STATS = 1e-6  # (0) the paper's standardisation buffers (float32) against ours
TOL_LOSS = {"32": 1e-5, "64": 1e-12}  # (a) relative difference of the losses at init
TOL_GRAD = {"32": 1e-3, "64": 1e-9}  # (b) worst layer, ||g_paper - g_ours|| / ||g_ours||
# (c) the named reason of a curve that differs from the paper's
REASONS = {
    "mapped": "the update rule: the suite's AdamW (decoupled decay, cosine per step) against "
    "the paper's Adam with an L2 term (cosine per epoch), the suite's departure, which "
    "mapped_paper_opt isolates",
    "mapped_paper_opt": "none known: the paper's start and update rule",
    "suite": "the update rule (as mapped) and the suite's own initial draw",
}
TOL_CURVE = 0.25  # (c) late training and held-out MSE of a curve within 25 % of the paper's


def run_config(task: str, model: str, seed: int):
    """The ``paper-core`` cell of ``model`` on ``task`` at the code's rate :data:`CODE_LR`,
    trained by the suite's AdamW (the experiment's cells under the paper's rule, ``adam_l2_clip``,
    are the same chain as :func:`~bench.sidebyside._mujoco_ours.paper_optimizer` with a cosine
    stepped per step rather than per epoch)."""
    import bench

    cells = [
        c
        for c in bench.expand("mujoco", PROFILE, seeds=[seed])
        if c.system == task
        and c.model == model
        and abs(c.lr - CODE_LR) < 1e-12
        and c.optimizer == "adamw"
    ]
    if len(cells) != 1:
        raise ValueError(f"{len(cells)} {PROFILE} cells of {model} on {task} at lr {CODE_LR}")
    return cells[0]


def side_by_side(name: str, a, root: Path, out: Path) -> list[str]:
    """Every check of model ``name``; returns the verdict lines."""
    from bench.core import Batches, model_of, observation_kinds

    c = run_config(a.task, name, a.seed)
    kind = observation_kinds()[c.observation]  # the controlled run's own steps
    built = kind.build(c, None)
    tcfg = kind.member.train_config(c)
    w = built.windows
    out.mkdir(parents=True, exist_ok=True)
    z, u = np.asarray(w.z_train), np.asarray(w.u_train)
    z_eval = np.asarray(built.split.test_z)[: a.n_eval]
    u_eval = np.asarray(built.split.test_u)[: a.n_eval]
    batches = Batches(len(z), tcfg.batch, tcfg.seed).take(max(a.steps, 1))
    per_epoch = len(z) // min(tcfg.batch, len(z))
    print(
        f"{name} on {a.task} ({c.config_hash}): {len(z)} windows of {z.shape[1]}, width "
        f"{c.width} depth {c.depth}, {tcfg.steps} steps of {tcfg.batch}, lr {tcfg.lr}, "
        f"{tcfg.optimizer} decay {tcfg.weight_decay}, clip {tcfg.clip}, {tcfg.integrator.method}"
        f" x {tcfg.integrator.substeps}",
        flush=True,
    )
    inp = out / "exchange_in.npz"
    np.savez(
        inp,
        model=name,
        task=a.task,
        width=c.width,
        depth=c.depth,
        net_seed=a.seed,
        weight_decay=tcfg.weight_decay,
        num_int_steps=PAPER_INT_STEPS,
        num_epochs=tcfg.steps // per_epoch,
        steps_per_epoch=per_epoch,
        z_train=z,
        u_train=u,
        batches=batches,
        steps=a.steps,
        log_every=a.log_every,
        z_eval=z_eval,
        u_eval=u_eval,
    )
    t0 = time.perf_counter()
    if a.reuse_paper and (out / "paper_out.npz").exists():
        paper = dict(np.load(out / "paper_out.npz"))  # the paper's side of an earlier call
        if int(paper["losses"].shape[0]) != a.steps:
            raise ValueError(f"--reuse-paper: {out}/paper_out.npz holds another --steps")
    else:
        paper = run_side(a.torch_python, TORCH_SCRIPT, out, "--seed-code", root, "--inp", inp)
    print(f"paper's side: {time.perf_counter() - t0:.0f} s", flush=True)
    rows, lines = [], []

    def record(check, quantity, paper_v, ours_v, rel):
        rows.append(
            {"check": check, "quantity": quantity, "paper": paper_v, "ours": ours_v, "rel": rel}
        )

    # (0) the setup
    state = {k[2:]: v for k, v in paper.items() if k.startswith("w:")}
    theirs = M.paper_statistics(z, u, c.dt, name)
    ours = M.our_statistics(built.model, w.scale, name)
    worst = 0.0
    for key, mine in ours.items():
        for who, v in (("buffer", state.get(key)), ("restated", theirs[key])):
            if v is None:  # z_std is no buffer: the loss's scale, float64 in the paper's code
                continue
            rel = M.relative_max(v, mine)
            record("0", f"{key} ({who}), max rel. diff", None, None, rel)
            worst = max(worst, rel)
    lines.append(verdict_line("0 standardisation", worst <= TOL_STATS, f"{worst:.1e}", TOL_STATS))
    record("0", "time step", float(paper["env_dt"]), c.dt, abs(paper["env_dt"] - c.dt) / c.dt)
    record("0", "learning rate (fit_net's)", float(paper["lr"]), tcfg.lr, None)
    ok = abs(float(paper["env_dt"]) - c.dt) < 1e-12 and abs(float(paper["lr"]) - tcfg.lr) < 1e-12
    lines.append(
        verdict_line(
            "0 time step and rate",
            ok,
            f"dt {float(paper['env_dt'])} / {c.dt}, lr {float(paper['lr'])} / {tcfg.lr}",
            "exact",
        )
    )
    sub = tcfg.integrator.substeps
    for part, n in (("train", z.shape[1] - 1), ("test", z_eval.shape[1] - 1)):
        for tag in ("32", "64"):
            seen = np.asarray(paper[f"sched_{part}_{tag}"])
            want = M.held_schedule(n, sub)
            k = min(len(seen), len(want))
            bad = int(np.sum(seen[:k] != want[:k]))
            extra = len(seen) - len(want)
            record(
                "0", f"controls read off, {part} windows, float{tag}: steps differing", 0, bad, None
            )
            record("0", f"solver steps beyond ours, {part} windows, float{tag}", extra, 0, None)
            lines.append(
                verdict_line(
                    f"0 control schedule {part} float{tag}",
                    bad == 0,
                    f"{k} solver steps, {bad} read another control; the paper's solver takes "
                    f"{extra} step(s) more (its extra interval, discarded by [:, :-1])",
                    "exact",
                )
            )

    # (a), (b) at initialisation
    mapped = {}
    for tag, dtype in (("32", "float32"), ("64", "float64")):
        c_t = dataclasses.replace(c, dtype=dtype)
        model = model_of(c_t, built.model.scene, width=c.width, depth=c.depth)
        model = M.with_paper_weights(name, model, state)
        mapped[tag] = model
        tc = dataclasses.replace(tcfg, dtype=dtype)
        lp = float(paper[f"loss0_{tag}"])
        lo, go = loss_and_grad(model, w, batches[0], tc)
        rel = abs(lp - lo) / abs(lp)
        record("a", f"loss at init, float{tag}", lp, lo, rel)
        grads_p = {k[4:]: v for k, v in paper.items() if k.startswith(f"g{tag}:")}
        worst = 0.0
        for prefix, layer, kind, gp, gn, r in M.gradient_rows(name, go, grads_p):
            record("b", f"grad {prefix} layer {layer} {kind}, float{tag}", gp, gn, r)
            worst = max(worst, r)
        lines.append(
            verdict_line(
                f"a loss at init float{tag}",
                rel <= TOL_LOSS[tag],
                f"paper {lp:.10g}, ours {lo:.10g} (rel. {rel:.1e})",
                TOL_LOSS[tag],
            )
        )
        lines.append(
            verdict_line(
                f"b first gradient float{tag}",
                worst <= TOL_GRAD[tag],
                f"worst layer rel. diff {worst:.1e}",
                TOL_GRAD[tag],
            )
        )
    grads_p = {k[4:]: v for k, v in paper.items() if k.startswith("g32:")}
    for prefix, _ in M.NETWORKS[name]:
        ratio = M.l2_to_gradient(state, grads_p, prefix, tcfg.weight_decay)
        record("b", f"the paper's L2 term against its first gradient, {prefix}", ratio, 0.0, None)
    ls, _ = loss_and_grad(built.model, w, batches[0], tcfg)
    record("a", "loss at init, the suite's own model and draw (float32)", None, ls, None)
    print("\n".join(lines), flush=True)

    # (c) the curves
    sides = {}
    if "mapped" in a.curves:
        sides["mapped"] = Ours(mapped["32"], c, tcfg, w)
    if "mapped_paper_opt" in a.curves:
        opt = paper_optimizer(tcfg, per_epoch, tcfg.steps // per_epoch)
        sides["mapped_paper_opt"] = Ours(mapped["32"], c, tcfg, w, opt=opt)
    if "suite" in a.curves:
        sides["suite"] = Ours(built.model, c, tcfg, w)
    curve_rows, losses = [], {"paper": np.asarray(paper["losses"], float)}
    previous = 0
    for step, pred in zip(paper["logged"], paper["preds"], strict=True):
        window = losses["paper"][previous : int(step)]
        previous = int(step)
        curve_rows.append(curve_row("paper", int(step), window, pred, z_eval, w.scale))
    for name_c, side in sides.items():
        done, trained = 0, [np.zeros(0)]
        while True:
            pred = side.predict(z_eval, u_eval, c.dt)
            curve_rows.append(curve_row(name_c, done, trained[-1], pred, z_eval, w.scale))
            r = curve_rows[-1]
            print(
                f"{name_c} step {done}: train {r['train_mse']:.4g}, held-out {r['heldout_mse']:.4g}"
            )
            if done >= a.steps:
                break
            n = min(a.log_every, a.steps - done)
            trained.append(side.train(batches[done : done + n]))
            done += n
        losses[name_c] = np.concatenate(trained)
    record(
        "cost",
        "seconds per training step, the paper's side",
        float(paper["seconds"]) / max(a.steps, 1),
        None,
        None,
    )
    for name_c, side in sides.items() if a.steps else ():
        record(
            "cost",
            f"seconds per training step, {name_c}",
            None,
            side.seconds / max(side.steps, 1),
            None,
        )
        lc, lp_all = losses[name_c], losses["paper"]
        n = min(len(lc), len(lp_all))
        gap = np.abs(lc[:n] - lp_all[:n]) / np.abs(lp_all[:n])
        apart = int(np.argmax(gap > 0.01)) if np.any(gap > 0.01) else f"none of {n}"
        record(
            "c",
            f"first step whose training MSE is 1 % off the paper's: {name_c}",
            None,
            apart,
            None,
        )
        judged = {}
        for key in ("train_mse", "heldout_mse"):
            vals = {
                cv: (
                    [r[key] for r in curve_rows if r["curve"] == cv and r["step"] > 0],
                    [r["step"] for r in curve_rows if r["curve"] == cv and r["step"] > 0],
                )
                for cv in ("paper", name_c)
            }
            lp_ = M.late(*vals["paper"], a.steps)
            lo_ = M.late(*vals[name_c], a.steps)
            judged[key] = (lp_, lo_, (lo_ - lp_) / lp_)
            record("c", f"late {key}: {name_c}", lp_, lo_, judged[key][2])
        ok = all(abs(v[2]) <= TOL_CURVE for v in judged.values())
        detail = "; ".join(
            f"{key} {p_:.4g} vs {o_:.4g} ({r_:+.1%})" for key, (p_, o_, r_) in judged.items()
        )
        lines.append(
            verdict_line(
                f"c {name_c}",
                ok,
                f"over steps {a.steps // 2 + 1}-{a.steps} (geometric mean of the checkpoints), "
                f"paper vs {name_c}: {detail}; first step 1 % apart in training MSE: {apart}"
                + ("" if ok else f"; reason: {REASONS[name_c]}"),
                f"{TOL_CURVE:.0%}",
            )
        )
    write_table(out / "curves.csv", curve_rows)
    write_table(out / "checks.csv", rows, ["check", "quantity", "paper", "ours", "rel"])
    for name_c, lc in losses.items():
        np.save(out / f"{name_c}_losses.npy", lc)
    (out / "verdicts.txt").write_text("\n".join(lines) + "\n")
    return lines


def curve_row(curve, step, window, pred, z_eval, scale) -> dict:
    """One checkpoint: the mean training MSE since the previous one, the held-out MSE."""
    return {
        "curve": curve,
        "step": step,
        "train_mse": float(np.mean(window)) if len(window) else float("nan"),
        "heldout_mse": normalised_mse(pred, z_eval, scale),
    }


def parse(argv):
    p = argparse.ArgumentParser(
        prog="python -m bench.sidebyside.decon_mujoco",
        description="The MuJoCo models beside the paper's own code (same windows, same "
        "batches, same initial parameters).",
    )
    p.add_argument("--seed-code", required=True, help="a checkout of ngruver/decon-hnn")
    p.add_argument("--task", default="HopperFull-v0")
    p.add_argument("--model", default=",".join(M.PAPER_CLASSES), help="comma-separated")
    p.add_argument("--steps", type=int, default=2000)
    p.add_argument("--log-every", type=int, default=250)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--n-eval", type=int, default=50, help="held-out test trajectories")
    p.add_argument("--curves", default=",".join(CURVES[1:]), help=f"of {', '.join(CURVES[1:])}")
    p.add_argument("--torch-python", default=os.environ.get("DECON_TORCH_PYTHON", "python3"))
    p.add_argument("--out", default="results/own/sidebyside/decon_mujoco")
    p.add_argument(
        "--reuse-paper",
        action="store_true",
        help="take the paper's side from --out's paper_out.npz of an earlier call (same steps)",
    )
    return p.parse_args(argv)


def argument_error(a) -> str | None:
    """One line naming a bad argument, or None."""
    from systems import mujoco_task

    a.models = [m.strip() for m in a.model.split(",") if m.strip()]
    a.curves = [c.strip() for c in a.curves.split(",") if c.strip()]
    if not a.models or any(m not in M.PAPER_CLASSES for m in a.models):
        return f"--model {a.model!r}: of {', '.join(M.PAPER_CLASSES)}"
    if any(c not in CURVES[1:] for c in a.curves):
        return f"--curves {','.join(a.curves)!r}: of {', '.join(CURVES[1:])}"
    if a.steps < 0 or a.log_every < 1 or a.n_eval < 1:
        return "--steps >= 0, --log-every >= 1, --n-eval >= 1"
    try:
        mujoco_task(a.task)
    except (KeyError, ValueError) as e:
        return f"--task {a.task!r}: {str(e).splitlines()[0] if str(e) else 'unknown'}"
    return None


def main(argv=None) -> int:
    a = parse(argv)
    try:
        root = M.check_paper_code(a.seed_code)
    except SeedCodeError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    msg = argument_error(a)
    if msg:
        print(f"error: {msg}", file=sys.stderr)
        return 2
    msg = torch_error(a.torch_python, ("torch", "torchdiffeq", "pandas"))
    if msg:
        print(f"error: {msg}", file=sys.stderr)
        return 2

    from bench.core import setup_process

    setup_process(n=1)
    for name in a.models:
        lines = side_by_side(name, a, root, Path(a.out) / name)
        print("\n".join(lines))
    print(f"wrote {a.out}/<model>/checks.csv, curves.csv, verdicts.txt")
    return 0


if __name__ == "__main__":
    sys.exit(main())
