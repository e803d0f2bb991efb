"""The pixel pendulum (claim 11) side by side with the HNN seed's own code.

    python -m bench.sidebyside.hnn_seed --seed-code /path/to/hamiltonian-nn \
        [--torch-python PATH] [--steps 2000] [--models hnn,node] [--out DIR]

``--seed-code`` is a checkout of the seed's public code (``git clone
https://github.com/greydanus/hamiltonian-nn``), read and run, never copied. The seed's side runs
in a separate Python with PyTorch (``--torch-python``, default ``$TORCH_PYTHON`` or ``python3``):
``_hnn_seed_torch.py`` imports its ``nn_models.py`` and ``hnn.py`` and runs, from
``experiment-pixels/train.py``, ``pixelhnn_loss`` and the statements of ``train`` that seed
torch and build ``MLPAutoencoder``, ``PixelHNN`` and ``torch.optim.Adam`` (details there).
Arrays go both ways through .npz files in ``--out``.

Both sides train on the SAME arrays: the suite's pixel dataset of the claim's rows
(``pixel_pendulum_hnn_seed`` at paper-core, seed ``--seed``: 160 training trajectories of 100
frames, 40 test ones of 102), the SAME batches (the windows the committed run drew, in its
order) and from the SAME initial parameters: the seed's, built by its code under
``torch.manual_seed(seed)`` and mapped onto our ``LatentModel`` (:mod:`._hnn_map`, which also
states the architectural differences). Checks, each with a one-line verdict:

- (a) the loss at initialisation term by term on the first batch: the reconstruction of the
  first observation (``ae0``, the seed's term) and of the second (``ae1``), the auxiliary
  term ``cc`` and the latent dynamics term ``dyn``; the seed's total ae0 + cc + 0.1 dyn. Our
  loss (``bench.core._pixels.seed_loss``) reconstructs both observations: (ae0 + ae1) / 2 +
  cc + 0.1 dyn, a stated difference;
- (b) the first gradient per layer, with our loss's definition on both sides (the seed's side:
  its ``pixelhnn_loss`` + (ae1 - ae0) / 2), float32 (as both ran) and float64, the seed's
  gradient of its own loss beside ours recorded as well; and the first Adam step of the
  dynamics network (whose gradient both losses share): PyTorch's Adam with weight decay against
  our ``adam_l2``;
- (c) curves over ``--steps`` steps: ``seed`` (its code: PyTorch's Adam, lr and weight decay
  read from train.py), ``ours`` (our model from the seed's parameters, our training step
  ``bench.core._train.make_step`` with the committed run's configuration: ``adam_l2``,
  constant lr, weight decay, Euler latent step) and ``suite`` (the committed run itself: our
  model from its own initialisation, its first ``--steps`` steps). Every ``--log-every`` steps
  the held-out terms on all test windows; every ``--eval-every`` steps and at the end the
  claim's metric, ``pixel_mse`` against ``pixel_mse_static`` (``evaluate_pixels`` of the
  committed rows, the seed's parameters mapped onto our model). The verdict compares the
  median held-out loss of the last quarter of the steps (tolerance in :mod:`._hnn_verdicts`);
- (d) the steps at which each curve first reaches the loss the seed's README reports and the
  claim's learning gate.

Writes ``curves.csv``, ``checks.csv`` and ``verdicts.txt`` to ``--out``, and caches the
rendered dataset there. The measured numbers: docs/sidebyside.md (the HNN seed's section).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from ._hnn_map import (  # noqa: F401 - the script's public names
    EXPECTED,
    SeedCodeError,
    check_seed_code,
    ours_to_seed,
    seed_to_ours,
)
from ._hnn_ours import (
    TERMS,
    Ours,
    all_windows,
    batch_stream,
    claim_metric,
    dataset,
    gather,
    our_grad,
    our_model,
    our_terms,
    run_config,
    seed_total,
)
from ._hnn_verdicts import curve_verdicts, init_checks, update_check
from ._seed import torch_error, write_table

MODELS = ("hnn", "node")
CURVES = ("seed", "ours", "suite")
TORCH_SCRIPT = Path(__file__).with_name("_hnn_seed_torch.py")


# ------------------------------------------------------------------------ the seed's side
def run_seed_side(python, root, model, seed, data, idx, held_idx, first, log_every, snaps, work):
    """Run ``_hnn_seed_torch.py``; its result (meta dict, arrays)."""
    req, res = work / f"request_{model}.npz", work / f"result_{model}.npz"
    meta = {
        "seed_code": str(root),
        "baseline": model == "node",
        "seed": seed,
        "log_every": log_every,
        "snapshots": sorted(snaps),
        "threads": int(os.environ.get("TORCH_THREADS", "1")),
    }
    np.savez(
        req,
        meta=json.dumps(meta),
        frames=data.frames_train,
        idx=idx.astype(np.int64),
        held_frames=data.frames_test,
        held_idx=held_idx.astype(np.int64),
        first=first.astype(np.int64),
    )
    subprocess.run([python, str(TORCH_SCRIPT), str(req), str(res)], check=True)
    z = np.load(res)
    arrays = {k: z[k] for k in z.files if k != "meta"}
    req.unlink()
    return json.loads(str(z["meta"])), arrays


def prefixed(arrays: dict, prefix: str) -> dict:
    return {k.split("/", 1)[1]: v for k, v in arrays.items() if k.startswith(prefix + "/")}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m bench.sidebyside.hnn_seed",
        description="Our pixel-pendulum training beside the HNN seed's code (same data, same "
        "batches, same initial parameters).",
    )
    p.add_argument("--seed-code", required=True, help="a checkout of greydanus/hamiltonian-nn")
    p.add_argument(
        "--torch-python",
        default=os.environ.get("TORCH_PYTHON", "python3"),
        help="a Python with torch and numpy (default: $TORCH_PYTHON or python3)",
    )
    p.add_argument("--steps", type=int, default=2000)
    p.add_argument("--log-every", type=int, default=100)
    p.add_argument(
        "--eval-every", type=int, default=500, help="claim metric; a multiple of --log-every"
    )
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--models", default=",".join(MODELS), help=f"of {', '.join(MODELS)}")
    p.add_argument("--curves", default=",".join(CURVES), help=f"of {', '.join(CURVES)}")
    p.add_argument("--out", default="results/own/sidebyside/hnn_seed")
    a = p.parse_args(argv)
    try:
        root = check_seed_code(a.seed_code)
    except SeedCodeError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    models_ = [m.strip() for m in a.models.split(",") if m.strip()]
    curves = [c.strip() for c in a.curves.split(",") if c.strip()]
    if (
        not models_
        or any(m not in MODELS for m in models_)
        or any(c not in CURVES for c in curves)
        or a.steps < 0
        or a.log_every < 1
        or a.eval_every < 1
        or a.eval_every % a.log_every
    ):
        msg = (
            f"--models of {', '.join(MODELS)}; --curves of {', '.join(CURVES)}; --steps >= 0; "
            "--eval-every a positive multiple of --log-every"
        )
        print(f"error: {msg}", file=sys.stderr)
        return 2
    msg = torch_error(a.torch_python, ("torch", "numpy"))
    if msg:
        print(f"error: {msg}", file=sys.stderr)
        return 2

    from bench.core import setup_process

    setup_process()
    import systems
    from bench.core import PixelObjective, pixel_train_config

    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    rows, lines, curve_rows = [], [], []

    def record(check, model, quantity, seed_v, ours_v, rel=None):
        rows.append(
            {
                "check": check,
                "model": model,
                "quantity": quantity,
                "seed": seed_v,
                "ours": ours_v,
                "rel": rel,
            }
        )

    for model in models_:
        c = run_config(model, a.seed)
        tcfg = pixel_train_config(c)
        system = systems.make(c.system, **c.system_kwargs())
        data = dataset(c, out / "dataset.npz")
        objective = PixelObjective(chunk=c.chunk)
        idx = batch_stream(objective, data.frames_train, tcfg, max(a.steps, 1))
        held_idx = all_windows(data.frames_test, c.chunk)
        held = gather(data.frames_test, held_idx, c.chunk)
        first = gather(data.frames_train, idx[0], c.chunk)
        evals = sorted(set(range(0, a.steps + 1, a.eval_every)) | {a.steps})
        snaps = sorted(set(evals) | ({1} if a.steps >= 1 else set()))
        if "seed" not in curves:  # the checks only: its first step
            snaps = [s for s in snaps if s <= 1]
        print(f"{model}: the seed's side, {a.steps} steps ...", flush=True)
        meta, arrays = run_seed_side(
            a.torch_python,
            root,
            model,
            a.seed,
            data,
            idx[: a.steps if "seed" in curves else min(a.steps, 1)],
            held_idx,
            idx[0],
            a.log_every,
            snaps,
            out,
        )
        st = meta["settings"]
        print(
            f"{model}: seed's train.py: lr {st['learn_rate']}, weight decay {st['weight_decay']}, "
            f"batch {st['batch_size']}, hidden {st['hidden_dim']}, latent {st['latent_dim']}, "
            f"{st['nonlinearity']}, Adam {st['adam']}; ours ({c.config_hash}): lr {tcfg.lr}, "
            f"weight decay {tcfg.weight_decay}, batch {tcfg.batch}, width {c.width}, "
            f"{tcfg.optimizer}, {tcfg.schedule}, train step {tcfg.integrator.method}"
        )
        init = prefixed(arrays, "init")
        base = our_model(c, system)
        mapped = seed_to_ours(init, base)
        for tag, dt in (("", "float32"), (" float64", "float64")):
            m = mapped if dt == "float32" else seed_to_ours(init, our_model(c, system, dt))
            w = first.astype(dt)
            ours_t = our_terms(m, w, tcfg.integrator)
            g_ours, extra = our_grad(m, w, tcfg.integrator)
            t = "64" if dt == "float64" else "32"
            g_pairs = {
                "b": (prefixed(arrays, f"grad_ours{t}"), g_ours),
                "b-own": (prefixed(arrays, f"grad_seed{t}"), g_ours),
            }
            init_checks(record, lines, model, tag, meta["init"][t], ours_t, g_pairs, extra)
        if a.steps >= 1:  # the first Adam step
            one = Ours(mapped, tcfg, data.frames_train, c.chunk)
            one.train(idx[:1])
            seed_layout = ours_to_seed(one.model)[0]
            update_check(record, lines, model, init, prefixed(arrays, "step1"), seed_layout)
        print("\n".join(lines[-5:]), flush=True)

        # (c) the curves
        seed_held = {h["step"]: h for h in meta["held"]}
        sides = {}
        if "ours" in curves:
            sides["ours"] = Ours(mapped, tcfg, data.frames_train, c.chunk)
        if "suite" in curves:
            sides["suite"] = Ours(base, tcfg, data.frames_train, c.chunk)
        seconds = dict.fromkeys(sides, 0.0)
        window = dict.fromkeys(sides, float("nan"))
        done = 0
        while True:
            for curve in ["seed", *sides] if "seed" in curves else list(sides):
                if curve == "seed":
                    h = seed_held[done]
                    tr = meta["train_loss"][max(0, done - a.log_every) : done]
                    row = {
                        "train_loss": float(np.mean(tr)) if tr else float("nan"),
                        "seconds": h["seconds"],
                        **{k: h[k] for k in TERMS},
                    }
                    cur = (
                        seed_to_ours(prefixed(arrays, f"step{done}"), base)
                        if done in evals
                        else None
                    )
                else:
                    cur = sides[curve].model
                    t_ = our_terms(cur, held, tcfg.integrator)
                    row = {
                        "train_loss": window[curve],
                        "seconds": seconds[curve],
                        **{k: t_[k] for k in TERMS},
                    }
                row["heldout_loss"] = seed_total(row)
                metric = claim_metric(c, system, data, cur) if done in evals else {}
                curve_rows.append({"model": model, "curve": curve, "step": done, **row, **metric})
            print(
                f"{model} step {done:6d} | "
                + " | ".join(
                    f"{r['curve']}: train {r['train_loss']:.3e} held-out {r['heldout_loss']:.3e}"
                    + (f" pixel MSE {r['pixel_mse']:.3e}" if "pixel_mse" in r else "")
                    for r in curve_rows[-(len(sides) + ("seed" in curves)) :]
                ),
                flush=True,
            )
            if done >= a.steps:
                break
            k = min(a.log_every, a.steps - done)
            for curve, side in sides.items():
                t0 = time.perf_counter()
                losses, _ = side.train(idx[done : done + k])
                seconds[curve] += time.perf_counter() - t0
                window[curve] = float(np.mean(losses))
            done += k
        curve_verdicts(record, lines, model, curve_rows, done)

    names = [
        "model",
        "curve",
        "step",
        "train_loss",
        "heldout_loss",
        *TERMS,
        "pixel_mse",
        "pixel_mse_static",
        "recon_mse",
        "seed_energy_mse",
        "seconds",
    ]
    write_table(out / "curves.csv", curve_rows, names)
    write_table(out / "checks.csv", rows, ["check", "model", "quantity", "seed", "ours", "rel"])
    for f in out.glob("result_*.npz"):
        f.unlink()
    (out / "verdicts.txt").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    print(f"wrote {out / 'curves.csv'}, {out / 'checks.csv'}, {out / 'verdicts.txt'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
