"""Validation of system parameters at the public boundary (one-line ValueErrors)."""

from __future__ import annotations

import math
import numbers

import numpy as np


def check_count(name: str, value) -> int:
    """An integer >= 1 (bools rejected)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 1:
        raise ValueError(f"{name} must be an integer >= 1; got {value!r}")
    return int(value)


def check_real(name: str, value) -> float:
    """A finite real number."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise ValueError(f"{name} must be a finite real number; got {value!r}")
    return float(value)


def check_nonneg(name: str, value) -> float:
    """A finite real number >= 0."""
    value = check_real(name, value)
    if value < 0:
        raise ValueError(f"{name} must be a finite number >= 0; got {value!r}")
    return value


def check_positive(name: str, value) -> float:
    """A finite real number > 0."""
    value = check_real(name, value)
    if value <= 0:
        raise ValueError(f"{name} must be a finite number > 0; got {value!r}")
    return value


def check_positive_values(name: str, values, k: int) -> np.ndarray:
    """k finite positive reals."""
    try:
        arr = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{name} must be {k} finite positive numbers; got {values!r}") from e
    if arr.shape != (k,):
        raise ValueError(
            f"{name} must be {k} finite positive numbers (one per body); got {arr.shape}"
        )
    if not np.all(np.isfinite(arr)) or not np.all(arr > 0):
        raise ValueError(f"{name} must be {k} finite positive numbers; got {arr.tolist()}")
    return arr
