"""Point clouds as binary little-endian PLY, through the ``plyfile`` library (an extra: ``pip install
'procam[ply]'``; imported only when a cloud is written or read).

Vertices carry ``x, y, z`` (float32), optionally ``red, green, blue`` (uchar) and further properties; the header's
comment lines say what the numbers are.  A cloud procam writes has the comment line
:data:`procam.io.formats.PLY_COMMENT` (``procam_format procam-point-cloud``), by which
:func:`procam.io.files.procam_wrote` knows it.  Files are written atomically (:func:`procam.io.files.atomic_path`).  The table is in
``docs/exports.md``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import ProcamError
from .files import atomic_path


#: The one line said when the optional ``plyfile`` package is missing.
PLY_MISSING = "{what} PLY needs the plyfile package: pip install 'procam[ply]' (or pip install plyfile)"


def require_plyfile() -> None:
    """Raise :class:`~procam.errors.ProcamError` now, before any work, when ``plyfile`` is not installed."""
    import importlib.util

    if importlib.util.find_spec("plyfile") is None:
        raise ProcamError(PLY_MISSING.format(what="writing"))


def write_ply(path, points, colours=None, *, extra: dict | None = None, comments=()) -> Path:
    """Write a binary little-endian PLY point cloud through ``plyfile``, atomically.

    Parameters
    ----------
    path : output file (``.ply``).
    points : (N, 3) -> vertex properties ``x, y, z`` (float32).
    colours : optional (N, 3) uint8 RGB -> ``red, green, blue`` (uchar).
    extra : optional ``{name: (N,) array}`` of further vertex properties (their dtype is kept).
    comments : header comment lines (e.g. the units and the frame).  A PLY header is ASCII, one comment a line:
        other characters (a folder named ``pose é``) are written as Python's escapes (``pose \\xe9``), a line break
        as a space.

    Raises
    ------
    ProcamError
        ``plyfile`` is not installed.
    """
    try:
        from plyfile import PlyData, PlyElement
    except ImportError:
        raise ProcamError(PLY_MISSING.format(what="writing")) from None
    P = np.asarray(points, float).reshape(-1, 3)
    fields = [("x", "<f4"), ("y", "<f4"), ("z", "<f4")]
    cols = None
    if colours is not None:
        cols = np.asarray(colours).reshape(-1, 3)
        if len(cols) != len(P):
            raise ValueError(f"{len(cols)} colours for {len(P)} points")
        fields += [("red", "u1"), ("green", "u1"), ("blue", "u1")]
    extra = dict(extra or {})
    for name, arr in extra.items():
        a = np.asarray(arr).reshape(-1)
        if len(a) != len(P):
            raise ValueError(f"extra property {name!r} has {len(a)} values for {len(P)} points")
        fields.append((name, a.dtype.newbyteorder("<").str))
    vert = np.empty(len(P), dtype=fields)
    vert["x"], vert["y"], vert["z"] = P[:, 0], P[:, 1], P[:, 2]
    if cols is not None:
        vert["red"], vert["green"], vert["blue"] = cols[:, 0], cols[:, 1], cols[:, 2]
    for name, arr in extra.items():
        vert[name] = np.asarray(arr).reshape(-1)
    ply = PlyData([PlyElement.describe(vert, "vertex")], text=False, byte_order="<",
                  comments=[_ascii(c) for c in comments])
    path = Path(path)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as f:
            ply.write(f)
    return path


def _ascii(comment) -> str:
    """One comment line of a PLY header: ASCII, non-ASCII characters (and undecodable bytes of a file name) as
    backslash escapes, line breaks as spaces."""
    text = " ".join(str(comment).splitlines())
    return text.encode("ascii", "backslashreplace").decode("ascii")


def read_ply(path):
    """Read a PLY point cloud: ``(points (N, 3) float64, colours (N, 3) uint8 or None, comments)``."""
    try:
        from plyfile import PlyData
    except ImportError:
        raise ProcamError(PLY_MISSING.format(what="reading")) from None
    ply = PlyData.read(str(path))
    v = ply["vertex"].data
    pts = np.column_stack([v["x"], v["y"], v["z"]]).astype(np.float64)
    names = v.dtype.names
    cols = (np.column_stack([v["red"], v["green"], v["blue"]]).astype(np.uint8)
            if all(c in names for c in ("red", "green", "blue")) else None)
    return pts, cols, list(ply.comments)
