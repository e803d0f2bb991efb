"""decon-bench: metrics, training, the sweep runner, the CLI, tables, figures and the report."""

from ._env import configure_threads as _configure_threads

_configure_threads()
