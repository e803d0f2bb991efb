"""Registry of learned-dynamics models assembled from inductive biases.

Public names: :class:`Scene`, :func:`available`, :func:`make`, the abstract model classes,
:func:`symplectic_error`, :func:`acceleration_from_lagrangian` (the shared Euler-Lagrange
solve), :func:`n_parameters`, and the integrators (``Integrator``, ``rollout``, ...).
"""

from bench._env import configure_threads

configure_threads()

from ._base import AbstractContinuousModel, AbstractDiscreteModel, AbstractModel  # noqa: E402
from ._models import available, make, n_parameters  # noqa: E402
from ._scalar import acceleration_from_lagrangian  # noqa: E402
from ._scene import Scene  # noqa: E402
from ._symplectic import symplectic_error  # noqa: E402

try:  # the integrators live in their own module, written alongside this package
    from ._integrators import (  # noqa: F401
        DESCRIPTIONS,
        METHODS,
        ORDERS,
        Integrator,
        count_evaluations,
        implicit_tolerance,
        rollout,
        rollout_batch,
    )
except ImportError:  # pragma: no cover - only while _integrators.py does not exist yet
    pass

__all__ = [
    "AbstractContinuousModel",
    "AbstractDiscreteModel",
    "AbstractModel",
    "Scene",
    "acceleration_from_lagrangian",
    "available",
    "make",
    "n_parameters",
    "symplectic_error",
]
