"""Synthetic projector-camera captures with ground truth (the oracle of every accuracy test).

A :class:`Scene` holds everything: the camera (K, size, lens distortion), the projector (K, size),
the camera -> projector extrinsics ``x_p = R x_c + T``, a printed chessboard at a pose (board ->
camera) and a background wall, plus the photometry of the capture (projector black level and
defocus, ambient light, camera gain, gamma, optical blur, shot and read noise, bit depth).

Two paths:

* :func:`correspondences` - the fast path: exact corner geometry plus Gaussian noise, no images.
* :func:`render` - physically plausible Gray-code captures: per camera pixel a ray (supersampled),
  board / wall albedo, projector illumination with defocus and black level, the board's shadow on
  the wall, ambient light, gain, optical blur, shot and read noise, gamma, 8/16-bit output.  The
  geometry is computed once per scene; each pattern image is then a cheap 1-D profile lookup,
  because Gray-code stripes depend on one projector coordinate only.

This module is independent of the solvers: it imports only numpy, scipy, cv2,
:mod:`procam.patterns`, :mod:`procam.capture` (the capture-folder format) and :mod:`procam._files` (file writing), and has its own projection, division model (with its Newton inverse) and
OpenCV-Brown distortion.

Conventions (see ``procam`` README): pixels ``(x, y)`` = (column, row), origin at the centre of the
top-left pixel; a pose ``(R, t)`` maps board -> device; board corner ``k = j*cols + i`` is at
``(i s, j s, 0)`` minus the centroid, z away from the devices; Euler angles ``(psi, nu, phi)`` are
intrinsic XYZ, ``R = Rx(psi) Ry(nu) Rz(phi)``, degrees at this module's surface.
"""

from __future__ import annotations

import dataclasses
import functools
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import cv2
import numpy as np
from scipy.optimize import minimize
from scipy.spatial.transform import Rotation

from . import capture as _capture
from . import patterns as _patterns
from ._files import to_jsonable, write_text

__all__ = [
    "Scene", "preset", "PRESETS", "RECOMMENDED_POSE", "DEFAULT_DISTANCE", "with_board_pose",
    "truth", "correspondences", "true_projector_maps", "render", "write_capture",
    "board_corners", "board_extent", "corner_truth", "fit_margin", "project", "distort", "undistort",
    "euler_matrix", "matrix_euler",
]

#: Board (psi, nu, phi) in degrees in the CAMERA frame recommended for a single-pose calibration
#: with the ``paper`` / ``ideal`` rigs: |psi_c| + |nu_c| = 27 > 10 and, through the rig's
#: R (nu = 14.44 deg), nu_p = 26.1 deg > 13 (checked in ``tests/test_simulate.py``).
RECOMMENDED_POSE: tuple[float, float, float] = (15.0, 12.0, 0.0)

#: Depth (mm, along the device's optical axis) tried first by :func:`with_board_pose` when no
#: distance is given (METHOD section 12 uses 500 mm).
DEFAULT_DISTANCE = 500.0


# --------------------------------------------------------------------------------------------
# small geometry helpers (independent of procam.models on purpose)
# --------------------------------------------------------------------------------------------

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


def distort(scene: "Scene", pts) -> np.ndarray:
    """Camera lens: undistorted (ideal pinhole) pixels (..., 2) -> distorted (observed) pixels."""
    pts = np.asarray(pts, float)
    if scene.cam_distortion == "none":
        return pts.copy()
    if scene.cam_distortion == "division":
        k1, k2 = scene.cam_dist_coeffs
        return _division_distort(pts, scene.cam_center, k1, k2)
    return _to_pix(scene.K_cam, _brown_distort_norm(_to_norm(scene.K_cam, pts), scene.cam_dist_coeffs))


def undistort(scene: "Scene", pts) -> np.ndarray:
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


# --------------------------------------------------------------------------------------------
# the scene
# --------------------------------------------------------------------------------------------

