"""The wall-time budget of the paper experiments and of ``make bench``."""

from __future__ import annotations

import math

import models

from ....core._config import RunConfig
from ....core._experiments import Experiment, expand
from ....kit import TRIVIAL_MODELS
from ..coordinates import COORDINATES
from ..damped import DAMPED
from ..double_pendulum import DOUBLE_PENDULUM_ENERGY
from ..energy import ENERGY
from ..loss import LOSS
from ..relativistic import RELATIVISTIC, RELATIVISTIC_SEED
from ..second_order import SECOND_ORDER
from ..symplectic import SYMPLECTIC
from ..vin import VIN

PAPER_EXPERIMENTS: tuple[Experiment, ...] = (
    ENERGY,
    SECOND_ORDER,
    COORDINATES,
    LOSS,
    SYMPLECTIC,
    DAMPED,
    RELATIVISTIC,
    RELATIVISTIC_SEED,
    DOUBLE_PENDULUM_ENERGY,
    VIN,
)


# Seconds of run time (``wall_seconds``: dataset, compile, training, test rollouts and the
# learning-curve checkpoints) of one run at the quick profile, split as (training, everything
# else), measured in a quick ``make bench`` with checkpoints (results/runs.parquet: means
# over the 1000-step runs; 2-core machine, 2 workers). Keys are
# (model, system); (model, None) applies to any system.
WALL_S: dict[tuple[str, str | None], tuple[float, float]] = {
    ("node", "chain_pendulum"): (3.1, 6.2),
    ("node", None): (2.9, 3.4),
    ("node_so", "chain_pendulum"): (3.3, 11.4),
    ("node_so", None): (3.3, 8.8),
    ("hnn", "relativistic_particle"): (11.4, 6.5),  # float64 (claim 7's test set)
    ("hnn", None): (7.3, 10.2),
    ("hnn_so", "chain_pendulum"): (15.6, 16.4),
    ("hnn_so", "spring_pendulum"): (18.0, 13.6),
    ("hnn_so", None): (17.0, 15.0),
    ("lnn", "relativistic_particle"): (31.1, 9.2),
    ("lnn", None): (30.6, 27.8),
    ("node_symreg", None): (9.5, 3.4),  # measured before (not at quick any more)
    ("node_so_symreg", None): (16.9, 8.7),
    ("mixture_hnn", "spring_pendulum"): (22.1, 11.0),
    ("mixture_hnn", None): (18.4, 10.9),
    ("resnet", None): (0.2, 1.1),
    ("vin", None): (0.5, 4.7),
    ("constant_velocity", None): (0.0, 0.2),
    ("at_rest", None): (0.0, 0.1),
}


# Milliseconds per training step at batch 200, width 128, chain-2 (the calibration against the
# paper's public code; the others guesses). Superseded here by WALL_S; kept for
# bench.studies.tradeoff's estimate.
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


# The stability study at quick in 2 processes (a `make bench`: 243 s, the long-horizon case
# alone 210 s, split by model over the processes), and the trade-off experiment's run time at
# 2 workers (274 s of run time measured with HNN+SO's training variants, 106 s, and the
# spring's evaluations, 78 s, which quick no longer runs).
STABILITY_S = 243.0
TRADEOFF_S = (274.0 - 106.0 - 78.0) / 2
# The HNN seed's tasks at quick (derivative targets, not in WALL_S's rollout-trained costs):
# 79 + 96 + 62 s wall for the three experiments, 2 workers, cold caches
# (`python -m bench sweep hnn_seed_<system> --profile quick --workers 2`)
SEED_TASKS_S = 237.0
# The pixel experiments at quick (claims 11 and 12): 20 runs, 300 s summed wall_seconds at 1
# worker with the paper-core campaign paused, /2 workers
PIXELS_S = 300.0 / 2
# The LNN seed's double pendulum at quick (claim 9): 15 runs, 294 s of run time at 1 worker
# under load (lnn_seed.MEASURED), /2 workers
LNN_SEED_S = 294.0 / 2
# Claim 9's notebook reading at quick (lnn_seed_notebook, seeds 0-4): 210 s of CPU time summed
# over its 15 runs (the rows' cpu_seconds: the time an idle core would take), /2 workers
LNN_NOTEBOOK_S = 210.0 / 2
# The seeds' own pixel protocols at quick, seeds 0-4 (CPU seconds summed over the runs, /2
# workers): claim 11's pixel_pendulum_hnn_seed (10 runs, 660 s) and claim 12's
# pixel_pendulum_vin_blog (20 runs, 642 s)
PIXELS_SEED_S = (660.0 + 642.0) / 2
# The HNN seed's three-body and real pendulum at quick (claims 14 and 15), seeds 0-4: 362 s and
# 131 s of CPU time summed over their 15 runs each (the rows' cpu_seconds), /2 workers
SEED_APPENDIX_S = (362.0 + 131.0) / 2


