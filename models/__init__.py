"""Registry of learned-dynamics models assembled from inductive biases.

Public names: :class:`Scene`, :func:`available`, :func:`make`, the abstract model classes,
:func:`symplectic_error`, :func:`acceleration_from_lagrangian` (the shared Euler-Lagrange
solve), :func:`n_parameters`, and the integrators (``Integrator``, ``rollout``, ...).
"""

from ._base import AbstractContinuousModel, AbstractDiscreteModel, AbstractModel
from ._integrators import Integrator, count_evaluations, rollout, rollout_batch
from ._models import available, make, n_parameters
from ._scalar import acceleration_from_lagrangian
from ._scene import Scene
from ._symplectic import symplectic_error

__all__ = [
    "AbstractContinuousModel",
    "Integrator",
    "count_evaluations",
    "rollout",
    "rollout_batch",
    "AbstractDiscreteModel",
    "AbstractModel",
    "Scene",
    "acceleration_from_lagrangian",
    "available",
    "make",
    "n_parameters",
    "symplectic_error",
]
