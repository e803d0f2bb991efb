"""Validators of the models' ``make`` options: each returns the checked value or raises a
one-line ValueError naming what is allowed."""

from __future__ import annotations


def _positive_float(name):
    def check(x):
        if isinstance(x, bool) or not isinstance(x, int | float) or not x >= 0:
            raise ValueError(f"option {name} must be a number >= 0, got {x!r}")
        return float(x)

    return check


def _choice(name, allowed):
    def check(x):
        if x not in allowed:
            raise ValueError(f"option {name} must be one of {allowed}, got {x!r}")
        return x

    return check


def _strictly_positive_float(name):
    def check(x):
        if isinstance(x, bool) or not isinstance(x, int | float) or not x > 0:
            raise ValueError(f"option {name} must be a number > 0, got {x!r}")
        return float(x)

    return check


def _positive_int(name):
    def check(x):
        if isinstance(x, bool) or not isinstance(x, int) or x < 1:
            raise ValueError(f"option {name} must be an int >= 1, got {x!r}")
        return x

    return check


def _boolean(name):
    def check(x):
        if not isinstance(x, bool):
            raise ValueError(f"option {name} must be True or False, got {x!r}")
        return x

    return check
