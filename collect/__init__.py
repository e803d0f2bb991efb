"""Data collection: what the suite records from a simulator to learn from, as opposed to the
systems' own physics (``systems``). The MuJoCo tasks' data is the whole replay buffer of a
soft actor-critic trained on the task (``python -m bench data mujoco <task>``,
``make mujoco-data``); the files are read back by ``systems.mujoco_data``.
"""

from ._sac import SACConfig
from ._sac_run import DEFAULT_CONFIG, SACRun, data_card, train_policy
from ._tasks import collect_task

__all__ = ["DEFAULT_CONFIG", "SACConfig", "SACRun", "collect_task", "data_card", "train_policy"]
