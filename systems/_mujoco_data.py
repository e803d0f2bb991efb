"""The MuJoCo tasks' datasets on disk. A task's file ``<folder>/<task>.npz`` holds what a
replay needs, compressed: each episode's first state ``z0`` (float64), its length, every
control ``u`` (float64) and the collection seed; the states and rewards are recomputed by
stepping the simulator (deterministic for a given MuJoCo build), a few times smaller than
storing them. Its data card ``<task>.json`` beside it holds ``file_sha256`` (the file's arrays)
and ``episodes_sha256`` (:func:`content_hash` of the replayed z, u, reward, episode, step): a
load checks both, and keeps the replay in the cache (``<cache>/data/mujoco``) under its hash.
The folder: ``$DECON_MUJOCO_DATA``, else the repository's ``data/mujoco`` (committed). The
stand-in (uniform random controls, for tests) is collected, never read from a file.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from . import _mujoco as mj
from ._atomic import atomic_write

ENV = "DECON_MUJOCO_DATA"  # a folder holding <task>.npz and <task>.json
COMMITTED = Path(__file__).resolve().parents[1] / "data" / "mujoco"
STAND_IN = "stand-in: uniform random controls (systems.collect_episodes), not the paper's data"
STAND_IN_EPISODE = 100  # the stand-in's time limit in steps: several episodes even in Swimmer
FILE_FIELDS = ("z0", "length", "u", "seed")


def data_dir() -> Path:
    """The folder of the task files: ``$DECON_MUJOCO_DATA``, else the repository's
    ``data/mujoco``."""
    return Path(os.environ.get(ENV) or COMMITTED)


def data_path(name: str, folder: Path | str | None = None) -> Path:
    """``<folder>/<task>.npz`` of a task (its paper name), in :func:`data_dir` by default."""
    return Path(folder or data_dir()) / f"{mj.task(name).name}.npz"


def compact(episodes: mj.Episodes) -> dict[str, np.ndarray]:
    """The arrays a replay needs: each episode's first state and length, the controls, the
    seed. ValueError unless the episodes are numbered 0, 1, ... and each starts at step 0."""
    e = episodes.episode
    starts = np.flatnonzero(np.r_[True, e[1:] != e[:-1]])
    length = np.diff(np.r_[starts, len(e)])
    if not (
        np.array_equal(e[starts], np.arange(len(starts))) and np.all(episodes.step[starts] == 0)
    ):
        raise ValueError(f"{episodes.task}: episodes must be numbered 0, 1, ... from step 0")
    return {
        "z0": episodes.z[starts],
        "length": length.astype(np.int64),
        "u": episodes.u,
        "seed": np.int64(episodes.seed),
    }


def replay(name: str, arrays) -> mj.Episodes:
    """The :class:`Episodes` of a file's arrays: each episode started from its ``z0`` (the
    simulator otherwise reset, as after ``env.reset``), then stepped under its controls,
    recording the raw state before each control and the task's reward."""
    t = mj.task(name)
    env = mj.make_env(t.name)
    env.reset(seed=0)
    z0, length, u = arrays["z0"], np.asarray(arrays["length"]), np.asarray(arrays["u"])
    n = int(length.sum())
    if n != len(u):
        raise ValueError(f"{t.name}: episode lengths sum to {n}, {len(u)} controls")
    z, reward = np.zeros((n, t.nq + t.nv)), np.zeros(n)
    episode, step = np.repeat(np.arange(len(length)), length), np.zeros(n, np.int64)
    i, sim = 0, env.unwrapped
    for zs, m in zip(z0, length, strict=True):
        mj.set_state(env, zs)
        for k in range(int(m)):
            z[i], step[i] = mj.raw_state(env), k
            reward[i] = sim.step(u[i])[1]
            i += 1
    env.close()
    return mj.Episodes(t.name, z, u.astype(np.float64), reward, episode, step, int(arrays["seed"]))


