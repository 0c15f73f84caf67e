"""Chessboard geometry and corner detection.

Board frame (METHOD §1, §7.4): corner ``k = j * cols + i`` (``i`` along the ``cols``
direction, ``j`` along ``rows``) sits at ``(i s, j s, 0) - centroid``; with the canonical
image order (corner 0 top-left in the image, ``i`` running to the right) the board's z axis
points away from the devices, so a fronto-parallel board has ``R = I``.
"""

from __future__ import annotations

import numpy as np


def object_points(cols: int, rows: int, square: float) -> np.ndarray:
    """(cols*rows, 3) board corners, row-major (``cols`` per row), centred at their centroid."""
    i, j = np.meshgrid(np.arange(cols, dtype=float), np.arange(rows, dtype=float))
    pts = np.column_stack([i.ravel() * square, j.ravel() * square, np.zeros(cols * rows)])
    pts[:, :2] -= pts[:, :2].mean(axis=0)
    return pts
