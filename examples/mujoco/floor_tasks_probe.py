"""The HNN (hnn_force) with and without a floor of 0.1 under M^-1's spectrum, beside the NODE,
on each of Fig. 7's tasks: quick's cell moved to the task (its dt and test length), seed 0,
App. C's learning rate, ``steps`` steps. Built through the registry's option, as the experiment
declares it (docs/studies/mujoco.md).

    PYTHONPATH=. .venv/bin/python examples/mujoco/floor_tasks_probe.py [steps] [seed]
"""

import sys

from _probe import on_task, score

from bench.core import expand
from bench.studies.decon.mujoco import TASKS

steps = int(sys.argv[1]) if len(sys.argv) > 1 else 2000
seed = int(sys.argv[2]) if len(sys.argv) > 2 else 0
quick = {c.model: c for c in expand("mujoco", "quick") if c.seed == seed and c.lr == 2e-4}
forms = (
    ("NODE", quick["node"], ()),
    ("HNN", quick["hnn_force"], ()),
    ("HNN floor 0.1", quick["hnn_force"], (("inverse_mass_floor", 0.1),)),
)
for task in TASKS:
    for label, cell, options in forms:
        run = on_task(cell, task, steps=steps, model_options=options)
        score(run, f"{task} {label:13s} seed {seed} steps {steps}")
