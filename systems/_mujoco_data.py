"""The MuJoCo tasks' datasets on disk: one file per task, ``<folder>/<task>.npz`` (the arrays
of :class:`Episodes`: z, u, reward, episode, step, and the collection seed), with its data card
``<task>.json`` beside it, whose ``episodes_sha256`` (:func:`content_hash` of the arrays) is
checked on every load. The folder: ``$DECON_MUJOCO_DATA``, else ``<cache>/data/mujoco``. The
stand-in (uniform random controls, for tests) is collected, never read from a file.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from . import _mujoco as mj

ENV = "DECON_MUJOCO_DATA"  # a folder holding <task>.npz and <task>.json
STAND_IN = "stand-in: uniform random controls (systems.collect_episodes), not the paper's data"
STAND_IN_EPISODE = 100  # the stand-in's time limit in steps: several episodes even in Swimmer


def data_dir() -> Path:
    """The folder of the task files: ``$DECON_MUJOCO_DATA``, else ``<cache>/data/mujoco``."""
    from ._dataset import cache_root

    return Path(os.environ.get(ENV) or cache_root() / "data" / "mujoco")


def data_path(name: str, folder: Path | str | None = None) -> Path:
    """``<folder>/<task>.npz`` of a task (its paper name), in :func:`data_dir` by default."""
    return Path(folder or data_dir()) / f"{mj.task(name).name}.npz"


def save_data(episodes: mj.Episodes, card: dict, folder: Path | str | None = None) -> Path:
    """Write a task's file and its card (``card["episodes_sha256"]`` set to the arrays' hash);
    returns the path of the npz. Both are written to temporary names, then renamed."""
    path = data_path(episodes.task, folder)
    path.parent.mkdir(parents=True, exist_ok=True)
    arrays = episodes.arrays()
    card = {**card, "task": episodes.task, "episodes_sha256": mj.content_hash(arrays)}
    tmp = path.with_name(f".{path.stem}.tmp.npz")
    np.savez(tmp, seed=np.int64(episodes.seed), **arrays)
    tmp_card = path.with_name(f".{path.stem}.tmp.json")
    tmp_card.write_text(json.dumps(card, indent=1, sort_keys=True, default=str))
    os.replace(tmp, path)
    os.replace(tmp_card, path.with_suffix(".json"))
    return path


def load_data(name: str, folder: Path | str | None = None) -> tuple[mj.Episodes, dict]:
    """(Episodes, card) of a task's file; a one-line ValueError when the file or its card is
    missing, or when the arrays' sha256 differs from the card's."""
    path = data_path(name, folder)
    card_path = path.with_suffix(".json")
    if not path.exists() or not card_path.exists():
        raise ValueError(
            f"no data for {mj.task(name).name}: {path} and its card {card_path.name} are needed "
            f"(set ${ENV} to their folder)"
        )
    card = json.loads(card_path.read_text())
    with np.load(path) as f:
        arrays = {k: f[k] for k in ("z", "u", "reward", "episode", "step")}
        seed = int(f["seed"]) if "seed" in f else 0
    sha = mj.content_hash(arrays)
    if sha != card.get("episodes_sha256"):
        raise ValueError(
            f"{path}: the arrays' sha256 {sha[:16]} differs from the card's "
            f"{str(card.get('episodes_sha256'))[:16]}"
        )
    return mj.Episodes(mj.task(name).name, seed=seed, **arrays), card


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
