"""decon-bench: metrics, training, the sweep runner, the CLI, tables, figures and the report.

Layers, each importing only those below it: ``bench.core`` (experiments, training, metrics,
runner, store, query layer, study registry) <- ``bench.kit`` (the claims kit: parts, gates,
verdicts, the policy, claim evaluation and replication) <- ``bench.studies`` (the paper's
studies, one folder each, the trade-off, the stability study, perf) <- the CLI
(``bench._cli``) and the report (``bench._report``). Importing ``bench`` loads no study (the
registry loads them all on its first use, ``bench.core.load_plugins``) and changes nothing in
the process: the entry points set threads and the compilation cache up
(``bench.core._env.setup_process``).
"""

from ._shadow import check as _check_shadowing

# before the suite's packages are imported: a models.py or systems.py of the folder Python
# started in would hide them, and their first import would fail far from the cause
_check_shadowing()

from . import experiments, metrics
from .core import (
    PROFILES,
    PROVENANCE_COLUMNS,
    Experiment,
    RunConfig,
    Study,
    TrainConfig,
    TrainResult,
    aggregate,
    available,
    compare_provenance,
    execute_run,
    expand,
    get,
    load_curves,
    load_runs,
    provenance_markdown,
    register,
    register_study,
    runs_of,
    sweep,
    train,
    train_ensemble,
)
from .core import studies as registered_studies

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
    "sweep",
    "train",
    "train_ensemble",
]
