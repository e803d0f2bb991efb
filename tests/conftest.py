import os

# The tests run tiny programs once or a few times each, so XLA's compile time dominates them,
# and most of it is LLVM's optimisation of code that then runs for milliseconds: without it
# the suite takes about 40% less CPU. Numbers compare within one process setting, never against
# stored runs, so the setting changes no assertion. An XLA_FLAGS already set wins.
os.environ.setdefault("XLA_FLAGS", "--xla_backend_optimization_level=0")

from bench.core._env import setup_process  # noqa: E402

setup_process()
