"""decon-bench: metrics, training, the sweep runner, the CLI, tables, figures and the report.

Layers, each importing only those below it: ``bench.core`` (experiments, training, metrics,
runner, store, query layer, study registry) <- ``bench.studies`` (the paper experiments with
their verdict rules and figures, the trade-off, the stability study, perf) <- the CLI
(``bench._cli``) and the report (``bench._report``). Importing ``bench`` registers the built-in
studies.
"""

from .core._env import configure_compilation_cache as _configure_compilation_cache
from .core._env import configure_threads as _configure_threads

_configure_threads()
_configure_compilation_cache()

from . import studies  # noqa: E402  (registers the built-in studies)
from .core import _experiments as experiments  # noqa: E402
from .core import _metrics as metrics  # noqa: E402
from .core._ensemble import train_ensemble  # noqa: E402
from .core._experiments import (  # noqa: E402
    PROFILES,
    Experiment,
    RunConfig,
    available,
    expand,
    get,
    register,
)
from .core._provenance import (  # noqa: E402
    PROVENANCE_COLUMNS,
    compare_provenance,
    provenance_markdown,
)
from .core._runner import execute_run, sweep  # noqa: E402
from .core._store import aggregate, load_curves, load_runs, runs_of  # noqa: E402
from .core._studies import Study, register_study  # noqa: E402
from .core._studies import studies as registered_studies  # noqa: E402
from .core._train import TrainConfig, TrainResult, train  # noqa: E402

__all__ = [
    "PROFILES",
    "PROVENANCE_COLUMNS",
    "Experiment",
    "RunConfig",
    "Study",
    "TrainConfig",
    "TrainResult",
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
    "register_study",
    "registered_studies",
    "runs_of",
    "studies",
    "sweep",
    "train",
    "train_ensemble",
]
