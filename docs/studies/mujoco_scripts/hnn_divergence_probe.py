"""When the HNN's training blows up on HalfCheetahFull-v0 (quick's cell, seed 0, the code's lr
5e-3): trained 800, 1200 and 1600 steps (each its own cosine schedule), its training MSE, last
batch loss and the eigenvalues of its learned M^-1(q) over 2,000 training states
(docs/studies/mujoco.md, "What the reference's HNN can fit").

    PYTHONPATH=. .venv/bin/python docs/studies/mujoco_scripts/hnn_divergence_probe.py
"""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from bench.core import _controlled as C
from bench.core._experiments import expand

c = next(c for c in expand("mujoco", "quick") if c.seed == 0 and c.model == "hnn_force")
for steps in (800, 1200, 1600):
    run = dataclasses.replace(c, lr=5e-3, steps=steps)
    built = C.build(run)
    model, meta = C.train(run, built, None, False)
    r = C.evaluate(run, built, model, meta, None)[0]
    q = jnp.asarray(built.windows.z_train[:2000, 0, : built.model.scene.dof])
    u = jnp.zeros((built.windows.u_train.shape[-1],), q.dtype)  # M^-1 never reads controls
    matrix = jax.vmap(model.hamiltonian_part.inverse_mass.matrix, in_axes=(0, None))
    ev = np.asarray(jnp.linalg.eigvalsh(matrix(q, u)))
    print(
        f"steps {steps}: train_mse {r['train_mse']:.4g} last loss {meta.get('final_loss'):.4g} "
        f"M^-1 eigenvalues: min {ev.min():.3g}, median of each state's min "
        f"{np.median(ev.min(1)):.3g}, max {ev.max():.3g}",
        flush=True,
    )