def _frozen(a, shape):
    a = np.array(a, dtype=float).reshape(shape)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class Scene:
    """A complete synthetic procam set-up (immutable; derive variants with ``dataclasses.replace``).

    Geometry (lengths in mm, pixels as (x, y) with the origin at the top-left pixel centre)

    cam_size, K_cam : camera (width, height) and intrinsic matrix ``[[f, 0, u0], [0, a f, v0], [0, 0, 1]]``.
    cam_distortion : ``"division"`` (Fitzgibbon, distorted -> undistorted
        ``m = c + d / (1 + k1 r^2 + k2 r^4)``, r in distorted pixels, about ``cam_dist_center``),
        ``"opencv"`` (Brown: k1, k2, p1, p2, k3 on normalised coordinates) or ``"none"``.
    cam_dist_coeffs : ``(k1, k2)`` in px^-2, px^-4 for ``division``; ``(k1, k2, p1, p2, k3)`` for ``opencv``.
    cam_dist_center : division centre (x, y) px; ``None`` = the principal point.
    proj_size, K_proj : projector (width, height) and intrinsics (no projector lens distortion).
    R, T : camera -> projector, ``x_p = R x_c + T``.
    board_cols, board_rows, square : inner corners and square pitch (mm).
    margin : white border (mm) of the printed board beyond its outer squares.
    R_board, t_board : board -> camera pose (``X_c = R_board X_b + t_board``); ``t_board`` is the
        board centre (corner centroid).
    wall_normal, wall_offset : background plane with unit normal ``wall_normal`` (camera frame)
        through ``t_board + wall_offset * e_z`` (it moves with the board).

    Photometry (linear values are fractions of the camera's full scale)

    albedo_white, albedo_black, albedo_wall : diffuse reflectances.
    gain : camera exposure x gain: full-white projector light at the board-centre distance on a
        frontal albedo-1 surface gives ``gain`` of full scale.
    ambient : ambient irradiance as a fraction of full projector white.
    proj_black : light of a black projector pixel as a fraction of white (black level).
    proj_defocus : projector defocus, Gaussian sigma in projector pixels.
    cam_blur : camera optics, Gaussian sigma in camera pixels.
    cam_vignetting, proj_vignetting : relative illumination ``cos(field angle) ** n`` of the camera
        lens (on everything it sees) and of the projector lens (on its light); 4 is the natural
        cos^4 law of a thin lens, 0 disables.
    full_well : electrons at full scale (shot noise variance = signal / full_well); 0 = no shot noise.
    read_noise : read noise sigma in 8-bit DN (scaled for 16-bit output).
    gamma : output = linear ** (1 / gamma).
    bits : 8 or 16 (output dtype uint8 / uint16).
    supersample : rays per pixel along each axis (anti-aliasing).
    name : label written to ``truth.json``.
    """

    cam_size: tuple = (1280, 800)
    K_cam: np.ndarray = field(default_factory=lambda: _K(1539.0, 1.004, 674.0, 512.0))
    cam_distortion: str = "division"
    cam_dist_coeffs: tuple = (-3e-8, 0.0)
    cam_dist_center: tuple | None = None
    proj_size: tuple = (1920, 1080)
    K_proj: np.ndarray = field(default_factory=lambda: _K(2421.0, 1.002, 1013.0, 1065.0))
    R: np.ndarray = field(default_factory=lambda: euler_matrix((0.87, 14.44, -0.25)))
    T: np.ndarray = field(default_factory=lambda: np.array([-170.05, -41.25, -65.35]))
    board_cols: int = 10
    board_rows: int = 6
    square: float = 24.0
    margin: float = 20.0
    R_board: np.ndarray = field(default_factory=lambda: np.eye(3))
    t_board: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, DEFAULT_DISTANCE]))
    wall_normal: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    wall_offset: float = 300.0
    albedo_white: float = 0.85
    albedo_black: float = 0.1
    albedo_wall: float = 0.5
    gain: float = 0.95
    ambient: float = 0.04
    proj_black: float = 0.03
    proj_defocus: float = 0.5
    cam_blur: float = 0.5
    cam_vignetting: float = 2.0
    proj_vignetting: float = 2.0
    full_well: float = 10000.0
    read_noise: float = 1.0
    gamma: float = 1.0
    bits: int = 8
    supersample: int = 3
    name: str = "custom"

    def __post_init__(self):
        s = object.__setattr__
        s(self, "cam_size", (int(self.cam_size[0]), int(self.cam_size[1])))
        s(self, "proj_size", (int(self.proj_size[0]), int(self.proj_size[1])))
        for name, shape in (("K_cam", (3, 3)), ("K_proj", (3, 3)), ("R", (3, 3)), ("T", (3,)),
                            ("R_board", (3, 3)), ("t_board", (3,)), ("wall_normal", (3,))):
            s(self, name, _frozen(getattr(self, name), shape))
        n = self.wall_normal / np.linalg.norm(self.wall_normal)
        s(self, "wall_normal", _frozen(n, (3,)))
        if self.cam_distortion not in ("division", "opencv", "none"):
            raise ValueError(f"cam_distortion must be division|opencv|none, got {self.cam_distortion!r}")
        want = {"division": 2, "opencv": 5, "none": None}[self.cam_distortion]
        coeffs = tuple(float(c) for c in self.cam_dist_coeffs)
        if want is not None and len(coeffs) != want:
            raise ValueError(f"{self.cam_distortion} distortion takes {want} coefficients, got {coeffs}")
        s(self, "cam_dist_coeffs", coeffs)
        if self.cam_dist_center is not None:
            s(self, "cam_dist_center", (float(self.cam_dist_center[0]), float(self.cam_dist_center[1])))
        if self.bits not in (8, 16):
            raise ValueError(f"bits must be 8 or 16, got {self.bits}")
        if int(self.supersample) < 1:
            raise ValueError(f"supersample must be >= 1, got {self.supersample}")
        s(self, "supersample", int(self.supersample))

    # convenient derived quantities ------------------------------------------------------------
    @property
    def cam_center(self) -> np.ndarray:
        """Division-model centre (2,) in pixels (the principal point unless set)."""
        if self.cam_dist_center is None:
            return self.K_cam[:2, 2].copy()
        return np.array(self.cam_dist_center, float)

    @property
    def proj_center_cam(self) -> np.ndarray:
        """Projector centre of projection in camera coordinates, ``-R^T T`` (3,)."""
        return -self.R.T @ self.T

    @property
    def R_board_proj(self) -> np.ndarray:
        """Board -> projector rotation ``R R_board``."""
        return self.R @ self.R_board

    @property
    def t_board_proj(self) -> np.ndarray:
        """Board -> projector translation ``R t_board + T``."""
        return self.R @ self.t_board + self.T

    def replace(self, **changes) -> "Scene":
        """``dataclasses.replace`` shortcut."""
        return dataclasses.replace(self, **changes)


def board_corners(scene: Scene) -> np.ndarray:
    """(cols*rows, 3) board-frame corners, ``k = j*cols + i`` at ``(i s, j s, 0)`` minus the centroid."""
    i, j = np.meshgrid(np.arange(scene.board_cols, dtype=float), np.arange(scene.board_rows, dtype=float))
    pts = np.column_stack([i.ravel() * scene.square, j.ravel() * scene.square, np.zeros(i.size)])
    pts[:, :2] -= pts[:, :2].mean(axis=0)
    return pts