# Per paper, the measured wall seconds of what the estimator does not describe, at quick, 2
# workers: the Deconstructing paper's stability cases and Fig. 9's rigid bodies (60 runs,
# 1005 s of CPU time summed over the quick sweep's seeds 0-4 under load: an upper bound, /2);
# the HNN seed's tasks, its pixel tasks (ours and its protocol's halves) and its appendix
# tasks; the LNN seed's two double-pendulum readings; the VIN seed's pixel tasks (ours and the
# blog's)
RIGID_BODIES_S = 1005.0 / 2
MEASURED_S = {
    "deconstructing": STABILITY_S + RIGID_BODIES_S,
    "hnn": SEED_TASKS_S + PIXELS_S / 2 + 660.0 / 2 + SEED_APPENDIX_S,
    "lnn": LNN_SEED_S + LNN_NOTEBOOK_S,
    "vin": PIXELS_S / 2 + 642.0 / 2,
}


# Runs that WALL_S (rollout training on states) does not describe: derivative targets (the LNN
# seed, claim 9) and pixel frames (claims 11 and 12). (ms per training step, seconds of
# everything else but the data) at the sizes the profiles run, keyed (kind, model, width, batch),
# kind "pixels", "frames" or "derivative". Pixels at paper-core (batch 200, width 200): the
# difference of 200- and 600-step runs of `expand(..., "paper-core")`'s configs, one process,
# the campaign paused; at quick (batch 64, width 128): the quick rows' train_seconds / steps.
# The LNN seed: lnn_seed.MEASURED at paper (width 500, 8 chunks of 4 states), the quick rows at
# quick. Other sizes fall back to WALL_S's scaling (the HNN seed's tasks, whose estimate was
# 0.14 CPU h against 0.19 h measured at paper-core).
STEP_COST: dict[tuple[str, str, int, int], tuple[float, float]] = {
    ("pixels", "hnn", 200, 200): (15.0, 4.7),
    ("pixels", "node", 200, 200): (14.4, 3.9),
    ("pixels", "vin", 200, 200): (12.9, 4.4),
    ("pixels", "resnet", 200, 200): (12.0, 3.2),
    ("pixels", "hnn", 128, 64): (6.2, 6.6),
    ("pixels", "node", 128, 64): (5.8, 5.0),
    ("pixels", "vin", 128, 64): (5.5, 5.0),
    ("pixels", "resnet", 128, 64): (5.1, 4.5),
    # The VIN seed's frames (claim 12's second reading, vin_blog): at quick (width 128, 32
    # windows of 11 frames) the quick rows' median train_seconds / steps and wall - train; at
    # paper-core (width 256, full batches of 120 windows) 300-step runs of seed 0, one process
    # under load (vin: two potential gradients per Verlet step)
    ("frames", "vin", 128, 32): (12.9, 8.0),
    ("frames", "resnet", 128, 32): (12.0, 1.2),
    ("frames", "at_rest", 128, 32): (12.3, 4.6),
    ("frames", "vin", 256, 200): (100.6, 20.0),
    ("frames", "resnet", 256, 200): (56.9, 20.0),
    ("frames", "at_rest", 256, 200): (54.7, 20.0),
    ("derivative", "lnn", 500, 8): (14.8, 20.0),
    ("derivative", "node_so", 500, 8): (2.7, 5.0),
    ("derivative", "lnn", 128, 8): (1.9, 16.7),
    ("derivative", "node_so", 128, 8): (0.4, 4.4),
    # The LNN seed's notebook reading (fresh box states; batch in states): 400-step runs of
    # `expand("lnn_seed_notebook", ...)`'s configs at paper-core (width 600, batch 512) and
    # 2000-step runs at quick (width 128, batch 128), under load (load average 5-9 on the 2
    # cores: upper bounds; the campaign's calibration corrects them); evaluation as the quick
    # rows' wall_seconds minus train_seconds
    ("derivative", "lnn", 600, 512): (213.8, 60.0),
    ("derivative", "node_so", 600, 512): (31.4, 10.0),
    ("derivative", "lnn", 128, 128): (31.7, 58.0),
    ("derivative", "node_so", 128, 128): (0.9, 7.0),
    # Claim 7 on the LNN seed's protocol (relativistic_seed, float64, depth 4, 16 chunks of 2
    # states). quick: medians of its 5-seed sweep at 1 worker under load (the HNN: both
    # coordinates); paper: ms per step of 300-step runs under load, the rest estimated
    # (50,000 trajectories of data, 200 test rollouts, 4 checkpoints)
    ("derivative", "lnn", 128, 16): (5.1, 7.5),
    ("derivative", "hnn", 128, 16): (1.7, 4.8),
    ("derivative", "lnn", 500, 16): (30.8, 60.0),
    ("derivative", "hnn", 500, 16): (15.5, 45.0),
    # Claim 16's MuJoCo runs (controlled, width 128, batch 200, 3-step windows, 8 Euler steps
    # per transition): the CPU time of 200- and 600-step runs on HopperFull-v0's file, one
    # process under load, n_test 50 (the NODEs' difference at noise level: NODE+SO's for both)
    ("controlled", "node", 128, 200): (6.6, 5.0),
    ("controlled", "node_so", 128, 200): (6.6, 5.0),
    ("controlled", "hnn_force", 128, 200): (48.5, 25.0),
    ("controlled", "constant_velocity", 128, 200): (0.0, 1.0),
    # Claim 2 at paper-core (chain-2, width 256, batch 200): the campaign's stored rows,
    # (cpu_seconds - 12 s of evaluation) / 8000 steps; the penalty's Jacobian, and
    # its gradient, cost more than the quick-to-paper scaling assumed (550 s a run), and at
    # weight 0 the model skips the penalty (280 s a run)
    ("rollout", "node_so_symreg", 256, 200): (112.0, 12.0),
    ("rollout", "node_so_symreg (weight 0)", 256, 200): (34.0, 12.0),
    # The HNN seed's three-body (claim 14; width 200, 30 orbits of 20 states) and real pendulum
    # (claim 15; full batches of the measured states): medians of the quick sweeps of seeds
    # 0-9, train_seconds / steps and wall - train, under load (load average 7-12 on the 2
    # cores: upper bounds). Paper evaluates 4x the three-body test orbits of quick.
    ("derivative", "hnn", 200, 30): (10.1, 116.0),
    ("derivative", "node", 200, 30): (4.0, 11.9),
    ("derivative", "constant_velocity", 200, 30): (0.0, 7.8),
    ("measured", "hnn", 200, 100_000): (20.1, 11.0),
    ("measured", "node", 200, 100_000): (6.1, 6.7),
    ("measured", "at_rest", 200, 100_000): (0.0, 0.1),
}
# Ground truth of a derivative-target dataset, ms per simulated second of one trajectory (the
# double pendulum at Dopri8 and 1e-11: 8.7 ms per 10 s trajectory, lnn_seed.MEASURED), keyed
# (system, k); charged once per dataset (the models of a seed share it), see data_seconds.
# Elsewhere the data is inside WALL_S's "everything else" (1000 trajectories at most).
# three_body: 1000 of the seed's orbits of 5 s at Dopri8 and 1e-13 in 9.0 s, compile included.
DATA_MS_PER_S: dict[tuple[str, int | None], float] = {
    ("chain_pendulum", 2): 0.87,
    ("three_body", None): 1.8,
}


