"""Claim 7's three models on the relativistic particle, side by side with the LNN seed's notebooks.

    python -m bench.sidebyside.lnn_relativistic --seed-code /path/to/lagrangian_nns \\
        [--steps 1500] [--models lnn,hnn_p,hnn_naive] [--curves seed,ours] [--out DIR]

``--seed-code`` is a checkout of the seed's public code (``git clone
https://github.com/MilesCranmer/lagrangian_nns``), read and run, never copied. From each of
``notebooks/SpecialRelativity.ipynb`` (the LNN), ``SpecialRelativity-HNN.ipynb`` (the naive HNN,
qdot standing in for p) and ``SpecialRelativity-HNN-CorrectP.ipynb`` (the HNN on canonical
(q, p)) the cells that define and train the model are taken out by name and run
(:mod:`bench.sidebyside._relativistic_seed`): its equation of motion, ``loss`` (L1 weighted by
1 + 1 / sqrt(1 - qdot^2)), ``gen_data_batch``, ``OneCycleLR``, ``update_derivative`` (Adam of
``jax.experimental.optimizers`` with the run's fraction as its step count), the loop's batch,
with ``hyperopt``'s ``extended_mlp`` and ``lnn.py``'s ``custom_init`` (the LNN only). The seed's
side runs in float32 with 64-bit mode off and jax's old (non-partitionable) threefry, as the
notebooks ran: its initial parameters and batches are then the notebooks' own, which check (0)
shows by reproducing the loss each notebook printed at initialisation.

Both sides start from the SAME parameters (the notebook's stax parameters mapped onto our MLP)
and see the SAME batches (the notebook's sampler): our models (``models.make`` of the
``relativistic_seed`` paper-core cells: the naive HNN, the canonical HNN, the pure LNN with the
pseudo-inverse) read the notebook's batch in the coordinates that make them compute what its
code computes (``to_ours``: q / 10 and g / 10 as the notebooks feed their networks, p for the
canonical HNN). Checks, with one-line verdicts per model:

- (0) the seed's code rerun here against the loss its notebook printed at initialisation;
- (a) at initialisation, on the first batch: the predicted field (as the notebook's loss
  compares it) and the notebook's loss, its code against our model, float32 and float64;
- (b) the gradient of the notebook's loss, per layer, its code against our model, float32 and
  float64; beside it, as information, the cosine between that gradient and our trainer's (its
  loss is plain L1 of dz/dt in our model's coordinates, unweighted: a designed difference);
- (c) ``--steps`` steps of each side's own training from that start, logged every
  ``--log-every`` steps: the training loss (each side's own) and the loss in the notebook's
  measure (what it prints) on ``--n-eval`` held-out states of the notebooks' distribution,
  beside the constant-velocity predictor's (qddot = 0, qdot exact); ``seed``: the notebook's
  step, its schedule over its 300,000 steps; ``ours``: our trainer's step
  (``bench.core.make_step``) with the paper-core configuration (AdamW, cosine over 30,000 steps,
  plain L1, float64), on the notebook's batches of 512 states (paper-core's are 32);
  ``ours_slow`` (not by default): the same at the notebook's effective starting rate
  (:data:`SLOW_LR`), and ``ours_weighted`` (not by default): our trainer on the notebook's
  weighted loss: they tell the step size's part of a gap from the loss weights'; and
  ``ours_seed_adam`` (not by default): our model on the notebook's loss, stepped by the
  notebook's own optimiser and schedule: what it leaves between the sides is the optimiser;
- (d) the budget: the step at which the seed's code reaches the final loss its notebook printed,
  or the loss reached and the measured seconds per step, and from them the CPU hours of the
  notebook's full schedule.

Writes ``checks.csv``, ``curves.csv`` and ``verdicts.txt`` to ``--out``; docs/sidebyside.md has
the measured numbers and the conclusion.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from pathlib import Path

import numpy as np

from . import _relativistic_seed as R
from ._relativistic_ours import (  # noqa: F401 - the script's public names
    CELLS,
    PROFILE,
    Ours,
    OursSeedAdam,
    SeedBatches,
    WeightedSeedBatches,
    net_of,
    our_model,
    ours_batch,
    paper_core_config,
)
from ._relativistic_seed import EXPECTED, MODELS, SeedCodeError, check_seed_code  # noqa: F401
from ._seed import (  # noqa: F401 - the script's public names
    ours_to_seed,
    seed_to_ours,
    verdict_line,
    write_table,
)

CURVES = ("seed", "ours", "ours_slow", "ours_weighted", "ours_seed_adam")
DEFAULT_CURVES = ("seed", "ours")
# ``ours_slow``: our trainer at the notebook's effective starting rate (its Adam counts steps in
# epoch fractions, so it moves at about a third of its one-cycle rate: about 2e-4)
SLOW_LR = 2e-4
# ``ours_weighted``: our trainer on the notebook's loss (its weights towards c), our rate
SEEDS_CLAIM = 10  # seeds per model in a claim-7 reading: the budget's multiplier
# Tolerances of the verdicts
TOL_PRINTED = 1e-3  # (0) relative, the seed's code here against the notebook's printout
TOL = {"float32": (1e-3, 1e-2), "float64": (1e-9, 1e-7)}  # (a) field and loss, (b) gradient
TOL_CURVE = 0.1  # (c) held-out loss of ours within 10 % of the seed's


# ------------------------------------------------------------------------ the checks
def ours_loss_and_grad(kind, model, batch, tcfg):
    """Through our model: the notebook's loss (our field as its loss compares it), its
    gradient and the predictions; then our trainer's own loss and gradient (``tcfg``)."""
    import equinox as eqx
    import jax
    import jax.numpy as jnp

    dt = jnp.dtype(model.dtype)
    z, a, _ = (jnp.asarray(x, dt) for x in R.to_ours(kind, *batch))
    v = jnp.asarray(np.asarray(batch[0], float)[:, 1:], dt)
    target = jnp.asarray(np.asarray(batch[2], float), dt)
    field = lambda m: jax.vmap(lambda zz, aa: m.vector_field(0.0, zz, aa))(z, a)
    notebook = lambda m: R.weighted_l1(R.seed_form(kind, field(m), v, jnp), target, v, jnp)
    loss, g = eqx.filter_value_and_grad(notebook)(model)
    pred = np.asarray(R.seed_form(kind, field(model), v, jnp), float)
    arr = jnp.asarray(ours_batch(kind, batch, model.dtype))
    cfg = dataclasses.replace(tcfg, dtype=model.dtype)
    own, g_own = eqx.filter_value_and_grad(lambda m: SeedBatches().loss(m, None, arr, cfg))(model)
    return float(loss), g, pred, float(own), g_own


