"""A MuJoCo task's data file from a trained policy: the soft actor-critic trained on the task,
its whole recorded buffer saved in the task's file format (``systems.mujoco_data``)."""

from __future__ import annotations

from pathlib import Path

import systems

from ._sac_run import data_card, train_policy


def collect_task(
    name: str,
    steps: int,
    *,
    seed: int = 0,
    checkpoint_dir: Path | str | None = None,
    folder: Path | str | None = None,
    progress=None,
) -> Path:
    """Train the SAC agent ``steps`` environment steps on a task (resuming from
    ``checkpoint_dir``, ``<cache>/mujoco`` by default), then save its whole recorded buffer as
    the task's file with a card: the policy, its budget, its evaluation returns along the way,
    the split's sizes. Returns the path of the npz."""
    ck = Path(checkpoint_dir) if checkpoint_dir is not None else systems.cache_root() / "mujoco"
    run = train_policy(name, steps, seed, ck, progress=progress)
    ep = run.episodes()
    card = data_card(run, systems.split_episodes(ep, seed=seed))
    card["policy_training"]["eval_returns"] = [
        [int(s), float(r)] for s, r in zip(run.eval_steps, run.eval_returns, strict=True)
    ]
    return systems.mujoco_data.save_data(ep, card, folder)
