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