def board_extent(scene: Scene) -> tuple[float, float, float, float]:
    """(xmin, xmax, ymin, ymax) of the printed board (squares plus white margin) in the board frame."""
    hx = 0.5 * (scene.board_cols - 1) * scene.square + scene.square + scene.margin
    hy = 0.5 * (scene.board_rows - 1) * scene.square + scene.square + scene.margin
    return -hx, hx, -hy, hy


def _outline(scene: Scene, per_edge: int = 9) -> np.ndarray:
    """Points along the printed board's outline (board frame), (4*per_edge, 3)."""
    x0, x1, y0, y1 = board_extent(scene)
    t = np.linspace(0.0, 1.0, per_edge, endpoint=False)
    xs = np.concatenate([x0 + (x1 - x0) * t, np.full_like(t, x1), x1 - (x1 - x0) * t, np.full_like(t, x0)])
    ys = np.concatenate([np.full_like(t, y0), y0 + (y1 - y0) * t, np.full_like(t, y1), y1 - (y1 - y0) * t])
    return np.column_stack([xs, ys, np.zeros_like(xs)])


# --------------------------------------------------------------------------------------------
# presets and poses
# --------------------------------------------------------------------------------------------

PRESETS = ("paper", "ideal")


def preset(name: str = "paper") -> Scene:
    """A ready scene at :data:`RECOMMENDED_POSE` (board centre placed by :func:`with_board_pose`).

    ``paper``
        The seed paper's simulated procam (METHOD section 12): camera 1280x800, f 1539, alpha 1.004,
        pp (674, 512); projector 1920x1080, f 2421, alpha 1.002, pp (1013, 1065); R, T from the
        paper's reference calibration (Euler (0.87, 14.44, -0.25) deg, T (-170.05, -41.25, -65.35)
        mm); board 10x6 at 24 mm.  Mild barrel distortion: division model k1 = -3e-8 px^-2 about the
        principal point (about 0.8-5 px at the board's outer corners at the recommended pose).
    ``ideal``
        The same rig with the single-pose method's assumptions true: u0p = 960 (W/2), alpha_p = 1,
        and a division-model distortion k1 = -1e-7 px^-2 about the principal point (METHOD section 13's
        reference value), strong enough (about 3-14 px at the board's outer corners at the
        recommended pose) for the centre of distortion to be observable (METHOD section 5.2).
    """
    if name not in PRESETS:
        raise ValueError(f"unknown preset {name!r}; choose one of {', '.join(PRESETS)}")
    return _preset_cached(name)


@functools.lru_cache(maxsize=None)
def _preset_cached(name: str) -> Scene:
    # Scenes are immutable (frozen, read-only arrays), so one instance per preset can be shared.
    if name == "paper":
        scene = Scene(name="paper")
    else:
        scene = Scene(name="ideal", K_proj=_K(2421.0, 1.0, 960.0, 1065.0), cam_dist_coeffs=(-1e-7, 0.0))
    return with_board_pose(scene, RECOMMENDED_POSE)


def _pose_in_camera(scene: Scene, R_bd: np.ndarray, c_d: np.ndarray, frame: str):
    """Board -> camera pose from a board -> device rotation and board centre in that device frame."""
    if frame == "camera":
        return R_bd, c_d
    return scene.R.T @ R_bd, scene.R.T @ (c_d - scene.T)


def _margins(scene: Scene, R_b: np.ndarray, t_b: np.ndarray) -> np.ndarray:
    """:func:`fit_margin` for M board -> camera poses sharing ``R_b`` (3, 3); ``t_b`` (M, 3) -> (M,)."""
    t_b = np.asarray(t_b, float).reshape(-1, 3)
    P = (_outline(scene) @ R_b.T)[None, :, :] + t_b[:, None, :]          # (M, K, 3) camera frame
    Pp = P @ scene.R.T + scene.T
    bad = np.any(P[..., 2] <= 1e-6, axis=1) | np.any(Pp[..., 2] <= 1e-6, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        mc = distort(scene, project(scene.K_cam, P.reshape(-1, 3))).reshape(P.shape[0], -1, 2)
        mp = project(scene.K_proj, Pp.reshape(-1, 3)).reshape(P.shape[0], -1, 2)
    bad |= ~np.all(np.isfinite(mc), axis=(1, 2))
    (wc, hc), (wp, hp) = scene.cam_size, scene.proj_size
    dc = np.minimum(np.minimum(mc[..., 0] + 0.5, wc - 0.5 - mc[..., 0]),
                    np.minimum(mc[..., 1] + 0.5, hc - 0.5 - mc[..., 1])).min(axis=1)
    dp = np.minimum(np.minimum(mp[..., 0] + 0.5, wp - 0.5 - mp[..., 0]),
                    np.minimum(mp[..., 1] + 0.5, hp - 0.5 - mp[..., 1])).min(axis=1)
    m = np.minimum(dc, dp * scene.K_cam[0, 0] / scene.K_proj[0, 0])
    return np.where(bad | ~np.isfinite(m), -1e9, m)


def fit_margin(scene: Scene, R_board=None, t_board=None) -> float:
    """Smallest distance (camera px) of the printed board's outline to the border of either image.

    Negative when part of the board (with its margin) is outside the camera image or the projector
    image, or behind a device.  Projector pixels are scaled by ``f_c / f_p`` to camera pixels.
    """
    R_b = scene.R_board if R_board is None else np.asarray(R_board, float)
    t_b = scene.t_board if t_board is None else np.asarray(t_board, float)
    return float(_margins(scene, R_b, t_b)[0])


def _grid_center(scene: Scene, R_bd, distance: float, frame: str, n: int = 41, span: float = 0.6):
    """Best board centre (x, y, distance) in ``frame`` on an n x n grid; returns (c, margin)."""
    g = np.linspace(-span, span, n) * distance
    X, Y = np.meshgrid(g, g)
    C = np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, distance)])
    if frame == "camera":
        R_b, T_b = R_bd, C
    else:
        R_b, T_b = scene.R.T @ R_bd, (C - scene.T) @ scene.R
    m = _margins(scene, R_b, T_b)
    k = int(np.argmax(m))
    return C[k], float(m[k])


