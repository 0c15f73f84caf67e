"""Figures (the only package that imports matplotlib, and only inside its functions).

Every function builds a :class:`matplotlib.figure.Figure` directly (no pyplot) and returns it;
:func:`save_figure` writes it.  Nothing here selects a backend or touches matplotlib's global
state: importing :mod:`procam.plots` imports no matplotlib at all, and drawing a figure leaves a
notebook's or an application's backend as it was.
"""

from __future__ import annotations

import sys
from pathlib import Path

__all__ = ["save_figure", "printable"]


def _figure(**kwargs):
    """A :class:`matplotlib.figure.Figure` not registered with pyplot (``kwargs`` go to ``Figure``).

    Figures made this way need no GUI backend and are freed when no longer referenced.
    """
    from matplotlib.figure import Figure

    return Figure(**kwargs)


def _close(fig) -> None:
    """Close ``fig`` if pyplot manages it (a figure made with ``plt.subplots``); others need nothing."""
    plt = sys.modules.get("matplotlib.pyplot")
    if plt is not None:
        plt.close(fig)


def printable(fig):
    """``fig`` with every text drawable: the bytes of a file name that no encoding decodes (lone surrogates, which
    matplotlib's fonts refuse) shown as escapes (:func:`procam.style.shown`).  Called before a figure is drawn to
    a file or an image; returns ``fig``."""
    from matplotlib.text import Text

    from ..style import shown

    for t in fig.findobj(Text):
        s = t.get_text()
        if isinstance(s, str):
            t.set_text(shown(s))
    return fig


def save_figure(fig, path, dpi: int = 110) -> Path:
    """Save ``fig`` to ``path`` atomically (hidden temporary name, then rename) and close it.

    Parameters
    ----------
    fig : matplotlib Figure (made by this package, or by pyplot: then it is closed too).
    path : output file; its suffix picks the format (``.png``, ``.pdf``, ``.svg``, ... - whatever
        matplotlib can write without a GUI).
    dpi : resolution of raster formats (dots per inch).

    Returns
    -------
    The path written.

    Raises
    ------
    ProcamError : the suffix is missing or not a format matplotlib can write (the figure is closed).
    """
    from ..errors import ProcamError
    from ..io.files import atomic_path
    from ..io.formats import PNG_TEXT_KEY, SOFTWARE

    path = Path(path)
    fmt = path.suffix.lstrip(".").lower()
    supported = fig.canvas.get_supported_filetypes()
    if fmt not in supported:
        _close(fig)
        what = f"unsupported figure format '.{fmt}'" if fmt else "no suffix to choose the figure format from"
        raise ProcamError(f"{path}: {what}; give a file name ending in one of "
                          f"{', '.join('.' + k for k in sorted(supported))}")
    try:
        # procam's mark (so a later run knows it may overwrite the file) and no dates: the same figure, the same bytes
        meta = {"png": {PNG_TEXT_KEY: SOFTWARE}, "pdf": {"Creator": SOFTWARE, "CreationDate": None},
                "svg": {"Creator": SOFTWARE, "Date": None}, "ps": {"Creator": SOFTWARE},
                "eps": {"Creator": SOFTWARE}}.get(fmt)
        import matplotlib

        # SVG element ids come from a random salt unless one is given
        with atomic_path(path) as tmp, matplotlib.rc_context({"svg.hashsalt": "procam"}):
            extra = {"metadata": meta} if meta else {}
            if fmt in ("jpg", "jpeg"):  # JPEG has no metadata dict in matplotlib: the mark is a comment segment
                extra = {"pil_kwargs": {"comment": SOFTWARE.encode()}}
            printable(fig).savefig(tmp, dpi=dpi, format=fmt, **extra)
    finally:
        _close(fig)
    return path
