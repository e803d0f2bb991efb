"""decon-bench: metrics, training, the sweep runner, the CLI, tables, figures and the report."""

from ._env import configure_compilation_cache as _configure_compilation_cache
from ._env import configure_threads as _configure_threads

_configure_threads()
_configure_compilation_cache()

from . import _experiments as experiments  # noqa: E402
from . import _metrics as metrics  # noqa: E402
from ._experiments import (  # noqa: E402
    PROFILES,
    Experiment,
    RunConfig,
    available,
    expand,
    get,
    register,
)
from ._provenance import PROVENANCE_COLUMNS, compare_provenance, provenance_markdown  # noqa: E402
from ._runner import execute_run, sweep  # noqa: E402
from ._store import aggregate, load_curves, load_runs, runs_of  # noqa: E402

__all__ = [
    "PROFILES",
    "PROVENANCE_COLUMNS",
    "Experiment",
    "RunConfig",
    "aggregate",
    "available",
    "compare_provenance",
    "execute_run",
    "expand",
    "experiments",
    "get",
    "load_curves",
    "load_runs",
    "metrics",
    "provenance_markdown",
    "register",
    "runs_of",
    "sweep",
]

try:  # the trainer lands separately; re-export it when it is there
    from ._train import TrainConfig, TrainResult, train  # noqa: E402, F401

    __all__ += ["TrainConfig", "TrainResult", "train"]
    from ._ensemble import train_ensemble  # noqa: E402, F401

    __all__ += ["train_ensemble"]
except ModuleNotFoundError as _e:  # pragma: no cover
    if _e.name != "bench._train":
        raise
