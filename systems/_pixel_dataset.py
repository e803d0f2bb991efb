"""Pixel observations of a pendulum (the HNN seed's task 5): float64 ground-truth trajectories
rendered to grey frames, each observation two consecutive frames stacked.

The seed's data (greydanus/hamiltonian-nn, experiment-pixels/data.py): OpenAI Gym's
Pendulum-v0, "no torque", starts kept only when |angle| < pi/6 (its angular velocity
U(-1, 1)), frames of 28 x 28, each input a frame with its successor. Ours: the suite's
``pendulum`` (or any renderable system, :mod:`systems._render`), starts with q0 ~ U(-a, a),
qdot0 ~ U(-v, v), trajectories simulated in float64 and rendered by :func:`render`.
Training and test starts come from disjoint keys.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from ._precision import require_x64
from ._render import read_state, render


@dataclass(frozen=True)
class PixelDatasetConfig:
    """``n_train`` training and ``n_test`` test trajectories of ``train_points`` and
    ``test_points`` frames ``dt`` apart, ``size`` x ``size`` pixels; starts q0 ~ U(-max_angle,
    max_angle), qdot0 ~ U(-max_speed, max_speed) (rad, rad/s). With ``min_angle`` > 0, |q0| ~
    U(min_angle, max_angle) with a random sign instead (the VIN seed's starts, far from rest)."""

    system: str = "pendulum"
    system_params: tuple = ()
    size: int = 28
    n_train: int = 160
    n_test: int = 40
    train_points: int = 100
    test_points: int = 100
    dt: float = 0.08
    max_angle: float = math.pi / 6
    max_speed: float = 1.0
    seed: int = 0
    min_angle: float = 0.0

    def __post_init__(self):
        for name in ("size", "n_train", "n_test", "train_points", "test_points", "seed"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int):
                raise ValueError(f"{name} must be an integer; got {v!r}")
        if self.n_train < 1 or self.n_test < 1:
            raise ValueError("n_train and n_test must be integers >= 1")
        if self.train_points < 3 or self.test_points < 3:
            raise ValueError("train_points and test_points must be integers >= 3 (two frames)")
        for name in ("dt", "max_angle"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be a finite number > 0; got {v!r}")
        if not (math.isfinite(self.max_speed) and self.max_speed >= 0):
            raise ValueError(f"max_speed must be a finite number >= 0; got {self.max_speed!r}")
        if not (math.isfinite(self.min_angle) and 0 <= self.min_angle < self.max_angle):
            raise ValueError(
                f"min_angle must be a finite number in [0, max_angle); got {self.min_angle!r}"
            )


@dataclass(frozen=True)
class PixelDataset:
    """Frames (n, T, S, S) float32 and the states (n, T, 2 dof) float64 they draw; ``ts`` the
    times of the test frames. ``observations(frames)`` stacks consecutive pairs."""

    config: PixelDatasetConfig
    frames_train: np.ndarray
    z_train: np.ndarray
    frames_test: np.ndarray
    z_test: np.ndarray
    ts_test: np.ndarray

    @staticmethod
    def observations(frames: np.ndarray) -> np.ndarray:
        """(..., T, S, S) -> (..., T - 1, 2, S, S): frame t with its successor."""
        return np.stack([frames[..., :-1, :, :], frames[..., 1:, :, :]], axis=-3)

    def read_states(self, observations) -> np.ndarray:
        """(q, qdot) read off observations (..., 2, S, S) (:func:`systems._render.read_state`)."""
        return np.asarray(read_state(observations, self.config.dt))


def _starts(key, n: int, dof: int, max_angle: float, max_speed: float, min_angle: float = 0.0):
    kq, kv = jax.random.split(key)
    if min_angle > 0:  # |q0| in [min_angle, max_angle], either sign
        ka, ks = jax.random.split(kq)
        q = jax.random.uniform(ka, (n, dof), jnp.float64, min_angle, max_angle)
        q = q * jnp.where(jax.random.bernoulli(ks, 0.5, (n, dof)), 1.0, -1.0)
    else:
        q = jax.random.uniform(kq, (n, dof), jnp.float64, -max_angle, max_angle)
    v = jax.random.uniform(kv, (n, dof), jnp.float64, -max_speed, max_speed)
    return jnp.concatenate([q, v], axis=-1)


def make_pixel_dataset(config: PixelDatasetConfig) -> PixelDataset:
    """Simulate (float64, the system's ground truth) and render the dataset of ``config``."""
    from ._registry import make

    require_x64("make_pixel_dataset")
    system = make(config.system, **dict(config.system_params))
    k_train, k_test = jax.random.split(jax.random.PRNGKey(config.seed))
    out = {}
    for split, key, n, points in (
        ("train", k_train, config.n_train, config.train_points),
        ("test", k_test, config.n_test, config.test_points),
    ):
        z0 = _starts(key, n, system.dof, config.max_angle, config.max_speed, config.min_angle)
        ts = jnp.arange(points, dtype=jnp.float64) * config.dt
        zs = system.simulate_batch(z0, ts)
        out[f"z_{split}"] = np.asarray(zs, dtype=np.float64)
        out[f"frames_{split}"] = np.asarray(render(system, zs, config.size), dtype=np.float32)
        out[f"ts_{split}"] = np.asarray(ts)
    return PixelDataset(
        config=config,
        frames_train=out["frames_train"],
        z_train=out["z_train"],
        frames_test=out["frames_test"],
        z_test=out["z_test"],
        ts_test=out["ts_test"],
    )
