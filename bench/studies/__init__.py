"""The studies: each paper experiment with its verdict rule and figure, the trade-off, the
stability study and the learning curves (registered here), and the performance benchmark
(``perf``, an entry point of its own that pins threads at import, so it is imported only by
``python -m bench perf``).

Importing this package registers every built-in study in :mod:`bench.core`'s registry
(:func:`bench.core.studies`); the order of the imports is the report's order. A study imports
``bench.core`` and other studies, never the CLI or the report.
"""

from . import paper, tradeoff  # noqa: I001 - registration order
from . import stability
from . import learning

__all__ = ["learning", "paper", "stability", "tradeoff"]