def _best_center(scene: Scene, R_bd, distance: float, frame: str):
    """Board centre (x, y, distance) in ``frame`` maximising :func:`fit_margin`; returns (c, margin)."""
    c0, m0 = _grid_center(scene, R_bd, distance, frame)

    def score(xy):
        c = np.array([xy[0], xy[1], distance])
        return fit_margin(scene, *_pose_in_camera(scene, R_bd, c, frame))

    step = 0.03 * distance
    res = minimize(lambda v: -score(v), x0=c0[:2], method="Nelder-Mead",
                   options={"xatol": 1e-3, "fatol": 1e-4, "initial_simplex":
                            [c0[:2], c0[:2] + [step, 0], c0[:2] + [0, step]]})
    if -res.fun >= m0:
        return np.array([res.x[0], res.x[1], distance]), float(-res.fun)
    return c0, m0


def with_board_pose(scene: Scene, angles_deg, distance: float | None = None, frame: str = "camera",
                    center=None, border_px: float = 8.0, max_distance: float = 3000.0,
                    step: float = 25.0) -> Scene:
    """The scene with the board at a new pose.

    Parameters
    ----------
    angles_deg : (psi, nu, phi) in degrees: ``R_board->device = Rx(psi) Ry(nu) Rz(phi)`` in ``frame``.
    distance : depth (mm, along the device's optical axis) of the board centre when ``center`` is
        None.  The lateral position is chosen to maximise the smallest distance of the printed board
        (all corners, outer squares and white margin) to the borders of BOTH the camera and the
        projector images.  If ``distance`` is None, depths from :data:`DEFAULT_DISTANCE` upwards in
        ``step`` mm are tried until that distance is at least ``border_px`` camera pixels (if none up
        to ``max_distance`` fits, the best-fitting depth is used: check :func:`fit_margin`).
    frame : ``"camera"`` or ``"projector"``: the device frame of ``angles_deg`` and ``center``.
    center : (3,) board centre in ``frame`` (mm); overrides ``distance``.

    Returns
    -------
    Scene with ``R_board``, ``t_board`` (board -> camera) set.
    """
    if frame not in ("camera", "projector"):
        raise ValueError(f"frame must be 'camera' or 'projector', got {frame!r}")
    R_bd = euler_matrix(angles_deg)
    if center is not None:
        c = np.asarray(center, float).reshape(3)
    elif distance is not None:
        c, _ = _best_center(scene, R_bd, float(distance), frame)
    else:
        best = None
        d = DEFAULT_DISTANCE
        while d <= max_distance + 1e-9:  # grid per depth, refined where it is nearly feasible
            c_d, m = _grid_center(scene, R_bd, d, frame)
            if m > border_px - 50:
                c_d, m = _best_center(scene, R_bd, d, frame)
            if best is None or m > best[1]:
                best = (c_d, m)
            if m >= border_px:
                best = (c_d, m)
                break
            d += step
        c = best[0]
    R_b, t_b = _pose_in_camera(scene, R_bd, c, frame)
    return dataclasses.replace(scene, R_board=R_b, t_board=t_b)


# --------------------------------------------------------------------------------------------
# ground truth and the fast path
# --------------------------------------------------------------------------------------------

def _pose_dict(R, t):
    return {"R": np.asarray(R).tolist(), "t": np.asarray(t).tolist(),
            "angles_deg": matrix_euler(R).tolist()}


def corner_truth(scene: Scene) -> dict[str, np.ndarray]:
    """Exact corners: ``board`` (N, 3), ``camera_undistorted``, ``camera_distorted``, ``projector`` (N, 2)."""
    B = board_corners(scene)
    Xc = B @ scene.R_board.T + scene.t_board
    cam_u = project(scene.K_cam, Xc)
    cam_d = distort(scene, cam_u)
    proj = project(scene.K_proj, Xc @ scene.R.T + scene.T)
    return {"board": B, "camera_distorted": cam_d, "camera_undistorted": cam_u, "projector": proj}


def _scene_params(scene: Scene) -> dict:
    Kc, Kp = scene.K_cam, scene.K_proj
    cam = {"size": list(scene.cam_size), "K": Kc.tolist(), "f": Kc[0, 0], "alpha": Kc[1, 1] / Kc[0, 0],
           "u0": Kc[0, 2], "v0": Kc[1, 2],
           "distortion": {"model": scene.cam_distortion, "coeffs": list(scene.cam_dist_coeffs)}}
    if scene.cam_distortion == "division":
        cam["distortion"].update({"center": scene.cam_center.tolist(), "k1": scene.cam_dist_coeffs[0],
                                  "k2": scene.cam_dist_coeffs[1],
                                  "definition": "m = c + (m_hat - c) / (1 + k1 r^2 + k2 r^4), "
                                                "r = |m_hat - c| in distorted pixels"})
    elif scene.cam_distortion == "opencv":
        cam["distortion"]["definition"] = "OpenCV (k1, k2, p1, p2, k3)"
    proj = {"size": list(scene.proj_size), "K": Kp.tolist(), "f": Kp[0, 0], "alpha": Kp[1, 1] / Kp[0, 0],
            "u0": Kp[0, 2], "v0": Kp[1, 2], "distortion": {"model": "none"}}
    ext = {"R": scene.R.tolist(), "T": scene.T.tolist(), "angles_deg": matrix_euler(scene.R).tolist(),
           "baseline": float(np.linalg.norm(scene.T)), "definition": "x_p = R x_c + T"}
    board = {"cols": scene.board_cols, "rows": scene.board_rows, "square": scene.square,
             "margin": scene.margin, "extent": list(board_extent(scene)),
             "albedo_white": scene.albedo_white, "albedo_black": scene.albedo_black}
    wall = {"normal": scene.wall_normal.tolist(), "offset": scene.wall_offset,
            "point": (scene.t_board + scene.wall_offset * np.array([0, 0, 1.0])).tolist(),
            "albedo": scene.albedo_wall}
    photo = {k: getattr(scene, k) for k in ("gain", "ambient", "proj_black", "proj_defocus", "cam_blur",
                                            "cam_vignetting", "proj_vignetting", "full_well", "read_noise",
                                            "gamma", "bits", "supersample")}
    return {"camera": cam, "projector": proj, "extrinsics": ext, "board": board, "wall": wall,
            "photometry": photo}


