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

import pytest  # noqa: E402

from bench.core import setup_process  # noqa: E402

setup_process()


@pytest.fixture
def clean_registry():
    """The model registry as it was before the test: plug-ins a test loads are forgotten."""
    import models
    from models import _registry

    before, sources = dict(_registry._REGISTRY), dict(_registry._SOURCES)
    modules, loaded = dict(_registry._MODULES), set(_registry._PLUGINS)
    yield
    _registry._MODULES.clear()
    _registry._MODULES.update(modules)
    _registry._PLUGINS.intersection_update(loaded)
    _registry._REGISTRY.clear()
    _registry._REGISTRY.update(before)
    _registry._SOURCES.clear()
    _registry._SOURCES.update(sources)
    models.spec.cache_clear()
