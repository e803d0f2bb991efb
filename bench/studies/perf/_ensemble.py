"""``python -m bench perf --ensemble``: training runs per minute, ensembles vs one at a time."""

from __future__ import annotations

import datetime
import json
import platform
import time
from pathlib import Path

import jax

from ...core import OWN_DIR, TrainConfig, cpu_count
from ._timing import (
    BATCH,
    DEPTH,
    N_TRAIN,
    THREADS,
    WIDTH,
    _load,
    _scene,
    _Synthetic,
)

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

    from ...core import train, train_ensemble

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

        out = Path(a.out or OWN_DIR / "perf_ensemble.csv")
        out.parent.mkdir(parents=True, exist_ok=True)
        pd.DataFrame(rows).to_csv(out, index=False)
        say(f"wrote {out}")
    return 0
