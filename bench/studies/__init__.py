"""The studies, by paper: the Deconstructing paper's (``decon``) and each seed's (``hnn_seed``,
``lnn_seed``, ``vin_seed``), one folder per study; what spans every claim (``paper``: the
campaigns and the report's claim sections) and what the claims' studies share (``_claims``);
the trade-off, the stability study and the learning curves (registered here), and the
performance benchmark (``perf``: its verb is registered here; its timing modules pin threads at
import, so they load only when ``python -m bench perf`` measures).

Importing this package registers every built-in study in :mod:`bench.core`'s registry
(:func:`bench.core.studies`); the order of the imports is the report's order. A study imports
``bench.core``, the claims kit (``bench.kit``) and other studies, never the CLI or the report.
The paper's campaign registers the suite's cost model (``run_seconds``, the paper budget's
estimate of a run's time; :func:`bench.core.run_cost`): sweeps start the longest runs first by it.
"""

# isort: off
# The import order is the registration order: the report's and the figures' order.
from .decon import energy, symplectic, second_order, coordinates, damped, loss  # noqa: F401
from .lnn_seed import relativistic, double_pendulum  # noqa: F401
from .hnn_seed import tasks  # noqa: F401
from .lnn_seed import notebook  # noqa: F401
from .vin_seed import vin  # noqa: F401
from .hnn_seed import pixels  # noqa: F401
from .vin_seed import vin_blog  # noqa: F401
from .decon import hnn_diagnosis, rigid_bodies  # noqa: F401
from .hnn_seed import three_body, real_pendulum  # noqa: F401
from .decon import mujoco  # noqa: F401
from . import paper, tradeoff
from . import stability
from . import learning
from . import perf

# isort: on
from ._claims import (
    CLAIM_TITLES,
    PAPER_MODELS,
    RELATIVISTIC_TEST_PARAMS,
    SHARED_OVERRIDES,
    SPRING_EQUILIBRIUM,
    SPRING_PAPER,
    SYMREG_WEIGHTS,
    SYSTEMS,
    initial_ok,
    shared_overrides,
)

__all__ = [
    "CLAIM_TITLES",
    "PAPER_MODELS",
    "RELATIVISTIC_TEST_PARAMS",
    "SHARED_OVERRIDES",
    "SPRING_EQUILIBRIUM",
    "SPRING_PAPER",
    "SYMREG_WEIGHTS",
    "SYSTEMS",
    "initial_ok",
    "learning",
    "paper",
    "perf",
    "shared_overrides",
    "stability",
    "tradeoff",
]