# Measured sweep time / (sum of per-run wall_seconds / 2 workers): 25.2 / 23.4 min in a quick
# sweep with one pool per experiment (the runner now uses one pool, longest runs first).
SWEEP_RATIO = 25.2 / 23.4


def _dof_scaled(model: str) -> bool:
    """Whether a model's step cost is scaled with the dof: the Hamiltonian models with a
    dissipation switch (hnn, hnn_so), whose step cost was measured against the dof."""
    s = models.spec(model)
    return s.hamiltonian and s.takes_dissipation


def _dof(c: RunConfig) -> int:
    if c.system == "spring_pendulum":
        return 3 * (c.k or 1)
    if c.system == "relativistic_particle":
        return 1
    return c.k or 1


def _wall(c: RunConfig) -> tuple[float, float]:
    return WALL_S.get((c.model, c.system)) or WALL_S.get((c.model, None)) or (20.0, 12.0)


def _kind(c: RunConfig) -> str:
    return c.observation if c.observation != "state" else c.train_target


def _cost_name(c: RunConfig) -> str:
    """The model as :data:`STEP_COST` keys it: a penalised model at weight 0 apart (it skips
    the penalty: ``penalty`` in ``models/_node.py``)."""
    if c.model in ("node_symreg", "node_so_symreg"):
        if float(dict(c.model_options).get("weight", 1.0)) == 0.0:
            return f"{c.model} (weight 0)"
    return c.model


