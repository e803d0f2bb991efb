"""The pure LNN on the double pendulum, side by side with the LNN seed's own notebook code.

    python -m bench.sidebyside.lnn_seed --seed-code /path/to/lagrangian_nns [--steps 2000]

``--seed-code`` is a checkout of the seed's public code (``git clone
https://github.com/MilesCranmer/lagrangian_nns``), which this script reads and runs but never
copies. What runs of it: ``lnn.py`` (``raw_lagrangian_eom``, the pseudo-inverse Euler-Lagrange
solve, and ``custom_init``, appendix B's initialisation), ``utils.py`` (``wrap_coords``),
``experiment_dblpend/physics.py`` (``analytical_fn``), ``hyperopt/HyperparameterSearch.py``
(``extended_mlp``, ``learned_dynamics``) and, from ``notebooks/DoublePendulum.ipynb``, the cells
that trained the double-pendulum LNN: ``args``, ``loss`` (L1 summed over the batch plus the L2
term), ``OneCycleLR``, ``update_derivative`` (Adam of ``jax.experimental.optimizers`` with the
epoch fraction as its step count) and the training loop's L2 weight, taken out of the notebook
by name (its other cells are not run). The seed's old ``jax.experimental.stax`` and
``optimizers`` are mapped onto ``jax.example_libraries`` (their modern home, as the seed's README
says); the seed's side runs in float32 with 64-bit mode off, as it ran.

Both sides train on the SAME arrays (the suite's uniform states of the notebook's box) from the
SAME parameters: the seed's stax parameters mapped onto our MLP (:func:`seed_to_ours`), our
``LNN`` reading the seed's input (wrapped q, qdot) instead of (cos q, sin q, qdot).

Checks, each with a one-line verdict: (0) the training targets (the seed's field at g = 9.81
against ours); (a) the loss at initialisation, in the notebook's unit (sum over the four
components of |dz/dt error|, per state); (b) the first step's gradient per layer (the seed's
is of its summed loss / 2, ``len(batch)`` of a (states, targets) pair, so it is 2 x 512 times
ours, the mean over states and components: divided out before comparing); (c) the curves over
``--steps`` steps, each with its own optimiser and schedule: the training loss of every step
and, every ``--log-every`` steps, a held-out set's loss and dz/dt MSE (the suite's
``derivative_mse_test`` measure) beside the constant-velocity predictor's, and the RMS of the
predicted qddot beside the true one's (a model that predicts qddot = 0 is the constant-velocity
predictor). Curves:

- ``seed``: the notebook's code, lr 1e-5, its OneCycle over its 600,000 steps;
- ``ours_seed_schedule``: our LNN and trainer step (``bench.core._train.make_step``: optax Adam,
  L1 mean) from the seed's parameters, the notebook's lr and schedule length;
- ``ours_paper_core``: the same model with the paper-core run's training configuration
  (``lnn_seed_notebook``: peak 2e-4, OneCycle over 30,000 steps), its first ``--steps``;
- ``suite_paper_core``: the suite's own model (cos/sin input, its own initialisation) with the
  same configuration: the paper-core run's first ``--steps`` steps (its model, data stream and
  step).

Writes ``curves.csv``, ``checks.csv`` and ``verdicts.txt`` to ``--out``. docs/sidebyside.md has
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

from ._seed import (  # noqa: F401 - the script's public names
    EXPECTED,
    SeedCodeError,
    _seed_features_class,
    check_seed_code,
    load_seed,
    ours_to_seed,
    seed_to_ours,
    verdict_line,
    write_table,
)

CURVES = ("seed", "ours_seed_schedule", "ours_paper_core", "suite_paper_core")
DEFAULT_CURVES = ("seed", "ours_seed_schedule", "ours_paper_core")
PROFILE = "paper-core"  # the budget whose run the curves "ours/suite_paper_core" start
# Tolerances of the verdicts (float32 on both sides)
TOL_DATA = 1e-4  # (0) max |seed field - ours| / max |ours|
TOL_LOSS = 1e-3  # (a) relative difference of the losses at initialisation
TOL_GRAD = 1e-2  # (b) per layer ||g_seed / (2 B) - g_ours|| / ||g_ours||
TOL_CURVE = 0.1  # (c) held-out loss of a curve within 10 % of the seed's


# ------------------------------------------------------------------------ our side
def paper_core_config(seed: int):
    """The ``lnn_seed_notebook`` pure LNN's RunConfig at paper-core, for ``seed``."""
    import bench

    (c,) = [x for x in bench.expand("lnn_seed_notebook", PROFILE, seeds=[seed]) if x.model == "lnn"]
    return c


