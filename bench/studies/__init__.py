"""The studies: each study of the paper in its folder (``paper/``), the trade-off, the
stability study and the learning curves (registered here), and the performance benchmark
(``perf``: its verb is registered here; its timing modules pin threads at import, so they load
only when ``python -m bench perf`` measures).

Importing this package registers every built-in study in :mod:`bench.core`'s registry
(:func:`bench.core.studies`); the order of the imports is the report's order. A study imports
``bench.core``, the claims kit (``bench.kit``) and other studies, never the CLI or the report.
The paper's campaign registers the suite's cost model (``run_seconds``, the paper budget's
estimate of a run's time; :func:`bench.core.run_cost`): sweeps start the longest runs first by it.
"""

from . import paper, tradeoff  # noqa: I001 - registration order
from . import stability
from . import learning
from . import perf

__all__ = ["learning", "paper", "perf", "stability", "tradeoff"]
