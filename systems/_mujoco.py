"""The Gym MuJoCo tasks of the paper's Sec. 5 (Fig. 7) as data sources: the raw state
z = [q, v] = [qpos, qvel] read from the simulator (no clipping, no truncation), episodes
collected under a policy, and the paper's by-episode split into 3-step training windows and
200-step test trajectories, with a content hash and a data card. The card: docs/studies/mujoco.md.
"""

from __future__ import annotations

import dataclasses
import hashlib
from collections.abc import Callable, Mapping
from types import MappingProxyType

import numpy as np

# The observation of the paper's "Full" environments is the raw state: gymnasium's v5 tasks
# with this keyword keep qpos[0] (and Swimmer's qpos[1]); the velocity clipping of
# Hopper/Walker2d observations is avoided by reading data.qpos/qvel directly.
_FULL = (("exclude_current_positions_from_observation", False),)


@dataclasses.dataclass(frozen=True)
class MujocoTask:
    """One task: the paper's name, the gymnasium id and keyword arguments that make its
    observation the full state, the transition step dt = frame_skip * timestep (the reference's
    ``timestep_table``), the sizes of q, v and u, and whether Fig. 7 shows it."""

    name: str
    gym_id: str
    kwargs: tuple[tuple[str, object], ...]
    dt: float
    frame_skip: int
    timestep: float
    integrator: str  # of the task's XML: MuJoCo's "RK4" or semi-implicit "Euler"
    nq: int
    nv: int
    nu: int
    in_fig7: bool

    @property
    def state_dim(self) -> int:
        return self.nq + self.nv


TASKS: Mapping[str, MujocoTask] = MappingProxyType(
    {
        t.name: t
        for t in (
            MujocoTask("HopperFull-v0", "Hopper-v5", _FULL, 0.008, 4, 0.002, "RK4", 6, 6, 3, True),
            MujocoTask("SwimmerFull-v0", "Swimmer-v5", _FULL, 0.04, 4, 0.01, "RK4", 5, 5, 2, True),
            MujocoTask(
                "HalfCheetahFull-v0", "HalfCheetah-v5", _FULL, 0.05, 5, 0.01, "Euler", 9, 9, 6, True
            ),
            # in the reference's timestep table, not in Fig. 7
            MujocoTask(
                "Walker2dFull-v0", "Walker2d-v5", _FULL, 0.008, 4, 0.002, "RK4", 9, 9, 6, False
            ),
        )
    }
)

# The paper's App. C sizes: 40K 3-step training windows, 200 test trajectories of 200 steps;
# the reference's converter held out every tenth episode for test.
N_TRAIN, TRAIN_LEN, N_TEST, TEST_LEN, TEST_FRACTION = 40_000, 3, 200, 200, 0.1

# A policy maps the raw state z (state_dim,) and a numpy Generator to a control u (nu,).
Policy = Callable[[np.ndarray, np.random.Generator], np.ndarray]


def task(name: str) -> MujocoTask:
    """The task of that name (a paper name such as ``"HopperFull-v0"`` or a gymnasium id)."""
    for t in TASKS.values():
        if name in (t.name, t.gym_id):
            return t
    raise ValueError(f"unknown MuJoCo task {name!r}; available: {', '.join(TASKS)}")


def make_env(name: str):
    """A gymnasium environment of the task, float64 physics (gymnasium's C MuJoCo)."""
    import gymnasium

    t = task(name)
    env = gymnasium.make(t.gym_id, **dict(t.kwargs))
    m = env.unwrapped.model
    if (env.unwrapped.frame_skip, m.nq, m.nv, m.nu) != (t.frame_skip, t.nq, t.nv, t.nu) or (
        abs(env.unwrapped.dt - t.dt) > 1e-12
    ):
        raise RuntimeError(f"{t.gym_id} no longer matches the task table entry {t}")
    return env


def raw_state(env) -> np.ndarray:
    """z = [qpos, qvel] of the simulator now, float64 copies (no clipping, no truncation)."""
    d = env.unwrapped.data
    return np.concatenate([d.qpos, d.qvel]).astype(np.float64, copy=True)


def set_state(env, z: np.ndarray) -> None:
    """Put the simulator in state z = [q, v] (the rest of its state reset, as after a reset)."""
    import mujoco

    u = env.unwrapped
    nq = u.model.nq
    mujoco.mj_resetData(u.model, u.data)
    u.data.qpos[:] = z[:nq]
    u.data.qvel[:] = z[nq:]
    mujoco.mj_forward(u.model, u.data)


def step_from(env, z: np.ndarray, u: np.ndarray) -> np.ndarray:
    """The simulator's next raw state from state z under control u held for frame_skip
    substeps: the ground-truth transition z_{t+1} = F(z_t, u_t)."""
    set_state(env, z)
    env.unwrapped.do_simulation(np.asarray(u, dtype=np.float64), env.unwrapped.frame_skip)
    return raw_state(env)


