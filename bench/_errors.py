"""One-line error messages for tables and the CLI."""

from __future__ import annotations


def one_line(err: BaseException, limit: int = 300) -> str:
    """The error's own message on one line.

    Equinox's runtime errors (a failed ``eqx.error_if`` or a diffrax solve inside jit) wrap
    their message in a stack dump whose first line says nothing; the line that names the
    error is the one to keep.
    """
    text = str(err)
    for line in text.splitlines():
        if "EquinoxRuntimeError:" in line or "XlaRuntimeError:" in line:
            return line.strip()[:limit]
    return f"{type(err).__name__}: {text}".replace("\n", " ").strip()[:limit]
