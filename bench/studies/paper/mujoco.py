"""The paper's MuJoCo experiment (Sec. 5, Fig. 7, App. C): claim 16's runs. NODE, NODE+SO and
the HNN with a learned force (``hnn_force``) fitted to the transitions of Fig. 7's three tasks
under their recorded controls, beside the constant-velocity predictor.

The experiment only: no verdict rule, figure or report section yet, so it is registered as an
experiment (``python -m bench sweep mujoco``), not as a study. Its runs read each task's file
(``systems.mujoco_data``) and exist only where the file is there; the smoke profile runs on the
random-control stand-in instead (a pipeline check). Facts and differences:
docs/studies/mujoco.md.
"""

from __future__ import annotations

import systems
from systems import mujoco_data

from ...core._config import RunConfig
from ...core._experiments import Experiment, register
from ._rules import CLAIM_TITLES

CLAIM = 16
TASKS = tuple(t.name for t in systems.MUJOCO_TASKS.values() if t.in_fig7)
DTS = tuple(sorted({systems.MUJOCO_TASKS[t].dt for t in TASKS}))
# (model, integrator): the reference's NODE and MixtureHNN with Euler, its CoupledNODE with the
# averaged-velocity Euler rule (euler_so), 8 steps per transition; and the trivial predictor
CELLS = (
    ("node", "euler"),
    ("node_so", "euler_so"),
    ("hnn_force", "euler"),
    ("constant_velocity", "euler"),
)
FILE, STAND_IN = (("data", "file"),), (("data", "stand-in"),)

# App. C and the reference's mujoco.py: 2 x 128 tanh MLPs, Adam (here AdamW) with weight decay
# 1e-4, batch 200, cosine from 2e-4 to 1e-6, 3-step windows, 8 integrator steps per transition
_PAPER = {
    "observation": "controlled",
    "width": 128,
    "depth": 2,
    "activation": "tanh",
    "batch": 200,
    "lr": 2e-4,
    "weight_decay": 1e-4,
    "optimizer": "adamw",
    "lr_schedule": "cosine",
    "loss": "l2",
    "chunk": 3,
    "train_substeps": 8,
    "eval_substeps": 8,
    "eval_checkpoints": 0,
    "dtype": "float32",
}
# the paper's sizes: 40K windows, 256 epochs (200 steps each), 200 test trajectories of 201
# states from the first 850K transitions (the reference's last saved buffer)
_SIZES = {
    "n_generated": 850_000,
    "n_train": 40_000,
    "n_test": 200,
    "test_chunks": 67,
    "steps": 256 * 200,
}
_QUICK = {**_SIZES, "steps": 4 * 200}  # 4 of the 256 epochs
_SMOKE = {
    "n_generated": 300,
    "n_train": 16,
    "n_test": 2,
    "test_chunks": 4,
    "width": 16,
    "batch": 8,
    "steps": 2,
    "system": (TASKS[0],),
    "system_params": (STAND_IN,),
    "seeds": (0,),
}


def _include(c: RunConfig) -> bool:
    """The cells of :data:`CELLS`, at the task's dt, the file's runs only where it is there."""
    task = systems.MUJOCO_TASKS.get(c.system)
    return (
        task is not None
        and (c.model, c.train_integrator) in CELLS
        and c.eval_integrator == c.train_integrator
        and abs(c.dt - task.dt) < 1e-12
        and (c.system_params != FILE or mujoco_data.data_path(c.system).exists())
    )


EXPERIMENT = register(
    Experiment(
        name="mujoco",
        title="MuJoCo transitions under controls (Fig. 7): NODE, NODE+SO, HNN with a force",
        axes={
            "model": tuple(m for m, _ in CELLS),
            "system": TASKS,
            "dt": DTS,
            "train_integrator": ("euler", "euler_so"),
            "eval_integrator": ("euler", "euler_so"),
            "system_params": (FILE,),
        },
        fixed=_PAPER,
        profile_overrides={
            "smoke": _SMOKE,
            "quick": _QUICK,
            "paper": _SIZES,
            "paper-core": {"seeds": (0, 1, 2, 3, 4)},
        },
        include=_include,
        claim=CLAIM,
    ),
    replace=True,
)
EXPERIMENTS = (EXPERIMENT,)
CLAIM_TITLES[CLAIM] = (
    "MuJoCo: NODE+SO beats NODE and HNN; the HNN underperforms NODE, fitting the training data "
    "poorly"
)