@dataclasses.dataclass(frozen=True)
class Episodes:
    """Transitions as a replay buffer holds them, one row per step t of an episode: the state
    z_t = [q_t, v_t] before the control, the control u_t (clipped to the control range, as
    the simulator applies it), the reward r_t, the episode id and t. An episode's state after
    its last control is not a row (as in the reference's buffer)."""

    task: str
    z: np.ndarray  # (N, nq + nv) float64
    u: np.ndarray  # (N, nu) float64
    reward: np.ndarray  # (N,)
    episode: np.ndarray  # (N,) int64, 0, 1, ... in collection order
    step: np.ndarray  # (N,) int64, index within the episode
    seed: int

    def arrays(self) -> dict[str, np.ndarray]:
        return {k: getattr(self, k) for k in ("z", "u", "reward", "episode", "step")}


class Recorder:
    """Writes transitions one at a time into preallocated rows of an :class:`Episodes`, and
    keeps the episode bookkeeping in one place for every collector (a fixed policy here, the
    learning SAC agent in ``collect._sac``): an episode ends when it terminates or reaches
    ``limit`` steps (a truncation); the episode id then advances and the step restarts at 0."""

    FIELDS = ("z", "u", "reward", "episode", "step", "terminated", "truncated")

    def __init__(self, name: str, capacity: int, *, seed: int, limit: int):
        self.name = name
        self.seed, self.limit, self.n, self.episode, self.k = seed, limit, 0, 0, 0
        self.capacity = capacity
        self.rows: dict[str, np.ndarray] = {}

    def _allocate(self, z: np.ndarray, u: np.ndarray) -> None:
        c = self.capacity
        self.rows = {
            "z": np.zeros((c, z.size)),
            "u": np.zeros((c, u.size)),
            "reward": np.zeros(c),
            "episode": np.zeros(c, np.int64),
            "step": np.zeros(c, np.int64),
            "terminated": np.zeros(c, bool),
            "truncated": np.zeros(c, bool),
        }

    def add(self, z: np.ndarray, u: np.ndarray, reward: float, terminated: bool) -> bool:
        """Record (z_t, u_t, r_t); True when this transition ends its episode."""
        if not self.rows:
            self._allocate(np.asarray(z), np.asarray(u))
        if self.n >= self.capacity:
            raise IndexError(f"recorder full ({self.capacity} rows)")
        truncated = not terminated and self.k + 1 >= self.limit
        row = (z, u, float(reward), self.episode, self.k, bool(terminated), truncated)
        for key, value in zip(self.FIELDS, row, strict=True):
            self.rows[key][self.n] = value
        self.n, self.k = self.n + 1, self.k + 1
        if terminated or truncated:
            self.episode, self.k = self.episode + 1, 0
            return True
        return False

    def arrays(self) -> dict[str, np.ndarray]:
        """The filled rows (views) and the counters, as a checkpoint stores them."""
        out = {key: a[: self.n] for key, a in self.rows.items()}
        out["counters"] = np.array([self.n, self.episode, self.k], np.int64)
        return out

    def restore(self, arrays: Mapping[str, np.ndarray]) -> None:
        """Continue from :meth:`arrays` (the capacity kept, at least the rows stored)."""
        self.n, self.episode, self.k = (int(c) for c in arrays["counters"])
        if self.n > self.capacity:
            raise ValueError(f"{self.n} rows stored, capacity {self.capacity}")
        if self.n:
            self._allocate(arrays["z"][0], arrays["u"][0])
            for key in self.FIELDS:
                self.rows[key][: self.n] = arrays[key]

    def episodes(self) -> Episodes:
        r = {key: a[: self.n].copy() for key, a in self.rows.items()}
        return Episodes(
            self.name, r["z"], r["u"], r["reward"], r["episode"], r["step"], seed=self.seed
        )


def control_range(env) -> tuple[np.ndarray, np.ndarray]:
    """The task's control bounds (float64): actions in [-1, 1] map affinely onto them."""
    return env.action_space.low.astype(np.float64), env.action_space.high.astype(np.float64)


def collect_episodes(
    name: str, policy: Policy, *, seed: int, n_steps: int, max_episode_steps: int | None = None
) -> Episodes:
    """Run ``policy`` in the task for ``n_steps`` transitions in all, resetting when an episode
    terminates or reaches its time limit (gymnasium's, 1000 steps, unless given); the last
    episode is cut where the budget ends. Deterministic given ``seed`` (the first reset is
    seeded, the policy gets its own Generator)."""
    if n_steps < 1:
        raise ValueError(f"n_steps must be >= 1, got {n_steps}")
    t = task(name)
    env = make_env(name)
    limit = max_episode_steps or env.spec.max_episode_steps
    rec = Recorder(t.name, n_steps, seed=seed, limit=limit)
    low, high = control_range(env)
    rng = np.random.default_rng(seed)
    env.reset(seed=seed)
    for _ in range(n_steps):
        z = raw_state(env)
        u = np.clip(np.asarray(policy(z, rng), dtype=np.float64).reshape(t.nu), low, high)
        _, r, terminated, _, _ = env.step(u)
        if rec.add(z, u, r, terminated):
            env.reset()
    env.close()
    return rec.episodes()


