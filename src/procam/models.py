"""Camera models: pinhole projection, the division distortion model, homographies, poses and angles.

Every solver, the Cramer-Rao bounds and the evaluation use these functions, so the bound is computed
on the model the solver fits (the simulator keeps its own independent copy on purpose: it is the
oracle). The projection and distortion functions accept complex arrays (complex-step derivatives), and the lens
models on coordinates (``*_xy``, :func:`brown`) forward-mode Duals too.

Conventions (``docs/conventions.md``)
------------------------------------
* Pixels are ``(x, y)`` = (column, row), origin at the centre of the top-left pixel.
* ``K = [[f, 0, u0], [0, alpha*f, v0], [0, 0, 1]]`` (zero skew).
* A transform named ``R_ab, t_ab`` (or a homography ``H_ab``) maps points of frame/plane ``b`` into
  ``a``: ``x_a = R_ab @ x_b + t_ab``. A board pose ``(R, t)`` maps board -> device.
* Division model (Fitzgibbon; paper Eq. 2), **distorted -> undistorted**, about the
  centre of distortion ``c`` with the radius measured in the distorted image::

      m = c + (m_hat - c) / (1 + k1 r^2 + k2 r^4),   r = |m_hat - c|   (pixels)

  Barrel distortion has ``k1 < 0``.  Its inverse (:func:`distort_division`) is solved
  per point by Newton's method.
* The lens models (the division model and OpenCV's ``k1, k2, p1, p2, k3`` model, :func:`brown`) are
  written once here on coordinates, generic over the derivative type (plain, complex and
  :mod:`procam._dual` arrays): every solver's lens model is one of them (OpenCV's own functions where
  no derivative is carried).
* Angles: the plain intrinsic XYZ Euler angles ``(psi, nu, phi)`` of a rotation,
  ``R = Rx(psi) @ Ry(nu) @ Rz(phi)`` (scipy ``Rotation.from_euler('XYZ', ...)``), are
  :func:`euler_to_matrix` / :func:`matrix_to_euler` (radians) and :func:`euler_deg` (degrees); the angles
  of a **board pose** (board z axis away from the device, so the same physical pose gets the same
  angles however its corners were numbered) are :func:`board_angles_deg`. Radians in code, degrees at
  the user surface.
"""

from __future__ import annotations

import numpy as np

#: Scale of the conditioned division coefficients in the single-pose camera parameter vector:
#: ``k1 = kappa1 / S^2``, ``k2 = kappa2 / S^4`` with ``S = KAPPA_SCALE`` pixels.
KAPPA_SCALE = 1000.0


# ----------------------------------------------------------------------------------------------
# intrinsics, rotations, poses
def intrinsic_matrix(f, u0, v0, alpha=1.0) -> np.ndarray:
    """(3, 3) pinhole matrix with zero skew: ``[[f, 0, u0], [0, alpha f, v0], [0, 0, 1]]``."""
    dtype = np.result_type(f, u0, v0, alpha, float)  # complex for complex-step derivatives
    return np.array([[f, 0.0, u0], [0.0, alpha * f, v0], [0.0, 0.0, 1.0]], dtype=dtype)


