"""Claim 16's models on HalfCheetahFull-v0 (quick's cells, seed 0) trained with the inputs and
outputs raw and standardised: the test and train MSE of each (docs/studies/mujoco.md).

    PYTHONPATH=. .venv/bin/python examples/mujoco/standardise_probe.py [steps]
"""

import dataclasses
import sys

from _probe import score

from bench.core import _controlled as C
from bench.core import expand

steps = int(sys.argv[1]) if len(sys.argv) > 1 else None
for c in (c for c in expand("mujoco", "quick") if c.seed == 0 and c.lr == 2e-4):
    for standardise in (False, True):
        if c.model == C.TRIVIAL and standardise:
            continue
        run = dataclasses.replace(c, standardise=standardise, steps=steps or c.steps)
        score(run, f"{c.model:18s} standardise={standardise!s:5s}")
