"""NODE and NODE+SO on HalfCheetahFull-v0 (quick's cells, seed 0) at App. C's learning rate
(2e-4) and at the one the reference's code hard-codes (5e-3), for ``steps`` steps on the
cosine schedule: test and train MSE of each (docs/studies/mujoco.md).

    PYTHONPATH=. .venv/bin/python examples/mujoco/lr_probe.py [steps]
"""

import dataclasses
import sys

from _probe import score

from bench.core import expand

steps = int(sys.argv[1]) if len(sys.argv) > 1 else 5000
cells = [
    c
    for c in expand("mujoco", "quick")
    if c.seed == 0 and c.model in ("node", "node_so") and c.lr == 2e-4
]
for c in cells:
    for lr in (2e-4, 5e-3):
        score(dataclasses.replace(c, lr=lr, steps=steps), f"{c.model:8s} lr {lr:g} steps {steps}")
