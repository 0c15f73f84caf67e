"""The printed chessboard: its geometry and the part of a camera image it covers.

Board frame: corner ``k = j * cols + i`` (``i`` along the ``cols``
direction, ``j`` along ``rows``) sits at ``(i s, j s, 0) - centroid``; with the canonical
image order (corner 0 top-left in the image, ``i`` running to the right) the board's z axis
points away from the devices, so a fronto-parallel board has ``R = I``.

:func:`board_region` is the one board-region mask: the camera pixels inside the detected corners' outer
boundary (their convex hull, filled at 1/16 px), which every check, plot and fit that needs "the pixels on
the board" uses.  Finding the corners is :mod:`procam.board.corners`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ProcamError

#: Inner corners per side that a board may have (OpenCV's detectors need at least 3; 500 is far beyond
#: any printed calibration board and keeps every array small).
CORNERS_PER_SIDE = (3, 500)
#: Square sizes accepted, in the user's length unit (1e-6 .. 1e6: microns to kilometres in mm).
SQUARE_RANGE = (1e-6, 1e6)


@dataclass(frozen=True)
class Board:
    """A printed chessboard: ``cols`` x ``rows`` **inner** corners (OpenCV's ``pattern_size``; a board of
    11 x 7 squares has 10 x 6 inner corners) and the side ``square`` of a square, which is the length
    unit of every output (say mm).

    Raises :class:`~procam.errors.ProcamError` for counts outside :data:`CORNERS_PER_SIDE` or a square
    size that is not a finite number in :data:`SQUARE_RANGE`.

    >>> Board(10, 6, 24.0).object_points().shape
    (60, 3)
    """

    cols: int
    rows: int
    square: float

    def __post_init__(self):
        lo, hi = CORNERS_PER_SIDE
        for what, v in (("columns", self.cols), ("rows", self.rows)):
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not lo <= v <= hi:
                raise ProcamError(f"board {self.cols}x{self.rows}: {what} of inner corners must be an integer "
                                  f"from {lo} to {hi}, got {v!r} (count inner corners, not squares)")
        sq = self.square
        if isinstance(sq, bool) or not isinstance(sq, (int, float, np.integer, np.floating)) \
                or not math.isfinite(sq) or not SQUARE_RANGE[0] <= sq <= SQUARE_RANGE[1]:
            raise ProcamError(f"board square size must be a finite length from {SQUARE_RANGE[0]:g} to "
                              f"{SQUARE_RANGE[1]:g} (the square's side in your length unit, e.g. 24 for mm), "
                              f"got {sq!r}")
        object.__setattr__(self, "cols", int(self.cols))
        object.__setattr__(self, "rows", int(self.rows))
        object.__setattr__(self, "square", float(sq))

    @property
    def pattern_size(self) -> tuple[int, int]:
        """``(cols, rows)``, OpenCV's ``pattern_size``."""
        return self.cols, self.rows

    @property
    def n_corners(self) -> int:
        return self.cols * self.rows

    def object_points(self) -> np.ndarray:
        """(cols*rows, 3) board corners (:func:`object_points`)."""
        return object_points(self.cols, self.rows, self.square)

    def to_dict(self) -> dict:
        return {"cols": self.cols, "rows": self.rows, "square": self.square}


def object_points(cols: int, rows: int, square: float) -> np.ndarray:
    """(cols*rows, 3) board corners, row-major (``cols`` per row), centred at their centroid."""
    i, j = np.meshgrid(np.arange(cols, dtype=float), np.arange(rows, dtype=float))
    pts = np.column_stack([i.ravel() * square, j.ravel() * square, np.zeros(cols * rows)])
    pts[:, :2] -= pts[:, :2].mean(axis=0)
    return pts


def board_outline(corners) -> np.ndarray:
    """(M, 2) float vertices of the detected corners' outer boundary (their convex hull), the outline that
    :func:`board_region` fills; (0, 2) with fewer than 3 finite corners (NaN rows ignored)."""
    import cv2

    pts = np.asarray(corners, float).reshape(-1, 2)
    pts = pts[np.isfinite(pts).all(1)]
    if len(pts) < 3:
        return np.zeros((0, 2))
    return cv2.convexHull(pts.astype(np.float32)).reshape(-1, 2).astype(np.float64)


