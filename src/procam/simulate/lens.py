"""The simulator's own lens and rotation model (independent of :mod:`procam.models` on purpose).

The simulator is the oracle the solvers are tested against, so it does not share their projection,
distortion or Euler-angle code: a bug in one is then caught by the other.

* :func:`project` - pinhole projection ``pi(K X)``.
* :func:`distort`, :func:`undistort` - the camera lens of a :class:`~procam.simulate.Scene`: the
  division model (Fitzgibbon; its inverse by Newton's method) or OpenCV's radial-tangential model
  (its inverse by fixed-point iteration, as ``cv2.undistortPoints``), or none.
* :func:`euler_matrix`, :func:`matrix_euler` - intrinsic XYZ angles ``(psi, nu, phi)`` in degrees,
  ``R = Rx(psi) Ry(nu) Rz(phi)``.

Pixels are ``(x, y)`` = (column, row) with the origin at the centre of the top-left pixel.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
from scipy.spatial.transform import Rotation


class CameraLens(Protocol):
    """What :func:`distort` and :func:`undistort` read of a scene (a :class:`~procam.simulate.Scene` is one)."""

    cam_distortion: str  # "none", "division" or "opencv"
    cam_dist_coeffs: tuple  # (k1, k2) of the division model, or OpenCV's (k1, k2, p1, p2[, k3])
    cam_center: tuple  # (x, y) px, centre of the division model
    K_cam: np.ndarray  # (3, 3) camera matrix

__all__ = ["project", "distort", "undistort", "euler_matrix", "matrix_euler"]


def euler_matrix(angles_deg) -> np.ndarray:
    """``Rx(psi) Ry(nu) Rz(phi)`` for ``(psi, nu, phi)`` in degrees, shape (3, 3)."""
    return Rotation.from_euler("XYZ", np.asarray(angles_deg, float).reshape(3), degrees=True).as_matrix()


def matrix_euler(R) -> np.ndarray:
    """Intrinsic XYZ angles ``(psi, nu, phi)`` in degrees of a rotation matrix (3, 3)."""
    R = np.asarray(R, float)
    nu = np.arcsin(np.clip(R[0, 2], -1.0, 1.0))
    psi = np.arctan2(-R[1, 2], R[2, 2])
    phi = np.arctan2(-R[0, 1], R[0, 0])
    return np.degrees([psi, nu, phi])


def project(K, X) -> np.ndarray:
    """Pinhole projection ``pi(K X)`` of (N, 3) points in the device frame -> (N, 2) pixels."""
    X = np.asarray(X, float).reshape(-1, 3)
    K = np.asarray(K, float)
    x, y, z = X[:, 0], X[:, 1], X[:, 2]
    w = K[2, 0] * x + K[2, 1] * y + K[2, 2] * z
    u = (K[0, 0] * x + K[0, 1] * y + K[0, 2] * z) / w
    v = (K[1, 0] * x + K[1, 1] * y + K[1, 2] * z) / w
    return np.column_stack([u, v])


def _division_undistort(pts, center, k1, k2):
    d = pts - center
    r2 = np.sum(d * d, axis=-1, keepdims=True)
    return center + d / (1.0 + k1 * r2 + k2 * r2 * r2)


def _division_distort(pts, center, k1, k2, iterations=60):
    """Newton inverse of the division model: undistorted -> distorted (NaN where no root)."""
    d = pts - center
    ru = np.hypot(d[..., 0], d[..., 1])
    rd = ru.copy()
    for _ in range(iterations):
        r2 = rd * rd
        g = rd - ru * (1.0 + k1 * r2 + k2 * r2 * r2)
        dg = 1.0 - ru * (2.0 * k1 * rd + 4.0 * k2 * r2 * rd)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = g / dg
        rd = rd - step
        if np.all(np.abs(step[np.isfinite(step)]) < 1e-13 * np.maximum(1.0, ru.max(initial=1.0))):
            break
    r2 = rd * rd
    ok = np.isfinite(rd) & (rd >= 0) & (np.abs(rd - ru * (1 + k1 * r2 + k2 * r2 * r2)) < 1e-7)
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(ru > 0, rd / np.where(ru > 0, ru, 1.0), 1.0)
    out = center + d * scale[..., None]
    out[~ok] = np.nan
    return out


def _brown_distort_norm(xn, coeffs):
    """OpenCV's radial-tangential model on normalised coordinates (..., 2)."""
    k1, k2, p1, p2, k3 = coeffs
    x, y = xn[..., 0], xn[..., 1]
    r2 = x * x + y * y
    radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
    xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    return np.stack([xd, yd], axis=-1)


def _brown_undistort_norm(xd, coeffs, iterations=30):
    """Fixed-point inverse of :func:`_brown_distort_norm` (as OpenCV's undistortPoints)."""
    k1, k2, p1, p2, k3 = coeffs
    x = xd[..., 0].copy()
    y = xd[..., 1].copy()
    for _ in range(iterations):
        r2 = x * x + y * y
        radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
        dx = 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
        dy = p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
        x = (xd[..., 0] - dx) / radial
        y = (xd[..., 1] - dy) / radial
    return np.stack([x, y], axis=-1)


def _to_norm(K, pts) -> np.ndarray:
    """Pixels (..., 2) -> normalised image coordinates with the camera matrix ``K``."""
    return np.stack([(pts[..., 0] - K[0, 2]) / K[0, 0], (pts[..., 1] - K[1, 2]) / K[1, 1]], axis=-1)


def _to_pix(K, xn) -> np.ndarray:
    """Normalised image coordinates (..., 2) -> pixels with the camera matrix ``K``."""
    return np.stack([K[0, 0] * xn[..., 0] + K[0, 2], K[1, 1] * xn[..., 1] + K[1, 2]], axis=-1)


def distort(scene: CameraLens, pts) -> np.ndarray:
    """Camera lens: undistorted (ideal pinhole) pixels (..., 2) -> distorted (observed) pixels."""
    pts = np.asarray(pts, float)
    if scene.cam_distortion == "none":
        return pts.copy()
    if scene.cam_distortion == "division":
        k1, k2 = scene.cam_dist_coeffs
        return _division_distort(pts, scene.cam_center, k1, k2)
    return _to_pix(scene.K_cam, _brown_distort_norm(_to_norm(scene.K_cam, pts), scene.cam_dist_coeffs))


def undistort(scene: CameraLens, pts) -> np.ndarray:
    """Camera lens: distorted (observed) pixels (..., 2) -> undistorted pixels."""
    pts = np.asarray(pts, float)
    if scene.cam_distortion == "none":
        return pts.copy()
    if scene.cam_distortion == "division":
        k1, k2 = scene.cam_dist_coeffs
        return _division_undistort(pts, scene.cam_center, k1, k2)
    return _to_pix(scene.K_cam, _brown_undistort_norm(_to_norm(scene.K_cam, pts), scene.cam_dist_coeffs))


def _K(f, alpha, u0, v0):
    return np.array([[f, 0.0, u0], [0.0, alpha * f, v0], [0.0, 0.0, 1.0]])
