"""The one way a study draws and saves a figure: on the Agg backend, as PNG and PDF files.

Figures are files here, never windows, so the backend is chosen where a figure is made
(:func:`subplots`, :func:`new_figure`), not when a study is imported.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["new_figure", "save_figure", "subplots"]


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")  # a no-op when Agg is already the backend
    import matplotlib.pyplot as plt

    return plt


def subplots(*args, **kwargs):
    """``matplotlib.pyplot.subplots`` on the Agg backend."""
    return _pyplot().subplots(*args, **kwargs)


def new_figure(*args, **kwargs):
    """``matplotlib.pyplot.figure`` on the Agg backend."""
    return _pyplot().figure(*args, **kwargs)


def save_figure(fig, outdir, stem: str, *, dpi: int = 130, tight: bool = True) -> list[Path]:
    """Write ``fig`` as PNG and PDF (``tight``: cropped to its content), close it, and return
    the two paths. The bytes depend only on the figure (no creation date), so regenerating
    unchanged figures leaves git clean."""
    import matplotlib.pyplot as plt

    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    paths = [outdir / f"{stem}.{ext}" for ext in ("png", "pdf")]
    for p in paths:  # no creation date in the PDF: the same figure gives the same bytes
        meta = {"CreationDate": None} if p.suffix == ".pdf" else None
        fig.savefig(p, dpi=dpi, metadata=meta, **({"bbox_inches": "tight"} if tight else {}))
    plt.close(fig)
    return paths