def truth(scene: Scene) -> dict:
    """Everything known about the scene, JSON-able (lists, floats; NaN written as null).

    Keys: ``format``, ``name``, ``camera``, ``projector``, ``extrinsics``, ``board``, ``wall``,
    ``photometry``, ``corners`` (``board`` (N, 3), ``camera_distorted``, ``camera_undistorted``,
    ``projector`` (N, 2), order ``k = j*cols + i``), ``pose`` (``camera`` / ``projector``: ``R``, ``t``,
    ``angles_deg`` = (psi, nu, phi) of board -> device), ``fit_margin_px`` (:func:`fit_margin`) and
    ``canonical_order`` (True when corner 0 is the top-left corner in the camera image and the index
    runs right then down, the order a detector canonicalises to; False e.g. for |phi| near 180 deg).
    """
    d = {"format": "procam-sim-truth", "version": 1, "name": scene.name}
    d.update(_scene_params(scene))
    d["corners"] = corner_truth(scene)
    d["pose"] = {"camera": _pose_dict(scene.R_board, scene.t_board),
                 "projector": _pose_dict(scene.R_board_proj, scene.t_board_proj)}
    d["fit_margin_px"] = fit_margin(scene)
    cam = d["corners"]["camera_distorted"]
    n, cols = len(cam), scene.board_cols
    d["canonical_order"] = bool(np.all(np.isfinite(cam)) and np.argmin(cam.sum(axis=1)) == 0
                                and cam[1, 0] > cam[0, 0] and cam[cols, 1] > cam[0, 1] and n > cols)
    return to_jsonable(d)


def correspondences(scene: Scene, sigma_cam: float = 0.1, sigma_proj: float = 0.2, seed: int = 0):
    """Fast path: exact corners plus i.i.d. Gaussian noise, no rendering.

    Returns
    -------
    obj : (N, 3) board corners (board frame, mm).
    cam : (N, 2) distorted camera corners + N(0, sigma_cam^2) per coordinate.
    proj : (N, 2) projector corners + N(0, sigma_proj^2) per coordinate.
    """
    c = corner_truth(scene)
    rng = np.random.default_rng(seed)
    n = len(c["board"])
    cam = c["camera_distorted"] + sigma_cam * rng.standard_normal((n, 2))
    proj = c["projector"] + sigma_proj * rng.standard_normal((n, 2))
    return c["board"], cam, proj


# --------------------------------------------------------------------------------------------
# rendering: geometry once per scene
# --------------------------------------------------------------------------------------------

#: Samples per projector pixel of the 1-D stripe profiles looked up by ``cv2.remap``.
PROFILE_UPSAMPLE = 8


def _box_filtered_step(u, w, n):
    """Box filter (width w) of the indicator of [0, n], evaluated at u (all in square units)."""
    return (np.clip(u + 0.5 * w, 0, n) - np.clip(u - 0.5 * w, 0, n)) / w


def _box_filtered_square_wave(u, w, n):
    """Box filter (width w) of sq(u) * [0 <= u <= n], sq = +1 on [2k, 2k+1), -1 on [2k+1, 2k+2)."""

    def F(x):  # integral of sq from 0 to x (a triangle wave), for x clipped to [0, n]
        fr = np.mod(np.clip(x, 0, n), 2.0)
        return np.where(fr < 1.0, fr, 2.0 - fr)

    return (F(u + 0.5 * w) - F(u - 0.5 * w)) / w


def _board_albedo(scene: Scene, bx, by, wx, wy):
    """Albedo of the printed board at board coords (bx, by) mm, box-filtered over (wx, wy) mm.

    The top-left square (smallest x, y) is black; squares alternate; a white margin surrounds them.
    """
    s = scene.square
    nx, ny = scene.board_cols + 1, scene.board_rows + 1  # printed squares
    u = (bx + 0.5 * nx * s) / s
    v = (by + 0.5 * ny * s) / s
    wu = np.maximum(wx / s, 1e-6)
    wv = np.maximum(wy / s, 1e-6)
    inside = _box_filtered_step(u, wu, nx) * _box_filtered_step(v, wv, ny)
    checker = _box_filtered_square_wave(u, wu, nx) * _box_filtered_square_wave(v, wv, ny)
    return scene.albedo_white + (scene.albedo_black - scene.albedo_white) * 0.5 * (inside + checker)