def our_model(config, seed_input: bool):
    """Our untrained LNN of ``config`` (``bench.core.model_of``, as a run makes it); with
    ``seed_input`` the seed's input (:class:`SeedFeatures`) instead of (cos q, sin q, qdot)."""
    import equinox as eqx

    import models
    from bench.core import model_of

    scene = models.Scene(dof=2, angular=(not seed_input,) * 2)
    model = model_of(config, scene)
    if seed_input:
        model = eqx.tree_at(lambda m: m.features, model, _seed_features_class()(scene))
    return model


def _box_stream(config, batch: int, seed: int):
    import systems
    from bench.core import BoxStates

    system = systems.make(config.system, **config.system_kwargs())
    return BoxStates(system, config.train_box, batch, seed, config.dtype), system


class Ours:
    """Our trainer's step (``bench.core._train.make_step``, the campaign's) on ``model`` with
    the training configuration ``tcfg``, ``block`` steps per compiled call."""

    def __init__(self, model, tcfg, config):
        import equinox as eqx
        import jax
        import jax.numpy as jnp

        from bench.core import make_step, objective, optimizer

        self.objective = objective(config)
        self.tcfg = tcfg
        params, self.static = eqx.partition(model, eqx.is_inexact_array)
        self.data = self.objective.data(model, None, tcfg)
        self.state = (params, optimizer(tcfg).init(params), jnp.asarray(False), params)
        step = make_step(self.static, tcfg, self.data, objective=self.objective)

        @jax.jit
        def run(state, idx):
            active = jnp.ones(idx.shape[0], bool)
            return jax.lax.scan(step, state, (idx, active))

        self._run = run
        self._field = jax.jit(
            lambda p, z: jax.vmap(
                lambda s: eqx.combine(p, self.static).vector_field(0.0, s, jnp.zeros((0,), s.dtype))
            )(z)
        )

    @property
    def model(self):
        import equinox as eqx

        return eqx.combine(self.state[0], self.static)

    def train(self, block):
        """``block`` (k, B, 2, 4) batches: k steps; their losses (before each update)."""
        self.state, (losses, failed) = self._run(self.state, block)
        return np.asarray(losses, float), bool(np.asarray(failed).any())

    def predict(self, z):
        return np.asarray(self._field(self.state[0], z), float)

    def loss_and_grad(self, batch):
        import equinox as eqx

        def f(m):
            return self.objective.loss(m, self.data, batch, self.tcfg)

        loss, g = eqx.filter_value_and_grad(f)(self.model)
        return float(loss), g


class Seed:
    """The notebook's training step, on its own Adam state; ``schedule_steps`` the length its
    ``OneCycleLR`` fraction runs over (the notebook: epochs x minibatches)."""

    def __init__(self, seed, params, schedule_steps: int):
        import jax

        self.s, self.schedule_steps, self.done = seed, schedule_steps, 0
        with jax.enable_x64(False):
            self.opt_state = seed.opt_init(params)
            self._loss = jax.jit(seed.loss)

    @property
    def params(self):
        return self.s.get_params(self.opt_state)

    def train(self, block):
        import jax

        losses = []
        with jax.enable_x64(False):
            for b in np.asarray(block):
                batch = (jax.numpy.asarray(b[:, 0]), jax.numpy.asarray(b[:, 1]))
                fraction = self.done / self.schedule_steps  # the notebook's (epoch + mb / mbs) / E
                self.opt_state, params = self.s.update_derivative(
                    fraction, self.opt_state, batch, self.s.l2reg
                )
                # the notebook's cur_loss: loss(params, batch, 0.0), params before the update
                losses.append(float(self._loss(params, batch, 0.0)) / len(b))
                self.done += 1
        return np.asarray(losses), not np.all(np.isfinite(losses))

    def predict(self, z):
        import jax

        with jax.enable_x64(False):
            return np.asarray(self.s.eom(self.params, jax.numpy.asarray(z, "float32")), float)

    def loss_and_grad(self, batch, x64: bool = False):
        """The loss (summed, L2 term off) and the gradient of the notebook's update (its L2
        term on) at the current parameters, in float32 or (``x64``) float64."""
        import jax
        import jax.numpy as jnp

        dtype = jnp.float64 if x64 else jnp.float32
        with jax.enable_x64(x64):
            params = jax.tree.map(lambda x: jnp.asarray(x, dtype), self.params)
            b = (jnp.asarray(batch[:, 0], dtype), jnp.asarray(batch[:, 1], dtype))
            # the notebook's update_derivative: jax.grad(lambda *args: loss(*args)/len(batch), 0)
            g = jax.grad(lambda *a: self.s.loss(*a) / len(b), 0)(params, b, self.s.l2reg)
            return float(self._loss(params, b, 0.0)), g


