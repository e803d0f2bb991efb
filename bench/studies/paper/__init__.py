"""The experiments of the paper (Gruver et al. 2022, Figs. 2-6 and 8) and of the HNN/LNN/VIN seeds.

One module per figure: its :class:`~bench.core.Experiment`, its claim's verdict rule and its
figure, registered together as a :class:`~bench.core.Study` at import. The claim numbers
are those of REFERENCE.md ("The paper's claims"). Where REFERENCE.md or an issue disagrees with
the paper's own text or code, the paper wins; each experiment's comment says where ours differs
from the paper and why.

Trivial predictors. Every experiment carries ``constant_velocity`` (q + t qdot, qdot held
fixed), and the damped one also ``at_rest`` (the initial state held), evaluated on the same test
trajectories with the same metrics (issue 10). They have no parameters and no training; the
verdicts (``_rules``) require a model to beat the best of them by a stated factor on
every seed before it "succeeds", and call an experiment whose best model does not "not
discriminating".

Shared runs. Figs. 2, 4, 5 and the L2 half of Fig. 8 use the same cells (the four paper models
and the constant-velocity predictor on the undamped chain and spring pendulums); they are
declared with the same RunConfig fields (the profile's defaults plus :data:`SHARED_OVERRIDES`),
so they expand to the same ``config_hash`` and the runner trains each cell once.

Spring pendulum initial states. The paper's spring figures (2, 4, 5, 6 and the Fig. 3 grid at
the paper profile) start the bobs where the reference does (``system_params`` ``initial =
"paper"``, about i - 1 m above the true equilibrium, REFERENCE.md "Initial conditions"); Fig. 5
(claim 4) also runs the physical equilibrium (the system's default, no system params, so these
cells share their hashes with the trade-off experiment and with older results) at every
profile. The trade-off's plain NODE on the spring (default start) no longer shares its training
with Fig. 2 (about 10 s of run time more in the trade-off).

Budgets. ``make bench`` must finish in 30 min on 2 cores (install included), so ``quick`` keeps
5 seeds on the cells each verdict reads and moves the rest to ``paper`` (k = 1..4, every
symplectic weight, the extras no verdict reads) or to the ``paper-core`` campaign (claim 2,
since 2026-11-25). The estimate lives in :mod:`._budget`: per-run costs measured at quick
(:data:`WALL_S`), scaled to a profile's steps, batch and width, costs measured at their own
sizes for derivative-target and pixel runs (:data:`STEP_COST`), and the measured shares of the
stability study, the trade-off and the seed tasks (:func:`make_bench_seconds`: 33.8 min on
2026-11-25, against 26.5 min measured on a fresh clone on a Zen 4 CPU; the costs were measured
on a slower Zen 3). ``python -m bench estimate --profile <profile>`` prints runs and hours per
claim; each experiment's module says what it cut at quick and why.
"""

import matplotlib

matplotlib.use("Agg")

# isort: off
# The import order is the registration order: the report's and the figures' order.
from . import energy, symplectic, second_order, coordinates, damped, loss  # noqa: E402
from . import relativistic, double_pendulum, lnn_seed, vin, hnn_seed  # noqa: E402, F401
from . import pixels, _hnn_diagnosis  # noqa: E402, F401
from . import _commands, _sections  # noqa: E402, F401 - the paper's verbs and report sections

# isort: on
from ._budget import (  # noqa: E402
    MS_PER_STEP,
    PAPER_EXPERIMENTS,
    WALL_S,
    estimate_seconds,
    make_bench_seconds,
)
from ._common import (  # noqa: E402
    PAPER_MODELS,
    RELATIVISTIC_TEST_PARAMS,
    SHARED_OVERRIDES,
    SPRING_EQUILIBRIUM,
    SPRING_PAPER,
    SYMREG_WEIGHTS,
    SYSTEMS,
    TRIVIAL_MODELS,
)
from ._rules import (  # noqa: E402
    CLAIM_TITLES,
    claim_studies,
    discrimination,
    evaluate_claims,
    succeeds,
)
from ._stats import MODEL_LABELS, TRIVIAL_FACTOR, VERDICTS, Verdict, scored  # noqa: E402
from .relativistic import RELATIVISTIC_CELLS, RELATIVISTIC_EXTRAS, velocity_scores  # noqa: E402

_MODULES = (energy, symplectic, second_order, coordinates, damped, loss, relativistic)
_MODULES += (double_pendulum, vin)
# experiment name -> figure function, in the report's order
FIGURES = {m.STUDY.name: m.STUDY.figure for m in _MODULES}
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
