"""Camera models: pinhole projection, the division distortion model, pose conventions.

Conventions
-----------
* Pixels are ``(x, y)`` = (column, row), origin at the centre of the top-left pixel.
* ``K = [[f, 0, u0], [0, alpha*f, v0], [0, 0, 1]]`` (zero skew).
* A pose ``(R, t)`` maps board (world) points into the device frame: ``X_dev = R @ X + t``.
* Division model (Fitzgibbon; paper Eq. 2), **distorted -> undistorted**, about the
  centre of distortion ``c`` with the radius measured in the distorted image::

      m = c + (m_hat - c) / (1 + k1 r^2 + k2 r^4),   r = |m_hat - c|   (pixels)

  Barrel distortion has ``k1 < 0``.  Its inverse (:func:`distort_division`) is solved
  per point by Newton's method.
* Euler angles ``(psi, nu, phi)`` are intrinsic XYZ: ``R = Rx(psi) @ Ry(nu) @ Rz(phi)``,
  i.e. ``scipy Rotation.from_euler('XYZ', ...)`` (upper case).  Radians in code.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation


def intrinsic_matrix(f: float, u0: float, v0: float, alpha: float = 1.0) -> np.ndarray:
    """(3, 3) pinhole matrix with zero skew: ``[[f, 0, u0], [0, alpha f, v0], [0, 0, 1]]``."""
    return np.array([[f, 0.0, u0], [0.0, alpha * f, v0], [0.0, 0.0, 1.0]])


def euler_to_matrix(psi: float, nu: float, phi: float) -> np.ndarray:
    """Rotation ``Rx(psi) @ Ry(nu) @ Rz(phi)`` (angles in radians), shape (3, 3)."""
    return Rotation.from_euler("XYZ", [psi, nu, phi]).as_matrix()


def matrix_to_euler(R: np.ndarray) -> np.ndarray:
    """Intrinsic XYZ angles ``(psi, nu, phi)`` in radians of a (3, 3) rotation.

    ``nu = asin(R[0, 2])``, ``psi = atan2(-R[1, 2], R[2, 2])``, ``phi = atan2(-R[0, 1], R[0, 0])``.
    """
    R = np.asarray(R, dtype=float)
    nu = np.arcsin(np.clip(R[0, 2], -1.0, 1.0))
    psi = np.arctan2(-R[1, 2], R[2, 2])
    phi = np.arctan2(-R[0, 1], R[0, 0])
    return np.array([psi, nu, phi])


def project(K: np.ndarray, R: np.ndarray, t: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Pinhole projection of (N, 3) points: ``pi(K (R X + t))``, returns (N, 2) pixels."""
    X = np.asarray(X, dtype=float).reshape(-1, 3)
    Xc = X @ np.asarray(R, float).T + np.asarray(t, float).reshape(1, 3)
    m = Xc @ np.asarray(K, float).T
    return m[:, :2] / m[:, 2:3]


def undistort_division(pts: np.ndarray, center, k1: float, k2: float = 0.0) -> np.ndarray:
    """Division model, distorted -> undistorted pixels. ``pts`` (N, 2) -> (N, 2)."""
    pts = np.asarray(pts, dtype=float).reshape(-1, 2)
    d = pts - np.asarray(center, float).reshape(1, 2)
    r2 = np.sum(d * d, axis=1, keepdims=True)
    return np.asarray(center, float).reshape(1, 2) + d / (1.0 + k1 * r2 + k2 * r2 * r2)


def distort_division(pts: np.ndarray, center, k1: float, k2: float = 0.0,
                     iterations: int = 50) -> np.ndarray:
    """Inverse of :func:`undistort_division`: undistorted -> distorted pixels, (N, 2).

    Solves ``r_d - r_u (1 + k1 r_d^2 + k2 r_d^4) = 0`` for ``r_d`` by Newton's method from
    ``r_d = r_u``.  Points where no root exists (strong pincushion far out) are NaN.
    """
    pts = np.asarray(pts, dtype=float).reshape(-1, 2)
    c = np.asarray(center, float).reshape(1, 2)
    d = pts - c
    ru = np.hypot(d[:, 0], d[:, 1])
    rd = ru.copy()
    for _ in range(iterations):
        r2 = rd * rd
        g = rd - ru * (1.0 + k1 * r2 + k2 * r2 * r2)
        dg = 1.0 - ru * (2.0 * k1 * rd + 4.0 * k2 * r2 * rd)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = g / dg
        rd = rd - step
        if np.all(np.abs(step[np.isfinite(step)]) < 1e-12):
            break
    r2 = rd * rd
    ok = np.isfinite(rd) & (np.abs(rd - ru * (1 + k1 * r2 + k2 * r2 * r2)) < 1e-6) & (rd >= 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(ru > 0, rd / ru, 1.0)
    out = c + d * scale[:, None]
    out[~ok] = np.nan
    return out


def rvec_to_matrix(rvec) -> np.ndarray:
    """Rotation vector (3,) -> (3, 3) matrix."""
    return Rotation.from_rotvec(np.asarray(rvec, float).reshape(3)).as_matrix()


def matrix_to_rvec(R) -> np.ndarray:
    """(3, 3) rotation matrix -> rotation vector (3,)."""
    return Rotation.from_matrix(np.asarray(R, float)).as_rotvec()


def compose(R_ab: np.ndarray, t_ab: np.ndarray, R_bc: np.ndarray, t_bc: np.ndarray):
    """``(R_ac, t_ac)`` with ``x_a = R_ab (R_bc x_c + t_bc) + t_ab``."""
    R_ab = np.asarray(R_ab, float)
    return R_ab @ np.asarray(R_bc, float), R_ab @ np.asarray(t_bc, float).reshape(3) + np.asarray(t_ab, float).reshape(3)


def invert(R: np.ndarray, t: np.ndarray):
    """Inverse pose: ``(R^T, -R^T t)``."""
    R = np.asarray(R, float)
    return R.T, -R.T @ np.asarray(t, float).reshape(3)


def euler_deg(R) -> np.ndarray:
    """Intrinsic XYZ angles ``(psi, nu, phi)`` of a (3, 3) rotation in **degrees** (3,).

    For rotations that are not a board pose (e.g. the camera -> projector ``R``); a board pose's
    angles are :func:`board_angles_deg`.
    """
    return np.degrees(matrix_to_euler(R))


def board_angles_deg(R, t) -> np.ndarray:
    """Board angles ``(psi, nu, phi)`` in degrees (3,) of a board -> device pose ``(R, t)``.

    Measured in the board frame whose z points away from the device (DESIGN conventions; a
    fronto-parallel board gives (0, 0, 0)): if the device is on the board's +z side
    (``invert(R, t)[1][2] > 0``) the board frame is first turned 180 deg about its x axis, so the
    same physical pose gets the same angles whichever way its corners were numbered.
    Single-pose, multi-pose and :mod:`procam.evaluate` all report board angles with this function.
    """
    R = np.asarray(R, float)
    _, O = invert(R, t)
    if O[2] > 0:
        R = R @ np.diag([1.0, -1.0, -1.0])
    return euler_deg(R)
