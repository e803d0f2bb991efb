"""The experiments of the paper (Gruver et al. 2022, Figs. 2-6 and 8) and of the HNN/LNN/VIN seeds.

One :class:`~bench._experiments.Experiment` per figure, registered at import. The claim numbers
are those of REFERENCE.md ("The paper's claims").

Shared runs. Figs. 2, 4, 5 and the L2 half of Fig. 8 use the same cells (the four paper models
on the undamped chain and spring pendulums); they are declared with the same RunConfig fields
(the profile's defaults plus :data:`SHARED_OVERRIDES`), so they expand to the same
``config_hash`` and the runner trains each cell once.

Quick-profile budget (``make bench``: every experiment in <= 30 min on 2 cores, 3 seeds).
Arithmetic from the calibration of REFERENCE.md (width 128, batch 200: NODE and NODE+SO about
8 ms per step, separable HNN 35 ms on chain-2 and 60 ms on spring-2) scaled to batch 100 and to
the dof; :func:`estimate_seconds` redoes it from :func:`expand`. Run counts (3 seeds):

============================  =====  ========================================================
experiment                    runs   note
============================  =====  ========================================================
energy (Fig. 2)               24     4 models x {chain, spring} x k=2 (k = 1..4 only in paper)
second_order (Fig. 4)         24     all shared with energy
coordinates (Fig. 5)          12     all shared with energy
loss (Fig. 8)                 24     12 new (L1); the L2 half is shared with energy
symplectic (Fig. 3)           18     node_symreg, 6 weights, chain-2
damped (Fig. 6)               24     4 variants x {chain, spring} k=2, friction 0.4
relativistic (LNN seed)       9      hnn(q, qdot), hnn(q, p), lnn(q, qdot)
double_pendulum_energy (LNN)  6      node vs lnn, unit masses and lengths
vin (VIN seed)                27     {vin, resnet, node_so} x n_train {8, 32, 128}, noise 0
                                     (noise 0.01 for vin and resnet at n_train 32 in paper)
============================  =====  ========================================================

Unique runs in quick: 24 + 12 + 18 + 24 + 9 + 6 + 27 = 120. The quick profile uses k = 2 only
in Fig. 2 because the separable HNN's cost grows with the dof (spring k = 3, 4 would cost
more than the whole rest of the sweep); the scatter over systems and models still gives 24
points.

Estimate: ``estimate_seconds("quick")`` gives about 22 min with the calibration's per-step
costs and 12 s of per-run overhead. Measured on 2026-11-22 on this machine while the team's
tests ran beside it (load average 8-10 on 2 cores), quick chain-2, seed 0: NODE+SO 9 s training
+ 15 s compile, 105 s wall (first run: includes the dataset); separable HNN 96 s training +
103 s compile, 276 s wall. With those costs the quick sweep would take about 2 h, so the
30-minute budget is NOT yet verified; re-measure on an idle machine before trimming cells.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from ._experiments import Experiment, RunConfig, expand, register

__all__ = [
    "PAPER_EXPERIMENTS",
    "SHARED_OVERRIDES",
    "estimate_seconds",
]

PAPER_MODELS = ("node", "node_so", "hnn", "hnn_so")
SYSTEMS = ("chain_pendulum", "spring_pendulum")
SYMREG_WEIGHTS = (0.0, 1e-3, 1e-2, 1e-1, 1.0, 10.0)
UNIT_DOUBLE_PENDULUM = (("lengths", (1.0, 1.0)), ("masses", (1.0, 1.0)))

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
    return model in ("node", "node_so", "node_symreg", "resnet")


def _damped_include(c: RunConfig) -> bool:
    # Free models ignore dissipation: one run each (None). The HNN runs twice: plain
    # (dissipation=False, the paper's "HNN") and with the dissipation term (True).
    return (c.dissipation is None) == _free(c.model)


def _relativistic_include(c: RunConfig) -> bool:
    return c.model == "hnn" or c.coordinates == "velocity"


def _vin_include(c: RunConfig) -> bool:
    # The noisy cells are for the VIN-vs-ResNet comparison only.
    return c.noise == 0.0 or c.model in ("vin", "resnet")


ENERGY = Experiment(
    name="energy",
    title="Fig. 2: energy violation vs rollout error, HNNs and NODEs",
    axes={"system": SYSTEMS, "k": (1, 2, 3, 4), "model": PAPER_MODELS},
    profile_overrides=_shared({"smoke": {"k": (2,)}, "quick": {"k": (2,)}}),
    claim=1,
)

SECOND_ORDER = Experiment(
    name="second_order",
    title="Fig. 4: second-order structure, NODE vs NODE+SO and HNN vs HNN+SO",
    axes={"system": SYSTEMS, "k": (2,), "model": PAPER_MODELS},
    profile_overrides=_shared(),
    claim=3,
)

COORDINATES = Experiment(
    name="coordinates",
    title="Fig. 5: NODE+SO vs HNN+SO in angular (chain) and Cartesian (spring) coordinates",
    axes={"system": SYSTEMS, "k": (2,), "model": ("node_so", "hnn_so")},
    profile_overrides=_shared(),
    claim=4,
)

LOSS = Experiment(
    name="loss",
    title="Fig. 8: L1 vs L2 training loss, every paper model on chain-2",
    axes={"system": ("chain_pendulum",), "k": (2,), "model": PAPER_MODELS, "loss": ("l1", "l2")},
    profile_overrides=_shared(),
    claim=6,
)

SYMPLECTIC = Experiment(
    name="symplectic",
    title="Fig. 3: symplectic regulariser weight on a NODE",
    axes={
        "system": ("chain_pendulum",),
        "k": (2,),
        "model": ("node_symreg",),
        "model_options": tuple((("weight", w),) for w in SYMREG_WEIGHTS),
    },
    profile_overrides={"paper": {"system": SYSTEMS}},
    claim=2,
)

DAMPED = Experiment(
    name="damped",
    title="Fig. 6: damped chain and spring, plain HNN vs HNN + dissipation vs NODE(+SO)",
    axes={
        "system": SYSTEMS,
        "k": (2,),
        "model": ("node", "node_so", "hnn_so"),
        "dissipation": (None, False, True),
    },
    fixed={"friction": 0.4},
    include=_damped_include,
    claim=5,
)

RELATIVISTIC = Experiment(
    name="relativistic",
    title="LNN seed: relativistic particle, HNN on (q, qdot) vs (q, p) vs LNN",
    axes={"model": ("hnn", "lnn"), "coordinates": ("velocity", "momentum")},
    fixed={"system": "relativistic_particle", "random_args": True},
    include=_relativistic_include,
    claim=7,
)

DOUBLE_PENDULUM_ENERGY = Experiment(
    name="double_pendulum_energy",
    title="LNN seed: energy error on the unit double pendulum, % of the max potential energy",
    axes={"model": ("node", "lnn")},
    fixed={"system": "chain_pendulum", "k": 2, "system_params": UNIT_DOUBLE_PENDULUM},
    claim=None,
)

VIN = Experiment(
    name="vin",
    title="VIN seed: pendulum from few and noisy trajectories, long horizon",
    axes={
        "model": ("vin", "resnet", "node_so"),
        "n_train": (8, 32, 128),
        "noise": (0.0,),
    },
    # 60 chunks = 300 points (9 s at dt = 0.03): 3x the paper's horizon, the longest window of
    # the protocol's 10 s trajectories
    fixed={"system": "chain_pendulum", "k": 1, "test_chunks": 60},
    profile_overrides={
        "smoke": {"n_train": (8, 16), "test_chunks": 8},
        "paper": {"noise": (0.0, 0.01)},
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

# Milliseconds per training step at batch 200, width 128, for a system of ``dof`` = 2 (chain-2):
# REFERENCE.md's calibration (NODE/NODE+SO 8 ms; separable HNN 35 ms on chain-2, 60 on spring-2
# whose dof is 6). Others are guesses until measured: the non-separable HNN and the regularised
# NODE cost a Jacobian more, the LNN a Hessian solve, the discrete models one step per dt.
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


def _dof(c: RunConfig) -> int:
    if c.system == "spring_pendulum":
        return 3 * (c.k or 1)
    if c.system == "relativistic_particle":
        return 1
    return c.k or 1


def estimate_seconds(
    profile: str = "quick",
    *,
    ms_per_step: Mapping[str, float] | None = None,
    overhead_s: float = 12.0,
    workers: int = 2,
    experiments=PAPER_EXPERIMENTS,
) -> dict:
    """Wall-time estimate of a profile: sum over the unique runs of

    ``t = steps * ms(model) * (min(batch, n_train) / 200) * g(dof) / 1000 + overhead_s``

    with ``g = 1`` for the free models and ``g = (dof / 2) ** 0.49`` for the structured ones (the
    separable HNN's cost rose from 35 to 60 ms from dof 2 to 6), divided by ``workers``.
    ``overhead_s`` covers compilation, data generation and the test rollouts.
    Returns ``{"runs": n_unique, "per_experiment": {name: n}, "seconds": total / workers}``.
    """
    ms = dict(MS_PER_STEP)
    ms.update(ms_per_step or {})
    seen: dict[str, RunConfig] = {}
    per = {}
    for exp in experiments:
        cfgs = expand(exp, profile)
        per[exp.name] = len(cfgs)
        for c in cfgs:
            seen.setdefault(c.config_hash, c)
    total = 0.0
    for c in seen.values():
        g = 1.0 if _free(c.model) else max(1.0, _dof(c) / 2) ** (math.log(60 / 35) / math.log(3))
        batch = min(c.batch, c.n_train) / 200
        total += c.steps * ms.get(c.model, 20.0) * batch * g / 1000 + overhead_s
    return {"runs": len(seen), "per_experiment": per, "seconds": total / max(1, workers)}
