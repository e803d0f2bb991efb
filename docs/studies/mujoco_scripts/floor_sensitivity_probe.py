"""Claim 16's HNN at quick's cell (HalfCheetahFull-v0, App. C's lr, 400 steps) with floors
0.01, 0.1 (the declared one) and 1 under its M^-1's spectrum, seeds 0-2, beside the NODE: how
much parts (b) and (c) at quick depend on the floor chosen (docs/studies/mujoco.md).

    PYTHONPATH=. .venv/bin/python docs/studies/mujoco_scripts/floor_sensitivity_probe.py [steps]
"""

import dataclasses
import sys

from _probe import score

from bench.core._experiments import expand

steps = int(sys.argv[1]) if len(sys.argv) > 1 else 400
quick = [c for c in expand("mujoco", "quick") if c.seed in (0, 1, 2) and c.lr == 2e-4]
for c in quick:
    if c.model == "node":
        score(dataclasses.replace(c, steps=steps), f"NODE          seed {c.seed} steps {steps}")
for floor in (0.01, 0.1, 1.0):
    for c in quick:
        if c.model != "hnn_force":
            continue
        run = dataclasses.replace(c, steps=steps, model_options=(("inverse_mass_floor", floor),))
        score(run, f"HNN floor {floor:<4g} seed {c.seed} steps {steps}")
