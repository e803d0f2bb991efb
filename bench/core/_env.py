"""Process settings made by entry points: jax's 64-bit mode and matmul precision, XLA's cores
on the CPU (thread pools) and the compilation cache.

Threads beyond the cores cost 3-5x on small training steps (measured on the reference code), so
sweep workers are pinned to their own cores. These must run before jax creates its backend
(its first computation), and only entry points call them (:func:`setup_process`): the CLI's
``main`` (``python -m bench``), the sweep's pool and Ray workers, the other ``main`` functions
and ``tests/conftest.py``. Importing ``bench`` changes nothing in the process.
"""

from __future__ import annotations

import os
import sys


def cpu_count() -> int:
    """The cores this process may run on (cgroup/affinity aware where the OS says)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - macOS
        return max(1, os.cpu_count() or 1)


def configure_threads(n: int | None = None, cores: list[int] | None = None) -> int:
    """Give this process ``n`` cores (default: all available), before jax starts its backend.

    XLA's CPU client sizes its thread pools from the process's CPU affinity mask, and it has no
    flag for the intra-op thread count (``intra_op_parallelism_threads`` is TensorFlow's, which
    XLA ignores or rejects). So the one working control is the mask itself: ``cores`` pins the
    process to those core ids, ``n`` to the first ``n`` available. Parallel sweep workers each
    take their own cores this way, so that two workers never run four threads on two cores.
    Returns the number of cores in effect.
    """
    try:
        available = sorted(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - no affinity API (macOS): nothing to pin
        return cpu_count()
    if cores is None and n is not None and n < len(available):
        cores = available[: max(1, int(n))]
    if cores is not None:
        os.sched_setaffinity(0, set(cores))
    count = cpu_count()
    os.environ.setdefault("OMP_NUM_THREADS", str(count))
    return count


def configure_compilation_cache(path: str | None = None) -> str | None:
    """Turn on JAX's persistent compilation cache (before jax is imported).

    Compilation dominates short runs on the CPU (tens of seconds for an HNN step against seconds
    of training), and runs that differ only in their seed, or a second sweep, compile the very
    same programs: XLA executables are keyed by the program, so they are reused across
    processes. ``DECON_JAX_CACHE=0`` turns it off; settings already in the environment win.
    """
    if os.environ.get("DECON_JAX_CACHE", "1") == "0":
        return None
    if path is None:
        import systems

        path = os.path.join(os.path.abspath(systems.cache_root()), "jax")
    os.environ.setdefault("JAX_COMPILATION_CACHE_DIR", path)
    os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0.5")
    os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES", "0")
    if "jax" in sys.modules:  # jax read its settings from the environment at import: tell it
        import jax

        jax.config.update("jax_compilation_cache_dir", os.environ["JAX_COMPILATION_CACHE_DIR"])
        jax.config.update(
            "jax_persistent_cache_min_compile_time_secs",
            float(os.environ["JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS"]),
        )
        jax.config.update(
            "jax_persistent_cache_min_entry_size_bytes",
            int(os.environ["JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES"]),
        )
    return os.environ["JAX_COMPILATION_CACHE_DIR"]


# jax computes float32 matmuls at reduced precision by default on recent NVIDIA GPUs (TF32: a
# 10-bit mantissa), at full float32 on CPUs. The suite asks for float32 everywhere, so that a
# run is the same computation on every backend (a row's numbers differ by round-off only) and
# models that invert learned Hessians (LNN) or differentiate twice keep float32's accuracy.
MATMUL_PRECISION = "float32"


def configure_numerics() -> None:
    """jax's 64-bit mode for the float64 ground truth (``systems.enable_x64``) and
    :data:`MATMUL_PRECISION` for float32 matmuls on every backend."""
    import jax

    import systems

    systems.enable_x64()
    jax.config.update("jax_default_matmul_precision", MATMUL_PRECISION)


def setup_process(n: int | None = None, cores: list[int] | None = None) -> int:
    """An entry point's process setup, before any computation: :func:`configure_threads`
    (``n``, ``cores``), :func:`configure_compilation_cache` and :func:`configure_numerics`.
    Returns the cores in effect."""
    count = configure_threads(n, cores)
    configure_compilation_cache()
    configure_numerics()
    return count


# XLA's CPU backend maps every compiled program's code into memory regions of its own, and jax's
# caches keep every program of the process alive. A sweep worker runs run after run in one
# process: measured at about 1200 maps per smoke run of a new model/system cell (24
# runs: 3300 -> 30,200 maps) and 8,000-8,600 after 7 paper-core runs per worker. At the
# kernel's vm.max_map_count (65530 here) LLVM fails with "Cannot allocate memory" and the
# process segfaults (it did: the 60th run of tests/test_runner.py's all-models smoke sweep in
# one process); in a pool that loses the run in flight and stalls the sweep. With
# ``jax.clear_caches()`` after each run the same 24 runs stayed at 1480 maps.
MAPS_FRACTION = 0.5


def _map_count() -> tuple[int, int] | None:
    """(memory maps of this process, the kernel's limit), or None where /proc does not say."""
    try:
        with open("/proc/self/maps", "rb") as f:
            n = sum(1 for _ in f)
        with open("/proc/sys/vm/max_map_count") as f:
            return n, int(f.read())
    except (OSError, ValueError):
        return None


def bound_compiled_programs(fraction: float = MAPS_FRACTION) -> bool:
    """Drop jax's caches of compiled programs when this process's memory maps pass
    ``fraction`` of the kernel's limit (see :data:`MAPS_FRACTION`); the runner calls it after
    every run. Programs recompile on their next use (from the persistent compilation cache where
    it is on). Returns whether it cleared them."""
    counts = _map_count()
    if counts is None or counts[0] < fraction * counts[1]:
        return False
    import jax

    jax.clear_caches()
    return True
