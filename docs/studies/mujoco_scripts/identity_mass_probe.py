"""A probe, not a model of the suite: hnn_force with its learned M^-1(q) replaced by I (the
reference's MixtureHNN), 8 Euler steps per transition, on HalfCheetahFull-v0 (quick's cell,
seed 0), at App. C's and the code's learning rates; then the same with its force's output read
as a rate of the velocity (NODE+SO's output map). Does its training stay finite where the
learned-M HNN's blows up? (docs/studies/mujoco.md, "What the reference's HNN can fit").

    PYTHONPATH=. .venv/bin/python docs/studies/mujoco_scripts/identity_mass_probe.py [steps]
"""

import dataclasses
import sys

import equinox as eqx
from _probe import Identity, score

from bench.core import _controlled as C
from bench.core._experiments import expand
from models import _forced

orig_build = C.build


def build(c):
    b = orig_build(c)
    m = b.model
    inv = m.hamiltonian_part.inverse_mass
    m = eqx.tree_at(lambda x: x.hamiltonian_part.inverse_mass, m, Identity(inv.dof, inv.jitter))
    return dataclasses.replace(b, model=m)


steps = int(sys.argv[1]) if len(sys.argv) > 1 else 2000
c = next(c for c in expand("mujoco", "quick") if c.seed == 0 and c.model == "hnn_force")
for lr in (2e-4, 5e-3):
    score(dataclasses.replace(c, lr=lr, steps=steps), f"M=I lr {lr:g} steps {steps}", build)

# and with the force's output as a rate of the velocity, as NODE+SO's acceleration


def force_term(self, q, p, args):
    st = self.scene.standardisation
    y = self.force(self.features(q, p, args))
    return y if st is None else st.rate(y, self.dtype, slice(self.scene.dof, None))


_forced.ForcedHNN.force_term = force_term
for lr in (2e-4, 5e-3):
    run = dataclasses.replace(c, lr=lr, steps=steps)
    score(run, f"M=I, F as a rate, lr {lr:g} steps {steps}", build)
