"""Experiments and run configurations: declare one with :class:`Experiment`, add it with
:func:`register`, expand it into :class:`RunConfig` s at a profile with :func:`expand`."""

from .core import (
    COORDINATES,
    DTYPES,
    LOSSES,
    OBSERVATIONS,
    PROFILES,
    TRAIN_TARGETS,
    Experiment,
    RunConfig,
    available,
    expand,
    get,
    profile_defaults,
    register,
    replication_seeds,
)

__all__ = [
    "COORDINATES",
    "DTYPES",
    "LOSSES",
    "OBSERVATIONS",
    "PROFILES",
    "TRAIN_TARGETS",
    "Experiment",
    "RunConfig",
    "available",
    "expand",
    "get",
    "profile_defaults",
    "register",
    "replication_seeds",
]
