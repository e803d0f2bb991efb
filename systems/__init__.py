"""Registry of physical systems with exact float64 ground truth, and their datasets.

Ground truth is float64: a process calls :func:`enable_x64` before computing it (the entry
points do); importing ``systems`` changes no jax setting.
"""

from . import _mujoco as mujoco_envs
from . import _mujoco_data as mujoco_data
from . import _real_pendulum as real_pendulum
from ._atomic import TMP_PREFIX, atomic_write, tmp_prefix
from ._base import MAX_STEPS, AbstractSystem, reference_masses_lengths
from ._chain import ChainPendulum
from ._coordinates import derivatives, to_momentum, to_velocity
from ._dataset import (
    Dataset,
    DatasetConfig,
    cache_root,
    dataset_path,
    make_dataset,
    source_fingerprint,
)
from ._magnet import MagnetPendulum
from ._mass_spring import MassSpring
from ._mujoco import TASKS as MUJOCO_TASKS
from ._mujoco import MujocoTask, collect_episodes, split_episodes
from ._mujoco import task as mujoco_task
from ._pendulum import Pendulum
from ._pixel_dataset import PixelDataset, PixelDatasetConfig, make_pixel_dataset
from ._precision import enable_x64, require_x64
from ._registry import available, make, parameters
from ._relativistic import RelativisticParticle
from ._render import reach, read_angle, read_state, render
from ._rigid import Gyroscope, Rotor
from ._spring import SpringPendulum
from ._three_body import ThreeBody
from ._two_body import TwoBody

__all__ = [
    "AbstractSystem",
    "TMP_PREFIX",
    "atomic_write",
    "tmp_prefix",
    "mujoco_envs",
    "MAX_STEPS",
    "ChainPendulum",
    "Dataset",
    "Gyroscope",
    "MagnetPendulum",
    "MassSpring",
    "MUJOCO_TASKS",
    "MujocoTask",
    "Pendulum",
    "PixelDataset",
    "PixelDatasetConfig",
    "TwoBody",
    "ThreeBody",
    "DatasetConfig",
    "RelativisticParticle",
    "Rotor",
    "SpringPendulum",
    "available",
    "cache_root",
    "dataset_path",
    "collect_episodes",
    "derivatives",
    "enable_x64",
    "require_x64",
    "make",
    "make_dataset",
    "make_pixel_dataset",
    "mujoco_data",
    "mujoco_task",
    "parameters",
    "real_pendulum",
    "reach",
    "read_angle",
    "read_state",
    "reference_masses_lengths",
    "render",
    "source_fingerprint",
    "split_episodes",
    "to_momentum",
    "to_velocity",
]
