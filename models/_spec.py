"""What a registered model can do, as data: :func:`spec` reads it off the model's class and its
registry entry, so no list of model names is kept anywhere else."""

from __future__ import annotations

import functools
from dataclasses import dataclass

from ._base import AbstractContinuousModel, AbstractDiscreteModel
from ._registry import _GENERATION, _REGISTRY, available, coordinates

__all__ = ["ModelSpec", "spec"]


@dataclass(frozen=True)
class ModelSpec:
    """The capabilities of a registered model.

    ``continuous``: a learned vector field dz/dt = F(z), integrated by ``models.rollout``;
    ``discrete``: a learned map z_n -> z_{n+1} over one dt (the integrator is the model); a
    trivial predictor is neither. ``second_order``: dq/dt = qdot holds exactly. ``structure``:
    the energy function the model is built on, "hamiltonian" (H(q, p)), "lagrangian"
    (L(q, qdot)) or None (a free model). ``takes_dissipation``: the model adds a learned
    dissipation term in damped scenes (``make(..., dissipation=...)``). ``coordinates``: the
    scene coordinates it accepts ("velocity", "momentum"). ``options``: the names of its
    ``make`` options. ``controls``: it reads the control input u of a controlled scene
    (``Scene.n_controls`` > 0; ``make`` refuses such a scene for a model that would ignore u,
    trivial predictors apart). ``forced``: a free learned force enters its field (the
    energy of its ``structure`` is not conserved even without damping)."""

    name: str
    continuous: bool
    discrete: bool
    second_order: bool
    structure: str | None
    trivial: bool
    takes_dissipation: bool
    coordinates: tuple[str, ...]
    default_activation: str
    options: tuple[str, ...]
    controls: bool = False
    forced: bool = False

    @property
    def hamiltonian(self) -> bool:
        return self.structure == "hamiltonian"

    @property
    def lagrangian(self) -> bool:
        return self.structure == "lagrangian"


def spec(name: str) -> ModelSpec:
    """The :class:`ModelSpec` of the registered model ``name`` (ValueError naming them).

    Read once per registry generation: a model registered again (a plug-in replacing a
    definition) is read afresh, without the registry knowing of this module."""
    if name not in available():  # available() loads the plug-ins first
        raise ValueError(f"unknown model {name!r}; allowed: {available()}")
    return _spec(name, _GENERATION[0])


@functools.cache
def _spec(name: str, generation: int) -> ModelSpec:
    entry = _REGISTRY[name]
    cls = entry.cls
    return ModelSpec(
        name=name,
        continuous=issubclass(cls, AbstractContinuousModel),
        discrete=issubclass(cls, AbstractDiscreteModel),
        second_order=bool(getattr(cls, "second_order", False)),
        structure=cls.structure,
        trivial=bool(cls.trivial),
        takes_dissipation=bool(entry.structured),
        coordinates=coordinates(name),
        default_activation=entry.activation,
        options=tuple(sorted(entry.options)),
        controls=bool(getattr(cls, "takes_controls", False)),
        forced=bool(getattr(cls, "forced", False)),
    )


spec.cache_clear = _spec.cache_clear  # type: ignore[attr-defined]