# ------------------------------------------------------------------------ the checks
def _per_state_l1(pred, target):
    """The notebook's printed loss: sum over components of |error|, mean over states."""
    return float(np.mean(np.sum(np.abs(pred - target), axis=-1)))


def _mse(pred, target):
    return float(np.mean((pred - target) ** 2))


def _batched(predict, z, size=512):
    return np.concatenate([predict(z[i : i + size]) for i in range(0, len(z), size)])


def _compare_init(record, tag, n, ls, gs, lo, go):
    """(a) and (b) on one batch of ``n`` states: the relative difference of the losses (both
    as the sum over components of |dz/dt error| per state) and the worst relative difference
    of a layer's gradient; one row per quantity through ``record``."""
    ls_state, lo_state = ls / n, lo * 4  # the seed's summed loss; ours, the mean over 4 dz/dt
    rel_a = abs(ls_state - lo_state) / abs(ls_state)
    record("a", f"loss at init (sum |dz/dt err| per state){tag}", ls_state, lo_state, rel_a)
    scale = 2.0 * n  # the seed's gradient is of sum / len((states, targets)) = sum / 2
    worst = 0.0
    dense = [p for p in gs if len(p)]
    for i, (w, b) in enumerate(zip(go.net.weights, go.net.biases, strict=True)):
        for kind, x_o, x_s in (("W", w, dense[i][0]), ("b", b, dense[i][1])):
            x_o, x_s = np.asarray(x_o, float), np.asarray(x_s, float) / scale
            rel = float(np.linalg.norm(x_s - x_o) / max(np.linalg.norm(x_o), 1e-300))
            worst = max(worst, rel)
            norms = float(np.linalg.norm(x_s)), float(np.linalg.norm(x_o))
            record("b", f"grad layer {i} {kind}{tag}", *norms, rel)
    return rel_a, worst


