"""The vocabularies of a run's fields and the checks of single values, shared by
:class:`~bench.core._config.RunConfig` and its users: each allowed set of names (that of
``observation`` read from the registry of observation kinds, :mod:`bench.core._observation`),
the pixel runs' sizes and starts, and one-line errors naming what is allowed."""

from __future__ import annotations

import difflib
import hashlib
import json
import math
from collections.abc import Mapping, Sequence

from ._observation import observations

COORDINATES = ("velocity", "momentum")
LOSSES = ("l1", "l2")
DTYPES = ("float32", "float64")
TRAIN_TARGETS = ("rollout", "derivative")
OPTIMIZERS = ("adamw", "adam_l2", "adam_l2_clip")  # bench.core._optim.optimizer
LR_SCHEDULES = ("cosine", "onecycle", "constant")  # bench.core._optim.lr_schedule
# A pixel run's data (the HNN seed's task 5): frames of PIXEL_SIZE x PIXEL_SIZE pixels, starts
# |q0| < PIXEL_MAX_ANGLE (the seed's pi/6), qdot0 ~ U(-PIXEL_MAX_SPEED, PIXEL_MAX_SPEED)
# (Pendulum-v0's reset).
PIXEL_SIZE = 28
PIXEL_MAX_ANGLE = math.pi / 6
PIXEL_MAX_SPEED = 1.0
# The VIN seed's pixel task (observation "frames": single frames, each encoded to a position):
# its starts |q0| in [pi/2, pi - 0.1] with either sign, qdot0 ~ U(-1, 1) (the authors' code,
# steindoringi/Variational_Integrator_Networks, systems.py), far from rest so that the frames
# go round most of the circle.
FRAMES_ANGLES = (math.pi / 2, math.pi - 0.1)


def _frozen(v):
    """Lists (as JSON gives them back) as tuples, so that a configuration is hashable."""
    return tuple(_frozen(x) for x in v) if isinstance(v, list | tuple) else v


def _is_missing(v) -> bool:
    return v is None or (isinstance(v, float) and math.isnan(v))


def _as_int(v, name):
    if isinstance(v, bool):
        raise ValueError(f"{name} must be an integer; got {v!r}")
    try:
        f = float(v)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be an integer; got {v!r}") from None
    if not f.is_integer():
        raise ValueError(f"{name} must be an integer; got {v!r}")
    return int(f)


def _as_float(v, name):
    if isinstance(v, bool):
        raise ValueError(f"{name} must be a number; got {v!r}")
    try:
        return float(v)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number; got {v!r}") from None


def _hash(d: Mapping) -> str:
    text = json.dumps(d, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def check_choice(what: str, value, allowed: Sequence[str]) -> None:
    """Raise ``ValueError("unknown <what> 'x'; allowed: ... (did you mean 'y'?)")``."""
    allowed = list(allowed)
    if value in allowed:
        return
    msg = f"unknown {what} {value!r}; allowed: {', '.join(map(str, allowed))}"
    close = difflib.get_close_matches(str(value), [str(a) for a in allowed], n=1)
    if close:
        msg += f" (did you mean {close[0]!r}?)"
    raise ValueError(msg)


def __getattr__(name: str):
    # OBSERVATIONS, the names of the registered observation kinds, read when asked for: a kind
    # registered after this module's import is in it
    if name == "OBSERVATIONS":
        return observations()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
