"""The wall-time budget of the paper experiments and of ``make bench``."""

from __future__ import annotations

import json
import math
from pathlib import Path

import models

from ....core import Experiment, RunConfig, expand
from ....kit import TRIVIAL_MODELS
from ...decon.coordinates import COORDINATES
from ...decon.damped import DAMPED
from ...decon.energy import ENERGY
from ...decon.loss import LOSS
from ...decon.second_order import SECOND_ORDER
from ...decon.symplectic import SYMPLECTIC
from ...lnn_seed.double_pendulum import DOUBLE_PENDULUM_ENERGY
from ...lnn_seed.relativistic import RELATIVISTIC, RELATIVISTIC_SEED
from ...vin_seed.vin import VIN

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


# The measured costs (costs.json beside this file, each table with where it was measured):
# WALL_S, seconds of one run at quick split as (training, everything else), keyed (model,
# system), (model, None) for any system; MS_PER_STEP, bench.studies.tradeoff's calibration;
# STEP_COST, (ms per training step, seconds of everything else but the data) keyed (kind,
# model, width, batch) for the runs WALL_S does not describe; DATA_MS_PER_S, the ground truth of
# a derivative-target dataset in ms per simulated second, keyed (system, k), charged once per
# dataset (:func:`data_seconds`); DISSIPATION, the run time of a Hamiltonian model with its
# learned Rayleigh term over the same model without; the measured seconds of what the
# estimator does not describe; SWEEP_RATIO, a sweep's measured time over its estimate.
COSTS = json.loads((Path(__file__).with_name("costs.json")).read_text())
WALL_S: dict[tuple[str, str | None], tuple[float, float]] = {
    (model, system): (train, other) for model, system, train, other, *_ in COSTS["wall_s"]["rows"]
}
MS_PER_STEP: dict[str, float] = dict(COSTS["ms_per_step"]["rows"])
STEP_COST: dict[tuple[str, str, int, int], tuple[float, float]] = {
    (kind, model, width, batch): (ms, other)
    for group in COSTS["step_cost"]["groups"]
    for kind, model, width, batch, ms, other in group["rows"]
}
DATA_MS_PER_S: dict[tuple[str, int | None], float] = {
    (system, k): ms for system, k, ms in COSTS["data_ms_per_s"]["rows"]
}
DISSIPATION: float = COSTS["dissipation"]["factor"]
_MEASURED = {name: sum(parts) / workers for name, parts, workers, _ in COSTS["measured_s"]["rows"]}
STABILITY_S = _MEASURED["stability"]
TRADEOFF_S = _MEASURED["tradeoff"]
SEED_TASKS_S = _MEASURED["hnn_seed_tasks"]
PIXELS_S = _MEASURED["pixels"]
LNN_SEED_S = _MEASURED["lnn_seed"]
LNN_NOTEBOOK_S = _MEASURED["lnn_notebook"]
PIXELS_SEED_S = _MEASURED["pixels_hnn_seed"] + _MEASURED["pixels_vin_blog"]
SEED_APPENDIX_S = _MEASURED["seed_appendix"]
RIGID_BODIES_S = _MEASURED["rigid_bodies"]
# Per paper, the measured wall seconds of what the estimator does not describe, at quick, 2
# workers: the Deconstructing paper's stability cases and Fig. 9's rigid bodies; the HNN seed's
# tasks, its pixel tasks (ours and its protocol's halves) and its appendix tasks; the LNN seed's
# two double-pendulum readings; the VIN seed's pixel tasks (ours and the blog's)
MEASURED_S = {
    "deconstructing": STABILITY_S + RIGID_BODIES_S,
    "hnn": SEED_TASKS_S + PIXELS_S / 2 + _MEASURED["pixels_hnn_seed"] + SEED_APPENDIX_S,
    "lnn": LNN_SEED_S + LNN_NOTEBOOK_S,
    "vin": PIXELS_S / 2 + _MEASURED["pixels_vin_blog"],
}
SWEEP_RATIO = COSTS["sweep"]["measured_minutes"] / COSTS["sweep"]["estimated_minutes"]


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
    rayleigh = DISSIPATION if _dof_scaled(c.model) and c.dissipation else 1.0
    train, other = _wall(c)
    # the dof at which WALL_S was measured: chain-2 / spring-2 (6), k = 1, the particle
    dof_quick = {"spring_pendulum": 6, "chain_pendulum": min(2, _dof(c))}.get(c.system, 1)
    g = (
        1.0
        if not _dof_scaled(c.model)
        else (_dof(c) / dof_quick) ** (math.log(60 / 35) / math.log(3))
    )
    s = (c.steps / 1000) * (c.batch / 100) * (c.width / 128) * g
    return (train * s + other) * rayleigh


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
    from ....core import PAPERS, available, get

    papers = PAPERS if papers is None else tuple(papers)
    extra = tuple(get(n) for n in ("learning_curves",) if n in available())
    mine = tuple(e for e in PAPER_EXPERIMENTS + extra if e.paper in papers)
    seconds = estimate_seconds(profile, workers=workers, experiments=mine)["seconds"] if mine else 0
    if "deconstructing" in papers:
        seconds += TRADEOFF_S
    return seconds * SWEEP_RATIO + sum(MEASURED_S[p] for p in papers)