def _geometry_band(scene: Scene, ys, xs):
    """Per-sample geometry for the sample grid ``ys`` x ``xs`` (camera pixel coordinates).

    Returns dict of (len(ys), len(xs)) arrays: ``xp``, ``yp`` projector coords (NaN where no
    surface), ``coef`` = gain * albedo * irradiance factor where lit by the projector (0 elsewhere),
    ``amb`` = gain * albedo * ambient, ``board`` (bool, the ray hits the board), ``lit`` (bool).
    Irradiance factor: cosine of incidence times the inverse-square fall-off, relative to the
    projector's distance to the board centre (Lambertian surfaces, so no view dependence).
    """
    X_pix, Y_pix = np.meshgrid(np.asarray(xs, float), np.asarray(ys, float))
    und = undistort(scene, np.stack([X_pix, Y_pix], axis=-1))
    Kc = scene.K_cam
    # camera rays with z = 1 (zero skew)
    dx = (und[..., 0] - Kc[0, 2]) / Kc[0, 0]
    dy = (und[..., 1] - Kc[1, 2]) / Kc[1, 1]
    del und
    Rb, tb = scene.R_board, scene.t_board
    nb = Rb[:, 2]
    x0, x1, y0, y1 = board_extent(scene)
    err = np.errstate(divide="ignore", invalid="ignore")
    err.__enter__()
    try:
        # board plane
        sb = (nb @ tb) / (dx * nb[0] + dy * nb[1] + nb[2])
        rx, ry, rz = dx * sb - tb[0], dy * sb - tb[1], sb - tb[2]
        bx = rx * Rb[0, 0] + ry * Rb[1, 0] + rz * Rb[2, 0]
        by = rx * Rb[0, 1] + ry * Rb[1, 1] + rz * Rb[2, 1]
        del rx, ry, rz
        on_board = (sb > 0) & (bx >= x0) & (bx <= x1) & (by >= y0) & (by <= y1)
        # wall plane
        nw = scene.wall_normal
        pw = tb + scene.wall_offset * np.array([0.0, 0.0, 1.0])
        sw = (nw @ pw) / (dx * nw[0] + dy * nw[1] + nw[2])
        on_wall = np.isfinite(sw) & (sw > 0)
        board = on_board & (~on_wall | (sb < sw))
        wall = on_wall & ~board
        surf = board | wall
        depth = np.where(board, sb, np.where(wall, sw, np.nan))
        del sb, sw
        X, Y, Z = dx * depth, dy * depth, depth
        cam_vig = (1.0 + dx * dx + dy * dy) ** (-0.5 * scene.cam_vignetting)  # cos(field angle) ** n
        del dx, dy

        # albedo; the board's is box-filtered over each sample's footprint (anti-aliasing)
        def footprint(a):
            g0 = np.abs(np.gradient(a, axis=0)) if a.shape[0] > 1 else 0.0
            g1 = np.abs(np.gradient(a, axis=1)) if a.shape[1] > 1 else 0.0
            return np.nan_to_num(g0 + g1, nan=1.0)

        albedo = np.where(wall, scene.albedo_wall, 0.0)
        albedo[board] = _board_albedo(scene, bx[board], by[board], footprint(bx)[board], footprint(by)[board])
        del bx, by

        # projector coordinates
        R, T, Kp = scene.R, scene.T, scene.K_proj
        Xp = R[0, 0] * X + R[0, 1] * Y + R[0, 2] * Z + T[0]
        Yp = R[1, 0] * X + R[1, 1] * Y + R[1, 2] * Z + T[1]
        Zp = R[2, 0] * X + R[2, 1] * Y + R[2, 2] * Z + T[2]
        xp = Kp[0, 0] * Xp / Zp + Kp[0, 1] * Yp / Zp + Kp[0, 2]
        yp = Kp[1, 1] * Yp / Zp + Kp[1, 2]
        Wp, Hp = scene.proj_size
        front = Zp > 0
        in_panel = front & (xp >= -0.5) & (xp <= Wp - 0.5) & (yp >= -0.5) & (yp <= Hp - 0.5)

        # shading
        Cp = scene.proj_center_cam
        Lx, Ly, Lz = Cp[0] - X, Cp[1] - Y, Cp[2] - Z
        dist2 = Lx * Lx + Ly * Ly + Lz * Lz
        cos_p = Zp / np.sqrt(Xp * Xp + Yp * Yp + Zp * Zp)  # projector field angle
        nx = np.where(board, nb[0], nw[0])
        ny = np.where(board, nb[1], nw[1])
        nz = np.where(board, nb[2], nw[2])
        ndotl = nx * Lx + ny * Ly + nz * Lz
        ndotv = -(nx * X + ny * Y + nz * Z)
        facing = (ndotl * ndotv) > 0
        d_ref2 = float(np.sum((Cp - tb) ** 2))
        irr = np.abs(ndotl) / np.sqrt(dist2) * (d_ref2 / dist2) * np.abs(cos_p) ** scene.proj_vignetting
        del nx, ny, nz, ndotv, ndotl, dist2, Xp, Yp, Zp, cos_p

        # the board's shadow on the wall, as the projector sees it
        uu = (nb @ tb - (X * nb[0] + Y * nb[1] + Z * nb[2])) / (Lx * nb[0] + Ly * nb[1] + Lz * nb[2])
        qx, qy, qz = X + uu * Lx - tb[0], Y + uu * Ly - tb[1], Z + uu * Lz - tb[2]
        sx = qx * Rb[0, 0] + qy * Rb[1, 0] + qz * Rb[2, 0]
        sy = qx * Rb[0, 1] + qy * Rb[1, 1] + qz * Rb[2, 1]
        shadow = wall & (uu > 1e-9) & (uu < 1) & (sx >= x0) & (sx <= x1) & (sy >= y0) & (sy <= y1)
    finally:
        err.__exit__(None, None, None)

    # the panel's edges are left to the (defocused) panel masks of the renderer; `lit` is the truth mask
    illuminated = surf & front & facing & ~shadow
    lit = illuminated & in_panel
    coef = np.where(illuminated, scene.gain * albedo * irr * cam_vig, 0.0)
    amb = scene.gain * scene.ambient * albedo * cam_vig
    xp = np.where(surf, xp, np.nan)
    yp = np.where(surf, yp, np.nan)
    return {"xp": xp, "yp": yp, "coef": coef, "amb": amb, "board": board, "lit": lit}


