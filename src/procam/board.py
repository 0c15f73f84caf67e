"""Chessboard geometry and corner detection.

Board frame: corner ``k = j * cols + i`` (``i`` along the ``cols``
direction, ``j`` along ``rows``) sits at ``(i s, j s, 0) - centroid``; with the canonical
image order (corner 0 top-left in the image, ``i`` running to the right) the board's z axis
points away from the devices, so a fronto-parallel board has ``R = I``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .errors import ProcamError

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


DETECTORS = ("auto", "classic", "sb")


def to_gray8(image: np.ndarray) -> np.ndarray:
    """8-bit grey copy of an image (uint8/uint16, grey or BGR), contrast-stretched to the
    0.5–99.5 percentiles so dim or 16-bit frames detect like well-exposed ones."""
    import cv2

    img = np.asarray(image)
    if img.ndim == 3:
        img = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY if img.shape[2] == 3 else cv2.COLOR_BGRA2GRAY)
    img = img.astype(np.float32)
    lo, hi = np.percentile(img, [0.5, 99.5])
    if hi <= lo:
        return np.zeros(img.shape, np.uint8)
    return np.clip((img - lo) * (255.0 / (hi - lo)), 0, 255).astype(np.uint8)


def canonical_order(corners: np.ndarray, cols: int, rows: int) -> np.ndarray:
    """Reorder detected corners (cols*rows, 2) into procam's canonical order.

    The grid keeps ``cols`` corners per row.  The order is made right-handed in the image
    (the ``i`` direction turned clockwise gives the ``j`` direction, so the board's z axis points
    away from the camera), and of the two right-handed orders the one whose corner 0 is nearest
    the image's top-left corner is kept.  For a square grid (cols == rows) the four rotations
    are considered.
    """
    g = np.asarray(corners, float).reshape(rows, cols, 2)
    cands = []
    variants = [g, g[::-1, ::-1], g[::-1, :], g[:, ::-1]]
    if cols == rows:
        variants += [np.transpose(v, (1, 0, 2)) for v in variants]
    for v in variants:
        di = v[:, -1].mean(0) - v[:, 0].mean(0)
        dj = v[-1, :].mean(0) - v[0, :].mean(0)
        if di[0] * dj[1] - di[1] * dj[0] > 0:  # right-handed with y down
            cands.append(v)
    best = min(cands, key=lambda v: v[0, 0].sum())
    return best.reshape(-1, 2).copy()


def detect_corners(image: np.ndarray, pattern_size: tuple[int, int], *, detector: str = "auto",
                   refine_window: int = 11) -> np.ndarray | None:
    """Find the inner corners of a chessboard in one image.

    Parameters
    ----------
    image : (H, W) or (H, W, 3) uint8/uint16
    pattern_size : (cols, rows) of inner corners (OpenCV's ``pattern_size``).
    detector : ``"classic"`` (``findChessboardCorners`` with adaptive threshold and normalisation),
        ``"sb"`` (``findChessboardCornersSB``, exhaustive + accuracy flags: slower, more tolerant of
        blur and uneven light) or ``"auto"`` (classic, then SB if classic fails).  Either way the
        corners are then refined with ``cornerSubPix``.
    refine_window : half-size of the ``cornerSubPix`` window in pixels (0 = none; clamped to half the
        corner spacing).  Default 11 (OpenCV's ``winSize=(11, 11)``, a 23x23 window), the measured best
        on rendered captures (``benchmarks/correspond.py``).

    Returns
    -------
    (cols*rows, 2) float64 corners in canonical order (see :func:`canonical_order`), or None.
    """
    import cv2

    cols, rows = int(pattern_size[0]), int(pattern_size[1])
    g8 = to_gray8(image)
    if detector == "auto":
        c = detect_corners(image, pattern_size, detector="classic", refine_window=refine_window)
        return c if c is not None else detect_corners(image, pattern_size, detector="sb",
                                                      refine_window=refine_window)
    if detector == "sb":
        flags = cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY
        ok, c = cv2.findChessboardCornersSB(g8, (cols, rows), flags=flags)
    elif detector == "classic":
        flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
        ok, c = cv2.findChessboardCorners(g8, (cols, rows), flags=flags)
    else:
        raise ValueError(f"detector must be one of {DETECTORS}, got {detector!r}")
    if not ok or c is None or len(c) != cols * rows:
        return None
    c = c.reshape(-1, 1, 2).astype(np.float32)
    if refine_window and refine_window > 0:
        # keep the window inside half the smallest corner spacing, or it would lock onto a neighbour
        spacing = np.min(np.linalg.norm(np.diff(c.reshape(rows, cols, 2), axis=1), axis=2)) if cols > 1 else 1e9
        win = int(max(2, min(refine_window, spacing / 2 - 1)))
        crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_MAX_ITER, 50, 0.001)
        c = cv2.cornerSubPix(g8, c, (win, win), (-1, -1), crit)
    return canonical_order(c.reshape(-1, 2).astype(np.float64), cols, rows)