def _write_atomic(path: Path, arrays: dict, card: dict) -> None:
    """The task's file, then its card, each through the one atomic write."""
    atomic_write(path, lambda tmp: np.savez_compressed(tmp, **arrays))
    text = json.dumps(card, indent=1, sort_keys=True, default=str) + "\n"
    atomic_write(path.with_suffix(".json"), lambda tmp: tmp.write_text(text))


def save_data(episodes: mj.Episodes, card: dict, folder: Path | str | None = None) -> Path:
    """Write a task's file and its card (``file_sha256``, ``episodes_sha256`` and the MuJoCo
    version set); returns the path of the npz. The file is replayed first: a ValueError, and
    nothing written, unless the replay gives the episodes bit for bit."""
    import mujoco

    arrays = compact(episodes)
    sha = mj.content_hash(episodes.arrays())
    got = mj.content_hash(replay(episodes.task, arrays).arrays())
    if got != sha:
        raise ValueError(f"{episodes.task}: the replay of the controls does not give the episodes")
    path = data_path(episodes.task, folder)
    card = {
        **card,
        "task": episodes.task,
        "file_sha256": mj.content_hash(arrays),
        "episodes_sha256": sha,
        "replay_mujoco": mujoco.__version__,
    }
    _write_atomic(path, arrays, card)
    return path


def _cached(name: str, sha: str) -> Path:
    from ._dataset import cache_root

    return cache_root() / "data" / "mujoco" / f"{mj.task(name).name}-{sha[:16]}.npz"


def load_data(name: str, folder: Path | str | None = None) -> tuple[mj.Episodes, dict]:
    """(Episodes, card) of a task's file, replayed (or read from the cache's replay); a
    one-line ValueError when the file or its card is missing, or when the file's or the
    replay's sha256 differs from the card's."""
    path = data_path(name, folder)
    card_path = path.with_suffix(".json")
    if not path.exists() or not card_path.exists():
        raise ValueError(
            f"no data for {mj.task(name).name}: {path} and its card {card_path.name} are needed "
            f"(set ${ENV} to their folder)"
        )
    card = json.loads(card_path.read_text())
    with np.load(path) as f:
        stored = {k: f[k] for k in FILE_FIELDS}
    sha = mj.content_hash(stored)
    if sha != card.get("file_sha256"):
        raise ValueError(
            f"{path}: the arrays' sha256 {sha[:16]} differs from the card's "
            f"{str(card.get('file_sha256'))[:16]}"
        )
    want = str(card.get("episodes_sha256"))
    cached = _cached(name, want)
    if cached.exists():
        with np.load(cached) as f:
            arrays = {k: f[k] for k in ("z", "u", "reward", "episode", "step")}
            seed = int(f["seed"])
        if mj.content_hash(arrays) == want:
            return mj.Episodes(mj.task(name).name, seed=seed, **arrays), card
    ep = replay(name, stored)
    sha = mj.content_hash(ep.arrays())
    if sha != want:
        import mujoco

        raise ValueError(
            f"{path}: its replay under MuJoCo {mujoco.__version__} has sha256 {sha[:16]}, the "
            f"card's (MuJoCo {card.get('replay_mujoco')}) {want[:16]}: another simulator build"
        )
    atomic_write(cached, lambda tmp: np.savez(tmp, seed=np.int64(ep.seed), **ep.arrays()))
    return ep, card


def stand_in(name: str, n_steps: int, seed: int = 0) -> tuple[mj.Episodes, dict]:
    """(Episodes, card) of ``n_steps`` transitions under uniform random controls in [-1, 1]
    (clipped to the task's range), episodes of at most :data:`STAND_IN_EPISODE` steps: a
    stand-in for tests, labelled :data:`STAND_IN`."""
    t = mj.task(name)
    ep = mj.collect_episodes(
        t.name,
        lambda z, rng: rng.uniform(-1.0, 1.0, t.nu),
        seed=seed,
        n_steps=n_steps,
        max_episode_steps=STAND_IN_EPISODE,
    )
    card = {
        "task": t.name,
        "source": STAND_IN,
        "policy": "uniform random controls",
        "collection": {"seed": seed, "transitions": int(n_steps)},
        "episodes_sha256": mj.content_hash(ep.arrays()),
    }
    return ep, card
