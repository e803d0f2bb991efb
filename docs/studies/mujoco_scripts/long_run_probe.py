"""Claim 16's declared HNN (floor 0.1 under M^-1) and the NODE on one task, quick's cell moved
to the task, App. C's lr, seed 0, trained ``steps`` steps (one cosine schedule over them):
whether the HNN stays stable over a longer training than quick's before paper-core spends
its 51,200 steps (docs/studies/mujoco.md). Prints the train and test MSE and ``loss_rise``.

    PYTHONPATH=. .venv/bin/python docs/studies/mujoco_scripts/long_run_probe.py [steps] [task]
"""

import sys
import time

from _probe import on_task

from bench.core import _controlled as C
from bench.core._experiments import expand
from bench.studies.paper.mujoco import QUICK_TASK

steps = int(sys.argv[1]) if len(sys.argv) > 1 else 10_000
task = sys.argv[2] if len(sys.argv) > 2 else QUICK_TASK
for cell in expand("mujoco", "quick"):
    if cell.seed != 0 or cell.lr != 2e-4 or cell.model not in ("node", "hnn_force"):
        continue
    run = on_task(cell, task, steps=steps)
    t = time.time()
    built = C.build(run)
    model, meta = C.train(run, built, None, False)
    r = C.evaluate(run, built, model, meta, None)[0]
    print(
        f"{task} {cell.model} {dict(run.model_options)} steps {steps}: train_mse "
        f"{r['train_mse']:.4g} test_mse {r['test_mse']:.4g} loss_rise {meta['loss_rise']:.3g} "
        f"final_loss {meta['final_loss']:.4g} status {meta['status']} ({time.time() - t:.0f} s)",
        flush=True,
    )
