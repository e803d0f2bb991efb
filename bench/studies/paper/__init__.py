"""The experiments of the paper (Gruver et al. 2022, Figs. 2-9) and of the HNN/LNN/VIN seeds.

One folder per study: its :class:`~bench.core.Experiment`\\ s, its claim's verdict rule, its
figure and its report section (and its diagnosis where it has one), registered together as a
:class:`~bench.core.Study` at import, the rules built from the claims kit (:mod:`bench.kit`).
The registry (:func:`bench.core.studies`) is the one list of them: the figures and the claims
are read from it. Beside the studies: what they share (``_common``), the paper's report
sections (``report``) and its campaigns with their budget and verbs (``campaign``). Trivial
predictors, shared runs, the spring's initial states and the budgets: docs/studies/paper.md.
"""

# isort: off
# The import order is the registration order: the report's and the figures' order.
from . import energy, symplectic, second_order, coordinates, damped, loss  # noqa: F401
from . import relativistic, double_pendulum, lnn_seed, vin, hnn_seed  # noqa: F401
from . import pixels, vin_blog, hnn_diagnosis  # noqa: F401
from . import rigid_bodies, three_body, real_pendulum, mujoco  # noqa: F401
from . import campaign, report  # noqa: F401 - the paper's verbs and report sections

# isort: on
from ._common import (
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
from .campaign import MS_PER_STEP, PAPER_EXPERIMENTS, WALL_S, estimate_seconds, make_bench_seconds
from .relativistic import (
    RELATIVISTIC_CELLS,
    RELATIVISTIC_EXTRAS,
    SEED_CELLS,
    velocity_scores,
)

__all__ = [
    "CLAIM_TITLES",
    "MS_PER_STEP",
    "PAPER_EXPERIMENTS",
    "PAPER_MODELS",
    "RELATIVISTIC_CELLS",
    "RELATIVISTIC_EXTRAS",
    "RELATIVISTIC_TEST_PARAMS",
    "SEED_CELLS",
    "SHARED_OVERRIDES",
    "SPRING_EQUILIBRIUM",
    "SPRING_PAPER",
    "SYMREG_WEIGHTS",
    "SYSTEMS",
    "WALL_S",
    "estimate_seconds",
    "initial_ok",
    "make_bench_seconds",
    "shared_overrides",
    "velocity_scores",
]
