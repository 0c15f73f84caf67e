"""Dense correspondences from the decoded maps: window means on the board and on the scene behind it.

Every decoded camera pixel pairs a camera position with a projector coordinate: tens of thousands per pose, where
the corners give 60. A single pixel's Gray-code coordinate is an integer (the projector pixel that lit it), so its
error is a sawtooth of the position that camera and projector grids turn into moire: fitted pixel by pixel, it
biases a projector's principal point by several of its own standard deviations. The mean of the decoded
coordinates over a small square window (``window`` camera pixels a side, every pixel decoded in column and row)
averages that sawtooth over many projector pixels, and at the window's centre it equals the local plane through
the coordinates, so one **sample** per window is the window-centre's projector coordinate to a small fraction of a
pixel. Windows are laid on a grid with the window's own pitch, so neighbouring samples share no pixel and their
errors are close to independent.

A window whose coordinates are not one plane -- it straddles an edge (board and wall, an object in front of the
wall), holds a decoding error or an interreflection -- is left out: the RMS of the coordinates about the window's
least-squares plane must stay under ``max_residual_px``. Each sample carries the noise of its mean
(``sigma``: that RMS over the square root of the window's pixel count, at least ``floor_px``), a relative weight;
the fits measure the absolute noise from their own residuals.

* **board samples**: windows wholly inside the corners' outer boundary (:func:`procam.board.board_region`),
  shrunk by half a window, so every sample lies on the board's plane;
* **background samples**: windows wholly outside the board grown by ``margin`` squares (the outer squares and
  the white border), so no sample lies on the board.
"""

from __future__ import annotations

import numpy as np

from ..board import board_region
from ..view import Samples

#: Default window side (camera pixels) of a sample.
WINDOW = 11


def _box(a, k):
    import cv2

    return cv2.boxFilter(a, cv2.CV_64F, (k, k), normalize=False, borderType=cv2.BORDER_CONSTANT)


def window_means(col, row, valid, region, *, window: int = WINDOW, min_fraction: float = 0.7,
                 max_residual_px: float = 1.0, floor_px: float = 0.005, noise=None) -> Samples:
    """One sample per ``window`` x ``window`` camera pixels inside ``region`` with enough decoded pixels.

    Each window's decoded pixels get a least-squares plane per projector axis (``coordinate = a + b dx + c dy``
    about the window's centre); the sample is the plane at the centre, ``a`` -- the plain mean when every pixel is
    decoded.

    Parameters
    ----------
    col, row : (H, W) decoded projector coordinates (NaN where not decoded).
    valid : (H, W) bool, decoded in column and row.
    region : (H, W) bool, where samples may lie (every pixel of a window must be in it).
    window : odd side of the window, camera pixels (>= 3).
    min_fraction : the fraction of a window's pixels that must be decoded (scattered undecoded pixels, e.g. on the
        board's dark squares, do not cost the window).
    max_residual_px : a window whose coordinates leave their plane by more than this RMS (projector pixels, either
        axis) is no sample.
    floor_px : the smallest per-sample noise (px).
    noise : optional (H, W) per-pixel noise of the decoded coordinate (px; a phase decode's), propagated into the
        sample's ``sigma`` instead of the plane's scatter where given.

    Returns
    -------
    :class:`procam.view.Samples` with the window centres (distorted camera pixels), the planes' values there, and
    ``sigma`` (M,) per sample (px).
    """
    import cv2

    k = int(window)
    if k < 3 or k % 2 == 0:
        raise ValueError(f"window must be an odd number of pixels >= 3, got {window}")
    H, W = valid.shape
    reg = np.asarray(region, bool)
    ok = np.asarray(valid, bool) & reg & np.isfinite(col) & np.isfinite(row)
    inside = cv2.erode(reg.astype(np.uint8), np.ones((k, k), np.uint8), borderType=cv2.BORDER_CONSTANT,
                       borderValue=0) > 0
    h = k // 2
    ys, xs = np.mgrid[h:H - h:k, h:W - h:k]
    okf = ok.astype(np.float64)
    n_all = _box(okf, k)
    keep = inside[ys, xs] & (n_all[ys, xs] >= max(6.0, min_fraction * k * k))
    ys, xs = ys[keep], xs[keep]
    empty = Samples(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0), window=k)
    if len(xs) == 0:
        return empty
    X = np.broadcast_to(np.arange(W, dtype=np.float64), (H, W))
    Y = np.broadcast_to(np.arange(H, dtype=np.float64)[:, None], (H, W))
    xc, yc = xs.astype(np.float64), ys.astype(np.float64)

    def at(a):
        return _box(a, k)[ys, xs]

    # moments of the decoded pixels about each window's centre
    n = n_all[ys, xs]
    sx, sy = at(okf * X) - xc * n, at(okf * Y) - yc * n
    sxx = at(okf * X * X) - 2 * xc * at(okf * X) + xc * xc * n
    syy = at(okf * Y * Y) - 2 * yc * at(okf * Y) + yc * yc * n
    sxy = at(okf * X * Y) - xc * at(okf * Y) - yc * at(okf * X) + xc * yc * n
    A = np.stack([np.stack([n, sx, sy], -1), np.stack([sx, sxx, sxy], -1), np.stack([sy, sxy, syy], -1)], -2)
    means, rss = [], np.zeros(len(xs))
    for values in (col, row):
        v = np.where(ok, values, 0.0).astype(np.float64)
        sv = at(v)
        svx = at(v * X) - xc * sv
        svy = at(v * Y) - yc * sv
        svv = at(v * v)
        rhs = np.stack([sv, svx, svy], -1)
        theta = np.linalg.solve(A, rhs[..., None])[..., 0]
        rss += np.maximum(svv - np.sum(theta * rhs, -1), 0.0)
        means.append(theta[:, 0])
    res_rms = np.sqrt(rss / (2 * np.maximum(n - 3, 1)))          # per axis, about the window's plane
    good = res_rms <= max_residual_px
    if noise is not None:
        nz = np.where(ok, np.asarray(noise, float) ** 2, 0.0)
        sigma = np.sqrt(at(nz)) / n
    else:
        sigma = res_rms / np.sqrt(n)
    sigma = np.maximum(sigma, floor_px)
    cam = np.column_stack([xc, yc])[good]
    proj = np.column_stack(means)[good]
    return Samples(cam, proj, sigma[good], window=k)