def _sample_grid(n_pix: int, s: int) -> np.ndarray:
    """Sample positions (pixel coordinates) of ``s`` supersamples per pixel: pixel i covers [i-.5, i+.5]."""
    return (np.arange(n_pix * s) + 0.5) / s - 0.5


def _geometry(scene: Scene, s: int | None = None, band_rows: int = 240):
    """Geometry on the supersampled grid (H*s, W*s), computed in row bands to bound memory."""
    s = scene.supersample if s is None else int(s)
    W, H = scene.cam_size
    xs, ys = _sample_grid(W, s), _sample_grid(H, s)
    out = {k: np.empty((len(ys), len(xs)), dtype=np.float32) for k in ("xp", "yp", "coef", "amb")}
    out.update({k: np.empty((len(ys), len(xs)), dtype=bool) for k in ("board", "lit")})
    for r0 in range(0, len(ys), band_rows):
        r1 = min(len(ys), r0 + band_rows)
        # one extra row on each side so footprint gradients are central everywhere
        e0, e1 = max(0, r0 - 1), min(len(ys), r1 + 1)
        g = _geometry_band(scene, ys[e0:e1], xs)
        for k, v in g.items():
            out[k][r0:r1] = v[r0 - e0: r0 - e0 + (r1 - r0)]
    return out


def true_projector_maps(scene: Scene):
    """Exact projector coordinates seen at every camera pixel centre.

    Returns
    -------
    col, row : (H, W) float64, projector x / y (pixels) of the surface (board or wall) seen at the
        pixel centre where it is lit by the projector, NaN elsewhere (outside the projector image,
        in the board's shadow, or no surface).
    lit_board : (H, W) bool, pixels lying entirely on the board (every supersample of the pixel)
        and entirely lit by the projector.
    """
    s = scene.supersample
    W, H = scene.cam_size
    g = _geometry(scene, s=s)
    ok = (g["board"] & g["lit"]).reshape(H, s, W, s).all(axis=(1, 3))
    del g
    exact = _geometry_band(scene, np.arange(H, dtype=float), np.arange(W, dtype=float))
    col = np.where(exact["lit"], exact["xp"], np.nan)
    row = np.where(exact["lit"], exact["yp"], np.nan)
    return col, row, ok


# --------------------------------------------------------------------------------------------
# rendering: the image sequence
# --------------------------------------------------------------------------------------------

def _profile(values: np.ndarray, sigma: float, pad: int):
    """Upsampled, defocused 1-D light profile of a projector line ``values`` (n,) in [0, 1].

    Sample ``q`` of the result is at projector coordinate ``(q - pad + 0.5) / U - 0.5`` with
    ``U = PROFILE_UPSAMPLE`` (projector pixel i covers [i - .5, i + .5]); zero outside the panel.
    """
    U = PROFILE_UPSAMPLE
    line = np.zeros(len(values) * U + 2 * pad, dtype=np.float32)
    line[pad:pad + len(values) * U] = np.repeat(values.astype(np.float32), U)
    if sigma > 0:
        line = cv2.GaussianBlur(line[None, :], (0, 0), sigmaX=sigma * U, sigmaY=1e-6,
                                borderType=cv2.BORDER_CONSTANT)[0]
    return line[None, :]


def _to_profile_map(p: np.ndarray, pad: int) -> np.ndarray:
    """Projector coordinates -> sample index of :func:`_profile` (float32; far outside where NaN)."""
    q = (p.astype(np.float64) + 0.5) * PROFILE_UPSAMPLE - 0.5 + pad
    return np.where(np.isfinite(q), q, -1e6).astype(np.float32)


