"""Camera lens distortion from one view of a planar board.

* :func:`estimate_cod` -- centre of distortion (COD) as the left null vector of the radial
  fundamental matrix ``F = [c]_x H`` (Hartley & Kang), with an observability score ``s8/s9``.
* :func:`estimate_division` -- the linear ("one-shot") solve of the division-model coefficients
  ``k1, k2`` and the board -> undistorted-image homography, given the centre.
* :func:`opencv_from_division` -- an OpenCV ``(k1, k2, p1, p2, k3)`` fit that reproduces a division
  model over the image, for files read by OpenCV-based tools.

Division model (distorted -> undistorted, radius ``r`` measured in the distorted image)::

    m = c + (m_hat - c) / (1 + k1 r^2 + k2 r^4),   r = |m_hat - c|   (pixels, k1 [px^-2], k2 [px^-4])
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import models

#: Default threshold on ``s8/s9`` below which the centre of distortion is unreliable.
MIN_COD_SCORE = 2.5


@dataclass(frozen=True)
class CODEstimate:
    """Centre of distortion from the radial fundamental matrix.

    Attributes
    ----------
    center : (2,) float
        ``(x, y)`` pixels; NaN when it could not be computed.
    singular_values : (9,) float
        Singular values ``s1 >= ... >= s9`` of the Hartley-normalised design matrix (NaN if not computed).
    score : float
        ``s8 / s9``: observability of the distortion (about 1 without distortion, large when strong).
    reliable : bool
        ``score >= min_score`` and the centre lies inside the image (when the image size is known).
    reason : str
        Human-readable explanation when not reliable (empty otherwise).
    F : (3, 3) float or None
        The radial fundamental matrix (distorted image <- board), ``x_d^T F X = 0``.
    """

    center: np.ndarray
    singular_values: np.ndarray
    score: float
    reliable: bool
    reason: str = ""
    F: np.ndarray | None = None


def _as_xy(pts) -> np.ndarray:
    a = np.asarray(pts, dtype=float)
    if a.ndim != 2 or a.shape[1] < 2:
        raise ValueError(f"points must be (N, 2) or (N, 3), got shape {a.shape}")
    return a[:, :2]




def _homog(pts: np.ndarray) -> np.ndarray:
    return np.column_stack([pts, np.ones(len(pts))])


def estimate_cod(obj_pts, cam_pts, *, image_size=None, min_score: float = MIN_COD_SCORE) -> CODEstimate:
    """Centre of distortion from one view. Never raises on bad numeric input.

    Parameters
    ----------
    obj_pts : (N, 2) or (N, 3) board points (z ignored; the board is planar).
    cam_pts : (N, 2) distorted camera pixels. Rows with a non-finite value are ignored.
    image_size : (width, height) or None
        When given, a centre outside the image is flagged unreliable.
    min_score : float
        Threshold on ``s8/s9`` (default 2.5, from simulations: below it the centre is off by 100 px or more).

    Returns
    -------
    CODEstimate
    """
    nan9 = np.full(9, np.nan)
    nan2 = np.full(2, np.nan)
    try:
        X = _as_xy(obj_pts)
        x = _as_xy(cam_pts)
        if len(X) != len(x):
            return CODEstimate(nan2, nan9, float("nan"), False,
                               f"point counts differ ({len(X)} board, {len(x)} image)")
        ok = np.isfinite(X).all(1) & np.isfinite(x).all(1)
        X, x = X[ok], x[ok]
        if len(X) < 9:
            return CODEstimate(nan2, nan9, float("nan"), False,
                               f"only {len(X)} usable corners (the radial fundamental matrix needs >= 9)")
        Td, Tb = models.hartley_normalizer(x), models.hartley_normalizer(X)
        xd = _homog(x) @ Td.T
        Xb = _homog(X) @ Tb.T
        A = np.einsum("ni,nj->nij", xd, Xb).reshape(len(x), 9)
        _, s, Vt = np.linalg.svd(A, full_matrices=False)
        if len(s) < 9 or not np.all(np.isfinite(s)):
            return CODEstimate(nan2, nan9, float("nan"), False, "SVD of the design matrix failed")
        eps = 1e-12 * s[0]
        score = float((s[7] + eps) / (s[8] + eps))
        Ft = Vt[-1].reshape(3, 3)
        U, S, Vt2 = np.linalg.svd(Ft)
        Ft = U @ np.diag([S[0], S[1], 0.0]) @ Vt2
        F = Td.T @ Ft @ Tb
        U, _, _ = np.linalg.svd(F)
        ch = U[:, 2]
        if abs(ch[2]) < 1e-12 * np.linalg.norm(ch):
            return CODEstimate(nan2, s, score, False, "the centre of distortion is at infinity", F)
        center = ch[:2] / ch[2]
        reasons = []
        if score < min_score:
            reasons.append(f"weak distortion: observability s8/s9 = {score:.2f} < {min_score:g}")
        if image_size is not None:
            w, h = image_size
            if not (-0.5 <= center[0] <= w - 0.5 and -0.5 <= center[1] <= h - 0.5):
                reasons.append(f"centre ({center[0]:.0f}, {center[1]:.0f}) outside the {w}x{h} image")
        return CODEstimate(center, s, score, not reasons, "; ".join(reasons), F)
    except (np.linalg.LinAlgError, ValueError, FloatingPointError) as e:  # pragma: no cover - guard
        return CODEstimate(nan2, nan9, float("nan"), False, f"numerical failure: {e}")


def estimate_division(obj_pts, cam_pts, center, *, n_coeffs: int = 2, radius_scale: float | None = None):
    """Linear division-model coefficients given the centre.

    Parameters
    ----------
    obj_pts : (N, 2|3) board points; cam_pts : (N, 2) distorted pixels (non-finite rows ignored).
    center : (2,) centre of distortion in pixels.
    n_coeffs : 1 or 2
        Estimate ``k1`` only (``k2 = 0``) or ``k1, k2``.
    radius_scale : float, optional
        Radius normalisation ``s_r`` for conditioning (default: the largest corner radius).

    Returns
    -------
    k1 : float [px^-2]
    k2 : float [px^-4]
    H : (3, 3)
        Board (x, y, 1) -> **undistorted** image pixels (absolute, not COD-centred), ``H[2, 2] = 1``.
    """
    X = _as_xy(obj_pts)
    x = _as_xy(cam_pts)
    ok = np.isfinite(X).all(1) & np.isfinite(x).all(1)
    X, x = X[ok], x[ok]
    if len(X) < 6:
        raise ValueError(f"need at least 6 corners for the division model, got {len(X)}")
    c = np.asarray(center, float).reshape(2)
    xb = x - c
    r = np.hypot(xb[:, 0], xb[:, 1])
    sr = float(radius_scale) if radius_scale else float(max(r.max(), 1.0))
    xb = xb / sr
    rho2 = (r / sr) ** 2
    Tb = models.hartley_normalizer(X)
    Xn = _homog(X) @ Tb.T
    # step 1: h1, h2 up to a common scale: xb_y (h1.X) - xb_x (h2.X) = 0
    M = np.hstack([xb[:, 1:2] * Xn, -xb[:, 0:1] * Xn])
    _, _, Vt = np.linalg.svd(M)
    h12 = Vt[-1]
    h1, h2 = h12[:3], h12[3:]
    a1, a2 = Xn @ h1, Xn @ h2
    # step 2: xb_j (h3.X) - (h_j.X)(K1 rho^2 + K2 rho^4) = h_j.X
    rows, rhs = [], []
    for xj, aj in ((xb[:, 0], a1), (xb[:, 1], a2)):
        cols = [xj[:, None] * Xn, -(aj * rho2)[:, None]]
        if n_coeffs >= 2:
            cols.append(-(aj * rho2 ** 2)[:, None])
        rows.append(np.hstack(cols))
        rhs.append(aj)
    sol, *_ = np.linalg.lstsq(np.vstack(rows), np.concatenate(rhs), rcond=None)
    h3 = sol[:3]
    K1 = sol[3]
    K2 = sol[4] if n_coeffs >= 2 else 0.0
    Hn = np.vstack([h1, h2, h3])
    S = np.array([[sr, 0.0, c[0]], [0.0, sr, c[1]], [0.0, 0.0, 1.0]])
    H = S @ Hn @ Tb
    H = H / H[2, 2]
    return float(K1 / sr ** 2), float(K2 / sr ** 4), H



def max_displacement(pts, center, k1: float, k2: float = 0.0) -> float:
    """Largest distance (px) between distorted points ``pts`` (N, 2) and their undistorted positions."""
    p = np.asarray(pts, float).reshape(-1, 2)
    p = p[np.isfinite(p).all(1)]
    if len(p) == 0:
        return float("nan")
    d = models.undistort_division(p, center, k1, k2) - p
    return float(np.max(np.hypot(d[:, 0], d[:, 1])))


def opencv_from_division(K, center, k1: float, k2: float, image_size, *, grid: tuple[int, int] = (41, 31),
                         min_denominator: float = 0.05):
    """OpenCV ``(k1, k2, p1, p2, k3)`` that reproduce a division model over the image.

    A grid of distorted pixels covering the whole image is undistorted with the division model;
    the OpenCV (Brown-Conrady) coefficients are the linear least-squares fit, in pixels, of
    OpenCV's forward model (undistorted normalised -> distorted pixels) to those pairs, using the
    same ``K`` (whose principal point need not equal the centre of distortion; ``p1, p2``
    absorb a small offset). The fit is what ``cam_kc`` in OpenCV YAML files holds; it is an
    approximation, and ``max_err_px`` says how good.

    Parameters
    ----------
    K : (3, 3) camera matrix.
    center : (2,) centre of distortion (px); k1 [px^-2], k2 [px^-4]: the division model.
    image_size : (width, height) in pixels.
    grid : (nx, ny) number of grid points across the image.
    min_denominator : grid points where ``1 + k1 r^2 + k2 r^4`` is below this are skipped (the
        division model folds over there).

    Returns
    -------
    coeffs : (5,) float, OpenCV order ``(k1, k2, p1, p2, k3)``.
    max_err_px : float
        Largest distance over the grid between OpenCV's prediction (``cv2.projectPoints``) and the
        division model's distorted pixel.
    """
    import cv2

    K = np.asarray(K, float)
    w, h = image_size
    gx, gy = np.meshgrid(np.linspace(-0.5, w - 0.5, grid[0]), np.linspace(-0.5, h - 0.5, grid[1]))
    md = np.column_stack([gx.ravel(), gy.ravel()])
    c = np.asarray(center, float).reshape(1, 2)
    r2 = np.sum((md - c) ** 2, axis=1)
    den = 1.0 + k1 * r2 + k2 * r2 * r2
    keep = den > min_denominator
    md = md[keep]
    mu = models.undistort_division(md, center, k1, k2)
    fx, fy, cx, cy = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
    x = (mu[:, 0] - cx) / fx
    y = (mu[:, 1] - cy) / fy
    rr = x * x + y * y
    Ax = fx * np.column_stack([x * rr, x * rr ** 2, 2 * x * y, rr + 2 * x * x, x * rr ** 3])
    Ay = fy * np.column_stack([y * rr, y * rr ** 2, rr + 2 * y * y, 2 * x * y, y * rr ** 3])
    bx = md[:, 0] - cx - fx * x
    by = md[:, 1] - cy - fy * y
    A = np.vstack([Ax, Ay])
    b = np.concatenate([bx, by])
    colscale = np.linalg.norm(A, axis=0)
    colscale[colscale == 0] = 1.0
    sol, *_ = np.linalg.lstsq(A / colscale, b, rcond=None)
    coeffs = sol / colscale
    pts3 = np.column_stack([x, y, np.ones_like(x)]).reshape(-1, 1, 3)
    proj, _ = cv2.projectPoints(pts3, np.zeros(3), np.zeros(3), K, coeffs)
    err = np.hypot(*(proj.reshape(-1, 2) - md).T)
    return coeffs, float(err.max()) if len(err) else float("nan")