def euler_to_matrix(psi: float, nu: float, phi: float) -> np.ndarray:
    """Rotation ``Rx(psi) @ Ry(nu) @ Rz(phi)`` (angles in radians), shape (3, 3)."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_euler("XYZ", [psi, nu, phi]).as_matrix()


def matrix_to_euler(R: np.ndarray) -> np.ndarray:
    """Intrinsic XYZ angles ``(psi, nu, phi)`` in radians of a (3, 3) rotation (inverse of
    :func:`euler_to_matrix`).

    ``nu = asin(R[0, 2])``, ``psi = atan2(-R[1, 2], R[2, 2])``, ``phi = atan2(-R[0, 1], R[0, 0])``.
    """
    R = np.asarray(R, dtype=float)
    nu = np.arcsin(np.clip(R[0, 2], -1.0, 1.0))
    psi = np.arctan2(-R[1, 2], R[2, 2])
    phi = np.arctan2(-R[0, 1], R[0, 0])
    return np.array([psi, nu, phi])


def euler_deg(R) -> np.ndarray:
    """Intrinsic XYZ angles ``(psi, nu, phi)`` of a (3, 3) rotation in **degrees** (3,).

    For rotations that are not a board pose (e.g. the camera -> projector ``R``); a board pose's
    angles are :func:`board_angles_deg`.

    >>> euler_deg(euler_to_matrix(*np.radians([12.0, -7.0, 3.0]))).round(6)
    array([12., -7.,  3.])
    """
    return np.degrees(matrix_to_euler(R))


def board_angles_deg(R, t) -> np.ndarray:
    """Board angles ``(psi, nu, phi)`` in degrees (3,) of a board -> device pose ``(R, t)``.

    Measured in the board frame whose z points away from the device (a fronto-parallel board gives
    (0, 0, 0)): if the device is on the board's +z side (``invert(R, t)[1][2] > 0``) the board frame is
    first turned 180 deg about its x axis, so the same physical pose gets the same angles whichever way
    its corners were numbered. Single-pose, multi-pose and :mod:`procam.evaluate` all report board
    angles with this function.

    >>> R = euler_to_matrix(*np.radians([15.0, 12.0, 0.0]))
    >>> board_angles_deg(R, [0.0, 0.0, 500.0]).round(6)
    array([15., 12.,  0.])
    """
    R = np.asarray(R, float)
    _, O = invert(R, t)
    if O[2] > 0:
        R = R @ np.diag([1.0, -1.0, -1.0])
    return euler_deg(R)


def rvec_to_matrix(rvec) -> np.ndarray:
    """Rotation vector (3,) -> (3, 3) matrix (Rodrigues).

    Real input goes through scipy's ``Rotation``; complex input (complex-step derivatives) through the
    Rodrigues formula, with its series near zero.
    """
    w = np.asarray(rvec).reshape(3)
    if not np.iscomplexobj(w):
        from scipy.spatial.transform import Rotation

        return Rotation.from_rotvec(w.astype(float)).as_matrix()
    th2 = w @ w
    W = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]], dtype=complex)
    if abs(th2) < 1e-12:
        a, b = 1.0 - th2 / 6.0, 0.5 - th2 / 24.0
    else:
        th = np.sqrt(th2)
        a, b = np.sin(th) / th, (1.0 - np.cos(th)) / th2
    return np.eye(3) + a * W + b * (W @ W)


def matrix_to_rvec(R) -> np.ndarray:
    """(3, 3) rotation matrix -> rotation vector (3,)."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(np.asarray(R, float)).as_rotvec()


def compose(R_ab: np.ndarray, t_ab: np.ndarray, R_bc: np.ndarray, t_bc: np.ndarray):
    """``(R_ac, t_ac)`` with ``x_a = R_ab (R_bc x_c + t_bc) + t_ab`` (b -> a after c -> b)."""
    R_ab = np.asarray(R_ab, float)
    return R_ab @ np.asarray(R_bc, float), R_ab @ np.asarray(t_bc, float).reshape(3) + np.asarray(t_ab, float).reshape(3)


def invert(R: np.ndarray, t: np.ndarray):
    """Inverse transform: ``(R_ba, t_ba) = (R^T, -R^T t)`` of ``(R_ab, t_ab)``."""
    R = np.asarray(R, float)
    return R.T, -R.T @ np.asarray(t, float).reshape(3)


