"""Thread configuration for XLA on CPU.

XLA's CPU client sizes its thread pools from the host; threads beyond the cores cost 3-5x on
small training steps (measured on the reference code), so we pin one intra-op thread per core.
This must run before jax is imported, which is why ``bench/__init__.py`` calls it first.
"""

from __future__ import annotations

import os


def cpu_count() -> int:
    """The cores this process may run on (cgroup/affinity aware where the OS says)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - macOS
        return max(1, os.cpu_count() or 1)


def configure_threads(n: int | None = None) -> int:
    """Set XLA's CPU thread flags to ``n`` threads (default: the available cores).

    Flags already present in ``XLA_FLAGS`` are kept; ours are only added when absent.
    Returns the thread count in effect.
    """
    n = cpu_count() if n is None else int(n)
    flags = os.environ.get("XLA_FLAGS", "")
    if "intra_op_parallelism_threads" not in flags:
        flags += f" --xla_cpu_multi_thread_eigen=true intra_op_parallelism_threads={n}"
    os.environ["XLA_FLAGS"] = flags.strip()
    os.environ.setdefault("OMP_NUM_THREADS", str(n))
    return n


def cache_root() -> str:
    """Root of the suite's git-ignored caches: ``$DECON_CACHE`` or ``./.cache/decon-bench``."""
    return os.environ.get("DECON_CACHE") or os.path.join(os.getcwd(), ".cache", "decon-bench")


def configure_compilation_cache(path: str | None = None) -> str | None:
    """Turn on JAX's persistent compilation cache (before jax is imported).

    Compilation dominates short runs on the CPU (tens of seconds for an HNN step against seconds
    of training), and runs that differ only in their seed, or a second sweep, compile the very
    same programs: XLA executables are keyed by the program, so they are reused across
    processes. ``DECON_JAX_CACHE=0`` turns it off; settings already in the environment win.
    """
    if os.environ.get("DECON_JAX_CACHE", "1") == "0":
        return None
    path = path or os.path.join(cache_root(), "jax")
    os.environ.setdefault("JAX_COMPILATION_CACHE_DIR", path)
    os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0.5")
    os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES", "0")
    return os.environ["JAX_COMPILATION_CACHE_DIR"]
