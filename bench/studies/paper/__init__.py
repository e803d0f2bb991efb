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

Quick-profile budget (``make bench`` <= 30 min on 2 cores, 2 workers). The quick sweep of
2026-11-22 took 25.8 min for 180 runs (120 paper runs, 60 trade-off evaluations) plus 4.1 min
of stability study. The per-run ``wall_seconds`` summed over runs / 2 workers predicts that
sweep at 27.0 min (0.96x measured), so the budget is that sum, from the measured per-model costs
of :data:`WALL_S` (models not measured yet: guesses, marked there). Check: the old declarations
give 1990 s with :func:`estimate_seconds`, the measured sum was 1990 s. Runs per experiment at
quick (3 seeds unless stated; shared cells counted once, where first declared):

============================  =====  ========================================================
experiment                    runs   cells
============================  =====  ========================================================
energy (Fig. 2)               30     {node, node_so, hnn, hnn_so, const. velocity} x {chain,
                                     spring (paper init)} x k=2 (k = 1..4 only in paper)
second_order (Fig. 4)         0 new  all 30 shared with energy
coordinates (Fig. 5)          9 new  node_so, hnn_so, const. velocity on spring-2 from the
                                     physical equilibrium (18 shared with energy)
loss (Fig. 8)                 12 new L1 for the four models (15 L2 cells shared with energy)
symplectic (Fig. 3)           18     node_so_symreg (q, p) x w in {0, 1e-6, 1e-3, 1, 1e3},
                                     const. velocity (q, p); chain-2
damped (Fig. 6)               32     {node_so, hnn_so plain, mixture_hnn, const. velocity,
                                     at rest} x 3 seeds, hnn_so + Rayleigh x seed 0; chain-2
                                     and spring-2, friction 0.4 (plain NODE: paper only)
relativistic (LNN seed)       12     {naive hnn (q, qdot), hnn (q, p), pure lnn, const.
                                     velocity} x 3 seeds (learned-map HNN, prior LNN: paper)
double_pendulum_energy (LNN)  3      node, lnn, const. velocity, seed 0 only (no verdict)
vin (VIN seed)                27     {vin, resnet} x n_train {8, 32} noise 0; {vin, resnet}
                                     x n_train 8 x noise {0.01, 0.05}; const. velocity at
                                     n_train 8 (n_train 128 and node_so: paper only)
============================  =====  ========================================================

Unique runs at quick: 30 + 9 + 12 + 18 + 32 + 12 + 3 + 27 = 143, of which 31 are trivial
predictors (about 4 s each: dataset and one rollout compile). ``estimate_seconds("quick")``:
2080 s of run time, 17.3 min at 2 workers (the old declarations: 1990 s, 16.6 min). With the
trade-off experiment (1248 s of run time, 10.4 min) the sweep is predicted at 27.7 min, i.e.
about 26.5 min at the measured 0.96 ratio, plus 4.1 min of stability study: ``make bench`` at
about 30.6 min (:func:`make_bench_seconds`), at the limit (today's cells: 29.9 min measured),
resting on guessed costs for node_so_symreg, mixture_hnn and the trivial predictors (remeasure
them after the first sweep and update :data:`WALL_S`). Cut to get there: k = 3 at quick for
claim 4 (chain-3 and spring-3 would add about 250 s of run time), the plain NODE + penalty on
(q, p) (node_symreg: paper only), the symplectic grid to 5 weights, one seed for the Rayleigh
HNN and the double-pendulum demonstration, the plain NODE in Fig. 6, the learned-map HNN and
prior LNN extras, node_so and n_train 128 in the VIN experiment and the noisy VIN cells at
n_train 32. The largest remaining lever is the trade-off experiment (60 evaluations, 10.4 min).
"""

import matplotlib

matplotlib.use("Agg")

# isort: off
# The import order is the registration order: the report's and the figures' order.
from . import energy, symplectic, second_order, coordinates, damped, loss  # noqa: E402
from . import relativistic, double_pendulum, lnn_seed, vin, hnn_seed  # noqa: E402, F401
from . import pixels  # noqa: E402, F401

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
