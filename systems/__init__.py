"""Registry of physical systems with exact float64 ground truth, and their datasets."""

import jax

jax.config.update("jax_enable_x64", True)

from ._base import AbstractSystem, reference_masses_lengths  # noqa: E402
from ._chain import ChainPendulum  # noqa: E402
from ._coordinates import derivatives, to_momentum, to_velocity  # noqa: E402
from ._dataset import Dataset, DatasetConfig, cache_root, make_dataset  # noqa: E402
from ._mass_spring import MassSpring  # noqa: E402
from ._pendulum import Pendulum  # noqa: E402
from ._pixel_dataset import PixelDataset, PixelDatasetConfig, make_pixel_dataset  # noqa: E402
from ._registry import available, make, parameters  # noqa: E402
from ._relativistic import RelativisticParticle  # noqa: E402
from ._render import read_angle, read_state, render  # noqa: E402
from ._spring import SpringPendulum  # noqa: E402
from ._two_body import TwoBody  # noqa: E402

__all__ = [
    "AbstractSystem",
    "ChainPendulum",
    "Dataset",
    "MassSpring",
    "Pendulum",
    "PixelDataset",
    "PixelDatasetConfig",
    "TwoBody",
    "DatasetConfig",
    "RelativisticParticle",
    "SpringPendulum",
    "available",
    "cache_root",
    "derivatives",
    "make",
    "make_dataset",
    "make_pixel_dataset",
    "parameters",
    "read_angle",
    "read_state",
    "reference_masses_lengths",
    "render",
    "to_momentum",
    "to_velocity",
]
