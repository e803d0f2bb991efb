"""Registry of learned-dynamics models assembled from inductive biases.

Public names: :class:`Scene` (with its optional :class:`Standardisation`), :func:`available`,
:func:`make`, the abstract model classes,
:func:`symplectic_error`, :func:`trivial_models` and :class:`AbstractTrivialModel` (the
parameter-free reference predictors), :func:`coordinates` (what a model accepts),
:func:`spec` (a model's capabilities as a frozen :class:`ModelSpec`), :func:`register` and
:func:`load_plugins` (models from outside the suite: entry-point group ``decon_bench.models``,
``$DECON_MODEL_MODULES``), :func:`plugin_fingerprint` (what a plug-in's source hashes to),
:func:`plugin_modules` (what another process needs to load the same plug-ins),
:func:`acceleration_from_lagrangian` (the shared Euler-Lagrange solve) and
:func:`velocity_hessian`, the :class:`MLP` every model is built from, :func:`n_parameters`,
and the integrators (``Integrator``, ``rollout``, ...). Parts to build a model of one's own
from: :class:`CholeskyNet` (a learned positive-definite matrix of q, its floor
:data:`INVERSE_MASS_JITTER`), :class:`CanonicalSecondOrderODE` (second-order structure in
(q, p)), :class:`MomentumSecondOrderODE` (the same reached from (q, qdot) through the
learned inverse mass), :func:`cholesky` and :func:`cho_solve` (the batched solves the models use).

Controls: a :class:`Scene` with ``n_controls`` > 0 makes each model's ``args`` the
concatenation (static args, u); ``rollout(..., controls=...)`` holds u_i on interval i.
"""

from ._autoencoder import Autoencoder
from ._base import AbstractContinuousModel, AbstractDiscreteModel, AbstractModel
from ._features import Features
from ._hamiltonian import INVERSE_MASS_JITTER
from ._implicit import implicit_tolerance
from ._integrators import (
    DESCRIPTIONS,
    METHODS,
    ORDERS,
    Integrator,
    count_evaluations,
    rollout,
    rollout_batch,
)
from ._latent import LatentModel, latent_scene
from ._linalg import cho_solve, cholesky
from ._mass import CholeskyNet
from ._mlp import MLP
from ._node import CanonicalSecondOrderODE, MomentumSecondOrderODE
from ._position_latent import PositionLatentModel
from ._registry import (
    MODULES_ENV,
    available,
    coordinates,
    load_plugins,
    make,
    n_parameters,
    plugin_fingerprint,
    plugin_modules,
    register,
    trivial_models,
)
from ._scalar import acceleration_from_lagrangian, velocity_hessian
from ._scene import Scene, Standardisation
from ._spec import ModelSpec, spec
from ._symplectic import symplectic_error
from ._trivial import AbstractTrivialModel

__all__ = [
    "AbstractContinuousModel",
    "CanonicalSecondOrderODE",
    "MomentumSecondOrderODE",
    "CholeskyNet",
    "INVERSE_MASS_JITTER",
    "cho_solve",
    "cholesky",
    "Autoencoder",
    "DESCRIPTIONS",
    "Features",
    "METHODS",
    "MODULES_ENV",
    "ORDERS",
    "Integrator",
    "LatentModel",
    "MLP",
    "PositionLatentModel",
    "implicit_tolerance",
    "count_evaluations",
    "rollout",
    "rollout_batch",
    "AbstractDiscreteModel",
    "AbstractModel",
    "AbstractTrivialModel",
    "ModelSpec",
    "Scene",
    "Standardisation",
    "acceleration_from_lagrangian",
    "available",
    "latent_scene",
    "coordinates",
    "load_plugins",
    "make",
    "n_parameters",
    "plugin_fingerprint",
    "plugin_modules",
    "register",
    "spec",
    "symplectic_error",
    "velocity_hessian",
    "trivial_models",
]
