"""jax's 64-bit mode, which the float64 ground truth needs, switched on by an explicit call.

Importing ``systems`` changes no jax setting: a process that computes ground truth (the CLI,
the sweep's workers, the tests, a user's script) calls :func:`enable_x64` first, and every
function that computes float64 ground truth asks :func:`require_x64`, so that it raises
instead of silently computing in float32.
"""

from __future__ import annotations

import jax

__all__ = ["enable_x64", "require_x64"]


def enable_x64() -> None:
    """Turn on jax's 64-bit mode (``jax.config.update("jax_enable_x64", True)``). Arrays that
    models and the trainer create carry explicit dtypes, so float32 models stay float32."""
    jax.config.update("jax_enable_x64", True)


def require_x64(what: str) -> None:
    """Raise ValueError when jax's 64-bit mode is off: ``what`` computes float64 ground truth."""
    if not jax.config.jax_enable_x64:
        raise ValueError(
            f"{what} computes float64 ground truth and needs jax's 64-bit mode: call "
            'systems.enable_x64() or jax.config.update("jax_enable_x64", True) first'
        )