def board_region(corners, image_size, *, shrink: float = 0.0) -> np.ndarray:
    """(H, W) bool: the camera pixels inside the detected corners' outer boundary (their convex hull).

    The hull is filled at 1/16 px (OpenCV's ``fillConvexPoly`` with ``shift=4``), so the mask follows
    the sub-pixel corners rather than their whole-pixel roundings.  Every corner lies on the printed
    board, so the mask is on the board (it stops one square short of the board's outer edge).

    Parameters
    ----------
    corners : (N, 2) detected (distorted) camera corners, pixels; NaN rows ignored.
    image_size : (width, height) of the camera image.
    shrink : pull the hull towards its centroid by this fraction (0 = the hull itself; negative grows it).

    Returns
    -------
    (H, W) bool mask; all False with fewer than 3 finite corners.
    """
    import cv2

    pts = np.asarray(corners, float).reshape(-1, 2)
    pts = pts[np.isfinite(pts).all(1)]
    W, H = (int(v) for v in image_size)
    mask = np.zeros((H, W), np.uint8)
    if len(pts) < 3:
        return mask.astype(bool)
    if shrink:
        c = pts.mean(0)
        pts = c + (1.0 - float(shrink)) * (pts - c)
    hull = cv2.convexHull(np.round(pts * 16).astype(np.int32).reshape(-1, 1, 2))
    cv2.fillConvexPoly(mask, hull, 1, lineType=cv2.LINE_8, shift=4)
    return mask.astype(bool)


#: Length units a printable board may be drawn in (SVG's absolute units).
PRINT_UNITS = ("mm", "cm", "in")


def printable_svg(board: Board, unit: str = "mm", creator: str = "procam") -> str:
    """The board as an SVG page to print at true scale: ``(cols + 1) x (rows + 1)`` squares of ``board.square``
    ``unit`` (top-left square black), a white margin of one square, and its size printed under it in words
    (what to measure, that it must be printed at 100 %).  ``creator`` is written into the page's metadata.

    Raises :class:`~procam.errors.ProcamError` for a unit not in :data:`PRINT_UNITS`."""
    if unit not in PRINT_UNITS:
        raise ProcamError(f"a printable board is drawn in {', '.join(PRINT_UNITS)}, got {unit!r}")
    s, nx, ny = board.square, board.cols + 1, board.rows + 1
    lines = (f"procam chessboard: {board.cols}x{board.rows} inner corners ({nx} x {ny} squares), square {s:g} {unit}",
             "Print at 100 % (no fit to page), then measure a square and give that size.")
    text_h = min(0.35 * s, nx * s / (0.6 * max(map(len, lines))))  # the lines fit under the squares
    width, height = (nx + 2) * s, (ny + 2) * s + 3 * text_h
    rects = "".join(f'<rect x="{(i + 1) * s:g}" y="{(j + 1) * s:g}" width="{s:g}" height="{s:g}"/>'
                    for j in range(ny) for i in range(nx) if (i + j) % 2 == 0)
    text = "".join(f'<text x="{s:g}" y="{(ny + 1.5) * s + k * 1.4 * text_h:g}" font-family="sans-serif" '
                   f'font-size="{text_h:g}">{line}</text>' for k, line in enumerate(lines))
    return (f'<?xml version="1.0" encoding="UTF-8"?>\n'
            f'<svg xmlns="http://www.w3.org/2000/svg" width="{width:g}{unit}" height="{height:g}{unit}" '
            f'viewBox="0 0 {width:g} {height:g}">\n'
            f'<metadata>Creator: {creator}</metadata>\n'
            f'<rect width="{width:g}" height="{height:g}" fill="white"/>\n'
            f'<g fill="black">{rects}</g>\n{text}\n</svg>\n')
