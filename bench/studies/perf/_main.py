"""``python -m bench perf`` / ``python -m bench.studies.perf``: the benchmark's command line."""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import sys
from pathlib import Path

import jax
import numpy as np

from ...core import OWN_DIR, TrainConfig, cpu_count
from ._ensemble import (
    ENSEMBLE_MODELS,
    ENSEMBLE_SIZES,
    _ensemble_main,
)
from ._timing import (
    BATCH,
    LNN_OVER_HNN_SO,
    THREADS,
    _Synthetic,
    bench_model,
    flag_sweep,
    matmul_peak_gflops,
    time_seeds,
)


def _cells_main(a) -> int:
    from ._cells import cell_configs, cell_rows

    names = {n for n in (a.models or "").split(",") if n}
    systems = {n for n in (a.systems or "").split(",") if n}
    try:
        cells = [
            (e, c)
            for e in a.cells.split(",")
            for c in cell_configs(e, a.profile, a.k, names, a.seed, systems)
        ]
    except ValueError as e:  # an unknown experiment or profile: the one line naming the allowed
        raise SystemExit(str(e)) from None
    rows = cell_rows(cells, a.profile, 3 if a.quick else max(1, a.repeats))
    if not a.no_write:
        import pandas as pd

        out = Path(a.out or OWN_DIR / "perf_cells.csv")
        out.parent.mkdir(parents=True, exist_ok=True)
        pd.DataFrame(rows).to_csv(out, index=False)
        print(f"wrote {out}")
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
        "--out", default=None, help="default results/own/perf.csv (--ensemble: perf_ensemble.csv)"
    )
    parser.add_argument(
        "--cells",
        metavar="EXPERIMENTS",
        default=None,
        help="time the training step of the own cells of EXPERIMENTS (comma-separated) under "
        "--profile instead, in blocks of the run's own size (results/own/perf_cells.csv; run under "
        "`taskset -c 1` to time one core, as a campaign worker runs)",
    )
    parser.add_argument("--profile", default="paper-core", help="the cells' profile (--cells)")
    parser.add_argument("--k", type=int, default=None, help="only the cells at k links (--cells)")
    parser.add_argument("--seed", type=int, default=0, help="the cells' seed (--cells)")
    parser.add_argument(
        "--systems", default=None, help="comma-separated: only these systems' cells (--cells)"
    )
    parser.add_argument("--no-write", action="store_true")
    parser.add_argument("--json", action="store_true", help="print the rows as one JSON line")
    a = parser.parse_args(argv)
    if a.ensemble:
        return _ensemble_main(a, (lambda *x: print(*x, file=sys.stderr)) if a.json else print)
    if a.cells:
        return _cells_main(a)
    a.out = a.out or str(OWN_DIR / "perf.csv")
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
