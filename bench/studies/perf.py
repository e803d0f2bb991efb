"""Performance benchmark: training-step and rollout cost of every model at the reference setting.

Setting (REFERENCE.md, "Cost of the reference code"): 2-link chain (dof 2, angles), MLP width
256 x 2 hidden layers, batch 200 chunks of 5 points, rk4_38 one step per dt, float32. The
training data are synthetic (timing does not depend on their values; no simulation needed).

Per model: the median ms per training step, timed over blocks of ``block`` steps run as one
compiled ``lax.scan`` exactly as ``bench.train`` runs them (compile first, then ``repeats``
blocks, each waited for); the compile time; the median ms of a 40 x 100-step test rollout
(jitted ``rollout_batch``, no gradient); the step's FLOPs from XLA's cost analysis of one
step; and the FLOP floor = FLOPs / measured float32 matmul peak. The load average is recorded
beside each measurement because the machine may be shared.

``python -m bench perf --ensemble`` (:func:`ensemble_table`) writes ``results/perf_ensemble.csv``:
training runs per minute, M runs as one ensemble (``bench.core._ensemble``) vs the same M runs one
at a time, for M in 1, 5, 10, 20 and the paper models.

``python -m bench.perf [--models node,hnn_so] [--repeats 5] [--quick] [--seeds] [--flags]``
writes ``results/perf.csv`` (and ``results/perf_seeds.csv``, ``results/perf_flags.csv``).
``compile_s`` comes from JAX's persistent compilation cache when ``bench`` turned it on (the
``compile_cache`` column); ``DECON_JAX_CACHE=0`` measures cold compiles.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

from ..core._env import cpu_count, setup_process

THREADS = setup_process()  # an entry point's module: imported only to measure

import equinox as eqx  # noqa: E402
import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

from models._integrators import Integrator, rollout_batch  # noqa: E402

from ..core._train import TrainConfig, _Batches, _block, _compiled_block, loss_fn, optimizer  # noqa: E402

# ms per step and per 40 x 100-step rollout of the PyTorch reference (mean of its two runs).
REFERENCE = {
    "node": (15.65, 59.0),
    "node_so": (43.3, 152.5),
    "hnn": (42.4, 230.5),
    "node_symreg": (84.8, 557.0),
    "hnn_so": (86.2, 485.5),
}
TARGET_STEP_MS = {"node": 7.5, "node_so": 21.0, "hnn": 21.0, "node_symreg": 42.0, "hnn_so": 42.0}
LNN_OVER_HNN_SO = 4.0

DOF, CHUNK, N_TRAIN, BATCH, DT, WIDTH, DEPTH = 2, 5, 800, 200, 0.03, 256, 2
ROLL_N, ROLL_T = 40, 101  # 40 trajectories x 100 steps


class _Synthetic:
    """Dataset-shaped random chunks of a 2-link chain (angles in [-pi, pi], velocities ~ N(0,1))."""

    def __init__(self, n=N_TRAIN, chunk=CHUNK, seed=0):
        rng = np.random.default_rng(seed)
        q = rng.uniform(-np.pi, np.pi, (n, 1, DOF)) + 0.05 * rng.standard_normal((n, chunk, DOF))
        v = rng.standard_normal((n, chunk, DOF))
        self.ts_train = np.arange(chunk) * DT
        self.z_train = np.concatenate([q, v], axis=-1)
        self.args_train = np.zeros((n, 0))
        self.angular = (True,) * DOF


def _scene():
    import models

    return models.Scene(dof=DOF, angular=(True,) * DOF)


def _make(name, key, dtype="float32"):
    import models

    return models.make(name, _scene(), key=key, width=WIDTH, depth=DEPTH, dtype=dtype)


def _load() -> float:
    return os.getloadavg()[0]


def matmul_peak_gflops(n=2048, repeats=7) -> float:
    """Median float32 GFLOP/s of an n x n @ n x n product (2 n^3 FLOPs)."""
    a = jax.random.normal(jax.random.key(0), (n, n), jnp.float32)
    f = jax.jit(lambda x: x @ x)
    f(a).block_until_ready()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        f(a).block_until_ready()
        times.append(time.perf_counter() - t0)
    return 2 * n**3 / np.median(times) / 1e9


def _flops(compiled) -> float:
    cost = compiled.cost_analysis()
    if isinstance(cost, list | tuple):
        cost = cost[0]
    return float(cost.get("flops", np.nan)) if cost else np.nan


def step_flops(model, data, config) -> float:
    """FLOPs of one training step (loss, gradient, optimiser update) by XLA's cost analysis.

    One step is analysed outside the scan because the analysis counts a loop body once.
    """
    params, static = eqx.partition(model, eqx.is_inexact_array)
    opt = optimizer(config)
    z, args, ts = data
    idx = jnp.arange(config.batch)

    def one(params, opt_state):
        m = eqx.combine(params, static)
        loss, grads = eqx.filter_value_and_grad(loss_fn)(m, z[idx], args[idx], ts, config)
        updates, opt_state = opt.update(grads, opt_state, params)
        return eqx.apply_updates(params, updates), opt_state, loss

    compiled = eqx.filter_jit(one).lower(params, opt.init(params)).compile()
    return _flops(compiled.compiled)


def _prepare(model, dataset, config):
    from ..core._train import prepare

    data = prepare(model, dataset, config)
    params, static = eqx.partition(model, eqx.is_inexact_array)
    params = jax.tree.map(jnp.copy, params)
    return data, params, static, optimizer(config).init(params)


def time_steps(model, dataset, config, repeats):
    """(per-step ms of each timed block, compile seconds, block length)."""
    data, params, static, opt_state = _prepare(model, dataset, config)
    k = config.steps_per_call
    batches = _Batches(data[0].shape[0], config.batch, config.seed)
    active = jnp.ones((k,), bool)
    dead = jnp.asarray(False)
    good = jax.tree.map(jnp.copy, params)
    idx = jnp.asarray(batches.take(k))
    run, compile_s = _compiled_block(
        params, static, opt_state, dead, good, data, idx, active, config
    )
    state = (params, opt_state, dead, good)
    per_step, loads = [], []
    for r in range(repeats + 1):  # the first block warms up (allocations, caches)
        idx = jnp.asarray(batches.take(k))
        t0 = time.perf_counter()
        *state, losses, _ = run(data, *state, idx, active)
        jax.block_until_ready(losses)
        if r:
            per_step.append(1e3 * (time.perf_counter() - t0) / k)
            loads.append(_load())
    return np.array(per_step), compile_s, loads


def time_rollout(model, repeats, dtype="float32"):
    z0s = jnp.asarray(_Synthetic(n=ROLL_N, chunk=1, seed=1).z_train[:, 0], dtype)
    ts = jnp.arange(ROLL_T, dtype=dtype) * DT
    args = jnp.zeros((ROLL_N, 0), dtype)
    f = eqx.filter_jit(lambda m, z, t, a: rollout_batch(m, z, t, a, Integrator("rk4_38")))
    f(model, z0s, ts, args).block_until_ready()
    times = []
    for _ in range(max(3, repeats)):
        t0 = time.perf_counter()
        f(model, z0s, ts, args).block_until_ready()
        times.append(1e3 * (time.perf_counter() - t0))
    return np.array(times)


def time_seeds(name, dataset, config, n_seeds=3, repeats=3):
    """ms per step for n_seeds trained as one vmapped program, and per seed sequentially."""
    models_ = [_make(name, jax.random.key(s)) for s in range(n_seeds)]
    prepared = [_prepare(m, dataset, config) for m in models_]
    data, _, static, _ = prepared[0]
    stack = lambda *xs: jnp.stack(xs)
    params = jax.tree.map(stack, *[p[1] for p in prepared])
    opt_state = jax.tree.map(stack, *[p[3] for p in prepared])
    k = config.steps_per_call
    active = jnp.ones((k,), bool)
    dead = jnp.zeros((n_seeds,), bool)
    good = jax.tree.map(jnp.copy, params)
    cfg = config

    def many(data, idx, params, opt_state, dead, good):
        one = lambda i, p, o, d, g: _block((data, i, active), p, o, d, g, static=static, config=cfg)
        return jax.vmap(one)(idx, params, opt_state, dead, good)

    batches = [_Batches(data[0].shape[0], config.batch, s) for s in range(n_seeds)]
    take = lambda: jnp.asarray(np.stack([b.take(k) for b in batches]))
    f = eqx.filter_jit(many)
    t0 = time.perf_counter()
    compiled = f.lower(data, take(), params, opt_state, dead, good).compile()
    compile_s = time.perf_counter() - t0
    state = (params, opt_state, dead, good)
    times = []
    for r in range(repeats + 1):
        idx = take()
        t0 = time.perf_counter()
        *state, losses, _ = compiled(data, idx, *state)
        jax.block_until_ready(losses)
        if r:
            times.append(1e3 * (time.perf_counter() - t0) / k)
    vmapped = float(np.median(times))
    single, _, _ = time_steps(models_[0], dataset, config, repeats)
    return {
        "model": name,
        "seeds": n_seeds,
        "vmapped_ms_per_step": vmapped,
        "sequential_ms_per_step": n_seeds * float(np.median(single)),
        "speedup_vmapped": n_seeds * float(np.median(single)) / vmapped,
        "vmapped_compile_s": compile_s,
        "load_avg": _load(),
    }


def bench_model(name, dataset, config, repeats, peak_gflops):
    model = _make(name, jax.random.key(0))
    data = _prepare(model, dataset, config)[0]
    load0 = _load()
    steps, compile_s, loads = time_steps(model, dataset, config, repeats)
    roll = time_rollout(model, repeats)
    gflop = step_flops(model, data, config) / 1e9
    ref_step, ref_roll = REFERENCE.get(name, (np.nan, np.nan))
    med = float(np.median(steps))
    q1, q3 = np.percentile(steps, [25, 75])
    return {
        "model": name,
        "ms_per_step_median": med,
        "ms_per_step_iqr": float(q3 - q1),
        "ms_per_step_min": float(steps.min()),
        "ms_per_step_max": float(steps.max()),
        "compile_s": compile_s,
        "rollout_ms_median": float(np.median(roll)),
        "rollout_ms_min": float(roll.min()),
        "reference_step_ms": ref_step,
        "reference_rollout_ms": ref_roll,
        "speedup_step": ref_step / med,
        "speedup_rollout": ref_roll / float(np.median(roll)),
        "target_step_ms": TARGET_STEP_MS.get(name, np.nan),
        "step_gflop": gflop,
        "flop_floor_ms": 1e3 * gflop / peak_gflops,
        "peak_gflops": peak_gflops,
        "block_steps": config.steps_per_call,
        "load_avg": float(np.median([load0, *loads])),
    }


def flag_sweep(models_arg, repeats):
    """ms per step of the first model under XLA thread settings, each in a fresh process."""
    # bench/core/_env.py adds its flags unless XLA_FLAGS names intra_op_parallelism_threads; XLA
    # ignores that bare token (not an XLA flag) when a "--" flag is present, so it serves as a
    # "leave alone" marker.
    keep = "intra_op_parallelism_threads=unset"
    variants = {
        "bench_env": None,  # whatever bench/core/_env.py sets (XLA's default threading)
        "eigen_single": f"--xla_cpu_multi_thread_eigen=false {keep}",
        "one_core": "AFFINITY1",
    }
    rows = []
    for label, flags in variants.items():
        env = dict(os.environ)
        env.pop("XLA_FLAGS", None)
        cmd = [
            sys.executable,
            "-m",
            "bench.perf",
            "--models",
            models_arg,
            "--repeats",
            str(repeats),
            "--json",
            "--no-write",
            "--block",
            "10",
        ]
        if flags == "AFFINITY1":
            cmd = ["taskset", "-c", "0", *cmd]
        elif flags is not None:
            env["XLA_FLAGS"] = flags
        out = subprocess.run(cmd, env=env, capture_output=True, text=True, cwd=os.getcwd())
        try:
            result = json.loads(out.stdout.strip().splitlines()[-1])
        except (IndexError, json.JSONDecodeError):
            print(f"flag variant {label} failed:\n{out.stderr[-2000:]}", file=sys.stderr)
            continue
        for row in result["rows"]:
            rows.append(
                {
                    "variant": label,
                    "xla_flags": result["xla_flags"],
                    **{
                        k: row[k]
                        for k in ("model", "ms_per_step_median", "rollout_ms_median", "load_avg")
                    },
                }
            )
    return rows


ENSEMBLE_MODELS = ("node", "node_so", "hnn", "hnn_so")
ENSEMBLE_SIZES = (1, 5, 10, 20)


def _machine() -> str:
    dev = jax.devices()[0]
    if dev.platform == "cpu":
        return f"{platform.node()} cpu {platform.machine()} {cpu_count()} cores"
    return f"{platform.node()} {dev.platform} {getattr(dev, 'device_kind', '')}".strip()


def ensemble_table(names=ENSEMBLE_MODELS, sizes=ENSEMBLE_SIZES, steps=None, say=print):
    """Training runs per minute: M runs as one ensemble vs the same M runs one at a time.

    Each run is ``steps`` training steps (one compiled block; default 100 on an accelerator,
    20 on CPU) of the chain-2 setting, at the paper sizes (width 256, batch 200, 800 chunks)
    on an accelerator and the quick-profile sizes (width 128, batch 100, 200 chunks) on CPU.
    Both ways are compiled first (``compile_s_*``) and then timed on wall clock over the M
    runs with distinct seeds, including the host-side batching of ``bench.train``. Evaluation
    is not included. ``load_avg`` is the 1-minute load when the row was measured.
    """
    import models

    from ..core._ensemble import train_ensemble
    from ..core._train import train

    accel = jax.default_backend() != "cpu"
    width, batch, n = (WIDTH, BATCH, N_TRAIN) if accel else (128, 100, 200)
    steps = steps or (100 if accel else 20)
    dataset = _Synthetic(n=n)
    machine = _machine()
    rows = []
    for name in names:

        def make(seed, name=name):
            return models.make(name, _scene(), key=jax.random.key(seed), width=width, depth=DEPTH)

        for m in sizes:
            cfgs = [
                TrainConfig(steps=steps, batch=batch, steps_per_call=steps, seed=s)
                for s in range(m)
            ]
            nets = [make(s) for s in range(m)]
            compile_single = train(nets[0], dataset, cfgs[0]).compile_seconds
            t0 = time.perf_counter()
            for net, c in zip(nets, cfgs, strict=True):
                train(net, dataset, c)
            single_s = time.perf_counter() - t0
            first = train_ensemble(nets, [dataset] * m, cfgs)
            compile_ens = first[0].compile_seconds * m
            t0 = time.perf_counter()
            train_ensemble(nets, [dataset] * m, cfgs)
            ens_s = time.perf_counter() - t0
            row = {
                "machine": machine,
                "backend": jax.default_backend(),
                "model": name,
                "ensemble_size": m,
                "steps_per_run": steps,
                "width": width,
                "batch": batch,
                "single_runs_per_min": 60 * m / single_s,
                "ensemble_runs_per_min": 60 * m / ens_s,
                "speedup": single_s / ens_s,
                "compile_s_single": compile_single,
                "compile_s_ensemble": compile_ens,
                "load_avg": _load(),
                "threads": THREADS,
                "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
            }
            rows.append(row)
            say(
                f"{name:8s} M={m:2d}  single {row['single_runs_per_min']:8.1f} runs/min  "
                f"ensemble {row['ensemble_runs_per_min']:8.1f} runs/min  "
                f"x{row['speedup']:.2f}  compile {compile_single:.1f}/{compile_ens:.1f} s  "
                f"load {row['load_avg']:.2f}"
            )
    return rows


def _ensemble_main(a, say) -> int:
    import models

    names = [n for n in (a.models or ",".join(ENSEMBLE_MODELS)).split(",") if n]
    unknown = sorted(set(names) - set(models.available()))
    if unknown:
        raise SystemExit(f"unknown model(s) {unknown}; allowed: {models.available()}")
    try:
        sizes = [int(x) for x in a.sizes.split(",") if x]
    except ValueError:
        raise SystemExit(
            f"--sizes must be comma-separated integers >= 1; got {a.sizes!r}"
        ) from None
    if not sizes or min(sizes) < 1 or (a.steps is not None and a.steps < 1):
        raise SystemExit("--sizes and --steps must be integers >= 1")
    rows = ensemble_table(names, sizes, a.steps, say=say)
    if a.json:
        print(json.dumps({"rows": rows}))
    if not a.no_write and rows:
        import pandas as pd

        out = Path(a.out or "results/perf_ensemble.csv")
        out.parent.mkdir(parents=True, exist_ok=True)
        pd.DataFrame(rows).to_csv(out, index=False)
        say(f"wrote {out}")
    return 0


def main(argv=None) -> int:
    import models

    parser = argparse.ArgumentParser(
        prog="python -m bench perf", description=__doc__.split("\n")[0]
    )
    parser.add_argument(
        "--models",
        default=None,
        help="comma-separated model names (default: every trainable velocity-scene model; "
        "with --ensemble " + ",".join(ENSEMBLE_MODELS) + ")",
    )
    parser.add_argument("--repeats", type=int, default=5, help="timed blocks per model")
    parser.add_argument("--block", type=int, default=20, help="training steps per timed block")
    parser.add_argument("--quick", action="store_true", help="3 repeats of 10-step blocks")
    parser.add_argument("--seeds", action="store_true", help="also time 3 seeds vmapped")
    parser.add_argument("--flags", action="store_true", help="also compare XLA thread flags")
    parser.add_argument(
        "--ensemble", action="store_true", help="runs/min, ensembles vs one at a time, only"
    )
    parser.add_argument(
        "--sizes",
        default=",".join(map(str, ENSEMBLE_SIZES)),
        help="ensemble sizes (--ensemble)",
    )
    parser.add_argument(
        "--steps", type=int, default=None, help="training steps per run (--ensemble)"
    )
    parser.add_argument(
        "--out", default=None, help="default results/perf.csv (--ensemble: perf_ensemble.csv)"
    )
    parser.add_argument("--no-write", action="store_true")
    parser.add_argument("--json", action="store_true", help="print the rows as one JSON line")
    a = parser.parse_args(argv)
    if a.ensemble:
        return _ensemble_main(a, (lambda *x: print(*x, file=sys.stderr)) if a.json else print)
    a.out = a.out or "results/perf.csv"
    a.models = a.models or ",".join(
        n
        for n in models.available()  # trainable, on the (q, qdot) scene timed here
        if n not in models.trivial_models() and "velocity" in models.coordinates(n)
    )
    if a.quick:
        a.repeats, a.block = 3, 10
    if a.repeats < 1 or a.block < 1:
        raise SystemExit("--repeats and --block must be >= 1")
    names = [n for n in a.models.split(",") if n]
    unknown = sorted(set(names) - set(models.available()))
    if unknown:
        raise SystemExit(f"unknown model(s) {unknown}; allowed: {models.available()}")

    config = TrainConfig(steps=10**6, batch=BATCH, steps_per_call=a.block)
    dataset = _Synthetic()
    peak = matmul_peak_gflops()
    say = (lambda *x: print(*x, file=sys.stderr)) if a.json else print
    say(
        f"matmul peak {peak:.0f} GFLOP/s; threads {THREADS}; "
        f"XLA_FLAGS={os.environ.get('XLA_FLAGS')}"
    )
    rows, skipped = [], []
    for name in names:
        try:
            row = bench_model(name, dataset, config, a.repeats, peak)
        except Exception as e:  # a model that does not build or compile is reported, not fatal
            skipped.append((name, f"{type(e).__name__}: {e}"))
            say(f"{name}: skipped ({type(e).__name__}: {str(e)[:200]})")
            continue
        rows.append(row)
        say(
            f"{name:12s} {row['ms_per_step_median']:8.2f} ms/step "
            f"(ref {row['reference_step_ms']:.1f},"
            f" target {row['target_step_ms']:.1f}, floor {row['flop_floor_ms']:.2f})  rollout "
            f"{row['rollout_ms_median']:7.1f} ms (ref {row['reference_rollout_ms']:.0f})  compile "
            f"{row['compile_s']:.1f} s  load {row['load_avg']:.2f}"
        )
    by_name = {r["model"]: r for r in rows}
    meta = {
        "machine": f"{platform.node()} {platform.machine()} {cpu_count()} cores",
        "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "jax_version": jax.__version__,
        "threads": THREADS,
        "xla_flags": os.environ.get("XLA_FLAGS", ""),
        # compile_s is a persistent-cache hit when on (DECON_JAX_CACHE=0 for cold compiles)
        "compile_cache": "on" if os.environ.get("JAX_COMPILATION_CACHE_DIR") else "off",
    }
    hnn_so = by_name.get("hnn_so", {}).get("ms_per_step_median", np.nan)
    for r in rows:
        r["ratio_to_hnn_so"] = r["ms_per_step_median"] / hnn_so
        r.update(meta)
    if "lnn" in by_name:
        say(f"lnn / hnn_so = {by_name['lnn']['ratio_to_hnn_so']:.2f} (target <= {LNN_OVER_HNN_SO})")

    seeds = []
    if a.seeds:
        for name in [n for n in ("node", "hnn_so") if n in by_name]:
            s = time_seeds(name, dataset, config, repeats=max(2, a.repeats // 2))
            s.update(meta)
            seeds.append(s)
            say(
                f"{name}: 3 seeds vmapped {s['vmapped_ms_per_step']:.1f} ms/step vs sequential "
                f"{s['sequential_ms_per_step']:.1f} (x{s['speedup_vmapped']:.2f})"
            )
    flags = flag_sweep(names[0], max(2, a.repeats // 2)) if a.flags and names else []
    for f in flags:
        say(
            f"flags {f['variant']:13s} {f['ms_per_step_median']:7.2f} ms/step  rollout "
            f"{f['rollout_ms_median']:6.1f} ms  load {f['load_avg']:.2f}  ({f['xla_flags']})"
        )

    if a.json:
        print(json.dumps({"rows": rows, "xla_flags": meta["xla_flags"], "skipped": skipped}))
    if not a.no_write and rows:
        import pandas as pd

        out = Path(a.out)
        out.parent.mkdir(parents=True, exist_ok=True)
        pd.DataFrame(rows).to_csv(out, index=False)
        if seeds:
            pd.DataFrame(seeds).to_csv(out.with_name("perf_seeds.csv"), index=False)
        if flags:
            pd.DataFrame(flags).to_csv(out.with_name("perf_flags.csv"), index=False)
        say(f"wrote {out}")
    for name, why in skipped:
        say(f"skipped {name}: {why[:300]}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
