"""What the paper experiments share: models, systems, spring initial states, shared overrides."""

from __future__ import annotations

from collections.abc import Mapping

import models

from ...core import RunConfig

# The Deconstructing paper's claims (1-8); each seed's study adds its own claims' titles.
CLAIM_TITLES = {
    1: "HNNs conserve energy no better than NODEs at equal rollout error; violation grows in time",
    2: "A symplectic regulariser gives no real gain at any weight",
    3: "Second-order structure explains most of the HNN's advantage",
    4: "HNN beats NODE+SO only in complex (angular) coordinates",
    5: "Damped: plain HNN fits poorly; NODE+SO matches the damped HNN, cheaper",
    6: "L1 vs L2 loss does not change the ordering of the models",
    7: "Relativistic particle: HNN on (q, qdot) fails; HNN on (q, p) and LNN succeed",
    8: "VIN: bounded energy over long horizons, learns from less/noisier data than a ResNet",
}
PAPER_MODELS = ("node", "node_so", "hnn", "hnn_so")
SYSTEMS = ("chain_pendulum", "spring_pendulum")
# Fig. 3's grid: log-spaced from 1e-6 to 1e3 (the paper's code), 0 = the unregularised model.
SYMREG_WEIGHTS = (0.0, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0, 10.0, 100.0, 1000.0)
# paper-core: five points spanning the paper's grid at the paper budget; quick: three of them,
# 0, the grid's log-midpoint 1e-3 and its largest 1e3 (the other two would cost 6 of the 62 CPU
# minutes of quick's sweep on this machine, which quick's five seeds need)
SYMREG_WEIGHTS_CORE = (0.0, 1e-6, 1e-3, 1.0, 1000.0)
SYMREG_WEIGHTS_QUICK = (0.0, 1e-3, 1000.0)
UNIT_DOUBLE_PENDULUM = (("lengths", (1.0, 1.0)), ("masses", (1.0, 1.0)))
SPRING_PAPER = (("initial", "paper"),)
# The physical equilibrium is the spring pendulum's default initial state: its cells carry no
# system params, so they share config hashes with the trade-off experiment's spring cells and
# with results older than the "initial" option.
SPRING_EQUILIBRIUM = ()
# Claim 7's test set must discriminate: on the default data (start speeds up to
# 0.9 c, g in [0.5, 2], 3 s windows anywhere in 10 s trajectories) the particle runs near light
# speed, where the acceleration is tiny, and constant velocity scores like the models (quick,
# seed 0: constant velocity 0.0072 vs HNN on (q, p) 0.0016 in (q, qdot), 4.4x). Slow particles
# in a weak field stay in the regime where the relativistic dynamics bend the trajectory:
# measured at quick (float32, scored in (q, qdot)), constant velocity 0.022 / 0.026 vs HNN on
# (q, p) 0.00064 / 0.00058 for seeds 0 / 1 (35x, 44x): at least the 10x that a discriminating
# test needs. Speeds stay far below c = 1, which is the honest price: the test no longer probes
# the ultra-relativistic regime, where no model can be told from a trivial one.
RELATIVISTIC_TEST_PARAMS = (("g_max", 0.3), ("g_min", 0.05), ("v0_max", 0.3))

# Overrides of the profile defaults that every shared cell carries. Empty: the profile
# defaults (quick: 200 chunks, width 128, 1000 steps, batch 100) are used as they are. Any entry
# here is applied to every experiment that shares cells, so the hashes stay equal.
SHARED_OVERRIDES: dict[str, dict[str, object]] = {
    "smoke": {},
    "quick": {},
    "paper": {},
    "paper-core": {},  # the selection (bench.core._experiments.SELECTIONS): the paper's cells
}


def shared_overrides(extra: Mapping[str, Mapping[str, object]] | None = None) -> dict:
    out = {p: dict(v) for p, v in SHARED_OVERRIDES.items()}
    for p, v in (extra or {}).items():
        out.setdefault(p, {}).update(v)
    return out


def is_free(model: str) -> bool:
    """Models without a dissipation switch (their cells leave ``dissipation`` unset)."""
    return not models.spec(model).takes_dissipation


def is_trivial(model: str) -> bool:
    return models.spec(model).trivial


def initial_ok(c: RunConfig, allowed=(SPRING_PAPER,)) -> bool:
    """Chain cells carry no system params; spring cells one of the ``allowed`` initial states
    (``SPRING_EQUILIBRIUM`` is ``()``, the default)."""
    if c.system == "spring_pendulum":
        return c.system_params in allowed
    return c.system_params == ()


def is_paper_cell(c: RunConfig) -> bool:
    # constant velocity only: at_rest is for damped scenes
    return initial_ok(c) and c.model != "at_rest"
