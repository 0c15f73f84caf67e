"""Figures (the only package that imports matplotlib; always the Agg backend)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

__all__ = ["save_figure"]


def save_figure(fig, path, dpi: int = 110) -> Path:
    """Save ``fig`` to ``path`` atomically (hidden temporary name, then rename) and close it.

    Parameters
    ----------
    fig : matplotlib Figure.
    path : output file; its suffix picks the format (``.png``, ``.pdf``, ``.svg``, ... - whatever
        matplotlib's Agg canvas supports).
    dpi : resolution of raster formats (dots per inch).

    Returns
    -------
    The path written.

    Raises
    ------
    ProcamError : the suffix is missing or not a format matplotlib can write (the figure is closed).
    """
    import matplotlib.pyplot as plt

    from ..errors import ProcamError
    from .._files import atomic_path

    path = Path(path)
    fmt = path.suffix.lstrip(".").lower()
    supported = fig.canvas.get_supported_filetypes()
    if fmt not in supported:
        plt.close(fig)
        what = f"unsupported figure format '.{fmt}'" if fmt else "no suffix to choose the figure format from"
        raise ProcamError(f"{path}: {what}; give a file name ending in one of "
                          f"{', '.join('.' + k for k in sorted(supported))}")
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=dpi, format=fmt)
    finally:
        plt.close(fig)
    return path