def _flat(dense):
    return np.concatenate([np.asarray(x, float).ravel() for layer in dense for x in layer])


def compare_init(record, kind, dtype, seed_out, ours_out):
    """(a) and (b) on one batch; one row per quantity through ``record``; returns the worst
    relative differences (field, loss, gradient) and the cosine of the trainers' gradients."""
    (ls, gs, ps), (lo, go, po, own, g_own) = seed_out, ours_out
    tag = f"{kind} {dtype}"
    rel_f = float(np.max(np.abs(ps - po)) / np.max(np.abs(ps)))
    record("a", f"{tag}: max |field difference| / max |field|", None, None, rel_f)
    rel_l = abs(ls - lo) / abs(ls)
    record("a", f"{tag}: the notebook's loss at init", ls, lo, rel_l)
    record("a", f"{tag}: our trainer's loss at init (plain L1, ours only)", None, own, None)
    dense = [p for p in gs if len(p)]
    net, worst = net_of(go), 0.0
    for i, (w, b) in enumerate(zip(net.weights, net.biases, strict=True)):
        for name, x_o, x_s in (("W", w, dense[i][0]), ("b", b, dense[i][1])):
            x_o, x_s = np.asarray(x_o, float), np.asarray(x_s, float)
            rel = float(np.linalg.norm(x_s - x_o) / max(np.linalg.norm(x_o), 1e-300))
            worst = max(worst, rel)
            record(
                "b", f"{tag}: grad layer {i} {name}", np.linalg.norm(x_s), np.linalg.norm(x_o), rel
            )
    own_net = net_of(g_own)
    a, b = _flat(dense), _flat(zip(own_net.weights, own_net.biases, strict=True))
    cos = float(a @ b / (np.linalg.norm(a) * np.linalg.norm(b)))
    record("b", f"{tag}: cosine, the notebook's gradient vs our trainer's", None, None, cos)
    return rel_f, rel_l, worst, cos


