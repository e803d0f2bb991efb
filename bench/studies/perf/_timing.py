"""The timings: training step, test rollout, FLOPs and the matmul peak (see the package). The
training step is timed, and its FLOPs counted, on the program that training runs: the one
training loop's compiled block (``bench.core.Training``), for one model or several seeds."""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
import time

from ...core import setup_process

THREADS = setup_process()  # an entry point's module: imported only to measure

import equinox as eqx  # noqa: E402
import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

from models import Integrator, rollout_batch  # noqa: E402

from ...core import Training  # noqa: E402

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


def _time_blocks(training, repeats) -> tuple[np.ndarray, list]:
    """ms per step of ``repeats`` blocks of ``training`` after one that warms up (allocations,
    caches), and the load average after each."""
    per_step, loads = [], []
    for r in range(repeats + 1):
        before = training.train_seconds
        training.advance()
        if r:
            per_step.append(1e3 * (training.train_seconds - before) / training.block)
            loads.append(_load())
    return np.array(per_step), loads


def time_steps(model, dataset, config, repeats):
    """(per-step ms of each timed block, compile seconds, load averages, the step's FLOPs): the
    training loop's own compiled block for ``model`` (its FLOPs: ``bench.core._train``'s
    ``step_flops``, one step with each loop body counted once)."""
    training = Training([model], [dataset], [config])
    per_step, loads = _time_blocks(training, repeats)
    return per_step, training.compile_seconds, loads, training.flops


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
    """ms per step for n_seeds trained as one program (an ensemble of the training loop), and
    per seed sequentially."""
    models_ = [_make(name, jax.random.key(s)) for s in range(n_seeds)]
    configs = [dataclasses.replace(config, seed=s) for s in range(n_seeds)]
    training = Training(models_, [dataset] * n_seeds, configs)
    vmapped = float(np.median(_time_blocks(training, repeats)[0]))
    single = time_steps(models_[0], dataset, config, repeats)[0]
    return {
        "model": name,
        "seeds": n_seeds,
        "vmapped_ms_per_step": vmapped,
        "sequential_ms_per_step": n_seeds * float(np.median(single)),
        "speedup_vmapped": n_seeds * float(np.median(single)) / vmapped,
        "vmapped_compile_s": training.compile_seconds,
        "load_avg": _load(),
    }


def bench_model(name, dataset, config, repeats, peak_gflops):
    model = _make(name, jax.random.key(0))
    load0 = _load()
    steps, compile_s, loads, flops = time_steps(model, dataset, config, repeats)
    roll = time_rollout(model, repeats)
    gflop = flops / 1e9
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
            "bench.studies.perf",
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
