import os

# The tests run tiny programs once or a few times each, so XLA's compile time dominates them,
# and much of it is LLVM optimising code that then runs for milliseconds: without that the
# suite takes about a quarter less CPU on a cold compilation cache (docs/measured.md). The tests
# compare numbers within one process setting, never with stored runs, so no assertion depends
# on it. XLA's newer CPU fusion emitters, off, compile the suite's programs faster as well (the
# suite's test durations about a fifth less, docs/measured.md). An XLA_FLAGS already set wins.
os.environ.setdefault(
    "XLA_FLAGS", "--xla_backend_optimization_level=0 --xla_cpu_use_fusion_emitters=false"
)
# Programs compiled that fast fall under the persistent cache's 0.5 s threshold; kept anyway,
# the test processes (two workers, the CLI's subprocesses) reuse one another's.
os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0")

from bench.core._env import setup_process  # noqa: E402

setup_process()
