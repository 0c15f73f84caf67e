"""Triangulation with a procam calibration: corners (sparse) and decoded maps (dense).

Every point is returned in the **camera frame** (board units, the unit of ``T``): the camera centre
is the origin, ``x`` right, ``y`` down, ``z`` forward (OpenCV's convention); the projector maps
camera points with ``x_p = R x_c + T``.

* :func:`rays` -- undistorted normalised rays ``(x, y, 1)`` of a device's distorted pixels.
* :func:`triangulate_points` -- camera pixel + projector pixel -> one 3-D point each: the midpoint
  of the two rays, then (``refine=True``, default) a per-point Gauss-Newton refinement that
  minimises the sum of the squared reprojection errors in both devices (undistorted pixels, equal
  weights); residuals are reported in each device's own distorted pixels.
* :func:`triangulate_dense` -- a decoded camera image: the ray of every camera pixel centre
  intersected with the projector's column plane, or with both its column and row planes where both
  are decoded (least squares along the ray, which minimises the projector reprojection error to
  first order: the camera pixel is exact, the decoded projector coordinate is the measurement).
  Vectorised; a 2 Mpx map takes well under a second without projector distortion.

Only :mod:`procam.calibration` devices are used (any distortion model: ``Device.undistort`` /
``Device.distortion.distort``).
"""

from __future__ import annotations

import numpy as np

from . import choices
from .errors import CalibrationError

#: Which projector coordinates a dense triangulation uses (``use=``).
USES = choices.TRIANGULATION_USES


def _require_stereo(calib):
    if calib.projector is None or calib.R is None or calib.T is None:
        raise CalibrationError("the calibration has no projector or no camera->projector extrinsics; "
                               "triangulation needs a procam calibration")
    return np.asarray(calib.R, float), np.asarray(calib.T, float).reshape(3)


def rays(device, pts) -> np.ndarray:
    """Undistorted normalised rays of distorted pixels.

    Parameters
    ----------
    device : :class:`procam.calibration.Device`
    pts : (N, 2) distorted pixels ``(x, y)`` of that device (NaN rows allowed).

    Returns
    -------
    (N, 3) float64 ``(x_n, y_n, 1)`` with ``K^-1`` applied to the undistorted pixel (z = 1, not unit
    length); NaN rows where the input is NaN or cannot be undistorted.
    """
    pts = np.asarray(pts, float).reshape(-1, 2)
    und = device.undistort(pts)
    K = np.asarray(device.K, float)
    y = (und[:, 1] - K[1, 2]) / K[1, 1]
    x = (und[:, 0] - K[0, 2] - K[0, 1] * y) / K[0, 0]
    return np.column_stack([x, y, np.ones(len(pts))])


