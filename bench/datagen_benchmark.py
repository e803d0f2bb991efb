"""Ground-truth cost and accuracy: ``python -m bench.datagen_benchmark [--n 1000] [--repeats 2]``.

1. Time to simulate the paper's training set for the 2-link chain (n trajectories x 334 points,
   float64, dt = 0.03): the first call includes the compile, later calls are timed with
   ``block_until_ready`` and the median is reported.
2. The 10 s energy drift of every conservative system (chain k = 1..4, spring k = 1..4,
   relativistic particle): max over time and trajectories of |E(t) - E(0)| / |E(0)|, and the
   absolute max |E(t) - E(0)|, over a few random initial states.
"""

from __future__ import annotations

import argparse
import statistics
import time

import jax
import numpy as np

import systems


def _time_datagen(n: int, repeats: int) -> None:
    system = systems.make("chain_pendulum", k=2)
    ts = np.arange(334) * 0.03
    z0 = system.sample_initial(jax.random.PRNGKey(0), n)
    start = time.perf_counter()
    system.simulate_batch(z0, ts).block_until_ready()
    first = time.perf_counter() - start
    times = []
    for i in range(repeats):
        z0 = system.sample_initial(jax.random.PRNGKey(i + 1), n)
        start = time.perf_counter()
        system.simulate_batch(z0, ts).block_until_ready()
        times.append(time.perf_counter() - start)
    median = statistics.median(times) if times else float("nan")
    print(f"chain_pendulum k=2: {n} trajectories x {len(ts)} points float64")
    print(f"  first call (incl. compile): {first:.2f} s; median of {repeats} later: {median:.2f} s")


def _energy_drift(n: int) -> None:
    ts = np.arange(334) * 0.03
    cases = [("chain_pendulum", {"k": k}) for k in range(1, 5)]
    cases += [("spring_pendulum", {"k": k}) for k in range(1, 5)]
    cases += [("relativistic_particle", {})]
    print(f"10 s energy drift, {n} random initial states each (rtol = atol = 1e-11, Dopri8):")
    print(f"  {'system':<28} {'max rel |dE|/|E0|':>18} {'max abs |dE|':>14} {'seconds':>8}")
    for name, params in cases:
        system = systems.make(name, **params)
        key_z, key_a = jax.random.split(jax.random.PRNGKey(123))
        z0 = system.sample_initial(key_z, n)
        args = system.sample_args(key_a, n) if system.n_args else None
        start = time.perf_counter()
        zs = np.asarray(system.simulate_batch(z0, ts, args))
        seconds = time.perf_counter() - start
        if args is None:
            args = np.broadcast_to(np.asarray(system.default_args()), (n, system.n_args))
        energy = np.asarray(_energies(system, zs, args))
        dabs = np.abs(energy - energy[:, :1])
        rel = np.max(dabs / np.abs(energy[:, :1]))
        label = f"{name}" + (f" k={params['k']}" if "k" in params else "")
        print(f"  {label:<28} {rel:>18.2e} {np.max(dabs):>14.2e} {seconds:>8.1f}")


def _energies(system, zs, args):
    """E along every trajectory, args (N, P) per trajectory."""
    per_traj = jax.vmap(system.energy, in_axes=(0, None))
    return jax.vmap(per_traj)(zs, args)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1000, help="trajectories for the timing")
    parser.add_argument("--repeats", type=int, default=2, help="timed calls after the first")
    parser.add_argument("--drift-n", type=int, default=16, help="trajectories per system")
    opts = parser.parse_args(argv)
    systems.enable_x64()
    _time_datagen(opts.n, opts.repeats)
    _energy_drift(opts.drift_n)


if __name__ == "__main__":
    main()
