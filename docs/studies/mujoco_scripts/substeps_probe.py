"""The HNN (hnn_force) on HalfCheetahFull-v0 (quick's cell, seed 0) with 8 Euler steps per
transition (App. C, ours) and with one (the reference code's MixtureHNN), at App. C's and the
code's learning rates, for ``steps`` steps: test and train MSE of each, beside the NODE at 8
(docs/studies/mujoco.md, "What the reference's HNN can fit").

    PYTHONPATH=. .venv/bin/python docs/studies/mujoco_scripts/substeps_probe.py [steps]
"""

import dataclasses
import sys

from _probe import score

from bench.core._experiments import expand

steps = int(sys.argv[1]) if len(sys.argv) > 1 else 400
cells = [
    c
    for c in expand("mujoco", "quick")
    if c.seed == 0 and c.model in ("hnn_force", "node") and c.lr == 2e-4
]
for c in cells:
    for lr in (2e-4, 5e-3):
        for substeps in (8, 1) if c.model == "hnn_force" else (8,):
            run = dataclasses.replace(
                c, lr=lr, steps=steps, train_substeps=substeps, eval_substeps=substeps
            )
            score(run, f"{c.model:9s} lr {lr:g} substeps {substeps} steps {steps}")
