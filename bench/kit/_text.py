"""The report's text conventions, shared by the report and the sections the studies register:
numbers to three significant figures, Markdown table cells, and folders named as the report
names them (relative to ``results/``, so a committed report holds no machine's paths)."""

from __future__ import annotations

import math
from pathlib import Path

from ..core import REFERENCE_ROOT

__all__ = ["fmt", "folder_label", "md_escape"]


def fmt(x, digits: int = 3) -> str:
    """``x`` to ``digits`` significant figures; ``-`` for a missing or non-finite value."""
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    return f"{x:.{digits}g}"


def md_escape(text: str) -> str:
    """``text`` as one cell of a Markdown table (pipes escaped, one line)."""
    return str(text).replace("|", "\\|").replace("\n", " ")


def folder_label(d: Path) -> str:
    """A folder as the report names it: relative to ``results/`` where it lies under it."""
    try:
        return str(Path(d).resolve().relative_to(REFERENCE_ROOT.parent))
    except ValueError:
        return Path(d).name
