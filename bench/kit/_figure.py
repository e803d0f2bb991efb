"""The one way a study draws and saves a figure: a ``matplotlib.figure.Figure`` saved as PNG
and PDF files.

Figures are files here, never windows: they are built on ``Figure`` objects, not through
pyplot, so no backend is chosen or switched, no global figure state is kept, and a figure is
freed when its last reference goes.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["new_figure", "save_figure", "subplots"]

# the keywords of pyplot.subplots that belong to the figure, not to its axes
_FIGURE_KEYWORDS = ("figsize", "dpi", "facecolor", "edgecolor", "layout", "constrained_layout",
                    "tight_layout", "frameon", "linewidth")  # fmt: skip


def subplots(nrows: int = 1, ncols: int = 1, **kwargs):
    """``(fig, axes)`` as ``matplotlib.pyplot.subplots`` returns them, on a new ``Figure``."""
    fig = new_figure(**{k: kwargs.pop(k) for k in _FIGURE_KEYWORDS if k in kwargs})
    return fig, fig.subplots(nrows, ncols, **kwargs)


def new_figure(*args, **kwargs):
    """A new ``matplotlib.figure.Figure`` (the arguments of ``Figure``) on an Agg canvas, as
    pyplot would give it (layouts that measure text, tight boxes and images read its
    renderer)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(*args, **kwargs)
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig, outdir, stem: str, *, dpi: int = 130, tight: bool = True) -> list[Path]:
    """Write ``fig`` as PNG and PDF (``tight``: cropped to its content) and return the two
    paths. The bytes depend only on the figure (no creation date), so regenerating unchanged
    figures leaves git clean."""
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    paths = [outdir / f"{stem}.{ext}" for ext in ("png", "pdf")]
    for p in paths:  # no creation date in the PDF: the same figure gives the same bytes
        meta = {"CreationDate": None} if p.suffix == ".pdf" else None
        fig.savefig(p, dpi=dpi, metadata=meta, **({"bbox_inches": "tight"} if tight else {}))
    return paths