def content_hash(arrays: Mapping[str, np.ndarray]) -> str:
    """sha256 over the arrays' names, dtypes, shapes and bytes, in sorted name order."""
    h = hashlib.sha256()
    for key in sorted(arrays):
        a = np.ascontiguousarray(arrays[key])
        h.update(f"{key}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


@dataclasses.dataclass(frozen=True)
class Split:
    """The paper's data: training windows of ``TRAIN_LEN`` consecutive steps (z (N, L, d),
    u (N, L, nu)) from training episodes, and test trajectories of ``TEST_LEN`` steps from
    the other episodes; each with its episode id and start step."""

    task: str
    dt: float
    train_z: np.ndarray
    train_u: np.ndarray
    train_episode: np.ndarray
    train_start: np.ndarray
    test_z: np.ndarray
    test_u: np.ndarray
    test_episode: np.ndarray
    test_start: np.ndarray

    def arrays(self) -> dict[str, np.ndarray]:
        return {
            f.name: getattr(self, f.name)
            for f in dataclasses.fields(self)
            if isinstance(getattr(self, f.name), np.ndarray)
        }

    def sha256(self) -> str:
        return content_hash(self.arrays())


def _windows(ep: Episodes, ids: np.ndarray, length: int) -> tuple[np.ndarray, np.ndarray]:
    """Row indices i of every window [i, i + length) lying inside one episode of ``ids``."""
    inside = np.isin(ep.episode, ids)
    n = len(ep.episode)
    starts = np.flatnonzero(inside[: n - length + 1]) if n >= length else np.zeros(0, np.int64)
    same = ep.episode[starts + length - 1] == ep.episode[starts]
    starts = starts[same]
    return starts, ep.episode[starts]


def split_episodes(
    ep: Episodes,
    *,
    seed: int,
    n_train: int = N_TRAIN,
    train_len: int = TRAIN_LEN,
    n_test: int = N_TEST,
    test_len: int = TEST_LEN,
    test_fraction: float = TEST_FRACTION,
) -> Split:
    """Split by episode (a random ``test_fraction`` of the episodes, at least one, is test),
    then draw ``n_train`` windows of ``train_len`` steps uniformly, without replacement, from
    all windows inside training episodes, and ``n_test`` of ``test_len`` steps from those
    inside test episodes. ValueError when there are fewer windows than asked."""
    if not 0 < test_fraction < 1:
        raise ValueError(f"test_fraction must be in (0, 1), got {test_fraction}")
    rng = np.random.default_rng(seed)
    ids = rng.permutation(np.unique(ep.episode))
    n_test_eps = min(len(ids) - 1, max(1, round(test_fraction * len(ids))))
    if n_test_eps < 1:
        raise ValueError("need at least two episodes to split by episode")
    test_ids, train_ids = ids[:n_test_eps], ids[n_test_eps:]

    def draw(ids_, count, length, what):
        starts, eps = _windows(ep, ids_, length)
        if len(starts) < count:
            raise ValueError(
                f"{what}: {count} windows of {length} steps asked, {len(starts)} available"
            )
        pick = np.sort(rng.choice(len(starts), size=count, replace=False))
        rows = starts[pick][:, None] + np.arange(length)
        return ep.z[rows], ep.u[rows], eps[pick], ep.step[starts[pick]]

    train = draw(train_ids, n_train, train_len, "train")
    test = draw(test_ids, n_test, test_len, "test")
    return Split(ep.task, task(ep.task).dt, *train, *test)


def data_card(
    split: Split,
    episodes: Episodes,
    *,
    policy: str,
    policy_budget: str,
    policy_return: float | None,
) -> dict:
    """A small card of a split: task, source (simulator and versions), the policy, its
    training budget and return, sizes and the content hashes."""
    import gymnasium
    import mujoco

    t = task(split.task)
    returns = np.bincount(episodes.episode, weights=episodes.reward)
    return {
        "task": t.name,
        "source": (
            f"gymnasium {gymnasium.__version__} {t.gym_id} {dict(t.kwargs)}, MuJoCo "
            f"{mujoco.__version__} (C, float64), state [qpos, qvel] read from the simulator"
        ),
        "dt": t.dt,
        "policy": policy,
        "policy_budget": policy_budget,
        "policy_return": policy_return,
        "collection": {
            "seed": episodes.seed,
            "transitions": int(len(episodes.episode)),
            "episodes": int(len(returns)),
            "mean_episode_return": float(returns.mean()),
        },
        "sizes": {
            "train": list(split.train_z.shape),
            "test": list(split.test_z.shape),
            "train_episodes": int(len(np.unique(split.train_episode))),
            "test_episodes": int(len(np.unique(split.test_episode))),
        },
        "sha256": split.sha256(),
        "episodes_sha256": content_hash(episodes.arrays()),
    }