def run_seconds(c: RunConfig) -> float:
    """Estimated run time of one run, its dataset aside where :func:`data_seconds` charges it
    (see :func:`estimate_seconds`); the sweep starts the longest runs first with it
    (``bench.core._runner.sweep(order=...)``)."""
    measured = STEP_COST.get((_kind(c), _cost_name(c), c.width, c.batch))
    if measured is not None:
        ms, other = measured
        return c.steps * ms / 1000 + other
    train, other = _wall(c)
    # the dof at which WALL_S was measured: chain-2 / spring-2 (6), k = 1, the particle
    dof_quick = {"spring_pendulum": 6, "chain_pendulum": min(2, _dof(c))}.get(c.system, 1)
    g = (
        1.0
        if not _dof_scaled(c.model)
        else (_dof(c) / dof_quick) ** (math.log(60 / 35) / math.log(3))
    )
    s = (c.steps / 1000) * (c.batch / 100) * (c.width / 128) * g
    return train * s + other


def data_seconds(c: RunConfig) -> float:
    """Seconds to generate the ground truth of ``c``'s dataset, where it is charged apart from
    the runs (:data:`DATA_MS_PER_S`: derivative-target datasets), else 0. Charge it once per
    ``c.dataset_config()``: :func:`total_seconds`."""
    if c.train_target != "derivative":
        return 0.0
    ms = DATA_MS_PER_S.get((c.system, c.k))
    return 0.0 if ms is None else c.n_generated * c.duration * ms / 1000


def total_seconds(cfgs, charged=None) -> float:
    """Run time of ``cfgs``: every run's :func:`run_seconds` plus each dataset's
    :func:`data_seconds` once (datasets in ``charged``, a set of ``dataset_config()``s that is
    updated, are taken as paid already)."""
    charged = set() if charged is None else charged
    total = 0.0
    for c in cfgs:
        total += run_seconds(c)
        extra = data_seconds(c)
        if extra:
            d = c.dataset_config()
            if d not in charged:
                charged.add(d)
                total += extra
    return total


def estimate_seconds(
    profile: str = "quick",
    *,
    workers: int = 2,
    experiments=PAPER_EXPERIMENTS,
) -> dict:
    """Wall-time estimate of the paper experiments of a profile: the sum over the unique runs of

    ``t = train(model, system) * s + other(model, system)``
    (or ``steps * ms + other`` where :data:`STEP_COST` has the run's kind, model and size; plus
    each derivative-target dataset's :func:`data_seconds` once),
    ``s = (steps / 1000) * (batch / 100) * (width / 128) * g(dof)``

    divided by ``workers``, with :data:`WALL_S`'s measured quick costs (``s = 1`` at quick for
    the measured dof 2 systems). ``g = 1`` for the free models and ``(dof / dof_quick) ** 0.49``
    for the structured ones (the separable HNN's step cost rose from 35 to 60 ms from dof 2 to
    6, as the paper's public code counts them). Returns ``{"runs", "trivial_runs",
    "per_experiment": {name: n},
    "seconds"}``.
    """
    seen: dict[str, RunConfig] = {}
    per = {}
    for exp in experiments:
        cfgs = expand(exp, profile)
        per[exp.name] = len(cfgs)
        for c in cfgs:
            seen.setdefault(c.config_hash, c)
    total = total_seconds(seen.values())
    return {
        "runs": len(seen),
        "trivial_runs": sum(c.model in TRIVIAL_MODELS for c in seen.values()),
        "per_experiment": per,
        "seconds": total / max(1, workers),
    }


def make_bench_seconds(profile: str = "quick", workers: int = 2, papers=None) -> float:
    """Predicted wall time of ``bench --papers`` (None: every paper) at ``profile``: the
    estimate (:func:`estimate_seconds`) of the papers' rollout-trained experiments, with the
    Deconstructing paper's learning curves and trade-off, times ``SWEEP_RATIO``, plus the
    measured shares of what that estimate does not describe (:data:`MEASURED_S`; the stability
    cases run with the Deconstructing paper). ``make bench`` is ``papers=("deconstructing",)``,
    ``make bench-seeds`` the three seeds. (The learning-curve experiment is read from the
    registry: ``bench.studies.learning`` imports this package, not the reverse.)"""
    from ....core._experiments import PAPERS, available, get

    papers = PAPERS if papers is None else tuple(papers)
    extra = tuple(get(n) for n in ("learning_curves",) if n in available())
    mine = tuple(e for e in PAPER_EXPERIMENTS + extra if e.paper in papers)
    seconds = estimate_seconds(profile, workers=workers, experiments=mine)["seconds"] if mine else 0
    if "deconstructing" in papers:
        seconds += TRADEOFF_S
    return seconds * SWEEP_RATIO + sum(MEASURED_S[p] for p in papers)
