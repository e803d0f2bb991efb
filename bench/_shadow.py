"""Whether a file of the folder Python started in hides one of the suite's packages.

``python -m bench`` puts the current folder first on ``sys.path``: a ``models.py`` or
``systems.py`` there (a researcher's own) is imported in place of the suite's ``models`` or
``systems``, and the first name the suite asks of it fails with a bare ImportError far from the
cause. :func:`check` runs before the package imports anything and names the cause in one line.
Standard library only: it must work when the suite's own imports would not.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

PACKAGES = ("models", "systems")  # the suite's top-level packages beside bench
CONSOLE_SCRIPT = "decon-bench"  # pyproject.toml [project.scripts]: bench._cli:main


def shadowing() -> str | None:
    """One line naming the first of :data:`PACKAGES` that ``import`` would take from somewhere
    other than the suite's folder (what shadows what, and what to do), or None."""
    home = Path(__file__).resolve().parents[1]
    for name in PACKAGES:
        try:
            spec = importlib.util.find_spec(name)  # finds, does not import
        except (ImportError, ValueError):
            continue
        places = [spec.origin] if spec and spec.has_location else []
        places += list(spec.submodule_search_locations or []) if spec else []
        if not places:  # missing altogether: the import's own error says so
            continue
        where, own = Path(places[0]).resolve(), home / name
        if where == own or own in where.parents:
            continue
        return (
            f"{where} shadows the suite's package {name!r} ({own}): Python puts the folder it "
            f"starts in first on the import path; run from another folder, or use the console "
            f"script {CONSOLE_SCRIPT} (e.g. {CONSOLE_SCRIPT} list)"
        )
    return None


def check() -> None:
    """Stop early where :func:`shadowing` finds a package hidden: under ``python -m bench``
    (the package imported while ``sys.argv[0]`` is still ``-m``) with that one line on stderr
    and exit code 2; on a plain ``import bench``, with an ImportError saying the same."""
    problem = shadowing()
    if problem is None:
        return
    if sys.argv[:1] == ["-m"]:
        print(f"error: {problem}", file=sys.stderr)
        raise SystemExit(2)
    raise ImportError(problem)