class _Renderer:
    """Precomputed geometry and profiles for one scene; ``linear(k)`` renders image k before noise."""

    def __init__(self, scene: Scene, order: str):
        self.scene = scene
        self.ps = _patterns.pattern_set(*scene.proj_size, order)
        Wp, Hp = scene.proj_size
        self.pad = int(np.ceil(4 * max(scene.proj_defocus, 0.25) * PROFILE_UPSAMPLE)) + PROFILE_UPSAMPLE
        g = _geometry(scene, scene.supersample)
        # float32 maps (faster than fixed-point ones for a one-row source image)
        self.mapx = _to_profile_map(g["xp"], self.pad)
        self.mapy = _to_profile_map(g["yp"], self.pad)
        self.zeros = np.zeros_like(self.mapx)
        self.sigma = scene.proj_defocus
        mask_x = self._lookup(_profile(np.ones(Wp), self.sigma, self.pad), "x")
        mask_y = self._lookup(_profile(np.ones(Hp), self.sigma, self.pad), "y")
        coef = g["coef"]
        self.coef_cols = coef * mask_y          # column patterns vary with x only
        self.coef_rows = coef * mask_x          # row patterns vary with y only
        self.full = coef * mask_x * mask_y      # a white panel
        self.amb = g["amb"]
        self.col_planes = _patterns.bit_planes(Wp, self.ps.col_bits, self.ps.col_offset)
        self.row_planes = _patterns.bit_planes(Hp, self.ps.row_bits, self.ps.row_offset)
        self.index = {}
        for j, (a, b) in enumerate(self.ps.pair_indices("col")):
            self.index[int(a)], self.index[int(b)] = ("col", j, False), ("col", j, True)
        for j, (a, b) in enumerate(self.ps.pair_indices("row")):
            self.index[int(a)], self.index[int(b)] = ("row", j, False), ("row", j, True)

    def _lookup(self, profile, axis):
        m = self.mapx if axis == "x" else self.mapy
        return cv2.remap(profile, m, self.zeros, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)

    def linear(self, k: int) -> np.ndarray:
        """Noise-free linear camera image k (H, W) float32 (fraction of full scale), before blur."""
        sc = self.scene
        black = sc.proj_black
        if k == self.ps.white:
            hi = self.full + self.amb
        elif k == self.ps.black:
            hi = black * self.full + self.amb
        else:
            axis, j, inv = self.index[k]
            plane = self.col_planes[j] if axis == "col" else self.row_planes[j]
            if inv:
                plane = ~plane
            light = black + (1.0 - black) * plane
            prof = _profile(light, self.sigma, self.pad)
            if axis == "col":
                hi = self._lookup(prof, "x") * self.coef_cols + self.amb
            else:
                hi = self._lookup(prof, "y") * self.coef_rows + self.amb
        W, H = sc.cam_size
        return cv2.resize(hi, (W, H), interpolation=cv2.INTER_AREA)

    def finish(self, lin: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Optics, noise, gamma and quantisation of a linear image."""
        sc = self.scene
        if sc.cam_blur > 0:
            lin = cv2.GaussianBlur(lin, (0, 0), sigmaX=sc.cam_blur, sigmaY=sc.cam_blur,
                                   borderType=cv2.BORDER_REFLECT)
        var = np.full_like(lin, (sc.read_noise / 255.0) ** 2)
        if sc.full_well > 0:
            var += np.maximum(lin, 0) / sc.full_well
        noisy = lin + np.sqrt(var) * rng.standard_normal(lin.shape, dtype=np.float32)
        np.clip(noisy, 0.0, 1.0, out=noisy)
        if sc.gamma != 1.0:
            noisy = noisy ** (1.0 / sc.gamma)
        top = 255 if sc.bits == 8 else 65535
        return np.rint(noisy * top).astype(np.uint8 if sc.bits == 8 else np.uint16)


def render(scene: Scene, order: str = "opencv", seed: int = 0,
           progress: Callable[[int, int], None] | None = None):
    """Render the full Gray-code capture of ``scene``.

    Parameters
    ----------
    scene : the set-up (board pose, photometry, bit depth, supersampling).
    order : pattern sequence order, ``"opencv"`` (default) or ``"moreno"`` (see :mod:`procam.patterns`).
    seed : noise seed; the same seed gives bit-identical images.
    progress : optional ``callable(done, total)`` called after the geometry and after each image.

    Returns
    -------
    stack : (K, H, W) uint8 (``bits=8``) or uint16 (``bits=16``, full scale 65535), K = 46 for a
        1920x1080 projector, in the sequence order.
    truth : dict, :func:`truth` plus ``"render"`` (order, seed, pattern set).
    """
    r = _Renderer(scene, order)
    total = r.ps.count + 1
    if progress is not None:
        progress(1, total)
    rng = np.random.default_rng(seed)
    W, H = scene.cam_size
    stack = np.empty((r.ps.count, H, W), dtype=np.uint8 if scene.bits == 8 else np.uint16)
    for k in range(r.ps.count):
        stack[k] = r.finish(r.linear(k), rng)
        if progress is not None:
            progress(k + 2, total)
    t = truth(scene)
    t["render"] = {"order": order, "seed": int(seed), "count": int(r.ps.count),
                   "white": int(r.ps.white), "black": int(r.ps.black),
                   "pattern_set": r.ps.to_dict()}
    return stack, to_jsonable(t)


# --------------------------------------------------------------------------------------------
# output
# --------------------------------------------------------------------------------------------

def write_capture(out_dir, stack: np.ndarray, truth: dict, order: str = "opencv") -> list[Path]:
    """Write a rendered capture in procam's default capture-folder layout.

    Files: ``00.png`` ... ``45.png`` (zero-padded index, sequence order), ``truth.json`` (``truth``)
    and ``patterns.json`` (:meth:`procam.patterns.PatternSet.to_dict` plus ``"files"``).  Every file
    is written under a hidden temporary name and renamed (:func:`procam.capture.write_sequence`), so an
    interrupted run leaves no half-written image that a loader would pick up.  Numbered PNGs
    (``NN.png``) left in ``out_dir`` by an earlier run with a longer sequence are deleted, so they
    are not read as part of this one.

    Parameters
    ----------
    out_dir : folder (created if missing).
    stack : (K, H, W) uint8 or uint16 images from :func:`render`.
    truth : the truth dict from :func:`render` (its projector size names the pattern set).
    order : the sequence order the stack was rendered in.

    Returns
    -------
    list of the image paths, in sequence order.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    wp, hp = truth["projector"]["size"]
    ps = _patterns.pattern_set(int(wp), int(hp), order)
    stack = np.asarray(stack)
    if stack.ndim != 3 or stack.shape[0] != ps.count:
        raise ValueError(f"stack must be ({ps.count}, H, W) for a {wp}x{hp} projector, got {stack.shape}")
    if stack.dtype not in (np.uint8, np.uint16):
        raise ValueError(f"stack must be uint8 or uint16, got {stack.dtype}")
    paths = _capture.write_sequence(out, stack, ps)
    write_text(out / "truth.json", json.dumps(to_jsonable(truth), indent=1))
    return paths
