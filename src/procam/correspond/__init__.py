"""Camera corners -> projector corners by local homographies (Moreno & Taubin).

For each chessboard corner, the decoded pixels in a window around it give a camera -> projector
homography that is valid locally; the corner's projector coordinates are its image under it.
Every corner carries its own diagnostics, and a corner that fails is NaN with a reason, so a
partially lit board, or one near the image border, still gives the corners it can.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._threads import single_threaded_blas
from ..stats import rms
from ..board import board_region
from ..decode import DecodeResult
from ..view import CORNER_REASONS
from .. import choices

ESTIMATORS = choices.ESTIMATORS


@dataclass(frozen=True)
class CornerOptions:
    """Local-homography options (defaults measured in ``benchmarks/correspond.py``).

    window : int, camera pixels — side of the square window around each corner (Moreno: 60).
    estimator : ``"trimmed"`` | ``"lsq"`` | ``"ransac"`` | ``"lmeds"`` — how the homography is fitted:
        ``"trimmed"`` (default) fits all corners at once by least squares, drops the points farther than
        ``ransac_threshold`` from the fit and refits until the points stay the same (:func:`fit_homographies`;
        a window where that does not settle on most of its points gets RANSAC); the others are
        ``cv2.findHomography``'s methods 0, RANSAC and LMEDS, one call per corner.
    ransac_threshold : float, projector pixels — inlier threshold of RANSAC and of the trimmed fit (Moreno: 3).
    min_valid_fraction : float — minimum fraction of the window's pixels with a decoded column
        and row (25 %, as the paper).
    max_residual : float, projector pixels — a corner whose fit RMS over the inliers exceeds it fails.
    """

    window: int = 60
    estimator: str = "trimmed"
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
    maps : :class:`~procam.decode.DecodeResult` of the same pose (only ``col``, ``row`` and ``valid`` in the
        windows around the corners are read).
    options : :class:`CornerOptions`.

    Returns
    -------
    proj_pts : (N, 2) float64, NaN where a corner failed.
    diagnostics : dict of (N,) arrays — ``reason`` (uint8, :data:`CORNER_REASONS`), ``pixels``
        (decoded pixels in the window), ``window_pixels`` (pixels of the window inside the image),
        ``inliers`` and ``residual_px`` (RMS of the fit over the inliers, projector pixels).
    """
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
    fit = []  # corners that get a homography
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
        pixels[k] = int(np.count_nonzero(valid[y0:y1, x0:x1]))
        if pixels[k] < max(8, options.min_valid_fraction * full_area):
            reason[k] = 2
            continue
        fit.append(k)
    ransac = fit
    if options.estimator == "trimmed" and fit:
        # all at once, in batches of corners whose windows hold at most TRIMMED_BATCH pixels in all: a window of
        # 1000 px held 9.6 GB for 60 corners at once
        per = max(1, TRIMMED_BATCH // (2 * half) ** 2)
        ransac = [k for i in range(0, len(fit), per) for k in
                  _trimmed_corners(np.array(fit[i:i + per]), cam_pts, maps, half, options, proj, reason, inliers,
                                   resid)]
    if ransac:
        _cv2_corners(ransac, cam_pts, maps, half, options, proj, reason, inliers, resid)
    return proj, {"reason": reason, "pixels": pixels, "window_pixels": wpix, "inliers": inliers,
                  "residual_px": resid}


def _finish(k, Hm, src, dst, do, inl, options, proj, reason, inliers, resid):
    """Diagnostics and projector corner of corner ``k`` from its homography ``Hm`` (centred coordinates)."""
    inliers[k] = int(inl.sum())
    ph = np.column_stack([src, np.ones(len(src))]) @ Hm.T
    e = ph[inl, :2] / ph[inl, 2:3] - dst[inl]
    resid[k] = rms(e) if inl.any() else np.inf
    if inliers[k] < 8 or resid[k] > options.max_residual:
        reason[k] = 4
        return
    p = Hm @ np.array([0.0, 0.0, 1.0])
    proj[k] = p[:2] / p[2] + do


def _cv2_corners(ks, cam_pts, maps, half, options, proj, reason, inliers, resid):
    """One ``cv2.findHomography`` per corner (estimators lsq, ransac, lmeds; the trimmed fit's fallback)."""
    import cv2

    H, W = maps.col.shape
    valid = maps.valid
    method = {"lsq": 0, "ransac": cv2.RANSAC, "lmeds": cv2.LMEDS, "trimmed": cv2.RANSAC}[options.estimator]
    for k in ks:
        x, y = cam_pts[k]
        cx, cy = int(round(x)), int(round(y))
        x0, x1 = max(0, cx - half), min(W, cx + half)
        y0, y1 = max(0, cy - half), min(H, cy + half)
        v = valid[y0:y1, x0:x1]
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
        _finish(k, Hm, src - so, dst - do, do, inl, options, proj, reason, inliers, resid)


#: Most window pixels (all corners' together) :func:`projector_corners` fits at once with the trimmed estimator
#: (its arrays hold about 20 float64 values a pixel): 2^21 is 60 windows of 187 px, or 582 of the default 60 px.
TRIMMED_BATCH = 1 << 21


def _trimmed_corners(ks, cam_pts, maps, half, options, proj, reason, inliers, resid) -> list:
    """The trimmed fit of the corners ``ks`` (all at once); returns the corners it leaves to RANSAC."""
    Hh, Ww = maps.col.shape
    d = np.arange(-half, half)
    gx, gy = np.meshgrid(d, d)
    grid = np.column_stack([gx.ravel(), gy.ravel()]).astype(float)  # (M, 2) window pixels around (cx, cy)
    c = np.rint(cam_pts[ks]).astype(np.intp)
    X, Y = c[:, :1] + gx.ravel(), c[:, 1:] + gy.ravel()
    inside = (X >= 0) & (X < Ww) & (Y >= 0) & (Y < Hh)
    flat = np.where(inside, Y * Ww + X, 0)
    ok = inside & maps.valid.ravel()[flat]
    dst = np.empty(ok.shape + (2,))
    dst[..., 0] = np.where(ok, maps.col.ravel()[flat], 0.0)
    dst[..., 1] = np.where(ok, maps.row.ravel()[flat], 0.0)
    do = dst.sum(1) / ok.sum(1)[:, None]  # centred on the mean, as the per-corner fit
    dst -= do[:, None, :]
    Hm, inl, settled, rms = fit_homographies(grid, dst, ok, options.ransac_threshold)
    # the corner itself is at grid point (corner - (cx, cy))
    p = Hm @ np.column_stack([cam_pts[ks] - c, np.ones(len(ks))])[..., None]
    with np.errstate(divide="ignore", invalid="ignore"):
        p = p[:, :2, 0] / p[:, 2:, 0] + do
    n_in = inl.sum(1)
    for i, k in enumerate(ks):
        if not settled[i]:
            continue
        inliers[k], resid[k] = n_in[i], rms[i]
        if n_in[i] < 8 or not rms[i] <= options.max_residual or not np.all(np.isfinite(p[i])):
            reason[k] = 4
        else:
            proj[k] = p[i]
    return [int(k) for k in ks[~settled]]


@single_threaded_blas()  # its one large product's sums must not depend on BLAS's threads (the same bytes anywhere)
def fit_homographies(src: np.ndarray, dst: np.ndarray, mask: np.ndarray, threshold: float = 3.0, *,
                     iterations: int = 12, min_inliers: float = 0.8):
    """Robust homographies of many point sets seen at the same source points (windows of pixels), all at once:
    least squares, trim, refit.

    Each set is fitted by linear least squares (DLT, normalised coordinates; from the second fit on, the rows
    are weighted by the previous fit's denominator, so the fit minimises the distances in ``dst``). A set is
    done when the points within ``threshold`` of its fit are the points it was fitted to. Otherwise the points
    within a threshold are kept and the set refitted; the threshold starts at 8 ``threshold`` and halves each
    round down to ``threshold``, so gross outliers (a wrongly decoded high bit) go first and cannot pull the fit
    that decides about the others.

    Parameters
    ----------
    src : (M, 2) float — the source points, shared by all sets.
    dst : (N, M, 2) float — where each set sees them.
    mask : (N, M) bool — which points each set has.
    threshold : float, units of ``dst`` — inlier distance.
    iterations : most fits per set.
    min_inliers : a set is ``settled`` when it is done and keeps at least this fraction of its points.

    Returns
    -------
    H : (N, 3, 3) float64, ``dst ~ H @ [src, 1]``; NaN where the normal equations were singular.
    inliers : (N, M) bool.
    settled : (N,) bool.
    rms : (N,) float — RMS distance of the inliers from the fit, units of ``dst``.
    """
    src = np.asarray(src, float)
    dst = np.asarray(dst, float)
    mask = np.asarray(mask, bool)
    n, M = mask.shape
    cnt = np.maximum(mask.sum(1), 1)
    # normalised coordinates: the source's centroid at 0 and RMS radius sqrt(2) (shared); each set's targets
    # likewise (Hartley)
    cs = src.mean(0)
    rs = max(float(np.sqrt(np.mean(np.sum((src - cs) ** 2, 1)) / 2.0)), 1e-12)
    x, y = (src[:, 0] - cs[0]) / rs, (src[:, 1] - cs[1]) / rs
    B = np.column_stack([np.ones(M), x, y, x * x, x * y, y * y])  # (M, 6) monomials of the source
    mf = mask.astype(float)
    u, v = np.where(mask, dst[..., 0], 0.0), np.where(mask, dst[..., 1], 0.0)
    cd = np.column_stack([u.sum(1), v.sum(1)]) / cnt[:, None]
    u -= cd[:, :1]
    v -= cd[:, 1:]
    u *= mf
    v *= mf
    rd = np.sqrt((np.einsum("nm,nm->n", u, u) + np.einsum("nm,nm->n", v, v)) / cnt / 2.0)
    rd = np.where(rd > 0, rd, 1.0)
    u /= rd[:, None]
    v /= rd[:, None]
    inl = mask.copy()
    den = np.ones((n, M))
    h = np.full((n, 8), np.nan)
    thr2 = (threshold / rd) ** 2  # per set, normalised units
    settled = np.zeros(n, bool)
    rms = np.full(n, np.nan)
    idx = np.arange(n)
    W = np.empty((4, n, M))
    for it in range(iterations):
        sub = slice(None) if idx.size == n else idx
        ui, vi, mi, ii = u[sub], v[sub], mask[sub], inl[sub]
        Wi = W[:, :idx.size]
        np.divide(ii, den[sub] ** 2, out=Wi[0])
        np.multiply(Wi[0], ui, out=Wi[1])
        np.multiply(Wi[0], vi, out=Wi[2])
        np.multiply(Wi[1], ui, out=Wi[3])
        Wi[3] += Wi[2] * vi
        S = (Wi.reshape(-1, M) @ B).reshape(4, idx.size, 6).transpose(1, 0, 2)  # (n, 4, 6) weighted sums
        hi = _solve_normal(S)
        h[idx] = hi
        a, b, c_, d_, e, f, g, hh = (hi[:, k:k + 1] for k in range(8))
        dn = g * x + hh * y + 1.0
        with np.errstate(divide="ignore", invalid="ignore"):
            r2 = ((a * x + b * y + c_) / dn - ui) ** 2 + ((d_ * x + e * y + f) / dn - vi) ** 2
        front = mi & (dn > 0)
        bad = ~np.all(np.isfinite(hi), axis=1)
        # done: the points within the threshold are those fitted (the first, algebraic fit is always refitted)
        done = (np.all((front & (r2 <= thr2[idx, None])) == ii, axis=1) & (it > 0)) | bad
        settled[idx] = done & ~bad
        with np.errstate(invalid="ignore"):
            rms[idx] = np.sqrt(np.sum(np.where(ii, r2, 0.0), 1) / ii.sum(1)) * rd[idx]
        t2 = thr2[idx, None] * max(1.0, 4.0 ** (3 - it))
        inl[idx] = np.where(done[:, None], ii, front & (r2 <= t2))
        den[idx] = np.where(dn > 0, dn, 1.0)
        idx = idx[~done]
        if idx.size == 0:
            break
    settled &= inl.sum(1) >= min_inliers * mask.sum(1)
    # back to the original coordinates: H = Td^-1 Hn Ts
    Hn = np.concatenate([h, np.ones((n, 1))], axis=1).reshape(n, 3, 3)
    Ts = np.array([[1.0 / rs, 0.0, -cs[0] / rs], [0.0, 1.0 / rs, -cs[1] / rs], [0.0, 0.0, 1.0]])
    Tdi = np.zeros((n, 3, 3))
    Tdi[:, 0, 0] = Tdi[:, 1, 1] = rd
    Tdi[:, 0, 2], Tdi[:, 1, 2], Tdi[:, 2, 2] = cd[:, 0], cd[:, 1], 1.0
    return Tdi @ Hn @ Ts, inl, settled, rms


def _solve_normal(S: np.ndarray) -> np.ndarray:
    """The 8 DLT unknowns ``(a, b, c, d, e, f, g, h)`` of ``u = (a x + b y + c) / (g x + h y + 1)``,
    ``v = (d x + e y + f) / (...)`` from the weighted sums ``S`` (n, 4, 6): rows ``w, w u, w v, w (u^2 + v^2)``,
    columns the monomials ``1, x, y, x^2, xy, y^2``. NaN where the normal equations are singular."""
    n = len(S)
    s0, su, sv, sq = S[:, 0], S[:, 1], S[:, 2], S[:, 3]

    def ppt(m):  # sum of w p p^T, p = (x, y, 1)
        return np.stack([np.stack([m[:, 3], m[:, 4], m[:, 1]], -1), np.stack([m[:, 4], m[:, 5], m[:, 2]], -1),
                         np.stack([m[:, 1], m[:, 2], m[:, 0]], -1)], 1)

    A = np.zeros((n, 8, 8))
    P = ppt(s0)
    A[:, 0:3, 0:3] = P
    A[:, 3:6, 3:6] = P
    A[:, 0:3, 6:8] = -ppt(su)[:, :, 0:2]
    A[:, 3:6, 6:8] = -ppt(sv)[:, :, 0:2]
    A[:, 6:8, 0:3] = np.transpose(A[:, 0:3, 6:8], (0, 2, 1))
    A[:, 6:8, 3:6] = np.transpose(A[:, 3:6, 6:8], (0, 2, 1))
    A[:, 6:8, 6:8] = ppt(sq)[:, 0:2, 0:2]
    rhs = np.concatenate([su[:, [1, 2, 0]], sv[:, [1, 2, 0]], -sq[:, [1, 2]]], axis=1)
    out = np.full((n, 8), np.nan)
    ok = np.all(np.isfinite(A), axis=(1, 2)) & np.all(np.isfinite(rhs), axis=1)
    try:
        out[ok] = np.linalg.solve(A[ok], rhs[ok][..., None])[..., 0]
    except np.linalg.LinAlgError:  # one singular system: solve them one by one
        for i in np.flatnonzero(ok):
            try:
                out[i] = np.linalg.solve(A[i], rhs[i])
            except np.linalg.LinAlgError:
                pass
    return out


#: :func:`dense_projector_corners`: full width of the local fit's window (camera pixels), the polynomial's degree,
#: the smallest noise a pixel is weighted by (projector pixels), and the largest distance (projector pixels) between
#: the fit and the local homography before the corner is refused.
DENSE_WINDOW, DENSE_DEGREE, DENSE_SIGMA_FLOOR, DENSE_TOLERANCE = 80, 2, 0.02, 1.0


def dense_projector_corners(cam_pts: np.ndarray, maps: DecodeResult, options: CornerOptions = CornerOptions(), *,
                            window: int = DENSE_WINDOW, degree: int = DENSE_DEGREE,
                            tolerance: float = DENSE_TOLERANCE):
    """Projector coordinates of camera corners from a sub-pixel map (a phase family's decode) by a local fit,
    with the local homography as the check.

    Per corner and per projector axis, a polynomial of ``degree`` in the camera offsets from the corner is fitted
    by weighted least squares to the decoded pixels of a ``window`` x ``window`` window (weights ``1 / sigma^2``
    from the decode's per-pixel noise, ``maps.coordinate_sigma``, floored at :data:`DENSE_SIGMA_FLOOR`; pixels
    beyond 4 standard deviations of the fit are dropped and it is refitted); the corner's coordinate is the
    polynomial's value at the corner.  A quadratic follows the camera -> projector map's curvature (perspective,
    lens distortion) that a homography cannot, and the weights leave out the board's dark squares, where the
    fringes' noise is several times larger.  :func:`projector_corners` (the local homography, ``options``) is the
    check: a corner whose two estimates are more than ``tolerance`` projector pixels apart fails (reason 6), as
    does one the homography fails.

    Returns
    -------
    proj_pts : (N, 2) float64, NaN where a corner failed.
    diagnostics : the homography's (:func:`projector_corners`) plus ``fit_sigma_px`` (N, 2), the fit's standard
        deviation at the corner from its covariance (it assumes independent pixels: the camera's blur correlates
        neighbours, so it is a lower bound), ``fit_pixels`` (N,) and ``homography_px`` (N,), the distance between
        the two estimates.
    """
    cam_pts = np.asarray(cam_pts, float).reshape(-1, 2)
    hom, diag = projector_corners(cam_pts, maps, options)
    n = len(cam_pts)
    H, W = maps.col.shape
    half = int(window) // 2
    proj = np.full((n, 2), np.nan)
    fit_sigma = np.full((n, 2), np.nan)
    fit_pixels = np.zeros(n, np.int32)
    reason = diag["reason"].copy()
    sig = [np.maximum(maps.coordinate_sigma(a), np.float32(DENSE_SIGMA_FLOOR)) for a in ("col", "row")]
    valid = maps.valid
    powers = [(i, d - i) for d in range(int(degree) + 1) for i in range(d, -1, -1)]
    for k in np.flatnonzero(np.isfinite(hom).all(axis=1)):
        x, y = cam_pts[k]
        cx, cy = int(round(x)), int(round(y))
        x0, x1, y0, y1 = max(0, cx - half), min(W, cx + half + 1), max(0, cy - half), min(H, cy + half + 1)
        v = valid[y0:y1, x0:x1]
        yy, xx = np.nonzero(v)
        if len(xx) < max(3 * len(powers), 30):
            reason[k] = 2
            continue
        dx, dy = (xx + x0 - x) / half, (yy + y0 - y) / half
        X = np.column_stack([dx ** i * dy ** j for i, j in powers])
        for a, m in enumerate((maps.col, maps.row)):
            z = m[y0:y1, x0:x1][v].astype(np.float64)
            w = 1.0 / sig[a][y0:y1, x0:x1][v].astype(np.float64)
            keep = np.ones(len(z), bool)
            for _ in range(2):
                A = X[keep] * w[keep, None]
                c, *_ = np.linalg.lstsq(A, z[keep] * w[keep], rcond=None)
                r = (X @ c - z) * w
                chi = float(np.sqrt(np.mean(r[keep] ** 2)))
                keep = np.abs(r) <= 4.0 * max(chi, 1.0)
            A = X[keep] * w[keep, None]
            c, *_ = np.linalg.lstsq(A, z[keep] * w[keep], rcond=None)
            r = (X[keep] @ c - z[keep]) * w[keep]
            dof = max(int(keep.sum()) - len(powers), 1)
            cov = np.linalg.pinv(A.T @ A) * max(float(r @ r) / dof, 1.0)
            proj[k, a] = c[0]
            fit_sigma[k, a] = float(np.sqrt(max(cov[0, 0], 0.0)))
        fit_pixels[k] = int(v.sum())
    dist = np.linalg.norm(proj - hom, axis=1)
    bad = ~(dist <= tolerance) & np.isfinite(proj).all(axis=1)
    reason[bad] = 6
    proj[reason != 0] = np.nan
    return proj, {**diag, "reason": reason, "fit_sigma_px": fit_sigma, "fit_pixels": fit_pixels,
                  "homography_px": dist}


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
    outside = (~board_region(c, (W, H))).astype(np.uint8)
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
