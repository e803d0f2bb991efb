"""NODE+SO and the HNNs on the chain pendulum (k = 2, or ``--k``), side by side with the
paper's own code.

    python -m bench.sidebyside.decon_hnn --seed-code /path/to/decon-hnn \\
        [--model node_so,hnn] [--k 2] [--steps 2000] [--out DIR]

``--seed-code`` is a checkout of the paper's public code (``git clone
https://github.com/ngruver/decon-hnn``), read and run, never copied. It is PyTorch code: its
side runs in another interpreter (``--torch-python``, default ``$DECON_TORCH_PYTHON`` or
``python3``, with torch, torchdiffeq, networkx, matplotlib and olive-oil-ml installed), the
script ``_decon_torch.py`` beside this one; the two sides exchange arrays through .npz files in
``--out``.

Our side is the ``paper`` profile's cell of the model (``second_order``, chain_pendulum, k =
``--k``, seed ``--seed``): its dataset, batch order (``Batches``), training configuration and step
(``bench.core._train.make_step``: the rollout loss over 5-point chunks by the 3/8-rule RK4,
clipping at 1, AdamW with decay 1e-4, cosine over 8000 steps). The paper's side runs its
``IntegratedDynamicsTrainer`` on the SAME arrays and batches, cast to float32 as its data are.

Per model (``node_so``: the paper's ``MechanicsNN``; ``hnn``: its ``NonseparableHNN``;
``hnn_so``: its ``HNN``; :mod:`bench.sidebyside._decon` says what differs), checks with
one-line verdicts:

- (0) the ground truth: the paper's constrained Cartesian chain mapped to angles against our
  field at the same states (qdot, qddot) and its energy, float32 (as it made its data) and
  float64; its data pipeline (dopri5 in float32, then angles) against our test windows;
- (a) the loss at initialisation on the first batch and (b) the first gradient per layer, of
  the paper's model against ours in the paper's parametrisation with the paper's parameters
  (``mapped``), float32 and float64; the suite's own model is reported beside them;
- (c) the curves over ``--steps`` steps of ``paper``, ``mapped``, ``suite`` (the suite's
  model as the campaign builds it: the run's first steps) and ``suite_mapped`` (the suite's
  model with the paper's network where one has a place in it,
  :data:`~bench.sidebyside._decon.SUITE_PLACES`) and ``registered`` (the registered model in
  the paper's parametrisation and initialisation, its own draw: :data:`REGISTERED`): the
  training loss, and every
  ``--log-every`` steps the paper's held-out metric (the geometric mean over the windows and
  times of ||err|| / (||pred|| + ||true||), angles not wrapped; from t = 1, and from t = 0 as
  the paper reports it) and the MSE; judged on the checkpoints of the second half (``late``);
- (l) learning, as the verdicts gate it (:mod:`._learn`): constant velocity's error over the
  model's on the held-out windows, for the paper's trained model and each curve's at the last
  step, beside our stored runs of the cell (``--results``, the seeds judged); the verdict asks
  whether the paper's code learns where ours does not.

Writes ``checks.csv``, ``curves.csv`` and ``verdicts.txt`` per model under ``--out``;
docs/sidebyside.md (the paper's code section) has the measured numbers.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time
from pathlib import Path

import numpy as np

from ._decon import (
    PAPER_CLASSES,
    build_mapped,
    cartesian_to_angular,
    check_paper_code,
    field_difference,
    first_point_term,
    gradient_rows,
    relative_max,
    suite_with_paper,
    wrapped_difference,
)
from ._decon_ours import Ours, loss_and_grad, paper_metric
from ._learn import constant_velocity, learns, scores, stored_ratio, verdict
from ._seed import SeedCodeError, run_side, torch_error, verdict_line, write_table

CURVES = ("paper", "mapped", "suite", "suite_mapped", "registered")
PROFILE = "paper"
# The suite's registered model in the paper's parametrisation and initialisation, per model
# (its own draw, not the paper's weights): the ``registered`` curve
REGISTERED = {
    "node_so": ("node_so_pq", {}),
    "hnn": ("hnn", {"inverse_mass": True, "init": "paper"}),
    "hnn_so": ("hnn_so", {"init": "paper"}),
}
TORCH_SCRIPT = Path(__file__).with_name("_decon_torch.py")
TOL_FIELD = {"32": 1e-4, "64": 1e-9}  # (0) max relative difference of qddot and of the energy
TOL_TRAJ = 1e-3  # (0) the paper's data pipeline against our windows, max |diff| / max |z|
TOL_LOSS = {"32": 1e-4, "64": 1e-10}  # (a) relative difference of the losses at init
TOL_GRAD = {"32": 1e-2, "64": 1e-8}  # (b) worst layer, ||g_paper - g_ours|| / ||g_ours||
TOL_CURVE = 0.25  # (c) late held-out metric (``late``) of a curve within 25 % of the paper's


def run_config(model: str, seed: int, k: int = 2):
    """The ``paper`` profile's chain-``k`` cell of ``model`` in ``second_order`` (its suite
    form, without model options)."""
    import bench

    cells = [
        c
        for c in bench.expand("second_order", PROFILE, seeds=[seed])
        if c.system == "chain_pendulum" and c.k == k and c.model == model and not c.model_options
    ]
    if len(cells) != 1:
        raise ValueError(f"{len(cells)} paper cells of {model} on chain_pendulum k = {k}")
    return cells[0]


def side_by_side(name: str, a, root: Path, out: Path) -> list[str]:
    """Every check of model ``name``; returns the verdict lines."""
    import jax

    import models
    from bench.core import Batches, build_run, train_config
    from systems import cache_root

    config = run_config(name, a.seed, a.k)
    system, data, scene, suite_model = build_run(config, cache_root())
    tcfg = train_config(config)
    out.mkdir(parents=True, exist_ok=True)
    k = system.dof
    z_train, ts_train = np.asarray(data.z_train), np.asarray(data.ts_train)
    z_eval = np.asarray(data.z_test)[: a.n_eval]
    ts_eval = np.asarray(data.ts_test) - float(np.asarray(data.ts_test)[0])
    batches = Batches(len(z_train), tcfg.batch, tcfg.seed).take(max(a.steps, 1))
    per_epoch = len(z_train) // min(tcfg.batch, len(z_train))
    gt_states = np.concatenate([z_eval[:, 0], z_train[:, 0]])
    traj = z_eval[: a.n_traj]
    print(
        f"{name} ({config.config_hash}): width {config.width}, {tcfg.steps} steps of "
        f"{tcfg.batch}, lr {tcfg.lr}, {tcfg.optimizer} decay {tcfg.weight_decay}, clip "
        f"{tcfg.clip}, {tcfg.schedule}, {tcfg.loss}, {config.train_integrator}",
        flush=True,
    )
    inp = out / "exchange_in.npz"
    np.savez(
        inp,
        model=name,
        k=k,
        width=config.width,
        net_seed=a.seed,
        lr=tcfg.lr,
        weight_decay=tcfg.weight_decay,
        num_epochs=tcfg.steps // per_epoch,
        steps_per_epoch=per_epoch,
        z_train=z_train,
        ts_train=ts_train,
        batches=batches,
        steps=a.steps,
        log_every=a.log_every,
        z_eval=z_eval,
        ts_eval=ts_eval,
        gt_states=gt_states,
        traj_z0=traj[:, 0],
        traj_ts=ts_eval,
    )
    t0 = time.perf_counter()
    if a.reuse_paper and (out / "paper_out.npz").exists():
        paper = dict(np.load(out / "paper_out.npz"))  # the paper's side of an earlier call
        if int(paper["losses"].shape[0]) < a.steps:
            raise ValueError(f"--reuse-paper: {out}/paper_out.npz holds fewer than {a.steps} steps")
    else:
        paper = run_side(a.torch_python, TORCH_SCRIPT, out, "--seed-code", root, "--inp", inp)
    print(f"paper's side: {time.perf_counter() - t0:.0f} s", flush=True)
    rows, lines = [], []

    def record(check, quantity, paper_v, ours_v, rel):
        rows.append(
            {"check": check, "quantity": quantity, "paper": paper_v, "ours": ours_v, "rel": rel}
        )

    # (0) the ground truth
    q = gt_states[:, :k]
    for tag in ("32", "64"):
        qdot, qddot = cartesian_to_angular(
            q, paper[f"gt{tag}_vel"], paper[f"gt{tag}_acc"], paper[f"gt{tag}_lengths"]
        )
        d = field_difference(system, gt_states, qdot, qddot, paper[f"gt{tag}_energy"])
        for key, v in d.items():
            record("0", f"{key} max rel. diff, float{tag}", None, None, v)
        ok = max(d["qddot"], d["energy"]) <= TOL_FIELD[tag]
        detail = ", ".join(f"{key} {v:.1e}" for key, v in d.items())
        lines.append(
            verdict_line(f"0 field float{tag}", ok, f"{len(q)} states: {detail}", TOL_FIELD[tag])
        )
    m_diff = relative_max(paper["gt64_masses"], np.asarray(system.masses))
    l_diff = relative_max(paper["gt64_lengths"], np.asarray(system.lengths))
    record("0", "masses, lengths max rel. diff", m_diff, l_diff, max(m_diff, l_diff))
    if "traj" in paper:
        dz = wrapped_difference(paper["traj"], traj, k)
        rel = float(np.max(np.abs(dz)) / np.max(np.abs(traj)))
        record("0", f"data pipeline, {len(traj)} windows of {len(ts_eval)} points", None, None, rel)
        lines.append(
            verdict_line(
                "0 data pipeline",
                rel <= TOL_TRAJ,
                f"{len(traj)} windows, max |diff| / max |z| {rel:.1e}",
                TOL_TRAJ,
            )
        )

    # (a), (b) at initialisation
    state = {key[2:]: v for key, v in paper.items() if key.startswith("w:")}
    key = jax.random.PRNGKey(a.seed)
    first = z_train[batches[0]]
    mapped = {}
    for tag, dtype in (("32", "float32"), ("64", "float64")):
        model = build_mapped(name, scene, config, dtype, state, key)
        mapped[tag] = model
        tc = dataclasses.replace(tcfg, dtype=dtype)
        lp = float(paper[f"loss0_{tag}"])
        grads_p = {key[4:]: v for key, v in paper.items() if key.startswith(f"g{tag}:")}
        z0 = np.asarray(first[:, 0], dtype)
        t0 = float(first_point_term(model, jax.numpy.asarray(z0), first.shape[1]))
        record("a", f"the paper's t = 0 term, float{tag}", t0, None, t0 / lp)
        worst = {}
        for extra in (False, True):  # ours as it is; ours plus the paper's t = 0 term
            lo, go = loss_and_grad(model, first, ts_train, tc, first_point=extra)
            what = " + the paper's t = 0 term" if extra else ""
            rel = abs(lp - lo) / abs(lp)
            record("a", f"loss at init{what}, float{tag}", lp, lo, rel)
            worst[extra] = 0.0
            for prefix, layer, kind, np_, no, r in gradient_rows(name, go, grads_p, k):
                record("b", f"grad {prefix} layer {layer} {kind}{what}, float{tag}", np_, no, r)
                worst[extra] = max(worst[extra], r)
            lines.append(
                verdict_line(
                    f"a loss at init{what} float{tag}",
                    rel <= TOL_LOSS[tag],
                    f"paper {lp:.10g}, ours {lo:.10g} (rel. {rel:.1e})",
                    TOL_LOSS[tag],
                )
            )
            lines.append(
                verdict_line(
                    f"b first gradient{what} float{tag}",
                    worst[extra] <= TOL_GRAD[tag],
                    f"worst layer rel. diff {worst[extra]:.1e}",
                    TOL_GRAD[tag],
                )
            )
    ls, _ = loss_and_grad(suite_model, first, ts_train, tcfg)
    record("a", "loss at init, the suite's own model and draw (float32)", None, ls, None)
    partial = suite_with_paper(name, suite_model, state)
    if partial is not None:
        ls, _ = loss_and_grad(partial, first, ts_train, tcfg)
        record("a", "loss at init, the suite's model with the paper's network", None, ls, None)
    print("\n".join(lines), flush=True)

    # (c) the curves
    from bench.core import prepare

    arrays = prepare(suite_model, data, tcfg)
    sides = {}
    if "mapped" in a.curves:
        sides["mapped"] = Ours(mapped["32"], tcfg, arrays)
    if "suite" in a.curves:
        sides["suite"] = Ours(suite_model, tcfg, arrays)
    if "suite_mapped" in a.curves and partial is not None:
        sides["suite_mapped"] = Ours(partial, tcfg, arrays)
    if "registered" in a.curves and name in REGISTERED:
        reg = models.make(
            REGISTERED[name][0],
            scene,
            key=jax.random.PRNGKey(a.seed),
            width=config.width,
            depth=config.depth,
            dtype=config.dtype,
            **REGISTERED[name][1],
        )
        sides["registered"] = Ours(reg, tcfg, arrays)
    curve_rows = []
    evals = paper["evals"]
    previous = 0
    for step, gerr_t0, gerr, mse, secs in evals:
        window = paper["losses"][previous : int(step)]
        previous = int(step)
        curve_rows.append(
            {
                "curve": "paper",
                "step": int(step),
                "train_loss": float(np.mean(window)) if len(window) else float("nan"),
                "heldout_gerr": gerr,
                "heldout_gerr_t0": gerr_t0,
                "heldout_mse": mse,
                "seconds": secs,
            }
        )
    final_paper = paper["pred_final"]
    trained, last = {}, {}
    for c, side in sides.items():
        done, losses, trained[c] = 0, np.zeros(0), []
        while True:
            pred = last[c] = side.predict(z_eval[:, 0], ts_eval)
            row = {
                "curve": c,
                "step": done,
                "train_loss": float("nan"),
                "heldout_gerr": paper_metric(pred, z_eval),
                "heldout_gerr_t0": paper_metric(pred, z_eval, t0=True),
                "heldout_mse": float(np.mean((pred - z_eval) ** 2)),
                "seconds": side.seconds,
            }
            if len(losses):
                row["train_loss"] = float(np.mean(losses))
            curve_rows.append(row)
            print(
                f"{c} step {done}: train {row['train_loss']:.4g}, held-out gerr "
                f"{row['heldout_gerr']:.4g}, MSE {row['heldout_mse']:.4g}",
                flush=True,
            )
            if done >= a.steps:
                break
            n = min(a.log_every, a.steps - done)
            losses = side.train(batches[done : done + n])
            trained[c].append(losses)
            done += n
    for t0, col in ((True, 1), (False, 2)):
        mine = paper_metric(final_paper, z_eval, t0=t0)
        record(
            "c",
            f"the paper's final gerr{' (t = 0 in)' if t0 else ''} by its trainer and "
            "by ours (metric parity)",
            evals[-1][col],
            mine,
            abs(mine - evals[-1][col]) / evals[-1][col],
        )
    gp = paper_metric(final_paper, z_eval)
    cost_p = float(paper["seconds"]) / max(a.steps, 1)
    record("cost", "seconds per training step, the paper's side", cost_p, None, None)
    for c, side in sides.items():
        record(
            "cost", f"seconds per training step, {c}", None, side.seconds / max(side.steps, 1), None
        )
        lc = np.concatenate(trained[c]) if trained[c] else np.zeros(0)
        np.save(out / f"{c}_losses.npy", lc)
        n = min(len(lc), len(paper["losses"]))
        gap = np.abs(lc[:n] - paper["losses"][:n]) / np.abs(paper["losses"][:n])
        apart = int(np.argmax(gap > 0.01)) if np.any(gap > 0.01) else None
        record(
            "c", f"first step whose training loss is 1 % off the paper's: {c}", None, apart, None
        )
        final = [r for r in curve_rows if r["curve"] == c][-1]
        record("c", f"held-out gerr at step {a.steps}: {c}", gp, final["heldout_gerr"], None)
        for key in ("train_loss", "heldout_gerr", "heldout_mse"):
            lp_, lo_ = late(curve_rows, "paper", key, a.steps), late(curve_rows, c, key, a.steps)
            record("c", f"late {key}: {c}", lp_, lo_, (lo_ - lp_) / lp_)
        lp_, lo_ = (
            late(curve_rows, "paper", "heldout_gerr", a.steps),
            late(curve_rows, c, "heldout_gerr", a.steps),
        )
        rel = (lo_ - lp_) / lp_
        word = "lags" if rel > TOL_CURVE else ("is ahead of" if rel < -TOL_CURVE else "matches")
        lines.append(
            verdict_line(
                f"c {c}",
                abs(rel) <= TOL_CURVE,
                f"held-out gerr over steps {a.steps // 2 + 1}-{a.steps} (geometric mean of the "
                f"checkpoints): paper {lp_:.4g}, {c} {lo_:.4g} ({rel:+.1%}: {word} the paper's); "
                f"at step {a.steps} paper {gp:.4g}, {c} {final['heldout_gerr']:.4g}",
                f"{TOL_CURVE:.0%}",
            )
        )
    lines += learning(name, system, a, z_eval, ts_eval, {"paper": final_paper, **last}, record)
    write_table(out / "curves.csv", curve_rows)
    write_table(out / "checks.csv", rows, ["check", "quantity", "paper", "ours", "rel"])
    np.save(out / "paper_losses.npy", paper["losses"])
    (out / "verdicts.txt").write_text("\n".join(lines) + "\n")
    return lines


def learning(name, system, a, z_eval, ts_eval, preds: dict, record) -> list[str]:
    """(l): constant velocity's error over each final prediction's on the held-out windows
    (the paper's trained model, each of our curves), our stored runs' ratio on the cell, and
    whether the paper's code learns where ours does not."""
    angular = tuple(system.angular)
    cv = scores(constant_velocity(z_eval, ts_eval), z_eval, angular)
    ratios = {c: cv["error"] / scores(p, z_eval, angular)["error"] for c, p in preds.items()}
    for c, r in ratios.items():
        what = f"constant velocity's error over the model's at step {a.steps}: {c}"
        record("l", what, r if c == "paper" else None, None if c == "paper" else r, None)
    cell = {"system": "chain_pendulum", "k": a.k}
    stored, n_seeds = stored_ratio(Path(a.results), cell, name)
    record("l", f"the same, our stored runs ({n_seeds} seeds)", None, stored, None)
    said = "; ".join(f"{c} {learns(r)}" for c, r in ratios.items())
    where = f"chain_pendulum k = {a.k}"
    return [
        f"l learning on {where}, constant velocity's error ({cv['error']:.4g}) over the model's "
        f"after {a.steps} steps: {said}; our stored runs ({n_seeds} seeds): {learns(stored)}",
        verdict(name, where, ratios["paper"], stored),
    ]


def late(rows, curve: str, key: str, steps: int) -> float:
    """The geometric mean of ``key`` over the checkpoints of ``curve`` in the second half of
    the ``steps`` (the last checkpoint alone when there is none): the held-out metric moves by
    tens of percent between checkpoints at the early, high learning rate."""
    vals = [r[key] for r in rows if r["curve"] == curve and r["step"] > steps // 2]
    vals = vals or [[r[key] for r in rows if r["curve"] == curve][-1]]
    return float(np.exp(np.mean(np.log(vals))))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m bench.sidebyside.decon_hnn",
        description="NODE+SO and the HNNs on the chain beside the paper's own code (same data, "
        "same batches, same initial parameters).",
    )
    p.add_argument("--seed-code", required=True, help="a checkout of ngruver/decon-hnn")
    p.add_argument("--model", default="node_so,hnn", help=f"of {', '.join(PAPER_CLASSES)}")
    p.add_argument("--steps", type=int, default=2000)
    p.add_argument("--log-every", type=int, default=250)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--k", type=int, default=2, help="the chain's links, 1-4 (the paper profile's)")
    p.add_argument(
        "--results", default="results/reference/paper", help="stored runs for (l) learning"
    )
    p.add_argument("--n-eval", type=int, default=200, help="held-out windows (of 200)")
    p.add_argument("--n-traj", type=int, default=4, help="windows through the paper's data code")
    p.add_argument("--curves", default=",".join(CURVES[1:]), help=f"of {', '.join(CURVES[1:])}")
    p.add_argument("--torch-python", default=os.environ.get("DECON_TORCH_PYTHON", "python3"))
    p.add_argument("--out", default="results/own/sidebyside/decon_hnn")
    p.add_argument(
        "--reuse-paper",
        action="store_true",
        help="take the paper's side from --out's paper_out.npz of an earlier call (same seed)",
    )
    a = p.parse_args(argv)
    try:
        root = check_paper_code(a.seed_code)
    except SeedCodeError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    names = [m.strip() for m in a.model.split(",") if m.strip()]
    a.curves = [c.strip() for c in a.curves.split(",") if c.strip()]
    if (
        not names
        or any(m not in PAPER_CLASSES for m in names)
        or any(c not in CURVES[1:] for c in a.curves)
        or a.steps < 0
        or a.log_every < 1
        or a.k not in (1, 2, 3, 4)
    ):
        msg = (
            f"--model of {', '.join(PAPER_CLASSES)}; --curves of {', '.join(CURVES[1:])}; "
            "--steps >= 0; --k of 1, 2, 3, 4"
        )
        print(f"error: {msg}", file=sys.stderr)
        return 2
    msg = torch_error(a.torch_python, ("torch", "torchdiffeq", "networkx", "oil"))
    if msg:
        print(f"error: {msg}", file=sys.stderr)
        return 2

    from bench.core import setup_process

    setup_process(n=1)
    for name in names:
        lines = side_by_side(name, a, root, Path(a.out) / name)
        print("\n".join(lines))
    print(f"wrote {a.out}/<model>/checks.csv, curves.csv, verdicts.txt")
    return 0


if __name__ == "__main__":
    sys.exit(main())