# ----------------------------------------------------------------------------------------------
# projection and distortion
def project(K: np.ndarray, R: np.ndarray, t: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Pinhole projection of (N, 3) points: ``pi(K (R X + t))``, returns (N, 2) pixels (complex-safe)."""
    X = np.asarray(X).reshape(-1, 3)
    Xc = X @ np.asarray(R).T + np.asarray(t).reshape(1, 3)
    m = Xc @ np.asarray(K).T
    return m[:, :2] / m[:, 2:3]


def undistort_division(pts: np.ndarray, center, k1: float, k2: float = 0.0) -> np.ndarray:
    """Division model, distorted -> undistorted pixels. ``pts`` (N, 2) -> (N, 2)."""
    pts = np.asarray(pts, dtype=float).reshape(-1, 2)
    c = np.asarray(center, float).reshape(2)
    return np.column_stack(undistort_division_xy(pts[:, 0], pts[:, 1], c[0], c[1], k1, k2))


def distort_division(pts: np.ndarray, center, k1, k2=0.0, iterations: int = 50) -> np.ndarray:
    """Inverse of :func:`undistort_division`: undistorted -> distorted pixels, (N, 2) (complex-safe;
    :func:`distort_division_xy`).

    >>> p = np.array([[900.0, 700.0]])
    >>> q = distort_division(p, (640.0, 400.0), -1e-7)
    >>> bool(np.allclose(undistort_division(q, (640.0, 400.0), -1e-7), p, atol=1e-9))
    True
    """
    pts = np.asarray(pts).reshape(-1, 2)
    c = np.asarray(center).reshape(2)
    return np.column_stack(distort_division_xy(pts[:, 0], pts[:, 1], c[0], c[1], k1, k2, iterations))


# The lens models on coordinates, generic over the derivative type: plain or complex arrays (complex-step
# derivatives) and procam._dual Duals (forward mode) alike.  Every solver's lens is one of these two.
def undistort_division_xy(x, y, cx, cy, k1, k2):
    """Division model (module docstring), distorted -> undistorted pixels ``(x_u, y_u)`` of distorted ``x, y``
    (arrays of one shape, px) about the centre ``(cx, cy)`` with ``k1`` [px^-2], ``k2`` [px^-4]."""
    from . import _dual as D

    dx, dy = x - cx, y - cy
    r2 = dx * dx + dy * dy
    den = 1.0 + k1 * r2 + k2 * r2 * r2
    if isinstance(den, D.Dual):  # one reciprocal's derivatives instead of two quotients'
        s = 1.0 / den
        return cx + dx * s, cy + dy * s
    return cx + dx / den, cy + dy / den


def distort_division_xy(x, y, cx, cy, k1, k2, iterations: int = 50):
    """Inverse of :func:`undistort_division_xy`: undistorted -> distorted pixels ``(x_d, y_d)``.

    With ``r_d = s r_u`` the scale ``s`` solves ``s = 1 + k1 s^2 q + k2 s^4 q^2``, ``q = r_u^2`` (the division
    model at the distorted radius), by Newton's method from ``s = 1`` -- the same iterates as Newton on ``r_d``
    from ``r_d = r_u``, without a square root (so no branch at the centre) -- until no step exceeds 1e-15 or
    ``iterations`` steps.  Complex input iterates in complex arithmetic (every step, so the complex step is
    carried); Duals iterate on their values, then one Newton step carries the derivatives (the implicit
    function's, exactly).  Points where no root exists (strong pincushion far out) are NaN.
    """
    from . import _dual as D

    dx, dy = x - cx, y - cy
    q = dx * dx + dy * dy
    dual = any(isinstance(a, D.Dual) for a in (q, k1, k2))
    qv, k1v, k2v = D.value(q), D.value(k1), D.value(k2)
    s = np.ones_like(qv)
    complex_step = np.iscomplexobj(qv) or np.iscomplexobj(k1v) or np.iscomplexobj(k2v)
    with np.errstate(all="ignore"):
        for _ in range(iterations):
            g = s - 1.0 - k1v * s * s * qv - k2v * s ** 4 * qv * qv
            dg = 1.0 - 2.0 * k1v * s * qv - 4.0 * k2v * s ** 3 * qv * qv
            step = g / dg
            s = s - step
            if not complex_step and np.all(np.abs(step[np.isfinite(step)]) < 1e-15):
                break
        g = s - 1.0 - k1v * s * s * qv - k2v * s ** 4 * qv * qv
        ok = np.isfinite(s) & (np.abs(g) * np.sqrt(np.abs(qv)) < 1e-6) & (np.real(s) >= 0)
        if dual:
            dg = 1.0 - 2.0 * k1v * s * qv - 4.0 * k2v * s ** 3 * qv * qv
            s = s - (s - 1.0 - k1 * s * s * q - k2 * s ** 4 * q * q) / dg
    xd, yd = cx + dx * s, cy + dy * s
    if np.all(ok):
        return xd, yd
    if dual:
        return D.where(ok, xd, np.nan), D.where(ok, yd, np.nan)
    xd, yd = np.array(xd, dtype=np.result_type(xd, float)), np.array(yd, dtype=np.result_type(yd, float))
    xd[~ok], yd[~ok] = np.nan, np.nan
    return xd, yd


def brown(x, y, k1, k2, p1, p2, k3):
    """OpenCV's distortion (``cv2.projectPoints``' model, terms ``k1, k2, p1, p2, k3``) of normalised coordinates
    ``x, y``: ``(x_d, y_d)``."""
    r2 = x * x + y * y
    rad = 1.0 + k1 * r2 + k2 * r2 * r2 + k3 * r2 * r2 * r2
    xy = x * y
    return x * rad + 2.0 * p1 * xy + p2 * (r2 + 2.0 * x * x), y * rad + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * xy


def brown_jacobian(x, y, k1, k2, p1, p2, k3):
    """``(a, b, d)``: the Jacobian ``[[a, b], [b, d]]`` of :func:`brown` at undistorted normalised ``(x, y)`` (plain
    or Dual)."""
    r2 = x * x + y * y
    rad = 1 + k1 * r2 + k2 * r2 ** 2 + k3 * r2 ** 3
    dr = k1 + 2 * k2 * r2 + 3 * k3 * r2 ** 2
    return (rad + 2 * x * x * dr + 2 * p1 * y + 6 * p2 * x, 2 * x * y * dr + 2 * p1 * x + 2 * p2 * y,
            rad + 2 * y * y * dr + 6 * p1 * y + 2 * p2 * x)


def brown_inverse(xd, yd, k1, k2, p1, p2, k3, iterations: int = 20):
    """Undistorted normalised coordinates of distorted ones (inverse of :func:`brown`): fixed-point iteration on
    the values, then, for Duals, one Newton step that carries the derivatives (the implicit function's, exactly)."""
    from . import _dual as D

    V = D.value
    kv = [V(k) for k in (k1, k2, p1, p2, k3)]
    xdv, ydv = V(xd), V(yd)
    x, y = xdv, ydv
    with np.errstate(all="ignore"):
        for _ in range(iterations):
            bx, by = brown(x, y, *kv)
            x, y = x - (bx - xdv), y - (by - ydv)
    if not any(isinstance(a, D.Dual) for a in (xd, yd, k1, k2, p1, p2, k3)):
        return x, y
    a, b, d = brown_jacobian(x, y, *kv)
    det = a * d - b * b
    bx, by = brown(x, y, k1, k2, p1, p2, k3)
    ex, ey = bx - xd, by - yd
    return x - (d * ex - b * ey) / det, y - (a * ey - b * ex) / det


def brown_recentred(coeffs, offset, extent, free=(0, 1, 2, 3, 4), n: int = 25) -> tuple[np.ndarray, float]:
    """OpenCV's coefficients about the principal point that best describe a lens whose distortion is centred
    ``offset`` away from it (decentred), and how far they miss.

    A decentred radial lens maps ``x -> e + brown(x - e)``; to first order in ``e`` that is radial about the
    principal point plus OpenCV's tangential terms (``p2 = -k1 e_x``, ``p1 = -k1 e_y``: the decentring distortion
    the tangential terms were made for). The coefficients are the linear least-squares fit of that map over the
    image (``brown`` is linear in them).

    Parameters
    ----------
    coeffs : (5,) OpenCV ``k1, k2, p1, p2, k3`` of the decentred lens (about its own centre).
    offset : (2,) the distortion centre minus the principal point, normalised (px / f).
    extent : (x0, x1, y0, y1) the image's undistorted normalised extent the fit covers.
    free : indices of the coefficients the fit may use (the others stay zero).

    Returns ``(coefficients (5,), largest miss over the grid, normalised)``.
    """
    c = np.asarray(coeffs, float)
    ex, ey = (float(v) for v in offset)
    x, y = np.meshgrid(np.linspace(extent[0], extent[1], n), np.linspace(extent[2], extent[3], n))
    x, y = x.ravel(), y.ravel()
    bx, by = brown(x - ex, y - ey, *c)
    tx, ty = bx + ex - x, by + ey - y              # what the decentred lens adds to the pinhole's point
    r2 = x * x + y * y
    cols = [np.r_[x * r2, y * r2], np.r_[x * r2 ** 2, y * r2 ** 2], np.r_[2 * x * y, r2 + 2 * y * y],
            np.r_[r2 + 2 * x * x, 2 * x * y], np.r_[x * r2 ** 3, y * r2 ** 3]]
    A = np.column_stack([cols[i] for i in free])
    sol = np.linalg.lstsq(A, np.r_[tx, ty], rcond=None)[0]
    out = np.zeros(5)
    out[list(free)] = sol
    miss = np.r_[tx, ty] - A @ sol
    return out, float(np.max(np.hypot(miss[:len(x)], miss[len(x):])))


def camera_predict(p, obj) -> np.ndarray:
    """Distorted pixels (N, 2) of board points ``obj`` (N, 3) for the single-pose camera parameters ``p``.

    ``p = (f, alpha, u0, v0, kappa1, kappa2, rvec (3), t (3))`` (the parameter vector
    :data:`procam.parameters.CAMERA_VECTOR`) with ``k1 = kappa1 / S^2``, ``k2 = kappa2 / S^4``,
    ``S = KAPPA_SCALE``; the division model's centre is the principal point. Complex-safe. Points where
    the division model has no inverse are NaN.
    """
    p = np.asarray(p)
    K = intrinsic_matrix(p[0], p[2], p[3], p[1])
    mu = project(K, rvec_to_matrix(p[6:9]), p[9:12], obj)
    k1, k2 = p[4] / KAPPA_SCALE ** 2, p[5] / KAPPA_SCALE ** 4
    if not np.iscomplexobj(p) and k1 == 0 and k2 == 0:
        return mu
    return distort_division(mu, p[2:4], k1, k2)


def projector_predict(q, obj, u0) -> np.ndarray:
    """Projector pixels (N, 2) for ``q = (f, v0, rvec (3), t (3))`` (:data:`procam.parameters.PROJECTOR_VECTOR`)
    with ``u0`` fixed and alpha = 1 (the single-pose projector model). Complex-safe."""
    q = np.asarray(q)
    return project(intrinsic_matrix(q[0], u0, q[1]), rvec_to_matrix(q[2:5]), q[5:8], obj)


# ----------------------------------------------------------------------------------------------
# homographies
def hartley_normalizer(pts: np.ndarray) -> np.ndarray:
    """Hartley similarity (3, 3) of (N, 2) points: centroid to 0, mean distance sqrt(2)."""
    pts = np.asarray(pts, float).reshape(-1, 2)
    c = pts.mean(axis=0)
    d = np.mean(np.hypot(pts[:, 0] - c[0], pts[:, 1] - c[1]))
    s = np.sqrt(2.0) / d if d > 0 else 1.0
    return np.array([[s, 0.0, -s * c[0]], [0.0, s, -s * c[1]], [0.0, 0.0, 1.0]])


def apply_homography(H, pts) -> np.ndarray:
    """``pi(H (x, y, 1))`` of (N, 2) points, returns (N, 2)."""
    pts = np.asarray(pts, float).reshape(-1, 2)
    p = np.column_stack([pts, np.ones(len(pts))]) @ np.asarray(H).T
    return p[:, :2] / p[:, 2:3]


def homography(src, dst, *, refine: bool = True) -> np.ndarray:
    """Homography ``H`` (3, 3) with ``dst ~ H src`` and ``H[2, 2] = 1``: normalised DLT, then LM on the
    dst-side error.

    Exact (to rounding) on noise-free correspondences, which ``cv2.findHomography`` is not (its
    refinement stops at ~1e-6 px). Raises ``ValueError`` if the points are degenerate (fewer than 4,
    collinear).

    >>> src = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.2]])
    >>> H = np.array([[2.0, 0.1, 3], [0.2, 1.5, -1], [0.01, 0.02, 1]])
    >>> bool(np.allclose(homography(src, apply_homography(H, src)), H))
    True
    """
    from scipy.optimize import least_squares

    src = np.asarray(src, float).reshape(-1, 2)
    dst = np.asarray(dst, float).reshape(-1, 2)
    if len(src) < 4:
        raise ValueError(f"homography needs >= 4 points, got {len(src)}")
    Ts, Td = hartley_normalizer(src), hartley_normalizer(dst)
    a = np.column_stack([src, np.ones(len(src))]) @ Ts.T
    b = np.column_stack([dst, np.ones(len(dst))]) @ Td.T
    z = np.zeros_like(a)
    A = np.vstack([np.hstack([a, z, -b[:, :1] * a]), np.hstack([z, a, -b[:, 1:2] * a])])
    _, s, Vt = np.linalg.svd(A)
    if s[-2] <= 1e-12 * s[0]:
        raise ValueError("homography estimation failed (points collinear or too few)")
    H = np.linalg.solve(Td, Vt[-1].reshape(3, 3) @ Ts)
    if not np.all(np.isfinite(H)) or abs(H[2, 2]) < 1e-300:
        raise ValueError("homography estimation failed (points collinear or too few)")
    H = H / H[2, 2]
    if refine:
        def fun(h):
            return (apply_homography(np.append(h, 1.0).reshape(3, 3), src) - dst).ravel()

        with np.errstate(all="ignore"):
            r = least_squares(fun, H.ravel()[:8], method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15)
        if np.all(np.isfinite(r.x)) and r.cost <= 0.5 * np.sum(fun(H.ravel()[:8]) ** 2):
            H = np.append(r.x, 1.0).reshape(3, 3)
    return H


def pose_from_homography(K, H_db):
    """Board -> device pose ``(R (3, 3), t (3,))`` from the board -> image homography ``H_db`` and ``K``
    (Zhang's decomposition, the rotation projected onto SO(3)); the board in front (``t_z > 0``)."""
    M = np.linalg.solve(np.asarray(K, float), np.asarray(H_db, float))
    lam = 1.0 / np.sqrt(np.linalg.norm(M[:, 0]) * np.linalg.norm(M[:, 1]))
    M = M * lam
    if M[2, 2] < 0:
        M = -M
    r1, r2 = M[:, 0], M[:, 1]
    U, _, Vt = np.linalg.svd(np.column_stack([r1, r2, np.cross(r1, r2)]))
    R = U @ Vt
    if np.linalg.det(R) < 0:
        R = U @ np.diag([1, 1, -1]) @ Vt
    return R, M[:, 2].copy()


def zhang_camera(H_cb, principal_point):
    """Closed-form ``(f, alpha)`` from the board -> image homography, known principal point (Zhang).

    Returns None when the pose is (near-)degenerate (no positive solution).
    """
    u0, v0 = principal_point
    Hs = np.array([[1.0, 0, -u0], [0, 1.0, -v0], [0, 0, 1.0]]) @ np.asarray(H_cb, float)
    Hs = Hs / np.linalg.norm(Hs)
    p, q = Hs[:, 0], Hs[:, 1]
    A = np.array([[p[0] * q[0], p[1] * q[1]], [p[0] ** 2 - q[0] ** 2, p[1] ** 2 - q[1] ** 2]])
    b = -np.array([p[2] * q[2], p[2] ** 2 - q[2] ** 2])
    try:
        a, bb = np.linalg.solve(A, b)
    except np.linalg.LinAlgError:
        return None
    if not (np.isfinite(a) and np.isfinite(bb)) or a <= 0 or bb <= 0:
        return None
    return float(a ** -0.5), float(np.sqrt(a / bb))
