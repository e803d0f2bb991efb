"""The observation kinds of a run (``RunConfig.observation``: what the models see) as one type
family, and their one registry.

A kind is a final subclass of the abstract :class:`Observation`, registered by name with
:func:`register_observation`: it checks a configuration of its kind (``check``: its values, when
the :class:`~bench.core._config.RunConfig` is built; ``check_model``: the registered models,
before a sweep), declares the fields that apply to it alone (``options``) and those of the other
runs that it pins (``fixed``), and runs the steps of a run: ``build``, ``train`` and
``evaluate`` (:func:`bench.core._execute.run_steps`). A kind whose runs can train as an
ensemble's members says how (:attr:`Observation.member`, a :class:`Member`).

The vocabulary of ``RunConfig.observation``, the executor's steps and the check of the models
all read this registry, so a new kind is one class and its registration. The built-in kinds
(:mod:`bench.core._kinds`) are imported by name the first time the registry is read, as the
studies are: their steps use the modules that build :class:`RunConfig`, which reads this
registry, so a static import here would close a cycle.
"""

from __future__ import annotations

import abc
import dataclasses
import importlib
import inspect
from collections.abc import Callable
from pathlib import Path
from typing import Any, ClassVar

BUILT_IN_KINDS = f"{__package__}._kinds"  # the module that registers state, pixels, ...


@dataclasses.dataclass(frozen=True)
class Member:
    """How the runs of one kind train as members of an ensemble (:mod:`bench.core._ensemble`),
    one program for runs that differ only in seed, learning rate or noise:

    - ``train_config(config) -> TrainConfig``: what its train step gives the one training loop
      (members share it up to ``seed`` and ``lr``);
    - ``inputs(config, built) -> (model, dataset, objective)``: what its train step fits;
    - ``record(config, result, cache_root) -> meta``: a member's :class:`bench.TrainResult` as
      its train step's meta (stored in the parameter cache where the kind caches);
    - ``rollouts``: its test rollouts run vmapped over the members
      (:func:`bench.core._ensemble.rollout_members`, state runs), else each member's own.
    """

    train_config: Callable
    inputs: Callable
    record: Callable
    rollouts: bool = False


class Observation(abc.ABC):
    """One observation kind: what the models of a run see, and the steps of such a run.

    Subclasses are abstract or final; a final one sets ``name`` (its ``RunConfig.observation``)
    and may set ``options`` and ``fixed``, each a tuple of ``(field, value)`` pairs of
    :class:`RunConfig` fields:

    - ``options``: the fields that apply to this kind only, with their defaults (the field's
      own default); another kind's run must leave them there;
    - ``fixed``: fields of every run that this kind supports at one value only.

    The steps take and return plain values: ``build`` makes the run's system, data and
    untrained model (``built``, in the kind's own layout); ``train`` returns ``(model, meta)``,
    the trained model and the training's record (:func:`bench.core._params.cached_training`);
    ``evaluate`` returns ``(columns, arrays)``, the row's metric columns (with ``curves``) and
    the arrays saved as ``curves.npz`` (may be empty).
    """

    name: ClassVar[str]
    options: ClassVar[tuple[tuple[str, Any], ...]] = ()
    fixed: ClassVar[tuple[tuple[str, Any], ...]] = ()

    @property
    def runs(self) -> str:
        """How messages name this kind's runs ("controlled runs")."""
        return f"{self.name} runs"

    @property
    def member(self) -> Member | None:
        """How its runs train as an ensemble's members; None: each trains alone."""
        return None

    def check_fixed(self, config) -> None:
        """One-line ValueError for a field of ``fixed`` away from its one value."""
        for name, value in self.fixed:
            if getattr(config, name) != value:
                what = f"{name} {getattr(config, name)!r}"
                raise ValueError(f"{self.runs} support no {what}; allowed: {value!r}")

    @abc.abstractmethod
    def check(self, config) -> None:
        """One-line ValueErrors naming what is allowed, for the values of a configuration of
        this kind (called once, when the configuration is built; no model is made)."""

    @abc.abstractmethod
    def check_model(self, config) -> None:
        """One-line ValueError for a model that cannot run ``config`` (asked of the registered
        models before a sweep: :func:`bench.core._runnable.check_runnable`)."""

    @abc.abstractmethod
    def build(self, config, cache_root: Path) -> Any:
        """The run's system, data and untrained model (``built``)."""

    @abc.abstractmethod
    def train(self, config, built, cache_root: Path, progress: bool) -> tuple:
        """``(model, meta)``: the trained model and the training's record."""

    @abc.abstractmethod
    def evaluate(self, config, built, model, meta: dict, cache_root: Path) -> tuple[dict, dict]:
        """``(columns, arrays)``: the row's metric columns and the arrays to save."""


_KINDS: dict[str, Observation] = {}
_LOADED = False


def register_observation(cls: type[Observation]) -> type[Observation]:
    """Register a final :class:`Observation` class under its ``name`` (a class decorator;
    re-registering a name replaces it). ValueError for anything else."""
    if not (isinstance(cls, type) and issubclass(cls, Observation)) or inspect.isabstract(cls):
        raise ValueError(f"register_observation expects a concrete Observation class; got {cls!r}")
    name = getattr(cls, "name", None)
    if not isinstance(name, str) or not name:
        raise ValueError(f"an observation kind needs a name; {cls.__name__} has {name!r}")
    _KINDS[name] = cls()
    return cls


def _load() -> None:
    global _LOADED
    if not _LOADED:
        _LOADED = True
        importlib.import_module(BUILT_IN_KINDS)


def observation_kinds() -> dict[str, Observation]:
    """The registered kinds, name -> instance, in the order of their registration."""
    _load()
    return dict(_KINDS)


def observations() -> tuple[str, ...]:
    """The names of the registered kinds: the values ``RunConfig.observation`` may take."""
    return tuple(observation_kinds())


def observation_kind(name: str) -> Observation:
    """The registered kind ``name`` (ValueError naming the registered ones)."""
    kinds = observation_kinds()
    if name not in kinds:
        raise ValueError(f"unknown observation {name!r}; allowed: {', '.join(kinds)}")
    return kinds[name]
