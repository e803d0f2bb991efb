"""The registry of systems: ``available()`` and ``make(name, **params)``."""

from __future__ import annotations

import difflib
import inspect
from collections.abc import Callable

from ._base import AbstractSystem
from ._chain import chain_pendulum
from ._magnet import magnet_pendulum
from ._mass_spring import mass_spring
from ._pendulum import pendulum
from ._relativistic import relativistic_particle
from ._rigid import gyroscope, rotor
from ._spring import spring_pendulum
from ._three_body import three_body
from ._two_body import two_body

DAMPED_FRICTION = 0.4  # the paper's damped runs

_FACTORIES: dict[str, tuple[Callable[..., AbstractSystem], dict]] = {
    "chain_pendulum": (chain_pendulum, {}),
    "spring_pendulum": (spring_pendulum, {}),
    "relativistic_particle": (relativistic_particle, {}),
    "damped_chain_pendulum": (chain_pendulum, {"friction": DAMPED_FRICTION}),
    "damped_spring_pendulum": (spring_pendulum, {"friction": DAMPED_FRICTION}),
    # the HNN seed's tasks
    "mass_spring": (mass_spring, {}),
    "pendulum": (pendulum, {}),
    "two_body": (two_body, {}),
    "three_body": (three_body, {}),
    # the Deconstructing paper's App. D.2 systems (Finzi et al. 2020)
    "gyroscope": (gyroscope, {}),
    "rotor": (rotor, {}),
    "magnet_pendulum": (magnet_pendulum, {}),
}


def available() -> list[str]:
    """Names accepted by :func:`make` (the damped_* names are aliases with friction 0.4)."""
    return sorted(_FACTORIES)


def parameters(name: str) -> list[str]:
    """Keyword parameters accepted by ``make(name, ...)``."""
    factory, _ = _lookup(name)
    return list(inspect.signature(factory).parameters)


def _lookup(name):
    if not isinstance(name, str) or name not in _FACTORIES:
        close = difflib.get_close_matches(str(name), list(_FACTORIES), n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise ValueError(f"unknown system {name!r}{hint}; available: {', '.join(available())}")
    return _FACTORIES[name]


def make(name: str, **params) -> AbstractSystem:
    """Build a registered system; ValueError for an unknown name or a bad parameter."""
    factory, defaults = _lookup(name)
    sig = inspect.signature(factory)
    unknown = sorted(set(params) - set(sig.parameters))
    if unknown:
        raise ValueError(
            f"unknown parameter(s) {', '.join(unknown)} for {name}; "
            f"allowed: {', '.join(sig.parameters)}"
        )
    missing = [
        p.name
        for p in sig.parameters.values()
        if p.default is inspect.Parameter.empty and p.name not in params
    ]
    if missing:
        raise ValueError(f"{name} needs parameter(s) {', '.join(missing)} (e.g. k=2)")
    return factory(**{**defaults, **params})