def seconds_per_step(rows, curve, kind):
    """Training seconds per step after the first logged block (which compiles)."""
    r = [x for x in rows if (x["model"], x["curve"]) == (kind, curve) and x["step"] > 0]
    if len(r) < 2:
        return r[-1]["seconds"] / r[-1]["step"] if r else math.nan
    return (r[-1]["seconds"] - r[0]["seconds"]) / (r[-1]["step"] - r[0]["step"])


def run_model(kind, a, root, curves, record, lines, curve_rows) -> dict:
    """Checks (0), (a), (b), the curves (c) and the budget (d) of one model; its budget."""
    from bench.core import train_config

    nb = R.load_notebook(root, kind)
    batch = a.batch or nb.batch
    config = paper_core_config(kind, a.seed)
    width, depth = int(nb.args.hidden_dim), int(nb.args.layers)
    if (config.width, config.depth) != (width, depth):
        print(f"note: {kind}: width/depth set to the notebook's {width}/{depth}")
        config = dataclasses.replace(config, width=width, depth=depth)
    if nb.args.act != config.activation:
        raise SeedCodeError(
            f"{nb.notebook}: activation {nb.args.act!r}, ours {config.activation!r}"
        )
    tcfg = dataclasses.replace(train_config(config), batch=batch)
    print(
        f"{kind}: {nb.notebook}: width {width}, layers {depth}, {nb.args.act}, batch {batch}, "
        f"lr {nb.lr} over {nb.steps} steps, custom_init {nb.custom_init}; ours "
        f"({config.config_hash}): lr {tcfg.lr} over {tcfg.steps} steps, {tcfg.optimizer}, "
        f"{tcfg.schedule}, {tcfg.loss}, {tcfg.dtype}",
        flush=True,
    )
    init = nb.init(a.seed)
    sampler = R.Sampler(nb, batch)
    first = sampler.take(1, 0)[0]

    if nb.printed_init is not None and a.seed == 0:  # (0) the notebook's own printout
        import jax

        n, value = nb.printed_init
        with jax.enable_x64(False):
            mine = float(nb.loss(init, *nb.gen_data_batch(0, n)))
        rel = abs(mine - value) / abs(value)
        record("0", f"{kind}: loss at init on gen_data_batch(0, {n})", value, mine, rel)
        detail = f"printed {value:.7g}, the seed's code here {mine:.7g} (rel. {rel:.1e})"
        lines.append(
            verdict_line(f"0 {kind} printed loss", rel <= TOL_PRINTED, detail, TOL_PRINTED)
        )

    for dtype, x64 in (("float32", False), ("float64", True)):  # (a), (b)
        s_out = R.seed_loss_and_grad(nb, init, first, x64)
        o_out = ours_loss_and_grad(kind, our_model(config, init, dtype), first, tcfg)
        rel_f, rel_l, worst, cos = compare_init(record, kind, dtype, s_out, o_out)
        tol_a, tol_b = TOL[dtype]
        detail = (
            f"the notebook's loss {s_out[0]:.7g}, through ours {o_out[0]:.7g} (rel. {rel_l:.1e}); "
            f"field max rel. {rel_f:.1e}; our trainer's own loss {o_out[3]:.4g}"
        )
        lines.append(verdict_line(f"a {kind} {dtype}", max(rel_f, rel_l) <= tol_a, detail, tol_a))
        detail = f"worst layer rel. {worst:.1e}; cosine with our trainer's gradient {cos:.3f}"
        lines.append(verdict_line(f"b {kind} {dtype} gradient", worst <= tol_b, detail, tol_b))
    print("\n".join(lines[-5:]), flush=True)

    all_sides = {"seed": lambda: R.Seed(nb, init)}  # (c) the curves
    all_sides["ours"] = lambda: Ours(kind, our_model(config, init, config.dtype), tcfg)
    slow = dataclasses.replace(tcfg, lr=SLOW_LR)
    all_sides["ours_slow"] = lambda: Ours(kind, our_model(config, init, config.dtype), slow)
    all_sides["ours_weighted"] = lambda: Ours(
        kind, our_model(config, init, config.dtype), tcfg, WeightedSeedBatches(kind)
    )
    all_sides["ours_seed_adam"] = lambda: OursSeedAdam(
        kind, our_model(config, init, config.dtype), tcfg, nb
    )
    sides = {c: all_sides[c]() for c in curves}
    hs, hg = R.held_out(a.n_eval, a.seed + 1_000_003)
    truth, v = R.seed_targets(kind, hs, hg), hs[:, 1:].astype(float)
    const = truth.copy()
    const[:, -1] = 0.0  # constant velocity: qddot = 0 (qdot exact)
    cv = float(R.weighted_l1(const, truth, v))
    cs, _, ct = sampler.epoch_arrays(0)  # the same on the batches of the notebook's epoch 0
    cv0 = float(R.weighted_l1(0.0 * ct[:, -1:], ct[:, -1:], cs[:, 1:].astype(float)))
    record("c", f"{kind}: constant velocity, held-out ({a.n_eval} states)", None, cv, None)
    record("c", f"{kind}: constant velocity, the notebook's epoch-0 batches", None, cv0, None)
    alive, secs = dict.fromkeys(sides, True), dict.fromkeys(sides, 0.0)
    window, done = dict.fromkeys(sides, math.nan), 0
    while True:
        for c, side in sides.items():
            pred = np.concatenate(
                [side.predict(hs[i : i + 2048], hg[i : i + 2048]) for i in range(0, len(hs), 2048)]
            )
            curve_rows.append(
                {
                    "model": kind,
                    "curve": c,
                    "step": done,
                    "train_loss": window[c],
                    "heldout_loss": float(R.weighted_l1(pred, truth, v)),
                    "heldout_qddot_l1": float(np.mean(np.abs(pred[:, -1] - truth[:, -1]))),
                    "const_velocity_loss": cv,
                    "seconds": secs[c],
                }
            )
        last = {r["curve"]: r for r in curve_rows[-len(sides) :]}
        print(
            f"{kind} step {done:6d} | "
            + " | ".join(
                f"{c}: train {r['train_loss']:.4g} held-out {r['heldout_loss']:.4g}"
                for c, r in last.items()
            )
            + f" | constant velocity {cv:.4g}",
            flush=True,
        )
        if done >= a.steps:
            break
        k = min(a.log_every, a.steps - done)
        batches = sampler.take(k, done)
        for c, side in sides.items():
            if not alive[c]:
                window[c] = math.nan
                continue
            t0 = time.perf_counter()
            losses, failed = side.train(batches)
            secs[c] += time.perf_counter() - t0
            window[c], alive[c] = float(np.mean(losses)), not failed
        done += k

    if {"seed", "ours"} <= set(sides):
        s, o = last["seed"]["heldout_loss"], last["ours"]["heldout_loss"]
        rel = (o - s) / s
        record("c", f"{kind}: held-out loss at step {done} (notebook's measure)", s, o, rel)
        word = "lags" if rel > TOL_CURVE else ("is ahead of" if rel < -TOL_CURVE else "matches")
        detail = (
            f"at step {done} held-out loss seed {s:.4g}, ours {o:.4g} ({rel:+.1%}: ours {word} "
            f"the seed's); constant velocity {cv:.4g} (on the notebook's epoch-0 batches {cv0:.4g})"
        )
        lines.append(verdict_line(f"c {kind}", abs(rel) <= TOL_CURVE, detail, f"{TOL_CURVE:.0%}"))
    sps = {c: seconds_per_step(curve_rows, c, kind) for c in sides}
    for c in sides:
        record("d", f"{kind}: seconds per step, {c} (CPU, batch {batch})", None, sps[c], None)
    budget = {c: nb.steps * sps[c] / 3600 for c in sides}
    if "seed" in sides:
        final = nb.log[-1][1] if nb.log else math.nan
        rows = [r for r in curve_rows if (r["model"], r["curve"]) == (kind, "seed")]
        hit = next((r["step"] for r in rows if r["train_loss"] <= final), None)
        near = next((e for e, x in nb.log if x <= 1.1 * final), None)
        record("d", f"{kind}: the notebook's final printed loss", None, final, None)
        record("d", f"{kind}: seed's step reaching it (none: not in {done})", None, hit, None)
        record("d", f"{kind}: seed's train loss at step {done}", None, rows[-1]["train_loss"], None)
        record(
            "d",
            f"{kind}: CPU hours of the notebook's {nb.steps} steps, seed",
            None,
            budget["seed"],
            None,
        )
        reached = f"at step {hit}" if hit is not None else f"not within {done} steps"
        lines.append(
            f"(d {kind} budget) the seed's code reaches the notebook's final loss {final:.3g} "
            f"{reached} (train loss {rows[-1]['train_loss']:.4g}, held-out "
            f"{rows[-1]['heldout_loss']:.4g}); its log is first within 10% of it at epoch {near} "
            f"(step {None if near is None else (near + 1) * nb.minibatch_per}); at "
            f"{sps['seed']:.3f} s/step its {nb.steps} steps take {budget['seed']:.1f} CPU hours"
            + (
                f" (ours: {sps['ours']:.3f} s/step, {budget['ours']:.1f} h)"
                if "ours" in sps
                else ""
            )
        )
    return budget


