"""The wall-time budget of the paper experiments and of ``make bench``."""

from __future__ import annotations

import math

import models

from ...core._experiments import Experiment, RunConfig, expand
from ._common import (
    TRIVIAL_MODELS,
)
from .coordinates import COORDINATES
from .damped import DAMPED
from .double_pendulum import DOUBLE_PENDULUM_ENERGY
from .energy import ENERGY
from .loss import LOSS
from .relativistic import RELATIVISTIC
from .second_order import SECOND_ORDER
from .symplectic import SYMPLECTIC
from .vin import VIN

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
# the others guesses). Superseded here by WALL_S; kept for bench.studies.tradeoff's estimate.
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
        g = (
            1.0
            if not _dof_scaled(c.model)
            else (_dof(c) / dof_quick) ** (math.log(60 / 35) / math.log(3))
        )
        s = (c.steps / 1000) * (c.batch / 100) * (c.width / 128) * g
        total += train * s + other
    return {
        "runs": len(seen),
        "trivial_runs": sum(c.model in TRIVIAL_MODELS for c in seen.values()),
        "per_experiment": per,
        "seconds": total / max(1, workers),
    }


def make_bench_seconds(profile: str = "quick", workers: int = 2) -> float:
    """Predicted wall time of ``make bench``: ``(paper experiments + learning curves +
    trade-off) * SWEEP_RATIO + stability study``, from :func:`estimate_seconds` and the
    measured shares of the others (the learning-curve experiment is read from the registry:
    ``bench.studies.learning`` imports this package, not the reverse)."""
    from ...core._experiments import available, get

    extra = tuple(get(n) for n in ("learning_curves",) if n in available())
    paper = estimate_seconds(profile, workers=workers, experiments=PAPER_EXPERIMENTS + extra)
    return (paper["seconds"] + TRADEOFF_S) * SWEEP_RATIO + STABILITY_S
