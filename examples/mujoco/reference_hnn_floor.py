"""The training-MSE floor that the reference code's MuJoCo HNN has by construction, from each
task's training windows alone (no training; docs/studies/mujoco.md).

decon-hnn's `MixtureHNN` (src/models/dynamics_models.py) evaluates H on the *standardised*
state, has M^-1 = I (its learned factor is multiplied by 0) and integrates the *raw* state with
one Euler step of dt per transition. So its position update is

    q1 = q0 + dt * (v0 - mean_v) / std_v

with no trainable parameter, whatever the networks learn: wherever std_v is not 1 (or mean_v
not 0) the first predicted position of every window is off. Its part of the reference's loss
(the squared error of each component over the training std, averaged over the window's
3 states and 2 nq components, t0 included) is a lower bound on that HNN's training MSE.
Printed beside it: the same bound for one Euler step with dq/dt = v (the physical kinematics,
the error of the step alone) and for the reference's CoupledNODE rule at 8 steps with a perfect
acceleration (q1 = q0 + dt * (v0 + v1) / 2, exact for constant acceleration).

    PYTHONPATH=. .venv/bin/python examples/mujoco/reference_hnn_floor.py
"""

import numpy as np

from bench.core import _controlled as C
from bench.core import expand


def floor(q1_hat, q1, scale_q):
    """The q1 share of the window's normalised MSE: 1 of 3 states, nq of 2 nq components."""
    return float(np.mean(((q1_hat - q1) / scale_q) ** 2)) / 3 / 2


print(f"{'task':20s} {'nq':>3s} {'dt':>6s}  floor: reference HNN  Euler dq/dt=v  (v0+v1)/2")
done = set()
for c in expand("mujoco", "paper-core"):
    if c.system in done or c.seed != 0:
        continue
    done.add(c.system)
    built = C.build(c)
    z, scale = built.windows.z_train, built.windows.scale  # (N, 3, 2 nq), (2 nq,)
    nq = z.shape[-1] // 2
    q0, v0 = z[:, 0, :nq], z[:, 0, nq:]
    q1, v1 = z[:, 1, :nq], z[:, 1, nq:]
    states = z.reshape(-1, z.shape[-1])
    mean_v, std_v = states[:, nq:].mean(0), states[:, nq:].std(0)

    reference = floor(q0 + c.dt * (v0 - mean_v) / std_v, q1, scale[:nq])
    euler = floor(q0 + c.dt * v0, q1, scale[:nq])
    average = floor(q0 + c.dt * (v0 + v1) / 2, q1, scale[:nq])
    print(
        f"{c.system:20s} {nq:3d} {c.dt:6.3f}  {reference:20.4g} {euler:14.4g} {average:10.4g}"
        f"   std_v {np.array2string(std_v, precision=2, max_line_width=200)}",
        flush=True,
    )
