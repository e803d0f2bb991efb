"""The probes' one step: build a MuJoCo run, train it, score it, and print one line."""

import tempfile
import time

import equinox as eqx
import jax.numpy as jnp

from bench.core import _controlled as C


def score(run, label: str, build=C.build) -> dict:
    """Train and evaluate ``run`` (its data and model from ``build``), print ``label`` with its
    train, test and rollout errors and the seconds taken, and return the row's columns."""
    t = time.time()
    built = build(run)
    with tempfile.TemporaryDirectory() as cache:  # a probe keeps no resume state
        model, meta = C.train(run, built, cache, False)
        r = C.evaluate(run, built, model, meta, cache)[0]
    print(
        f"{label}: train_mse {r['train_mse']:.4g} test_mse {r['test_mse']:.4g} "
        f"rollout_error {r['rollout_error']:.4g} ({time.time() - t:.0f} s)",
        flush=True,
    )
    return r


def on_task(cell, task: str, **changes):
    """Quick's ``cell`` moved to ``task``: its dt and test length, and ``changes``."""
    import dataclasses

    import systems
    from bench.studies.decon.mujoco import task_test_chunks

    dt, chunks = systems.MUJOCO_TASKS[task].dt, task_test_chunks(task)
    return dataclasses.replace(cell, system=task, dt=dt, test_chunks=chunks, **changes)


class Identity(eqx.Module):
    """M^-1 = I in place of a learned one, with the kinetic term's jitter share taken out of
    the factor (so that H = 1/2 |p|^2 + V)."""

    dof: int = eqx.field(static=True)
    jitter: float = eqx.field(static=True)

    def factor(self, q, args):
        return jnp.sqrt(1.0 - self.jitter) * jnp.eye(self.dof, dtype=q.dtype)

    def matrix(self, q, args):
        return jnp.eye(self.dof, dtype=q.dtype)
