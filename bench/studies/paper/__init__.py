"""The experiments of the paper (Gruver et al. 2022, Figs. 2-9) and of the HNN/LNN/VIN seeds.

One module per figure: its :class:`~bench.core.Experiment`, its claim's verdict rule and its
figure, registered together as a :class:`~bench.core.Study` at import. Rules are built from
the study kit (:mod:`.kit`). Trivial predictors, shared runs, the spring's initial states and
the budgets: docs/studies/paper.md.
"""

# isort: off
# The import order is the registration order: the report's and the figures' order.
from . import energy, symplectic, second_order, coordinates, damped, loss
from . import relativistic, double_pendulum, lnn_seed, vin, hnn_seed  # noqa: F401
from . import pixels, vin_blog, _hnn_diagnosis  # noqa: F401
from . import rigid_bodies, three_body, real_pendulum, mujoco  # noqa: F401
from . import _commands, _sections  # noqa: F401 - the paper's verbs and report sections

# isort: on
from ._budget import (
    MS_PER_STEP,
    PAPER_EXPERIMENTS,
    WALL_S,
    estimate_seconds,
    make_bench_seconds,
)
from ._common import (
    PAPER_MODELS,
    RELATIVISTIC_TEST_PARAMS,
    SHARED_OVERRIDES,
    SPRING_EQUILIBRIUM,
    SPRING_PAPER,
    SYMREG_WEIGHTS,
    SYSTEMS,
    TRIVIAL_MODELS,
)
from ._rules import CLAIM_TITLES, claim_studies, evaluate_claims
from .kit import MODEL_LABELS, TRIVIAL_FACTOR, VERDICTS, Verdict, discrimination, scored, succeeds
from .relativistic import (
    RELATIVISTIC_CELLS,
    RELATIVISTIC_EXTRAS,
    SEED_CELLS,
    velocity_scores,
)

_MODULES = (energy, symplectic, second_order, coordinates, damped, loss, relativistic)
_MODULES += (double_pendulum, vin)
_STUDIES = tuple(m.STUDY for m in _MODULES[:7]) + (relativistic.SEED_STUDY,)
_STUDIES += tuple(m.STUDY for m in _MODULES[7:])
# experiment name -> figure function, in the report's order
FIGURES = {s.name: s.figure for s in _STUDIES}
# claim number -> verdict rule
CLAIMS = {m.STUDY.claim: m.STUDY.rule for m in _MODULES if m.STUDY.rule is not None}

__all__ = [
    "CLAIMS",
    "CLAIM_TITLES",
    "FIGURES",
    "MODEL_LABELS",
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
    "TRIVIAL_FACTOR",
    "TRIVIAL_MODELS",
    "VERDICTS",
    "Verdict",
    "WALL_S",
    "claim_studies",
    "discrimination",
    "estimate_seconds",
    "evaluate_claims",
    "make_bench_seconds",
    "scored",
    "succeeds",
    "velocity_scores",
]
