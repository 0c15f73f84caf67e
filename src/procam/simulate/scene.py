"""The simulated set-up: :class:`Scene`, the presets, board poses and the exact ground truth.

* :class:`Scene` - camera, projector, extrinsics, printed board at a pose, background wall and the
  photometry of a capture (immutable; variants with :meth:`Scene.replace`).
* :func:`preset`, :data:`PRESETS`, :data:`RECOMMENDED_POSE` - the seed paper's simulated rig and a
  variant where the single-pose method's assumptions hold.
* :func:`with_board_pose`, :func:`fit_margin` - place the board at given angles so that it is seen
  whole by both devices.
* :func:`board_corners`, :func:`board_extent`, :func:`corner_truth`, :func:`truth` - the exact
  geometry; :func:`correspondences` - the fast path: exact corners plus Gaussian noise, no images.

Conventions: a pose ``(R, t)`` maps board -> device; board corner ``k = j*cols + i`` is at
``(i s, j s, 0)`` minus the centroid, z away from the devices; angles in degrees at this surface.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize

from ..io.files import to_jsonable
from .lens import _K, distort, euler_matrix, matrix_euler, project

__all__ = ["Scene", "preset", "PRESETS", "RECOMMENDED_POSE", "DEFAULT_DISTANCE", "with_board_pose",
           "fit_margin", "board_corners", "board_extent", "corner_truth", "truth", "truth_calibration",
           "correspondences"]

#: Board (psi, nu, phi) in degrees in the CAMERA frame recommended for a single-pose calibration
#: with the ``paper`` / ``ideal`` rigs: |psi_c| + |nu_c| = 27 > 10 and, through the rig's
#: R (nu = 14.44 deg), nu_p = 26.1 deg > 13 (checked in ``tests/test_simulate.py``).
RECOMMENDED_POSE: tuple[float, float, float] = (15.0, 12.0, 0.0)

#: Depth (mm, along the device's optical axis) tried first by :func:`with_board_pose` when no
#: distance is given (the board distance of the paper's simulation study).
DEFAULT_DISTANCE = 500.0

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
        The simulated procam of the seed paper's simulation study: camera 1280x800, f 1539, alpha 1.004,
        pp (674, 512); projector 1920x1080, f 2421, alpha 1.002, pp (1013, 1065); R, T from the
        paper's reference calibration (Euler (0.87, 14.44, -0.25) deg, T (-170.05, -41.25, -65.35)
        mm); board 10x6 at 24 mm.  Mild barrel distortion: division model k1 = -3e-8 px^-2 about the
        principal point (about 0.8-5 px at the board's outer corners at the recommended pose).
    ``ideal``
        The same rig with the single-pose method's assumptions true: u0p = 960 (W/2), alpha_p = 1,
        and a division-model distortion k1 = -1e-7 px^-2 about the principal point (the reference
        value of procam's Cramér-Rao analysis), strong enough (about 3-14 px at the board's outer
        corners at the recommended pose) for the centre of distortion to be observable from one
        view (:mod:`procam.distortion`).
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


def truth_calibration(scene: Scene, method: str = "truth"):
    """The scene's exact devices and extrinsics as a :class:`procam.calibration.Calibration` (no ``std``;
    ``stereo_rms`` 0, the per-device RMS not computed): what a perfect calibration of this rig would return, to
    hold a result or a metric against."""
    from ..calibration import Calibration, Device, Distortion

    if scene.cam_distortion == "division":
        dist = Distortion("division", tuple(float(v) for v in scene.cam_center), *scene.cam_dist_coeffs)
    elif scene.cam_distortion == "opencv":
        dist = Distortion("opencv", coeffs=tuple(scene.cam_dist_coeffs))
    else:
        dist = Distortion()
    return Calibration(Device(np.array(scene.K_cam), scene.cam_size, dist),
                       Device(np.array(scene.K_proj), scene.proj_size), np.array(scene.R), np.array(scene.T),
                       method, stereo_rms=0.0)


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