def _project(K, X):
    """Pinhole pixels (N, 2) and depth (N,) of points X (N, 3) in the device frame."""
    z = X[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        xn, yn = X[:, 0] / z, X[:, 1] / z
    return np.column_stack([K[0, 0] * xn + K[0, 1] * yn + K[0, 2], K[1, 1] * yn + K[1, 2]]), z


def _pinhole_jac(K, X):
    """d(pixel)/dX of the pinhole projection at X (N, 3): (N, 2, 3)."""
    x, y, z = X[:, 0], X[:, 1], X[:, 2]
    iz = 1.0 / z
    J = np.zeros((len(X), 2, 3))
    J[:, 0, 0] = K[0, 0] * iz
    J[:, 0, 1] = K[0, 1] * iz
    J[:, 0, 2] = -(K[0, 0] * x + K[0, 1] * y) * iz * iz
    J[:, 1, 1] = K[1, 1] * iz
    J[:, 1, 2] = -K[1, 1] * y * iz * iz
    return J


def midpoint(d_cam, d_proj, R, T) -> np.ndarray:
    """Midpoint of the closest points of camera rays and projector rays (camera frame).

    Parameters
    ----------
    d_cam : (N, 3) camera ray directions (camera frame, through the origin).
    d_proj : (N, 3) projector ray directions in the **projector** frame.
    R, T : camera -> projector.

    Returns
    -------
    (N, 3) points; NaN where the rays are parallel.
    """
    R = np.asarray(R, float)
    T = np.asarray(T, float).reshape(3)
    c = -R.T @ T                          # projector centre in the camera frame
    a = np.asarray(d_cam, float)
    b = np.asarray(d_proj, float) @ R     # rows: R^T d_p
    # minimise |s a - (c + t b)|^2 over (s, t)
    aa = np.einsum("ij,ij->i", a, a)
    bb = np.einsum("ij,ij->i", b, b)
    ab = np.einsum("ij,ij->i", a, b)
    ac = a @ c
    bc = b @ c
    den = aa * bb - ab * ab
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (ac * bb - ab * bc) / den
        t = (ab * ac - aa * bc) / den
        bad = ~(np.abs(den) > 1e-15 * aa * bb)
    X = 0.5 * (s[:, None] * a + (c + t[:, None] * b))
    X[bad] = np.nan
    return X


def triangulate_points(calib, cam_pts, proj_pts, *, refine: bool = True, iterations: int = 10):
    """3-D points from matching camera and projector pixels.

    Parameters
    ----------
    calib : :class:`procam.calibration.Calibration` with a projector and ``(R, T)``.
    cam_pts : (N, 2) distorted camera pixels; proj_pts : (N, 2) (distorted) projector pixels.
        Rows with a NaN give NaN.
    refine : after the midpoint of the two undistorted rays, minimise per point
        ``|pi(Kc X) - c_u|^2 + |pi(Kp (R X + T)) - p_u|^2`` (``c_u``, ``p_u`` the undistorted
        observations, pixels, equal weights) by Gauss-Newton (``iterations`` steps, vectorised).
        Without it the points are the plain midpoints.

    Returns
    -------
    X : (N, 3) camera-frame points, board units.
    cam_res, proj_res : (N, 2) reprojection residuals, observed - predicted, in each device's own
        (distorted) pixels.
    """
    R, T = _require_stereo(calib)
    cam_pts = np.asarray(cam_pts, float).reshape(-1, 2)
    proj_pts = np.asarray(proj_pts, float).reshape(-1, 2)
    if len(cam_pts) != len(proj_pts):
        raise ValueError(f"cam_pts and proj_pts differ in length: {len(cam_pts)} vs {len(proj_pts)}")
    Kc = np.asarray(calib.camera.K, float)
    Kp = np.asarray(calib.projector.K, float)
    rc = rays(calib.camera, cam_pts)
    rp = rays(calib.projector, proj_pts)
    X = midpoint(rc, rp, R, T)
    ok = np.isfinite(X).all(1)
    if refine and ok.any():
        cu = _project(Kc, rc[ok])[0]     # undistorted observations, pixels
        pu = _project(Kp, rp[ok])[0]
        Y = X[ok]
        for _ in range(int(iterations)):
            mc, _ = _project(Kc, Y)
            Yp = Y @ R.T + T
            mp, _ = _project(Kp, Yp)
            r = np.concatenate([cu - mc, pu - mp], axis=1)                    # (n, 4)
            J = np.concatenate([_pinhole_jac(Kc, Y), _pinhole_jac(Kp, Yp) @ R], axis=1)  # (n, 4, 3)
            JT = np.transpose(J, (0, 2, 1))
            try:
                step = np.linalg.solve(JT @ J, (JT @ r[:, :, None]))[:, :, 0]
            except np.linalg.LinAlgError:
                break
            step[~np.isfinite(step).all(1)] = 0.0
            Y = Y + step
            if np.max(np.abs(step)) < 1e-12 * max(1.0, float(np.max(np.abs(Y)))):
                break
        X[ok] = Y
    cam_pred = np.full_like(cam_pts, np.nan)
    proj_pred = np.full_like(proj_pts, np.nan)
    if ok.any():
        cam_pred[ok] = calib.camera.project(np.eye(3), np.zeros(3), X[ok])
        proj_pred[ok] = calib.projector.project(R, T, X[ok])
    return X, cam_pts - cam_pred, proj_pts - proj_pred


def _planes(Kp, R, T, coord, axis: int):
    """Projector column (axis 0) or row (axis 1) planes ``a . X + b = 0`` in the camera frame.

    ``a = (Kp[axis] - coord Kp[2]) R``, ``b = (Kp[axis] - coord Kp[2]) . T``: the algebraic residual
    ``a . X + b`` is the projector reprojection error along that axis in pixels times the depth
    of X in the projector frame (so columns and rows are weighted alike).
    """
    w = Kp[axis][None, :] - coord[:, None] * Kp[2][None, :]      # (N, 3)
    return w @ R, w @ T


def _undistort_projector_coords(projector, col, row, use_col, use_row):
    """Undistorted projector coordinates where both are known; for one coordinate, the input."""
    col_u, row_u = col.copy(), row.copy()
    both = use_col & use_row
    if projector.distortion.model != "none" and both.any():
        u = projector.undistort(np.column_stack([col[both], row[both]]))
        col_u[both], row_u[both] = u[:, 0], u[:, 1]
    return col_u, row_u


def triangulate_dense(calib, col, row, valid_col=None, valid_row=None, *, use: str = "both",
                      pixels=None, newton_iterations: int = 20):
    """Triangulate decoded camera pixels: camera ray x projector column plane (and row plane).

    Parameters
    ----------
    calib : calibration with a projector and ``(R, T)``.
    col, row : (H, W) decoded projector column / row of every camera pixel (projector pixels; NaN
        where invalid), e.g. :attr:`procam.decode.DecodeResult.col` / ``row``.
    valid_col, valid_row : (H, W) bool, default ``isfinite(col)`` / ``isfinite(row)``.
    use : ``"both"`` (default): least squares on both planes where both coordinates are valid,
        the column plane where only the column is, the row plane where only the row is;
        ``"col"`` / ``"row"``: that coordinate only.  With a mostly horizontal baseline the row
        planes nearly contain the camera rays, so ``"row"`` alone is ill-conditioned (the
        least-squares ``"both"`` weights each plane by how well it constrains the depth).
    pixels : optional (N, 2) int camera pixels ``(x, y)`` to triangulate instead of every valid one.
    newton_iterations : with a distorted projector and one coordinate only, the surface of a
        projector column is not a plane: the depth along the camera ray is found by Newton steps
        on the distorted projector coordinate, started from the undistorted plane.

    Returns
    -------
    dict with
        ``points`` (N, 3) camera frame, board units; ``pixels`` (N, 2) int64 camera pixel (x, y) of
        each point; ``both`` (N,) bool, both coordinates used; ``residual_px`` (N,) projector
        reprojection error (pixels, Euclidean, in the undistorted projector image) of the point,
        0 when only one coordinate was used (nothing to compare with).
        Points not in front of both devices are left out.
    """
    if use not in USES:
        raise ValueError(f"use must be one of {', '.join(USES)}, got {use!r}")
    R, T = _require_stereo(calib)
    col = np.asarray(col)
    row = np.asarray(row)
    if col.shape != row.shape or col.ndim != 2:
        raise ValueError(f"col and row must be (H, W) maps of one shape, got {col.shape} and {row.shape}")
    vc = np.isfinite(col) if valid_col is None else (np.asarray(valid_col, bool) & np.isfinite(col))
    vr = np.isfinite(row) if valid_row is None else (np.asarray(valid_row, bool) & np.isfinite(row))
    if use == "col":
        vr = np.zeros_like(vr)
    elif use == "row":
        vc = np.zeros_like(vc)
    if pixels is None:
        ys, xs = np.nonzero(vc | vr)
    else:
        pix = np.asarray(pixels, np.int64).reshape(-1, 2)
        xs, ys = pix[:, 0], pix[:, 1]
    uc = vc[ys, xs]
    ur = vr[ys, xs]
    keep = uc | ur
    xs, ys, uc, ur = xs[keep], ys[keep], uc[keep], ur[keep]
    c = np.where(uc, col[ys, xs], np.nan).astype(np.float64)
    r = np.where(ur, row[ys, xs], np.nan).astype(np.float64)
    d = rays(calib.camera, np.column_stack([xs, ys]).astype(np.float64))   # (N, 3)
    Kp = np.asarray(calib.projector.K, float)
    cu, ru = _undistort_projector_coords(calib.projector, c, r, uc, ur)
    num = np.zeros(len(d))
    den = np.zeros(len(d))
    for use_axis, coord, axis in ((uc, cu, 0), (ur, ru, 1)):
        if not use_axis.any():
            continue
        a, b = _planes(Kp, R, T, np.where(use_axis, coord, 0.0), axis)
        ad = np.einsum("ij,ij->i", a, d)
        num -= np.where(use_axis, ad * b, 0.0)
        den += np.where(use_axis, ad * ad, 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = num / den
    both = uc & ur
    one = uc ^ ur
    if calib.projector.distortion.model != "none" and one.any():
        s[one] = _newton_depth(calib, d[one], np.where(uc[one], c[one], r[one]), np.where(uc[one], 0, 1),
                               s[one], R, T, newton_iterations)
    X = s[:, None] * d
    Xp = X @ R.T + T
    front = np.isfinite(s) & (s > 0) & (Xp[:, 2] > 0)
    res = np.zeros(len(d))
    if both.any():
        m, _ = _project(Kp, Xp[both])
        res[both] = np.hypot(m[:, 0] - cu[both], m[:, 1] - ru[both])
    return {"points": X[front], "pixels": np.column_stack([xs, ys])[front].astype(np.int64),
            "both": both[front], "residual_px": res[front]}


def _newton_depth(calib, d, obs, axis, s0, R, T, iterations, rel_tol: float = 1e-13):
    """Depth s along rays d (N, 3) whose distorted projector coordinate ``axis`` (0/1) equals ``obs``.

    Chord-Newton: the derivative is taken once (finite difference at the start, where the
    undistorted plane already puts s within the distortion's small perturbation), then each point
    is updated until its step is below ``rel_tol * s`` (only the unconverged ones are re-projected).
    """
    proj = calib.projector
    s = np.asarray(s0, float).copy()

    def coord(idx, sv):
        with np.errstate(invalid="ignore", divide="ignore"):
            p = proj.project(R, T, sv[:, None] * d[idx])
        return p[np.arange(len(idx)), axis[idx]] - obs[idx]

    act = np.nonzero(np.isfinite(s) & (s > 0))[0]
    if not len(act):
        return s
    f = coord(act, s[act])
    h = 1e-6 * s[act]
    with np.errstate(invalid="ignore", divide="ignore"):
        df = (coord(act, s[act] + h) - f) / h
    for _ in range(int(iterations)):
        with np.errstate(invalid="ignore", divide="ignore"):
            step = f / df
        good = np.isfinite(step)
        act, df, step = act[good], df[good], step[good]
        s[act] -= step
        keep = np.abs(step) > rel_tol * np.abs(s[act])
        act, df = act[keep], df[keep]
        if not len(act):
            break
        f = coord(act, s[act])
    return s
