"""The LNN seed's double pendulum: its two experiments (the seed's script and its notebook) and
the costs measured for them."""

from __future__ import annotations

import math

from ....core import (
    Experiment,
    RunConfig,
)
from ..._claims import UNIT_DOUBLE_PENDULUM

# Costs measured on this 2-core machine, the paper-core campaign paused (other
# sessions' processes running): ms per training step at the paper's size (width 500, 3 hidden
# layers, 32 states a step), float32; ground-truth data per training trajectory (Dopri8 at
# 1e-11 over 10 s; 150,000 per seed at paper, one dataset per seed shared by the models); the
# LNN's 40 test rollouts at paper; quick's 15 runs' summed wall_seconds (1 worker, campaign
# running). paper-core per seed: 22 min of data + 7.4 (LNN) + 1.4 (NODE+SO) min of training
# + about 1 min of evaluation, i.e. about 32 CPU minutes, 2.7 CPU hours for the five seeds.
MEASURED = {
    "ms_per_step_lnn_paper": 14.8,
    "ms_per_step_node_so_paper": 2.7,
    "ms_per_trajectory_data": 8.7,
    "s_lnn_test_rollouts_paper": 17.6,
    "s_quick_sweep_1_worker": 294.0,
}
PURE_LNN = (("kinetic_prior", 0.0), ("solve", "pinv"))
LNN = {"model": "lnn"}
BASELINE = {"model": "node_so"}
# The seed's numbers (its text): % of max potential energy (its scale: 3 g), final losses
SEED_NUMBERS = {
    "energy_pct": {"node_so": 8.0, "lnn": 0.4},
    "loss": {"node_so": 7.4e-2, "lnn": 7.3e-2},
}
SEED_SCALE = 2.0  # our denominator (6 g) over the seed's (3 g)

_FIXED = {
    "system": "chain_pendulum",
    "k": 2,
    "system_params": UNIT_DOUBLE_PENDULUM,
    "train_target": "derivative",
    "chunk": 4,  # four states 0.1 s apart per trajectory (data cost: module docstring)
    "dt": 0.1,
    "duration": 10.0,
    "test_chunks": 25,  # x chunk 4 = 100 points of 0.1 s (99 steps)
    "n_test": 40,
    "width": 500,
    "depth": 3,
    "activation": "softplus",
    "batch": 8,  # chunks: 32 states
    "lr": 1e-3,
    "loss": "l2",
    "eval_integrator": "rk4_38",
    "eval_substeps": 10,
    "eval_checkpoints": 0,
    "dtype": "float32",
    "n_generated": 150_000,
    "n_train": 150_000,  # x 4 states = 600,000
    "steps": 30_000,
}
_QUICK = {"n_generated": 1_000, "n_train": 1_000, "width": 128, "steps": 15_000}
_SMOKE = {
    "n_generated": 16,
    "n_train": 16,
    "n_test": 2,
    "width": 16,
    "steps": 20,
    "batch": 2,
    "seeds": (0,),
}


def _include(c: RunConfig) -> bool:
    return c.model_options == (PURE_LNN if c.model == "lnn" else ())


LNN_SEED = Experiment(
    name="lnn_seed_double_pendulum",
    paper="lnn",
    title="LNN seed: unit double pendulum from instantaneous accelerations, energy % of max PE",
    axes={"model": ("lnn", "node_so", "constant_velocity"), "model_options": ((), PURE_LNN)},
    fixed=_FIXED,
    profile_overrides={"smoke": _SMOKE, "quick": _QUICK, "paper-core": {}},
    include=_include,
    claim=9,
)
# The seed's notebook as it ran (notebooks/DoublePendulum.ipynb and DoublePendulum-Baseline
# .ipynb of MilesCranmer/lagrangian_nns; docs/studies/lnn_seed.md): fresh uniform states every
# batch, L1 loss on dz/dt, batch 512, Adam with the notebook's OneCycle schedule (peak 1e-5 for
# the LNN, 4e-5 for the baseline), 3 hidden layers of 600 (softplus LNN with appendix B's
# initialisation; ReLU baseline), 300 epochs of 2000 steps. Its L2 term (1e-6 ||theta||^2 /
# 512 on a loss summed over the batch) is 1e-12 on our mean loss: left out. The paper profile
# runs its steps; a CPU affords 1/20 of them at paper-core and 1/300 at quick (ms per step:
# campaign/costs.json's step_cost), so the peak learning rate is raised by the same factor (lr x
# steps, the distance Adam can travel, as the notebook's).
NOTEBOOK_BOX = (0.0, 2.0 * math.pi, -10.0, 10.0)  # q in [0, 2 pi)^2, qdot in [-10, 10]^2
NOTEBOOK_STEPS = 300 * 2000
NOTEBOOK_LR = {"lnn": 1e-5, "node_so": 4e-5}
NOTEBOOK_ACTIVATION = {"lnn": "softplus", "node_so": "relu"}
_NOTEBOOK_PROFILE_STEPS = {
    "smoke": 20,
    "quick": 2_000,
    "paper-core": 30_000,
    "paper": NOTEBOOK_STEPS,
}


def notebook_lr(model: str, steps: int) -> float:
    """The peak learning rate of ``model`` at ``steps``: the notebook's, times its steps over
    ``steps`` (rounded to 3 significant digits, so that it is a stable axis value)."""
    return float(f"{NOTEBOOK_LR[model] * NOTEBOOK_STEPS / steps:.3g}")


_NOTEBOOK = {
    **_FIXED,
    "train_box": NOTEBOOK_BOX,
    "n_generated": 1,  # no training trajectories: the test set alone (same as LNN_SEED's)
    "n_train": 1,
    "width": 600,
    "depth": 3,
    "batch": 512,
    "loss": "l1",
    "optimizer": "adam_l2",
    "weight_decay": 0.0,
    "lr_schedule": "onecycle",
    "steps": _NOTEBOOK_PROFILE_STEPS["paper"],
}
_NOTEBOOK_LRS = tuple(
    sorted({notebook_lr(m, n) for m in NOTEBOOK_LR for n in _NOTEBOOK_PROFILE_STEPS.values()})
)


def _include_notebook(c: RunConfig) -> bool:
    if c.model == "constant_velocity":
        return c.lr == _NOTEBOOK_LRS[0] and c.activation == "softplus" and not c.model_options
    return (
        _include(c)
        and c.lr == notebook_lr(c.model, c.steps)
        and c.activation == NOTEBOOK_ACTIVATION[c.model]
    )


LNN_SEED_NOTEBOOK = Experiment(
    name="lnn_seed_notebook",
    paper="lnn",
    title="LNN seed: unit double pendulum as the seed's notebook trained it (fresh uniform states)",
    axes={
        "model": ("lnn", "node_so", "constant_velocity"),
        "model_options": ((), PURE_LNN),
        "lr": _NOTEBOOK_LRS,
        "activation": ("softplus", "relu"),
    },
    fixed=_NOTEBOOK,
    profile_overrides={
        "smoke": {**_SMOKE, "n_generated": 1, "n_train": 1, "batch": 8},
        "quick": {"steps": _NOTEBOOK_PROFILE_STEPS["quick"], "width": 128, "batch": 128},
        "paper-core": {"steps": _NOTEBOOK_PROFILE_STEPS["paper-core"]},
    },
    include=_include_notebook,
    claim=9,
)
EXPERIMENTS = (LNN_SEED, LNN_SEED_NOTEBOOK)