def main(argv=None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m bench.sidebyside.lnn_seed",
        description="Our pure LNN's training beside the LNN seed's notebook code (same data, "
        "same initial parameters).",
    )
    p.add_argument("--seed-code", required=True, help="a checkout of MilesCranmer/lagrangian_nns")
    p.add_argument("--steps", type=int, default=2000)
    p.add_argument("--log-every", type=int, default=100)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--n-eval", type=int, default=1024, help="held-out states")
    p.add_argument("--curves", default=",".join(DEFAULT_CURVES), help=f"of {', '.join(CURVES)}")
    p.add_argument("--width", type=int, default=None, help="override (default: the notebook's)")
    p.add_argument("--batch", type=int, default=None, help="override (default: the notebook's)")
    p.add_argument("--out", default="results/own/sidebyside/lnn_seed")
    a = p.parse_args(argv)
    try:
        root = check_seed_code(a.seed_code)
    except SeedCodeError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    curves = [c.strip() for c in a.curves.split(",") if c.strip()]
    bad = [c for c in curves if c not in CURVES]
    if bad or a.steps < 0 or a.log_every < 1:
        msg = f"--curves of {', '.join(CURVES)}; --steps >= 0, --log-every >= 1"
        print(f"error: {msg}", file=sys.stderr)
        return 2

    from bench.core import setup_process

    setup_process()
    import jax

    from bench.core import train_config

    overrides = {"hidden_dim": a.width, "batch_size": a.batch}
    seed = load_seed(root, **{k: v for k, v in overrides.items() if v is not None})
    width, batch = int(seed.args.hidden_dim), int(seed.args.batch_size)
    config = paper_core_config(a.seed)
    if (config.width, config.depth, config.batch) != (width, int(seed.args.layers), batch):
        print(f"note: width/depth/batch set to the seed's {width}/{seed.args.layers}/{batch}")
        config = dataclasses.replace(config, width=width, depth=int(seed.args.layers), batch=batch)
    if seed.args.act != config.activation:
        print(f"error: the notebook's activation {seed.args.act!r}, ours {config.activation!r}")
        return 2
    tcfg_run = train_config(config)
    tcfg_seed = dataclasses.replace(tcfg_run, steps=seed.steps, lr=seed.lr)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    print(
        f"seed code {root}; notebook: width {seed.args.hidden_dim}, layers {seed.args.layers}, "
        f"{seed.args.act}, batch {seed.args.batch_size}, lr {seed.lr} over {seed.steps} steps, "
        f"L2 {seed.l2reg}; ours ({config.config_hash}): width {width}, batch {batch}, "
        f"lr {tcfg_run.lr} over {tcfg_run.steps} steps, {tcfg_run.optimizer}, {tcfg_run.loss}"
    )

    import equinox as eqx

    init = seed.init(a.seed)
    base = our_model(config, seed_input=True)
    mapped_model = eqx.tree_at(lambda m: m.net, base, seed_to_ours(init, base.net))
    stream, system = _box_stream(config, batch, a.seed)
    first = stream.take(1)[0]  # (B, 2, 4): the first step's batch of every side
    held, _ = _box_stream(config, a.n_eval, a.seed + 1_000_003)
    z_eval = held.take(1)[0]
    z_held, dz_held = z_eval[:, 0], z_eval[:, 1].astype(float)
    cv = np.concatenate([z_held[:, 2:], np.zeros_like(z_held[:, 2:])], axis=1)

    rows, lines = [], []

    def record(check, quantity, seed_v, ours_v, rel=None):
        rows.append(
            {"check": check, "quantity": quantity, "seed": seed_v, "ours": ours_v, "rel": rel}
        )

    # (0) the targets: the seed's analytic field at our g against ours (float64 truth)
    g = float(getattr(system, "g", 9.81))
    with jax.enable_x64(False):
        f_seed = np.asarray(seed.field(jax.numpy.asarray(first[:, 0]), g), float)
        f_seed_98 = np.asarray(seed.field(jax.numpy.asarray(first[:, 0]), 9.8), float)
    f_ours = first[:, 1].astype(float)
    d0 = float(np.max(np.abs(f_seed - f_ours)) / np.max(np.abs(f_ours)))
    d98 = float(np.max(np.abs(f_seed_98 - f_ours)) / np.max(np.abs(f_ours)))
    record("0", f"max |field| rel. diff at g={g}", None, None, d0)
    record("0", "max |field| rel. diff, the seed's g=9.8", None, None, d98)
    lines.append(
        verdict_line(
            "0 targets",
            d0 <= TOL_DATA,
            f"max rel. diff {d0:.2e} at g = {g} ({d98:.2e} at the "
            "notebook's 9.8: our targets use 9.81)",
            TOL_DATA,
        )
    )

    # (a) the loss at initialisation and (b) the first gradient, on the first batch; float32
    # (as both ran) and float64 (both sides; what remains there is not rounding)
    side_seed = Seed(seed, init, seed.steps)
    side_ours = Ours(mapped_model, tcfg_seed, config)
    c64 = dataclasses.replace(config, dtype="float64")
    base64 = our_model(c64, seed_input=True)
    ours64 = Ours(
        eqx.tree_at(lambda m: m.net, base64, seed_to_ours(init, base64.net)),
        dataclasses.replace(tcfg_seed, dtype="float64"),
        c64,
    )
    for tag, x64, ours_side in (("", False, side_ours), (" float64", True, ours64)):
        batch0 = first.astype(np.float64 if x64 else np.float32)
        ls, gs = side_seed.loss_and_grad(batch0, x64=x64)
        lo, go = ours_side.loss_and_grad(batch0)
        rel_a, worst = _compare_init(record, tag, first.shape[0], ls, gs, lo, go)
        lines.append(
            verdict_line(
                f"a loss at init{tag}",
                rel_a <= TOL_LOSS,
                f"seed {ls / first.shape[0]:.6g}, ours {lo * first.shape[-1]:.6g} per state "
                f"(rel. {rel_a:.1e})",
                TOL_LOSS,
            )
        )
        lines.append(
            verdict_line(
                f"b first gradient{tag}",
                worst <= TOL_GRAD,
                f"worst layer rel. diff {worst:.1e} (the seed's / {2 * first.shape[0]} "
                "against ours)",
                TOL_GRAD,
            )
        )
    print("\n".join(lines))

    # (c) the curves
    sides = {}
    for c in curves:
        if c == "seed":
            sides[c] = side_seed
        elif c == "ours_seed_schedule":
            sides[c] = side_ours
        elif c == "ours_paper_core":
            sides[c] = Ours(mapped_model, tcfg_run, config)
        else:
            sides[c] = Ours(our_model(config, seed_input=False), tcfg_run, config)
    streams = {c: _box_stream(config, batch, a.seed)[0] for c in curves}
    curve_rows = []
    cv_mse, cv_l1 = _mse(cv, dz_held), _per_state_l1(cv, dz_held)
    print(f"held-out ({a.n_eval} states): constant velocity MSE {cv_mse:.4g}, L1 {cv_l1:.4g}")
    alive = dict.fromkeys(curves, True)
    seconds = dict.fromkeys(curves, 0.0)
    window = dict.fromkeys(curves, math.nan)
    done = 0
    while True:
        for c in curves:
            pred = _batched(sides[c].predict, z_held)
            curve_rows.append(
                {
                    "curve": c,
                    "step": done,
                    "train_loss": window[c],
                    "heldout_l1": _per_state_l1(pred, dz_held),
                    "heldout_mse": _mse(pred, dz_held),
                    "qddot_rms": float(np.sqrt(np.mean(pred[:, 2:] ** 2))),
                    "true_qddot_rms": float(np.sqrt(np.mean(dz_held[:, 2:] ** 2))),
                    "const_velocity_mse": cv_mse,
                    "seconds": seconds[c],
                }
            )
        print(
            f"step {done:6d} | "
            + " | ".join(
                f"{c}: train {r['train_loss']:.4g} held-out L1 {r['heldout_l1']:.4g} "
                f"MSE {r['heldout_mse']:.4g}"
                for c, r in zip(curves, curve_rows[-len(curves) :], strict=True)
            ),
            flush=True,
        )
        if done >= a.steps:
            break
        k = min(a.log_every, a.steps - done)
        for c in curves:
            block = streams[c].take(k)
            if not alive[c]:
                window[c] = math.nan
                continue
            t0 = time.perf_counter()
            losses, failed = sides[c].train(block)
            seconds[c] += time.perf_counter() - t0
            if c != "seed":
                losses = losses * block.shape[-1]  # mean over components -> sum per state
            window[c] = float(np.mean(losses))
            alive[c] = not failed
        done += k

    write_table(out / "curves.csv", curve_rows)
    if "seed" in curves:
        final = {r["curve"]: r for r in curve_rows if r["step"] == done}
        s = final["seed"]["heldout_l1"]
        for c in curves:
            if c == "seed":
                continue
            o = final[c]["heldout_l1"]
            rel = (o - s) / s
            record("c", f"held-out L1 at step {done}: {c}", s, o, rel)
            word = "lags" if rel > TOL_CURVE else ("is ahead of" if rel < -TOL_CURVE else "matches")
            lines.append(
                verdict_line(
                    f"c {c}",
                    abs(rel) <= TOL_CURVE,
                    f"at step {done} held-out L1 seed {s:.4g}, {c} {o:.4g} ({rel:+.1%}: {word} "
                    f"the seed's); MSE seed {final['seed']['heldout_mse']:.4g}, {c} "
                    f"{final[c]['heldout_mse']:.4g}, constant velocity {cv_mse:.4g}",
                    f"{TOL_CURVE:.0%}",
                )
            )
    write_table(out / "checks.csv", rows, ["check", "quantity", "seed", "ours", "rel"])
    (out / "verdicts.txt").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    print(f"wrote {out / 'curves.csv'}, {out / 'checks.csv'}, {out / 'verdicts.txt'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
