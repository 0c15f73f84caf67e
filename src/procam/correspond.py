"""Camera corners -> projector corners by local homographies (Moreno & Taubin).

For each chessboard corner, the decoded pixels in a window around it give a camera -> projector
homography that is valid locally; the corner's projector coordinates are its image under it.
Every corner carries its own diagnostics, and a corner that fails is NaN with a reason, so a
partially lit board, or one near the image border, still gives the corners it can.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .decode import DecodeResult

#: Per-corner reason codes (``diagnostics["reason"]``).
CORNER_REASONS = {
    0: "ok",
    1: "corner not detected in the camera image",
    2: "too few decoded pixels in the window (unlit, shadowed or low contrast)",
    3: "window leaves the image",
    4: "poor local homography fit (residual above max_residual)",
    5: "homography estimation failed",
}
ESTIMATORS = ("lsq", "ransac", "lmeds")


@dataclass(frozen=True)
class CornerOptions:
    """Local-homography options (defaults measured in ``benchmarks/correspond.py``).

    window : int, camera pixels — side of the square window around each corner (Moreno: 60).
    estimator : ``"lsq"`` | ``"ransac"`` | ``"lmeds"`` — how the homography is fitted
        (``cv2.findHomography`` methods 0, RANSAC, LMEDS).
    ransac_threshold : float, projector pixels — RANSAC inlier threshold (Moreno: 3).
    min_valid_fraction : float — minimum fraction of the window's pixels with a decoded column
        and row (25 %, as the paper).
    max_residual : float, projector pixels — a corner whose fit RMS over the inliers exceeds it fails.
    """

    window: int = 60
    estimator: str = "ransac"
    ransac_threshold: float = 3.0
    min_valid_fraction: float = 0.25
    max_residual: float = 2.0

    def __post_init__(self):
        if self.estimator not in ESTIMATORS:
            raise ValueError(f"estimator must be one of {ESTIMATORS}, got {self.estimator!r}")
        if self.window < 6:
            raise ValueError(f"window must be at least 6 px, got {self.window}")


def projector_corners(cam_pts: np.ndarray, maps: DecodeResult, options: CornerOptions = CornerOptions()):
    """Projector coordinates of camera corners by local homographies.

    Parameters
    ----------
    cam_pts : (N, 2) float — camera corners (distorted pixels; NaN rows are skipped).
    maps : :class:`~procam.decode.DecodeResult` of the same pose.
    options : :class:`CornerOptions`.

    Returns
    -------
    proj_pts : (N, 2) float64, NaN where a corner failed.
    diagnostics : dict of (N,) arrays — ``reason`` (uint8, :data:`CORNER_REASONS`), ``pixels``
        (decoded pixels in the window), ``window_pixels`` (pixels of the window inside the image),
        ``inliers`` and ``residual_px`` (RMS of the fit over the inliers, projector pixels).
    """
    import cv2

    cam_pts = np.asarray(cam_pts, float).reshape(-1, 2)
    n = len(cam_pts)
    H, W = maps.col.shape
    half = options.window // 2
    full_area = (2 * half) ** 2
    proj = np.full((n, 2), np.nan)
    reason = np.zeros(n, np.uint8)
    pixels = np.zeros(n, np.int32)
    wpix = np.zeros(n, np.int32)
    inliers = np.zeros(n, np.int32)
    resid = np.full(n, np.nan)
    valid = maps.valid
    method = {"lsq": 0, "ransac": cv2.RANSAC, "lmeds": cv2.LMEDS}[options.estimator]
    for k, (x, y) in enumerate(cam_pts):
        if not (np.isfinite(x) and np.isfinite(y)):
            reason[k] = 1
            continue
        cx, cy = int(round(x)), int(round(y))
        x0, x1 = max(0, cx - half), min(W, cx + half)
        y0, y1 = max(0, cy - half), min(H, cy + half)
        wpix[k] = max(0, x1 - x0) * max(0, y1 - y0)
        if wpix[k] < options.min_valid_fraction * full_area or not (0 <= x < W - 1 and 0 <= y < H - 1):
            reason[k] = 3
            continue
        v = valid[y0:y1, x0:x1]
        pixels[k] = int(v.sum())
        if pixels[k] < max(8, options.min_valid_fraction * full_area):
            reason[k] = 2
            continue
        yy, xx = np.nonzero(v)
        src = np.column_stack([xx + x0, yy + y0]).astype(np.float64)
        dst = np.column_stack([maps.col[y0:y1, x0:x1][v], maps.row[y0:y1, x0:x1][v]]).astype(np.float64)
        # centre the coordinates for a well-conditioned fit
        so, do = np.array([x, y]), dst.mean(0)
        if method == 0:
            Hm, mask = cv2.findHomography(src - so, dst - do, 0)
        else:
            Hm, mask = cv2.findHomography(src - so, dst - do, method, options.ransac_threshold)
        if Hm is None or not np.all(np.isfinite(Hm)):
            reason[k] = 5
            continue
        inl = mask.ravel().astype(bool) if mask is not None else np.ones(len(src), bool)
        inliers[k] = int(inl.sum())
        ph = np.column_stack([src - so, np.ones(len(src))]) @ Hm.T
        pred = ph[:, :2] / ph[:, 2:3]
        e = pred[inl] - (dst[inl] - do)
        resid[k] = float(np.sqrt(np.mean(np.sum(e * e, axis=1)))) if inl.any() else np.inf
        if inliers[k] < 8 or resid[k] > options.max_residual:
            reason[k] = 4
            continue
        p = Hm @ np.array([0.0, 0.0, 1.0])
        proj[k] = p[:2] / p[2] + do
    return proj, {"reason": reason, "pixels": pixels, "window_pixels": wpix, "inliers": inliers,
                  "residual_px": resid}


def reason_summary(reason: np.ndarray) -> str:
    """``"3 too few decoded pixels ..., 1 window leaves the image"`` for the failed corners."""
    counts = np.bincount(np.asarray(reason, int), minlength=len(CORNER_REASONS))
    parts = [f"{c} {CORNER_REASONS[k]}" for k, c in enumerate(counts) if k and c]
    return ", ".join(parts) if parts else "none failed"


def background_points(maps: DecodeResult, board_cam_pts: np.ndarray, *, margin: float = 2.0,
                      max_points: int = 3000, max_dropped: int | None = None):
    """Decoded pixels off the board (wall, table behind it) and their projector coordinates.

    Only pixels decoded in **both** column and row are kept: a column alone fixes no epipolar
    constraint (a camera pixel's epipolar line crosses every projector column once), so it says
    nothing about the camera-projector geometry.

    Parameters
    ----------
    maps : :class:`~procam.decode.DecodeResult` of the pose.
    board_cam_pts : (N, 2) camera corners of the board (distorted pixels; NaN rows ignored).
    margin : how far beyond the convex hull of the corners the board is assumed to extend, in
        squares (the square size is the 90th percentile of the corners' nearest-neighbour distances in
        pixels); the default 2 covers the outer squares and a white border of up to one square.
    max_points : the kept pixels are subsampled on a regular grid (the same step in x and y) to at
        most about this many.
    max_dropped : keep only pixels with at most this many uncertain finest bits in each axis
        (``maps.dropped_col`` / ``dropped_row``); None keeps all decoded pixels.

    Returns
    -------
    cam_pts : (M, 2) float64 camera pixel centres (x, y), distorted.
    proj_pts : (M, 2) float64 decoded projector (column, row) there.
    Both are empty (0, 2) when there are no corners or nothing outside the board is decoded.
    """
    import cv2

    H, W = maps.col.shape
    c = np.asarray(board_cam_pts, float).reshape(-1, 2)
    c = c[np.isfinite(c).all(1)]
    empty = np.zeros((0, 2))
    if len(c) < 3 or not (np.isfinite(margin) and margin >= 0) or int(max_points) < 1:
        return empty, empty.copy()
    d = np.linalg.norm(c[:, None, :] - c[None, :, :], axis=2)
    np.fill_diagonal(d, np.inf)
    square = float(np.percentile(d.min(axis=1), 90))
    outside = np.ones((H, W), np.uint8)
    cv2.fillConvexPoly(outside, np.round(cv2.convexHull(c.astype(np.float32))).astype(np.int32), 0)
    # distance (px) of every pixel outside the hull to the hull
    dist = cv2.distanceTransform(outside, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    ok = maps.valid_col & maps.valid_row & (dist > margin * square)
    if max_dropped is not None:
        for dropped in (maps.dropped_col, maps.dropped_row):
            if dropped is not None:
                ok &= dropped <= max_dropped
    n = int(ok.sum())
    if n == 0:
        return empty, empty.copy()
    step = max(1, int(np.ceil(np.sqrt(n / int(max_points)))))
    grid = np.zeros_like(ok)
    grid[step // 2::step, step // 2::step] = True
    ok &= grid
    yy, xx = np.nonzero(ok)
    cam = np.column_stack([xx, yy]).astype(np.float64)
    proj = np.column_stack([maps.col[ok], maps.row[ok]]).astype(np.float64)
    return cam, proj
