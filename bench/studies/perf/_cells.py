"""``python -m bench.studies.perf --cells EXPERIMENTS``: the training step of experiments' own
cells (their data, model, objective, batch and width under a profile), not the synthetic
chain-2 setting; several experiments comma-separated. A cell is built and fitted as its run's
own train step does (its observation kind's :class:`bench.core.Member`): state and controlled
runs (MuJoCo's, say); the kinds that train alone (pixels) are refused with one line.

A campaign worker trains one run on one core, so the figure to hold a step against is one
core's matmul rate: run it as a worker runs, ``taskset -c 1 python -m bench.studies.perf
--cells coordinates --profile paper-k --k 4``. Each cell (system, model, k; one seed, the first
of its starts) is timed over ``repeats`` blocks after one that warms up; its FLOPs are XLA's
count of the compiled block (:func:`bench.core._train.step_flops`), and ``of_peak`` is the
step's FLOP rate over the float32 matmul peak measured in the same process. XLA counts a loop's
body once, so where a rollout loops rather than unrolls (8 Euler substeps per interval, say)
both are lower bounds, comparable only between cells that loop alike."""

from __future__ import annotations

import datetime
import os

import numpy as np

from ...core import Training, cpu_count, expand, observation_kinds
from ._timing import _time_blocks, matmul_peak_gflops


def cell_configs(experiment, profile, k=None, names=None, seed=0, systems=None) -> list:
    """One configuration per (system, model, k) of ``experiment`` under ``profile`` (seed
    ``seed``; only ``names``' models and ``systems``' systems where given), trivial models
    left out: the first of a cell's variants (its starts, say), since they train the same
    program on data of the same shape."""
    import models

    trivial = set(models.trivial_models())
    trainable = [c for c in expand(experiment, profile, seeds=[seed]) if c.model not in trivial]
    kinds = observation_kinds()
    alone = sorted({c.observation for c in trainable if kinds[c.observation].member is None})
    if alone:
        raise SystemExit(
            f"perf --cells times cells that train by the one training loop (state and "
            f"controlled runs); {experiment!r} has {', '.join(alone)} runs"
        )
    cells = {}
    for c in trainable:
        if (k is not None and c.k != k) or (names and c.model not in names):
            continue
        if systems and c.system not in systems:
            continue
        cells.setdefault((c.system, c.model, c.k), c)
    if not cells:

        def offered(field):
            return ", ".join(sorted({str(getattr(c, field)) for c in trainable}))

        raise SystemExit(
            f"no trainable cells of {experiment!r} under {profile!r}"
            + (f" at k = {k}" if k is not None else "")
            + (f" for models {sorted(names)}" if names else "")
            + (f" on systems {sorted(systems)}" if systems else "")
            + f"; it has k {offered('k')}; models {offered('model')}; systems {offered('system')}"
        )
    return list(cells.values())


def cell_rows(cells, profile, repeats, say=print) -> list[dict]:
    """ms per training step of each ``(experiment, configuration)`` of ``cells`` (under
    ``profile``), its FLOP rate and its share of the peak."""
    from systems import cache_root

    peak = matmul_peak_gflops()
    say(f"float32 matmul peak {peak:.0f} GFLOP/s on {cpu_count()} core(s)")
    date = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
    rows = []
    for experiment, c in cells:
        kind = observation_kinds()[c.observation]
        member = kind.member  # what the run's own train step fits, and how
        model, data, objective = member.inputs(c, kind.build(c, cache_root()))
        training = Training([model], [data], [member.train_config(c)], objective)
        steps, loads = _time_blocks(training, repeats)
        med = float(np.median(steps))
        gflop = training.flops / 1e9
        rate = gflop / med * 1e3
        rows.append(
            {
                "experiment": experiment,
                "profile": profile,
                "system": c.system,
                "model": c.model,
                "k": c.k,
                "batch": c.batch,
                "width": c.width,
                "ms_per_step_median": med,
                "ms_per_step_min": float(steps.min()),
                "ms_per_step_max": float(steps.max()),
                "step_gflop": gflop,
                "gflops": rate,
                "peak_gflops": peak,
                "of_peak": rate / peak,
                "compile_s": training.compile_seconds,
                "cores": cpu_count(),
                "load_avg": float(np.median(loads)),
                "xla_flags": os.environ.get("XLA_FLAGS", ""),
                "date": date,
            }
        )
        say(
            f"{experiment:13s} {c.system:16s} k={c.k} {c.model:12s} {med:8.2f} ms/step  "
            f"{gflop:6.2f} GFLOP  {rate:5.1f} GFLOP/s ({rate / peak:.0%} of peak)  "
            f"load {rows[-1]['load_avg']:.2f}"
        )
    say(
        "GFLOP: XLA's count with each loop body once (step_flops): where a rollout loops (more "
        "than 4 substeps, as MuJoCo's 8, or a long chunk) the rate and share are lower bounds"
    )
    return rows
