"""The HNN (hnn_force) on HalfCheetahFull-v0 (quick's cell) trained ``steps`` steps on seeds
0-2 at App. C's and the code's learning rates, in three forms: as the suite builds it (a
learned M^-1 = L L^T + 1e-4 I), with a floor of 0.1 under M^-1's spectrum (the jitter raised,
in H and M^-1 alike), and with M^-1 = I (the reference's). A probe: the suite's model is the
first; the other two are set up here only (docs/studies/mujoco.md).

    PYTHONPATH=. .venv/bin/python docs/studies/mujoco_scripts/hnn_variants_probe.py [steps]
"""

import dataclasses
import sys

import equinox as eqx
from _probe import Identity, score

from bench.core import _controlled as C
from bench.core._experiments import expand
from models import _hamiltonian


def builder(form):
    def build(c):
        # the jitter is read when the model is built and when H is traced: set for both
        _hamiltonian.INVERSE_MASS_JITTER = 0.1 if form == "floor 0.1" else 1e-4
        b = C.build(c)
        if form == "M = I":
            inv = b.model.hamiltonian_part.inverse_mass
            m = eqx.tree_at(
                lambda x: x.hamiltonian_part.inverse_mass, b.model, Identity(inv.dof, inv.jitter)
            )
            b = dataclasses.replace(b, model=m)
        return b

    return build


steps = int(sys.argv[1]) if len(sys.argv) > 1 else 2000
cells = [c for c in expand("mujoco", "quick") if c.model == "hnn_force" and c.seed in (0, 1, 2)]
for form in ("learned", "floor 0.1", "M = I"):
    for c in cells:
        for lr in (2e-4, 5e-3):
            run = dataclasses.replace(c, lr=lr, steps=steps)
            score(run, f"{form:9s} seed {c.seed} lr {lr:g} steps {steps}", builder(form))
