"""The experiments of the paper (Gruver et al. 2022, Figs. 2-6 and 8) and of the HNN/LNN/VIN seeds.

One :class:`~bench._experiments.Experiment` per figure, registered at import. The claim numbers
are those of REFERENCE.md ("The paper's claims"). Where REFERENCE.md or an issue disagrees with
the paper's own text or code, the paper wins; each experiment's comment says where ours differs
from the paper and why.

Trivial predictors. Every experiment carries ``constant_velocity`` (q + t qdot, qdot held
fixed), and the damped one also ``at_rest`` (the initial state held), evaluated on the same test
trajectories with the same metrics (issue 10). They have no parameters and no training; the
verdicts of ``bench._claims`` require a model to beat the best of them by a stated factor on
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

from __future__ import annotations

import math
from collections.abc import Mapping

from ._experiments import Experiment, RunConfig, expand, register

__all__ = [
    "MS_PER_STEP",
    "PAPER_EXPERIMENTS",
    "RELATIVISTIC_TEST_PARAMS",
    "SHARED_OVERRIDES",
    "SPRING_EQUILIBRIUM",
    "SPRING_PAPER",
    "SYMREG_WEIGHTS",
    "TRIVIAL_MODELS",
    "WALL_S",
    "estimate_seconds",
    "make_bench_seconds",
]

PAPER_MODELS = ("node", "node_so", "hnn", "hnn_so")
TRIVIAL_MODELS = ("constant_velocity", "at_rest")
SYSTEMS = ("chain_pendulum", "spring_pendulum")
# Fig. 3's grid: log-spaced from 1e-6 to 1e3 (REFERENCE.md), 0 = the unregularised model.
SYMREG_WEIGHTS = (0.0, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0, 10.0, 100.0, 1000.0)
SYMREG_WEIGHTS_QUICK = (0.0, 1e-6, 1e-3, 1.0, 1000.0)
UNIT_DOUBLE_PENDULUM = (("lengths", (1.0, 1.0)), ("masses", (1.0, 1.0)))
SPRING_PAPER = (("initial", "paper"),)
# The physical equilibrium is the spring pendulum's default initial state: its cells carry no
# system params, so they share config hashes with the trade-off experiment's spring cells and
# with results older than the "initial" option.
SPRING_EQUILIBRIUM = ()
# Claim 7's test set must discriminate (issue 10): on the default data (start speeds up to
# 0.9 c, g in [0.5, 2], 3 s windows anywhere in 10 s trajectories) the particle runs near light
# speed, where the acceleration is tiny, and constant velocity scores like the models (quick,
# seed 0: constant velocity 0.0072 vs HNN on (q, p) 0.0016 in (q, qdot), 4.4x). Slow particles
# in a weak field stay in the regime where the relativistic dynamics bend the trajectory:
# measured on 2026-11-22 at quick (float32, scored in (q, qdot)), constant velocity 0.022 /
# 0.026 vs HNN on (q, p) 0.00064 / 0.00058 for seeds 0 / 1 (35x, 44x): the >= 10x that the
# issue asks for. Speeds stay far below c = 1, which is the honest price: the test no longer
# probes the ultra-relativistic regime, where no model can be told from a trivial one.
RELATIVISTIC_TEST_PARAMS = (("g_max", 0.3), ("g_min", 0.05), ("v0_max", 0.3))

# Overrides of the profile defaults that every shared cell carries. Empty for now: the profile
# defaults (quick: 200 chunks, width 128, 1000 steps, batch 100) are used as they are. Any entry
# here is applied to every experiment that shares cells, so the hashes stay equal.
SHARED_OVERRIDES: dict[str, dict[str, object]] = {"smoke": {}, "quick": {}, "paper": {}}


def _shared(extra: Mapping[str, Mapping[str, object]] | None = None) -> dict:
    out = {p: dict(v) for p, v in SHARED_OVERRIDES.items()}
    for p, v in (extra or {}).items():
        out.setdefault(p, {}).update(v)
    return out


def _free(model: str) -> bool:
    """Models without a dissipation switch (everything but the HNN family)."""
    return not model.startswith("hnn")


def _trivial(model: str) -> bool:
    return model in TRIVIAL_MODELS


def _initial_ok(c: RunConfig, allowed=(SPRING_PAPER,)) -> bool:
    """Chain cells carry no system params; spring cells one of the ``allowed`` initial states
    (``SPRING_EQUILIBRIUM`` is ``()``, the default)."""
    if c.system == "spring_pendulum":
        return c.system_params in allowed
    return c.system_params == ()


def _paper_cell(c: RunConfig) -> bool:
    # constant velocity only: at_rest is for damped scenes
    return _initial_ok(c) and c.model != "at_rest"


ENERGY = Experiment(
    name="energy",
    title="Fig. 2: energy violation vs rollout error, HNNs and NODEs",
    axes={
        "system": SYSTEMS,
        "k": (1, 2, 3, 4),
        "model": (*PAPER_MODELS, "constant_velocity"),
        "system_params": ((), SPRING_PAPER),
    },
    profile_overrides=_shared({"smoke": {"k": (2,)}, "quick": {"k": (2,)}}),
    include=_paper_cell,
    claim=1,
)

SECOND_ORDER = Experiment(
    name="second_order",
    title="Fig. 4: second-order structure, NODE vs NODE+SO and HNN vs HNN+SO",
    axes={
        "system": SYSTEMS,
        "k": (2,),
        "model": (*PAPER_MODELS, "constant_velocity"),
        "system_params": ((), SPRING_PAPER),
    },
    profile_overrides=_shared(),
    include=_paper_cell,
    claim=3,
)


def _coordinates_include(c: RunConfig) -> bool:
    return _initial_ok(c, (SPRING_PAPER, SPRING_EQUILIBRIUM))


# Claim 4. The paper's published plotting code draws Fig. 5 from the test MSE over k = 1..4;
# the verdict is given for both MSE and the geometric-mean rollout error, and per spring initial
# state. k = 3 does not fit the quick budget (module docstring): quick is k = 2 only.
COORDINATES = Experiment(
    name="coordinates",
    title="Fig. 5: NODE+SO vs HNN+SO in angular (chain) and Cartesian (spring) coordinates",
    axes={
        "system": SYSTEMS,
        "k": (2,),
        "model": ("node_so", "hnn_so", "constant_velocity"),
        "system_params": (SPRING_EQUILIBRIUM, SPRING_PAPER),
    },
    profile_overrides=_shared({"paper": {"k": (1, 2, 3, 4)}}),
    include=_coordinates_include,
    claim=4,
)


def _loss_include(c: RunConfig) -> bool:
    return _paper_cell(c) and (not _trivial(c.model) or c.loss == "l2")


LOSS = Experiment(
    name="loss",
    title="Fig. 8: L1 vs L2 training loss, every paper model on chain-2",
    axes={
        "system": ("chain_pendulum",),
        "k": (2,),
        "model": (*PAPER_MODELS, "constant_velocity"),
        "loss": ("l1", "l2"),
    },
    profile_overrides=_shared(),
    include=_loss_include,
    claim=6,
)


def _symplectic_include(c: RunConfig) -> bool:
    if _trivial(c.model):
        return c.model == "constant_velocity" and c.model_options == () and _initial_ok(c)
    return c.model_options != () and _initial_ok(c)


# Claim 2. The penalty ||(J DF)^T - J DF||^2 is only zero for the true field in canonical
# coordinates: the true chain-2 field's penalty is ~1e-29 in (q, p) and 30-180 in (q, qdot), so
# the regulariser is put on models of (q, p) states (coordinates="momentum"). The reference's
# regularised model is NODE+SO in (q, p) with a learned mass matrix (node_so_symreg); the plain
# NODE + penalty on (q, p) (node_symreg) is the simpler row, at the paper profile only (budget).
SYMPLECTIC = Experiment(
    name="symplectic",
    title="Fig. 3: symplectic regulariser weight on NODE+SO in canonical (q, p)",
    axes={
        "system": ("chain_pendulum",),
        "k": (2,),
        "model": ("node_so_symreg", "constant_velocity"),
        "model_options": ((), *((("weight", w),) for w in SYMREG_WEIGHTS_QUICK)),
        "system_params": ((), SPRING_PAPER),
    },
    fixed={"coordinates": "momentum"},
    profile_overrides={
        "smoke": {"model_options": ((), (("weight", 0.0),), (("weight", 1.0),))},
        "paper": {
            "system": SYSTEMS,
            "model": ("node_so_symreg", "node_symreg", "constant_velocity"),
            "model_options": ((), *((("weight", w),) for w in SYMREG_WEIGHTS)),
        },
    },
    include=_symplectic_include,
    claim=2,
)

# Extra rows of the damped experiment (no verdict): the Rayleigh HNN runs at seed 0 only at
# quick and smoke, the plain NODE at the paper profile only (budget).
DAMPED_EXTRAS = (("node", None), ("hnn_so", True))


def _damped_include(c: RunConfig) -> bool:
    # Free models ignore dissipation: one run each (None). The HNN runs twice: plain
    # (dissipation=False, the paper's "HNN") and with the Rayleigh term (True, an extra).
    if (c.dissipation is None) != _free(c.model) or not _initial_ok(c):
        return False
    if (c.model, c.dissipation) in DAMPED_EXTRAS and c.n_train < 800:  # quick, smoke
        return c.model != "node" and c.seed == 0
    return True


# Claim 5. The paper's damped comparator ("SymODEN" in Fig. 6, MixtureHNN in the reference) is
# a separable HNN plus a free MLP field on the whole state: that is mixture_hnn, and claim 5 is
# judged against it. REFERENCE.md's Rayleigh form (-D(q) qdot on dp/dt, hnn_so with
# dissipation=True) is a stronger, correctly specified model of this friction: kept as an extra
# row, labelled "HNN+SO + Rayleigh", not used by the verdict.
DAMPED = Experiment(
    name="damped",
    title="Fig. 6: damped chain and spring: plain HNN, mixture HNN (paper), NODE(+SO)",
    axes={
        "system": SYSTEMS,
        "k": (2,),
        "model": ("node", "node_so", "hnn_so", "mixture_hnn", *TRIVIAL_MODELS),
        "dissipation": (None, False, True),
        "system_params": ((), SPRING_PAPER),
    },
    fixed={"friction": 0.4},
    include=_damped_include,
    claim=5,
)

# (model, coordinates, model_options) of the relativistic test; the extras run at seed 0 only
# at quick and smoke.
RELATIVISTIC_CELLS = (
    ("hnn", "velocity", (("momentum_map", False),)),  # the LNN seed's naive HNN: claim row
    ("hnn", "momentum", ()),
    ("lnn", "velocity", (("kinetic_prior", 0.0),)),  # the LNN seed's pure LNN: claim row
    ("constant_velocity", "velocity", ()),
)
RELATIVISTIC_EXTRAS = (
    ("hnn", "velocity", (("momentum_map", True),)),  # learned momentum map
    ("lnn", "velocity", (("kinetic_prior", 0.1),)),  # the suite's stabilised LNN
)


def _relativistic_include(c: RunConfig) -> bool:
    cell = (c.model, c.coordinates, c.model_options)
    if cell in RELATIVISTIC_CELLS:
        return True
    # the extras (learned-map HNN, LNN with the kinetic prior): paper profile only (budget)
    return cell in RELATIVISTIC_EXTRAS and c.n_train >= 800


# Claim 7. All three models are scored on (q, qdot): the (q, p) HNN's predictions are decoded
# to velocities (row column rollout_error_velocity). The LNN seed's baseline HNN takes (q, qdot)
# with qdot standing in for p (momentum_map=False), and its LNN has no kinetic prior; both of
# today's variants stay as extra rows. The test data are RELATIVISTIC_TEST_PARAMS (see there).
# Precision: the experiment runs in float64 (all models alike). The seed's pure LNN
# (kinetic_prior=0, L = MLP) has a near-singular d2L/dqdot2 at initialisation for a few states:
# at quick, seed 0, in float32 one training chunk of 200 gives a non-finite step-0 loss and the
# run diverges at step 0, with the solve and with the seed's pseudo-inverse alike (seed 1: ok,
# 0.0060); in float64 the same run trains (0.0038). The paper-scale models in the other
# experiments stay float32, as in the reference.
RELATIVISTIC = Experiment(
    name="relativistic",
    title="LNN seed: relativistic particle, naive HNN on (q, qdot) vs HNN on (q, p) vs LNN",
    axes={
        "model": ("hnn", "lnn", "constant_velocity"),
        "coordinates": ("velocity", "momentum"),
        "model_options": tuple(
            dict.fromkeys(o for *_, o in RELATIVISTIC_CELLS + RELATIVISTIC_EXTRAS)
        ),
    },
    fixed={
        "system": "relativistic_particle",
        "random_args": True,
        "system_params": RELATIVISTIC_TEST_PARAMS,
        "dtype": "float64",
    },
    include=_relativistic_include,
    claim=7,
)


def _double_pendulum_include(c: RunConfig) -> bool:
    return c.model_options == ((("kinetic_prior", 0.1),) if c.model == "lnn" else ())


# No verdict (a demonstration of the LNN seed's Fig. 5): seed 0 only at quick (budget). The LNN
# keeps the suite's kinetic prior 0.1 here (recorded in model_options): fresh pure LNNs diverged
# at step 0 on this system.
DOUBLE_PENDULUM_ENERGY = Experiment(
    name="double_pendulum_energy",
    title="LNN seed: energy error on the unit double pendulum, % of the max potential energy",
    axes={
        "model": ("node", "lnn", "constant_velocity"),
        "model_options": ((), (("kinetic_prior", 0.1),)),
    },
    fixed={"system": "chain_pendulum", "k": 2, "system_params": UNIT_DOUBLE_PENDULUM},
    profile_overrides={"smoke": {"seeds": (0,)}, "quick": {"seeds": (0,)}},
    include=_double_pendulum_include,
    claim=None,
)

# Noisy data are at the smallest data size (n_train 8 at every profile), the VIN seed's
# "fewer and noisier" comparison.
VIN_NOISY_N_TRAIN = 8


def _vin_include(c: RunConfig) -> bool:
    if _trivial(c.model):
        return c.model == "constant_velocity" and c.noise == 0.0 and c.n_train == VIN_NOISY_N_TRAIN
    if c.noise > 0:
        return c.model in ("vin", "resnet") and c.n_train == VIN_NOISY_N_TRAIN
    return True


VIN = Experiment(
    name="vin",
    title="VIN seed: pendulum from few and noisy trajectories, long horizon",
    axes={
        "model": ("vin", "resnet", "node_so", "constant_velocity"),
        "n_train": (8, 32, 128),
        "noise": (0.0, 0.01, 0.05),
    },
    # 60 chunks = 300 points (9 s at dt = 0.03): 3x the paper's horizon, the longest window of
    # the protocol's 10 s trajectories
    fixed={"system": "chain_pendulum", "k": 1, "test_chunks": 60},
    profile_overrides={
        "smoke": {
            "n_train": (8, 16),
            "test_chunks": 8,
            "model": ("vin", "resnet", "constant_velocity"),
        },
        "quick": {"model": ("vin", "resnet", "constant_velocity"), "n_train": (8, 32)},
    },
    include=_vin_include,
    claim=8,
)

PAPER_EXPERIMENTS: tuple[Experiment, ...] = (
    ENERGY,
    SECOND_ORDER,
    COORDINATES,
    LOSS,
    SYMPLECTIC,
    DAMPED,
    RELATIVISTIC,
    DOUBLE_PENDULUM_ENERGY,
    VIN,
)

for _exp in PAPER_EXPERIMENTS:
    register(_exp, replace=True)


# ----------------------------------------------------------------------------- the budget

# Seconds of run time (``wall_seconds``: dataset, compile, training, test rollouts) of one run
# at the quick profile, split as (training, everything else), measured in the quick sweep of
# 2026-11-22 (results/runs.csv, means over seeds; 2-core machine, 2 workers). Keys are (model,
# system); (model, None) applies to any system. Entries marked "guess" have not been measured.
WALL_S: dict[tuple[str, str | None], tuple[float, float]] = {
    ("node", None): (3.0, 6.5),
    ("node_so", None): (3.4, 6.2),
    ("hnn", None): (7.2, 11.2),
    # float64 since the claim-7 test set changed: measured 20 s / 70 s of training for hnn (q, p)
    # / pure lnn at load ~4 on 2 cores (about half speed), so halved here
    ("hnn", "relativistic_particle"): (10.0, 12.0),
    ("lnn", "relativistic_particle"): (35.0, 14.0),
    ("hnn_so", "chain_pendulum"): (16.0, 15.7),
    ("hnn_so", "spring_pendulum"): (18.1, 17.0),
    ("hnn_so", None): (17.0, 16.0),
    ("lnn", "chain_pendulum"): (35.5, 18.8),
    ("lnn", None): (25.2, 14.3),
    ("node_symreg", None): (9.5, 3.4),
    ("resnet", None): (0.8, 1.8),
    ("vin", None): (2.9, 6.4),
    ("node_so_symreg", None): (10.5, 4.0),  # guess: node_symreg (q, qdot) + the mass matrix
    ("mixture_hnn", None): (19.0, 17.0),  # guess: hnn_so plus an MLP field
    ("constant_velocity", None): (0.0, 4.0),  # guess: dataset + one rollout compile
    ("at_rest", None): (0.0, 4.0),  # guess
}
# Milliseconds per training step at batch 200, width 128, chain-2 (REFERENCE.md's calibration;
# the others guesses). Superseded here by WALL_S; kept for bench._tradeoff's estimate.
MS_PER_STEP = {
    "node": 8.0,
    "node_so": 8.0,
    "hnn": 20.0,
    "hnn_so": 35.0,
    "node_symreg": 25.0,
    "lnn": 40.0,
    "vin": 4.0,
    "resnet": 2.0,
}
# The stability study at quick, measured 2026-11-22 on the quiet 2-core machine after the
# integrator rework (`python -m bench stability --profile quick`: 6 min 22 s), and the trade-off
# experiment's share of the run time: the measured 1248 s of run time less the LNN's 821 s (now
# paper only), plus about 80 s for the new implicit evaluations, at 2 workers.
STABILITY_S = 382.0
TRADEOFF_S = (1248.0 - 821.0 + 80.0) / 2
# Measured sweep time / sum of per-run wall_seconds at 2 workers (25.8 / 27.0 min).
SWEEP_RATIO = 25.8 / 27.0


def _dof(c: RunConfig) -> int:
    if c.system == "spring_pendulum":
        return 3 * (c.k or 1)
    if c.system == "relativistic_particle":
        return 1
    return c.k or 1


def _wall(c: RunConfig) -> tuple[float, float]:
    return WALL_S.get((c.model, c.system)) or WALL_S.get((c.model, None)) or (20.0, 12.0)


def estimate_seconds(
    profile: str = "quick",
    *,
    workers: int = 2,
    experiments=PAPER_EXPERIMENTS,
) -> dict:
    """Wall-time estimate of the paper experiments of a profile: the sum over the unique runs of

    ``t = train(model, system) * s + other(model, system)``,
    ``s = (steps / 1000) * (batch / 100) * (width / 128) * g(dof)``

    divided by ``workers``, with :data:`WALL_S`'s measured quick costs (``s = 1`` at quick for
    the measured dof 2 systems). ``g = 1`` for the free models and ``(dof / dof_quick) ** 0.49``
    for the structured ones (the separable HNN's step cost rose from 35 to 60 ms from dof 2 to
    6, REFERENCE.md). Returns ``{"runs", "trivial_runs", "per_experiment": {name: n},
    "seconds"}``.
    """
    seen: dict[str, RunConfig] = {}
    per = {}
    for exp in experiments:
        cfgs = expand(exp, profile)
        per[exp.name] = len(cfgs)
        for c in cfgs:
            seen.setdefault(c.config_hash, c)
    total = 0.0
    for c in seen.values():
        train, other = _wall(c)
        # the dof at which WALL_S was measured: chain-2 / spring-2 (6), k = 1, the particle
        dof_quick = {"spring_pendulum": 6, "chain_pendulum": min(2, _dof(c))}.get(c.system, 1)
        g = 1.0 if _free(c.model) else (_dof(c) / dof_quick) ** (math.log(60 / 35) / math.log(3))
        s = (c.steps / 1000) * (c.batch / 100) * (c.width / 128) * g
        total += train * s + other
    return {
        "runs": len(seen),
        "trivial_runs": sum(c.model in TRIVIAL_MODELS for c in seen.values()),
        "per_experiment": per,
        "seconds": total / max(1, workers),
    }


def make_bench_seconds(profile: str = "quick", workers: int = 2) -> float:
    """Predicted wall time of ``make bench``: ``(paper experiments + trade-off) * SWEEP_RATIO +
    stability study``, from :func:`estimate_seconds` and the measured shares of the others."""
    paper = estimate_seconds(profile, workers=workers)["seconds"]
    return (paper + TRADEOFF_S) * SWEEP_RATIO + STABILITY_S
