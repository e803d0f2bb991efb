"""The separable HNN's first training steps on a rigid-body cell of claim 13, one step at a time.

Replays paper-core's run of ``hnn_so`` on ``system`` with ``seed`` through the trainer's own
compiled block (one step per call), at learning rate ``lr``, and prints after each step the
batch loss, whether the trainer flagged the run dead (non-finite), the extreme eigenvalues of
the learned M^-1(q) over the first state of every training window, and the largest predicted
acceleration with the window it occurs at::

    python examples/rigid_bodies/hnn_first_steps.py rotor 0 0.005 12

(docs/studies/rigid_bodies.md quotes its output.)
"""

import dataclasses
import sys
from pathlib import Path

from bench.core import setup_process

setup_process(1)

import equinox as eqx  # noqa: E402
import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import systems  # noqa: E402
from bench.core import Training, build_run, expand, prepare, train_config  # noqa: E402


def main(system: str, seed: int, lr: float, n_steps: int) -> None:
    cfg = next(
        c
        for c in expand("rigid_bodies", "paper-core")
        if c.system == system and c.model == "hnn_so" and c.seed == seed
    )
    _, data, scene, model = build_run(cfg, Path(systems.cache_root()))
    tc = dataclasses.replace(train_config(cfg), steps_per_call=1, lr=lr)
    arrays = prepare(model, data, tc)
    z_all, args_all = arrays[0], arrays[1]
    dof = scene.dof
    rates = np.abs(np.asarray(z_all[:, :, dof:]))
    print(
        f"{system} seed {seed}: {z_all.shape[0]} training windows; |qdot| median "
        f"{np.median(rates):.3g}, 99th percentile {np.percentile(rates, 99):.3g}, "
        f"max {rates.max():.3g}"
    )
    training = Training([model], [data], [tc])  # the trainer's own program, one step a block
    states, states_args = z_all[:, 0], args_all

    @eqx.filter_jit
    def probe(m):
        minv = jax.vmap(lambda q, a: m.hamiltonian_part.inverse_mass.matrix(q, a))(
            states[:, :dof], states_args
        )
        eig = jnp.linalg.eigvalsh(minv)
        f = jax.vmap(lambda z, a: m.vector_field(0.0, z, a))(states, states_args)
        acc = jnp.abs(f[:, dof:]).max(1)
        return eig.min(), eig.max(), acc.max(), jnp.argmax(acc)

    def show(step, loss=None):
        lo, hi, acc, at = (float(x) for x in probe(training.model(0)))
        dead = bool(training.dead[0])
        head = "init" if loss is None else f"step {step}: loss {loss:.4g}, dead {dead};"
        print(f"{head} eig M^-1 [{lo:.3g}, {hi:.3g}], max |qddot| {acc:.4g} (window {int(at)})")
        return int(at)

    at = show(0)
    for step in range(1, min(n_steps, tc.steps) + 1):
        block, _ = training.advance()
        at = show(step, float(block[0, 0]))
        if training.dead[0]:
            break
    print(f"window {at}'s first state (q, qdot): {np.round(np.asarray(states[at]), 3).tolist()}")


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4]))
