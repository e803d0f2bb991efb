"""Performance benchmark: training-step and rollout cost of every model at the reference setting.

Setting (that of the paper's public code, timed on this machine class): 2-link chain (dof 2,
angles), MLP width 256 x 2 hidden layers, batch 200 chunks of 5 points, rk4_38 one step per dt,
float32. The training data are synthetic (timing does not depend on their values; no simulation
needed).

Per model: the median ms per training step, timed over blocks of ``block`` steps of the very
program that ``bench.train`` runs (the training loop's compiled block, ``bench.core.Training``:
compile first, then ``repeats`` blocks, each waited for); the compile time; the median ms of a
40 x 100-step test rollout (jitted ``rollout_batch``, no gradient); the step's FLOPs from XLA's
cost analysis of that same block (one step, each loop body counted once); and the FLOP floor =
FLOPs / measured float32 matmul peak. ``--seeds`` times 3 seeds as one ensemble of the same
training loop. The load average is recorded beside each measurement because the machine may be
shared.

``python -m bench perf --ensemble`` (:func:`ensemble_table`) writes
``results/own/perf_ensemble.csv``: training runs per minute, M runs as one ensemble
(``bench.core.train_ensemble``) vs the same M runs one at a time, for M in 1, 5, 10, 20 and the
paper models.

``python -m bench.studies.perf --cells EXPERIMENTS [--profile P] [--k K]`` times the training
step of experiments' own cells instead (:mod:`._cells`: their data, model and batch; one core
under ``taskset``) and writes ``results/own/perf_cells.csv``.

``python -m bench.studies.perf [--models node,hnn_so] [--repeats 5] [--quick] [--seeds] [--flags]``
writes ``results/own/perf.csv`` (and ``perf_seeds.csv``, ``perf_flags.csv`` beside it).
``compile_s`` comes from JAX's persistent compilation cache when ``bench`` turned it on (the
``compile_cache`` column); ``DECON_JAX_CACHE=0`` measures cold compiles.
"""

import importlib

from . import _commands  # noqa: F401 - registers `python -m bench perf`

# The timing modules pin the threads at import (an entry point's setting), so the package loads
# them only when one of their names is used: importing bench registers the verb and no more.
_LAZY = {
    "ENSEMBLE_MODELS": "_ensemble",
    "ENSEMBLE_SIZES": "_ensemble",
    "ensemble_table": "_ensemble",
    "main": "_main",
    "REFERENCE": "_timing",
    "TARGET_STEP_MS": "_timing",
    "THREADS": "_timing",
    "bench_model": "_timing",
    "matmul_peak_gflops": "_timing",
}


def __getattr__(name):
    if name in _LAZY:
        return getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "ENSEMBLE_MODELS",
    "ENSEMBLE_SIZES",
    "REFERENCE",
    "TARGET_STEP_MS",
    "THREADS",
    "bench_model",
    "ensemble_table",
    "main",
    "matmul_peak_gflops",
]
