"""The one way a study saves a figure: ``<outdir>/<stem>.png`` and ``.pdf``, then closed."""

from __future__ import annotations

from pathlib import Path

__all__ = ["save_figure"]


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