def _square_px(corners) -> float:
    """A square's side in camera pixels: the 90th percentile of the corners' nearest-neighbour distances."""
    d = np.linalg.norm(corners[:, None, :] - corners[None, :, :], axis=2)
    np.fill_diagonal(d, np.inf)
    return float(np.percentile(d.min(axis=1), 90))


def dense_samples(maps, board_cam_pts, *, window: int = WINDOW, margin: float = 2.0,
                  max_residual_px: float = 1.0) -> tuple[Samples, Samples]:
    """Board and background samples of one decoded pose (module docstring).

    Parameters
    ----------
    maps : :class:`procam.decode.DecodeResult` (``col``, ``row``, ``valid``; a ``noise`` map if it has one).
    board_cam_pts : (N, 2) the board's camera corners (distorted pixels; NaN rows ignored).
    window : window side, camera pixels (odd).
    margin : how far beyond the corners' boundary the board reaches, in squares (background samples start there).
    max_residual_px : see :func:`window_means`.

    Returns
    -------
    ``(board, background)`` :class:`procam.view.Samples`; empty ones when there are fewer than 3 corners.
    """
    import cv2

    H, W = maps.col.shape
    c = np.asarray(board_cam_pts, float).reshape(-1, 2)
    c = c[np.isfinite(c).all(1)]
    empty = Samples(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0), window=int(window))
    if len(c) < 3:
        return empty, empty
    inside = board_region(c, (W, H))
    valid = np.asarray(maps.valid_col, bool) & np.asarray(maps.valid_row, bool)
    noise = getattr(maps, "noise", None)
    board = window_means(maps.col, maps.row, valid, inside, window=window, max_residual_px=max_residual_px,
                         noise=noise)
    dist = cv2.distanceTransform((~inside).astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    back = window_means(maps.col, maps.row, valid, dist > margin * _square_px(c), window=window,
                        max_residual_px=max_residual_px, noise=noise)
    return board, back
