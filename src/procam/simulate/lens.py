"""The simulator's own lens and rotation model (independent of :mod:`procam.models` on purpose).

The simulator is the oracle the solvers are tested against, so it does not share their projection,
distortion or Euler-angle code: a bug in one is then caught by the other.

* :class:`Lens` - one device's lens distortion: none, the division model (Fitzgibbon; its inverse by
  Newton's method) or OpenCV's radial-tangential model, optionally with radial terms beyond OpenCV's
  (r^8, r^10, ...) and a radial centre offset from the principal point (decentring): lenses OpenCV's
  5-term model does not describe exactly.  Its inverse: fixed-point iteration (as
  ``cv2.undistortPoints``) polished by Newton's method.
* :func:`project` - pinhole projection ``pi(K X)``; :func:`project_points` - 3-D points to the
  pixels a device records (camera) or lights (projector panel), through its lens.
* :func:`distort`, :func:`undistort` - a scene device's lens on pixels.
* :func:`euler_matrix`, :func:`matrix_euler` - intrinsic XYZ angles ``(psi, nu, phi)`` in degrees,
  ``R = Rx(psi) Ry(nu) Rz(phi)``.

The projector is a reversed camera: the panel pixel that lights a 3-D point ``X`` (projector frame)
is ``K * distort(X / Z)``, exactly what ``cv2.projectPoints`` returns for an OpenCV lens; "distorted"
pixels are panel pixels, "undistorted" ones those of the ideal pinhole with the same ``K``.

Pixels are ``(x, y)`` = (column, row) with the origin at the centre of the top-left pixel; ``K`` has
zero skew.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from scipy.spatial.transform import Rotation

__all__ = ["Lens", "LENS_MODELS", "project", "project_points", "distort", "undistort", "euler_matrix",
           "matrix_euler"]

#: The lens models of :class:`Lens`.
LENS_MODELS = ("none", "division", "opencv")

#: Coefficients each model takes (``none`` ignores any it is given).
_N_COEFFS = {"none": 0, "division": 2, "opencv": 5}


@dataclass(frozen=True)
class Lens:
    """One device's lens distortion (immutable).

    Parameters
    ----------
    model : ``"none"``; ``"division"`` (Fitzgibbon, distorted -> undistorted pixels
        ``m = c + d / (1 + k1 r^2 + k2 r^4)``, ``d = m_hat - c``, ``r = |d|`` in distorted pixels); or
        ``"opencv"``: on normalised coordinates ``x = ((u - u0) / fx, (v - v0) / fy)`` (undistorted)::

            d = x - delta,  r^2 = |d|^2
            radial = 1 + k1 r^2 + k2 r^4 + k3 r^6 + h1 r^8 + h2 r^10 + ...
            x_d = delta + d * radial + tangential(x; p1, p2)     (OpenCV's tangential terms, about the pp)

        with ``delta`` the radial centre in normalised coordinates (0 at the principal point).
        ``delta = 0`` and no higher terms is OpenCV's 5-term model exactly (``cv2.projectPoints``).
    coeffs : ``(k1, k2)`` in px^-2, px^-4 for ``division``; ``(k1, k2, p1, p2, k3)`` for ``opencv``;
        ``()`` for ``none``.
    center : (x, y) px: the division model's centre, or the ``opencv`` lens's radial centre (a decentred
        lens when it is not the principal point); ``None`` = the principal point.
    higher : ``opencv`` only: coefficients ``(h1, h2, ...)`` of r^8, r^10, ... (dimensionless, r
        normalised).

    A lens is *describable* (:meth:`describable`) when procam's :class:`procam.calibration.Distortion`
    holds it exactly: none, division, or opencv with its radial centre at the principal point and no
    higher terms.
    """

    model: str = "none"
    coeffs: tuple = ()
    center: tuple | None = None
    higher: tuple = ()

    def __post_init__(self):
        s = object.__setattr__
        if self.model not in LENS_MODELS:
            raise ValueError(f"distortion must be division|opencv|none, got {self.model!r}")
        coeffs = tuple(float(c) for c in self.coeffs)
        want = _N_COEFFS[self.model]
        if self.model != "none" and len(coeffs) != want:
            raise ValueError(f"{self.model} distortion takes {want} coefficients, got {coeffs}")
        s(self, "coeffs", coeffs)
        higher = tuple(float(c) for c in self.higher)
        if higher and self.model != "opencv":
            raise ValueError(f"higher radial terms belong to the opencv model, not {self.model!r}")
        s(self, "higher", higher)
        if self.center is not None:
            c = tuple(float(v) for v in np.asarray(self.center, float).reshape(2))
            if not all(np.isfinite(c)):
                raise ValueError(f"distortion centre must be finite, got {c}")
            s(self, "center", c)
        if not all(np.isfinite(coeffs + higher)):
            raise ValueError(f"distortion coefficients must be finite, got {coeffs + higher}")

    # --------------------------------------------------------------------------------------------
    def center_px(self, K) -> np.ndarray:
        """The distortion centre (2,) px: ``center``, or the principal point of ``K``."""
        if self.center is None:
            return np.asarray(K, float)[:2, 2].copy()
        return np.array(self.center, float)

    def describable(self, K) -> bool:
        """True when :class:`procam.calibration.Distortion` holds this lens exactly (see the class)."""
        return not self.left_out(K)

    def left_out(self, K) -> list[str]:
        """What procam's distortion models cannot hold of this lens, in words (empty when describable)."""
        if self.model != "opencv":
            return []
        out = []
        if any(h != 0.0 for h in self.higher):
            terms = ", ".join(f"r^{2 * (4 + i)} {h:g}" for i, h in enumerate(self.higher) if h != 0.0)
            out.append(f"radial terms beyond k3 ({terms})")
        off = self.center_px(K) - np.asarray(K, float)[:2, 2]
        if np.any(off != 0.0):
            out.append(f"radial centre ({off[0]:+.6g}, {off[1]:+.6g}) px from the principal point")
        return out

    def _opencv(self, K):
        """(radial coefficients k1, k2, k3, h1, ..., p1, p2, delta or None) of an ``opencv`` lens."""
        k1, k2, p1, p2, k3 = self.coeffs
        K = np.asarray(K, float)
        delta = None
        if self.center is not None:
            off = (np.array(self.center) - K[:2, 2]) / np.array([K[0, 0], K[1, 1]])
            delta = off if np.any(off != 0.0) else None
        return (k1, k2, k3) + self.higher, p1, p2, delta

    def fold_radius(self, K) -> float:
        """Normalised radius (about the radial centre) beyond which the radial map ``r -> r * radial(r)``
        turns back (``inf`` if never; ``inf`` for models other than ``opencv``).  Distorting a point beyond
        it gives NaN: ``cv2.projectPoints`` returns a folded, meaningless point there."""
        if self.model != "opencv":
            return float("inf")
        radial, *_ = self._opencv(K)
        return _fold_radius(radial)

    # --------------------------------------------------------------------------------------------
    def distort(self, K, pts) -> np.ndarray:
        """Undistorted (ideal pinhole) pixels (..., 2) -> distorted pixels (observed / panel); NaN where
        the model has no value (division: no root; opencv: beyond :meth:`fold_radius`)."""
        pts = np.asarray(pts, float)
        K = np.asarray(K, float)
        if self.model == "none":
            return pts.copy()
        if self.model == "division":
            return _division_distort(pts, self.center_px(K), *self.coeffs)
        return _to_pix(K, self.distort_normalized(K, _to_norm(K, pts)))

    def undistort(self, K, pts) -> np.ndarray:
        """Distorted pixels (..., 2) -> undistorted pixels (NaN where the inverse does not converge)."""
        pts = np.asarray(pts, float)
        K = np.asarray(K, float)
        if self.model == "none":
            return pts.copy()
        if self.model == "division":
            return _division_undistort(pts, self.center_px(K), *self.coeffs)
        return _to_pix(K, self.undistort_normalized(K, _to_norm(K, pts)))

    def distort_normalized(self, K, xn) -> np.ndarray:
        """``opencv`` / ``none``: normalised undistorted coordinates (..., 2) -> normalised distorted ones."""
        xn = np.asarray(xn, float)
        if self.model == "none":
            return xn.copy()
        if self.model != "opencv":
            raise ValueError("distort_normalized is for the opencv model (the division model works in pixels)")
        radial, p1, p2, delta = self._opencv(K)
        out = _brown_distort_norm(xn, radial, p1, p2, delta)
        r_max = _fold_radius(radial)
        if np.isfinite(r_max):
            d = xn if delta is None else xn - delta
            out[np.sum(d * d, axis=-1) > r_max * r_max] = np.nan
        return out

    def undistort_normalized(self, K, xd) -> np.ndarray:
        """``opencv`` / ``none``: normalised distorted coordinates (..., 2) -> normalised undistorted ones."""
        xd = np.asarray(xd, float)
        if self.model == "none":
            return xd.copy()
        if self.model != "opencv":
            raise ValueError("undistort_normalized is for the opencv model (the division model works in pixels)")
        return _brown_undistort_norm(xd, *self._opencv(K))

    def project(self, K, X) -> np.ndarray:
        """Pixels (N, 2) a device records (lights) of (N, 3) points in its frame: ``K * distort(X / Z)``."""
        X = np.asarray(X, float).reshape(-1, 3)
        K = np.asarray(K, float)
        if self.model == "none":
            return project(K, X)
        if self.model == "division":
            return self.distort(K, project(K, X))
        with np.errstate(divide="ignore", invalid="ignore"):
            xn = X[:, :2] / X[:, 2:3]
        return _to_pix(K, self.distort_normalized(K, xn))

    def to_dict(self, K) -> dict:
        """JSON-able description: ``model``, ``coeffs`` and, but for ``none``, ``center`` (px),
        ``definition``, ``describable`` (:meth:`describable`) and, when not, ``left_out`` (:meth:`left_out`);
        division also ``k1``, ``k2``; opencv also ``higher``."""
        d = {"model": self.model, "coeffs": list(self.coeffs)}
        if self.model == "none":
            return d
        d["center"] = self.center_px(K).tolist()
        if self.model == "division":
            d.update({"k1": self.coeffs[0], "k2": self.coeffs[1],
                      "definition": "m = c + (m_hat - c) / (1 + k1 r^2 + k2 r^4), r = |m_hat - c| in distorted pixels"})
        else:
            d["higher"] = list(self.higher)
            d["definition"] = "OpenCV (k1, k2, p1, p2, k3)"
            if not self.describable(K):
                d["definition"] += (" on normalised coordinates, its radial part about `center` with `higher` "
                                    "terms h1 r^8 + h2 r^10 + ... (procam.simulate.Lens)")
        d["describable"] = self.describable(K)
        if not d["describable"]:
            d["left_out"] = self.left_out(K)
        return d


class Lensed(Protocol):
    """What :func:`distort`, :func:`undistort` and :func:`project_points` read of a scene (a
    :class:`~procam.simulate.Scene` is one)."""

    K_cam: np.ndarray  # (3, 3) camera matrix
    K_proj: np.ndarray  # (3, 3) projector matrix
    cam_lens: Lens
    proj_lens: Lens


def _device(scene: Lensed, device: str):
    if device == "camera":
        return scene.K_cam, scene.cam_lens
    if device == "projector":
        return scene.K_proj, scene.proj_lens
    raise ValueError(f"device must be 'camera' or 'projector', got {device!r}")


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


def project_points(scene: Lensed, X, device: str = "camera") -> np.ndarray:
    """(N, 3) points in the frame of the scene's ``device`` -> the (N, 2) pixels it records (the camera,
    distorted) or lights (the projector's panel): ``K * distort(X / Z)`` (:meth:`Lens.project`)."""
    K, lens = _device(scene, device)
    return lens.project(K, X)


def distort(scene: Lensed, pts, device: str = "camera") -> np.ndarray:
    """A scene device's lens: undistorted (ideal pinhole) pixels (..., 2) -> distorted pixels (the camera's
    observed pixels, the projector's panel pixels)."""
    K, lens = _device(scene, device)
    return lens.distort(K, pts)


def undistort(scene: Lensed, pts, device: str = "camera") -> np.ndarray:
    """A scene device's lens: distorted pixels (..., 2) -> undistorted pixels."""
    K, lens = _device(scene, device)
    return lens.undistort(K, pts)


# ------------------------------------------------------------------------------------------------
# the models
# ------------------------------------------------------------------------------------------------

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


def _fold_radius(radial) -> float:
    """Smallest r > 0 with d/dr [r (1 + k1 r^2 + k2 r^4 + ...)] = 0 for radial = (k1, k2, ...); inf if none."""
    # 1 + 3 k1 r^2 + 5 k2 r^4 + ... as a polynomial in r^2 (highest power first for np.roots)
    poly = [(2 * i + 3) * k for i, k in enumerate(radial)][::-1] + [1.0]
    while len(poly) > 1 and poly[0] == 0.0:
        poly = poly[1:]
    if len(poly) == 1:
        return float("inf")
    roots = np.roots(poly)
    real = roots[(np.abs(roots.imag) <= 1e-12 * np.maximum(1.0, np.abs(roots.real))) & (roots.real > 0)].real
    return float(np.sqrt(real.min())) if real.size else float("inf")


def _radial_poly(r2, radial):
    """``1 + r2 (k1 + r2 (k2 + r2 (k3 + ...)))`` (Horner) for radial = (k1, k2, k3, ...)."""
    acc = radial[-1]
    for k in radial[-2::-1]:
        acc = k + r2 * acc
    return 1.0 + r2 * acc


def _radial_poly_derivative(r2, radial):
    """d radial / d(r^2) of :func:`_radial_poly`."""
    acc = len(radial) * radial[-1] + 0.0 * r2
    for i in range(len(radial) - 2, -1, -1):
        acc = (i + 1) * radial[i] + r2 * acc
    return acc


def _brown_distort_norm(xn, radial, p1, p2, delta=None):
    """OpenCV's radial-tangential model on normalised coordinates (..., 2), radial = (k1, k2, k3[, h1, ...]),
    radial part about ``delta`` (normalised; None = the principal point)."""
    x, y = xn[..., 0], xn[..., 1]
    r2 = x * x + y * y
    if delta is None:
        rad = _radial_poly(r2, radial)
        xr, yr = x * rad, y * rad
    else:
        ex, ey = x - delta[0], y - delta[1]
        rad = _radial_poly(ex * ex + ey * ey, radial)
        xr, yr = delta[0] + ex * rad, delta[1] + ey * rad
    xd = xr + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = yr + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    return np.stack([xd, yd], axis=-1)


def _brown_undistort_norm(xd, radial, p1, p2, delta=None, iterations=30, newton=20):
    """Inverse of :func:`_brown_distort_norm`: OpenCV's fixed-point iteration (as ``cv2.undistortPoints``),
    then Newton's method where that has not converged to 1e-15 (strong or non-OpenCV lenses); NaN where
    neither converges (beyond the fold of the radial map)."""
    x = xd[..., 0].copy()
    y = xd[..., 1].copy()
    cx, cy = (0.0, 0.0) if delta is None else (float(delta[0]), float(delta[1]))
    tangential = p1 != 0.0 or p2 != 0.0
    dx = dy = 0.0
    for _ in range(iterations):
        r2 = x * x + y * y
        if delta is None:
            radial_v = _radial_poly(r2, radial)
        else:
            radial_v = _radial_poly((x - cx) ** 2 + (y - cy) ** 2, radial)
        if tangential:
            dx = 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
            dy = p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            x = (xd[..., 0] - cx - dx) / radial_v + cx
            y = (xd[..., 1] - cy - dy) / radial_v + cy
    out = np.stack([x, y], axis=-1)
    with np.errstate(invalid="ignore", over="ignore"):
        res = _brown_distort_norm(out, radial, p1, p2, delta) - xd
        bad = ~(np.abs(res).max(axis=-1, initial=0.0) <= 1e-15)
    if not np.any(bad):
        return out
    # Newton's method on the points the fixed point left (started from it where finite, else from xd)
    z = np.where(np.isfinite(out[bad]), out[bad], xd[bad])
    target = xd[bad]
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        for _ in range(newton):
            f = _brown_distort_norm(z, radial, p1, p2, delta) - target
            J = _brown_jacobian(z, radial, p1, p2, delta)
            det = J[..., 0, 0] * J[..., 1, 1] - J[..., 0, 1] * J[..., 1, 0]
            sx = (J[..., 1, 1] * f[..., 0] - J[..., 0, 1] * f[..., 1]) / det
            sy = (J[..., 0, 0] * f[..., 1] - J[..., 1, 0] * f[..., 0]) / det
            z = z - np.stack([sx, sy], axis=-1)
            if np.all(~np.isfinite(sx) | (np.maximum(np.abs(sx), np.abs(sy)) < 1e-16)):
                break
        res = np.abs(_brown_distort_norm(z, radial, p1, p2, delta) - target).max(axis=-1, initial=0.0)
        # converged, and on the increasing branch of the radial map (not a folded root)
        e = z if delta is None else z - np.asarray(delta, float)
        fold = _fold_radius(radial)
        ok = (res <= 1e-12) & (np.sum(e * e, axis=-1) <= fold * fold)
    z[~ok] = np.nan
    out[bad] = z
    return out


def _brown_jacobian(xn, radial, p1, p2, delta=None) -> np.ndarray:
    """d x_d / d x (..., 2, 2) of :func:`_brown_distort_norm`."""
    x, y = xn[..., 0], xn[..., 1]
    ex, ey = (x, y) if delta is None else (x - delta[0], y - delta[1])
    e2 = ex * ex + ey * ey
    rad = _radial_poly(e2, radial)
    drad = _radial_poly_derivative(e2, radial)
    J = np.empty(xn.shape + (2,))
    J[..., 0, 0] = rad + 2 * drad * ex * ex + 2 * p1 * y + 6 * p2 * x
    J[..., 0, 1] = 2 * drad * ex * ey + 2 * p1 * x + 2 * p2 * y
    J[..., 1, 0] = 2 * drad * ex * ey + 2 * p1 * x + 2 * p2 * y
    J[..., 1, 1] = rad + 2 * drad * ey * ey + 6 * p1 * y + 2 * p2 * x
    return J


def _to_norm(K, pts) -> np.ndarray:
    """Pixels (..., 2) -> normalised image coordinates with the camera matrix ``K``."""
    return np.stack([(pts[..., 0] - K[0, 2]) / K[0, 0], (pts[..., 1] - K[1, 2]) / K[1, 1]], axis=-1)


def _to_pix(K, xn) -> np.ndarray:
    """Normalised image coordinates (..., 2) -> pixels with the camera matrix ``K``."""
    return np.stack([K[0, 0] * xn[..., 0] + K[0, 2], K[1, 1] * xn[..., 1] + K[1, 2]], axis=-1)


def _K(f, alpha, u0, v0):
    return np.array([[f, 0.0, u0], [0.0, alpha * f, v0], [0.0, 0.0, 1.0]])