def main(argv=None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m bench.sidebyside.lnn_relativistic",
        description="Claim 7's models beside the LNN seed's relativistic notebooks (same "
        "batches, same initial parameters).",
    )
    p.add_argument("--seed-code", required=True, help="a checkout of MilesCranmer/lagrangian_nns")
    p.add_argument("--steps", type=int, default=1500)
    p.add_argument("--log-every", type=int, default=100)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--n-eval", type=int, default=8192, help="held-out states")
    p.add_argument("--models", default="lnn,hnn_p,hnn_naive", help=f"of {', '.join(MODELS)}")
    p.add_argument("--curves", default=",".join(DEFAULT_CURVES), help=f"of {', '.join(CURVES)}")
    p.add_argument("--batch", type=int, default=None, help="override (default: the notebooks')")
    p.add_argument("--out", default="results/own/sidebyside/lnn_relativistic")
    a = p.parse_args(argv)
    try:
        root = check_seed_code(a.seed_code)
    except SeedCodeError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    kinds = [m.strip() for m in a.models.split(",") if m.strip()]
    curves = [c.strip() for c in a.curves.split(",") if c.strip()]
    bad = [x for x in kinds if x not in MODELS] + [c for c in curves if c not in CURVES]
    if bad or not kinds or not curves or a.steps < 0 or a.log_every < 1 or a.n_eval < 1:
        msg = (
            f"--models of {', '.join(MODELS)}; --curves of {', '.join(CURVES)}; "
            "--steps >= 0, --log-every >= 1, --n-eval >= 1"
        )
        print(f"error: {msg}" + (f" (got {', '.join(bad)})" if bad else ""), file=sys.stderr)
        return 2
    if a.batch is not None and a.batch < 1:
        print("error: --batch must be >= 1", file=sys.stderr)
        return 2

    from bench.core import setup_process

    setup_process()
    import jax

    # the notebooks' jax drew with the non-partitionable threefry: their batches and initial
    # parameters are reproduced only with it (check (0))
    jax.config.update("jax_threefry_partitionable", False)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    rows, lines, curve_rows, budget = [], [], [], {}

    def record(check, quantity, seed_v, ours_v, rel=None):
        rows.append(
            {"check": check, "quantity": quantity, "seed": seed_v, "ours": ours_v, "rel": rel}
        )

    for kind in kinds:
        try:
            budget[kind] = run_model(kind, a, root, curves, record, lines, curve_rows)
        except SeedCodeError as e:
            print(f"error: {e}", file=sys.stderr)
            return 2
    for c in curves:
        total = SEEDS_CLAIM * sum(b[c] for b in budget.values())
        record("d", f"CPU hours, {SEEDS_CLAIM} seeds x {', '.join(kinds)}, {c}", None, total, None)
        lines.append(
            f"(d total) {c}: {SEEDS_CLAIM} seeds x {len(kinds)} models of the notebooks' schedule: "
            f"{total:.0f} CPU hours at the measured step times"
        )
    write_table(out / "curves.csv", curve_rows)
    write_table(out / "checks.csv", rows, ["check", "quantity", "seed", "ours", "rel"])
    (out / "verdicts.txt").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    print(f"wrote {out / 'curves.csv'}, {out / 'checks.csv'}, {out / 'verdicts.txt'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
