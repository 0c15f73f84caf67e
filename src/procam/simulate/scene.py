"""The simulated set-up: :class:`Scene` and the board's geometry.

* :class:`Scene` - camera, projector (each with its lens, :class:`~procam.simulate.Lens`),
  extrinsics, printed board at a pose, background (the default wall that moves with the board, or a
  :class:`~procam.simulate.Background` fixed in the room) and the photometry of a capture (immutable;
  variants with :meth:`Scene.replace`).
* :func:`board_corners`, :func:`board_extent` - the printed board in its own frame.

The presets are in :mod:`~procam.simulate.presets`, board placement in :mod:`~procam.simulate.poses`,
the exact ground truth and the fast corner path in :mod:`~procam.simulate.truth`.

Conventions: a pose ``(R, t)`` maps board -> device; board corner ``k = j*cols + i`` is at
``(i s, j s, 0)`` minus the centroid, z away from the devices; angles in degrees at this surface.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from .background import Background, Plane
from .lens import _K, Lens, euler_matrix

__all__ = ["Scene", "DEFAULT_DISTANCE", "board_corners", "board_extent"]

#: Cell size (mm) of the board's print texture (:attr:`Scene.board_grain`).
BOARD_GRAIN_MM = 1.0

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
        ``"opencv"`` (Brown: k1, k2, p1, p2, k3 on normalised coordinates, radial part about
        ``cam_dist_center``, plus ``cam_dist_higher``) or ``"none"``; see :class:`~procam.simulate.Lens`.
    cam_dist_coeffs : ``(k1, k2)`` in px^-2, px^-4 for ``division``; ``(k1, k2, p1, p2, k3)`` for ``opencv``.
    cam_dist_center : the centre (x, y) px of the division model or of an opencv lens's radial
        distortion (decentring); ``None`` = the principal point.
    cam_dist_higher : opencv only: radial coefficients of r^8, r^10, ... beyond OpenCV's k3 (a lens
        OpenCV's model does not describe exactly); ``()`` = none.
    proj_size, K_proj : projector panel (width, height) and intrinsics; the principal point may lie
        anywhere, e.g. beyond the panel's last row (vertical lens shift).
    proj_distortion, proj_dist_coeffs, proj_dist_center, proj_dist_higher : the projector's lens,
        as the camera's (default ``"none"``: an ideal pinhole).  The panel pixel that lights a point
        ``X`` (projector frame) is ``K_proj * distort(X / Z)``, what ``cv2.projectPoints`` returns.
    R, T : camera -> projector, ``x_p = R x_c + T``.
    board_cols, board_rows, square : inner corners and square pitch (mm).
    margin : white border (mm) of the printed board beyond its outer squares.
    R_board, t_board : board -> camera pose (``X_c = R_board X_b + t_board``); ``t_board`` is the
        board centre (corner centroid).
    background : ``None`` (default): one wall with unit normal ``wall_normal`` (camera frame) through
        ``t_board + wall_offset * e_z``, albedo ``albedo_wall``: it MOVES WITH THE BOARD (the renders
        procam's tests were written against).  A :class:`~procam.simulate.Background` instead: planes
        and solids FIXED IN THE ROOM (camera frame), as in a real capture, with occlusion and shadows;
        ``wall_normal``, ``wall_offset`` and ``albedo_wall`` are then unused.  The camera and the
        projector must lie on one side of each of its planes and outside its solids.
    wall_normal, wall_offset : the default wall (see ``background``).

    Photometry (linear values are fractions of the camera's full scale)

    albedo_white, albedo_black, albedo_wall : diffuse reflectances.
    board_grain : the print's texture (a speckled print, a board on grainy stock): ``board_grain * n`` added
        to the board's albedo (then clipped to [0, 1]), ``n`` a fixed zero-mean, unit-variance field in board
        coordinates (cells of :data:`BOARD_GRAIN_MM`, bilinear); the same in every frame, so it is not noise but a
        busy board surface.  0 (default) = a uniform print.
    gain : camera exposure x gain: full-white projector light at the board-centre distance on a
        frontal albedo-1 surface gives ``gain`` of full scale.
    ambient : ambient irradiance as a fraction of full projector white.
    proj_black : light of a black projector pixel as a fraction of white (black level).
    proj_gamma : the projector's response: a pattern value ``v`` (0-255) emits
        ``proj_black + (1 - proj_black) * (v / 255) ** proj_gamma`` of white (binary Gray-code
        patterns are unchanged by it).
    proj_defocus : projector defocus, Gaussian sigma in projector pixels.
    cam_blur : camera optics, Gaussian sigma in camera pixels.
    cam_vignetting, proj_vignetting : relative illumination ``cos(field angle) ** n`` of the camera
        lens (on everything it sees) and of the projector lens (on its light); 4 is the natural
        cos^4 law of a thin lens, 0 disables.
    full_well : electrons at full scale (shot noise variance = signal / full_well); 0 = no shot noise.
    read_noise : read noise sigma in 8-bit DN (scaled for 16-bit output).
    gamma : the camera's response: output = linear ** (1 / gamma).
    bits : 8 or 16 (output dtype uint8 / uint16).
    supersample : rays per pixel along each axis (anti-aliasing).
    name : label written to ``truth.json``.
    """

    cam_size: tuple = (1280, 800)
    K_cam: np.ndarray = field(default_factory=lambda: _K(1539.0, 1.004, 674.0, 512.0))
    cam_distortion: str = "division"
    cam_dist_coeffs: tuple = (-3e-8, 0.0)
    cam_dist_center: tuple | None = None
    cam_dist_higher: tuple = ()
    proj_size: tuple = (1920, 1080)
    K_proj: np.ndarray = field(default_factory=lambda: _K(2421.0, 1.002, 1013.0, 1065.0))
    proj_distortion: str = "none"
    proj_dist_coeffs: tuple = ()
    proj_dist_center: tuple | None = None
    proj_dist_higher: tuple = ()
    R: np.ndarray = field(default_factory=lambda: euler_matrix((0.87, 14.44, -0.25)))
    T: np.ndarray = field(default_factory=lambda: np.array([-170.05, -41.25, -65.35]))
    board_cols: int = 10
    board_rows: int = 6
    square: float = 24.0
    margin: float = 20.0
    R_board: np.ndarray = field(default_factory=lambda: np.eye(3))
    t_board: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, DEFAULT_DISTANCE]))
    background: Background | None = None
    wall_normal: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    wall_offset: float = 300.0
    albedo_white: float = 0.85
    albedo_black: float = 0.1
    albedo_wall: float = 0.5
    board_grain: float = 0.0
    gain: float = 0.95
    ambient: float = 0.04
    proj_black: float = 0.03
    proj_gamma: float = 1.0
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
        for dev in ("cam", "proj"):  # the lens checks its own fields; the scene keeps them as floats
            try:
                lens = Lens(getattr(self, f"{dev}_distortion"), getattr(self, f"{dev}_dist_coeffs"),
                            getattr(self, f"{dev}_dist_center"), getattr(self, f"{dev}_dist_higher"))
            except ValueError as e:
                raise ValueError(f"{dev}_{e}" if str(e).startswith("distortion") else f"{dev} lens: {e}") from None
            s(self, f"{dev}_dist_coeffs", lens.coeffs)
            s(self, f"{dev}_dist_center", lens.center)
            s(self, f"{dev}_dist_higher", lens.higher)
        if self.bits not in (8, 16):
            raise ValueError(f"bits must be 8 or 16, got {self.bits}")
        if int(self.supersample) < 1:
            raise ValueError(f"supersample must be >= 1, got {self.supersample}")
        s(self, "supersample", int(self.supersample))
        if not 0.0 <= float(self.board_grain) <= 1.0:
            raise ValueError(f"board_grain must be from 0 to 1 (an albedo's standard deviation), got "
                             f"{self.board_grain}")
        if not float(self.proj_gamma) > 0:
            raise ValueError(f"proj_gamma must be positive, got {self.proj_gamma}")
        if self.background is not None:
            if not isinstance(self.background, Background):
                raise ValueError(f"background must be a Background or None, got {type(self.background).__name__}")
            self.background.check_devices([np.zeros(3), self.proj_center_cam], ("camera", "projector"))

    # convenient derived quantities ------------------------------------------------------------
    @property
    def cam_center(self) -> np.ndarray:
        """The camera lens's distortion centre (2,) in pixels: ``cam_dist_center``, or the principal point."""
        if self.cam_dist_center is None:
            return self.K_cam[:2, 2].copy()
        return np.array(self.cam_dist_center, float)

    @property
    def cam_lens(self) -> Lens:
        """The camera's lens (:class:`~procam.simulate.Lens`)."""
        return Lens(self.cam_distortion, self.cam_dist_coeffs, self.cam_dist_center, self.cam_dist_higher)

    @property
    def proj_lens(self) -> Lens:
        """The projector's lens (:class:`~procam.simulate.Lens`)."""
        return Lens(self.proj_distortion, self.proj_dist_coeffs, self.proj_dist_center, self.proj_dist_higher)

    @property
    def fixed_background(self) -> bool:
        """True when the background is fixed in the room (a :class:`~procam.simulate.Background`), False
        for the default wall that moves with the board."""
        return self.background is not None

    def surfaces(self) -> Background:
        """The background at this board pose, camera frame: ``background``, or the default wall as a
        one-plane :class:`~procam.simulate.Background`."""
        if self.background is not None:
            return self.background
        return Background((Plane(self.t_board + self.wall_offset * np.array([0.0, 0.0, 1.0]), self.wall_normal,
                                 self.albedo_wall),))

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

    def scaled(self, factor: float) -> "Scene":
        """The same rig with both devices' pixel grids scaled by ``factor`` (the same angles of view; e.g. 0.25
        for a render 16 times cheaper).  Sizes are rounded to whole pixels; focal lengths scale, principal points
        and lens centres scale about the pixel-centre convention (``u' = (u + 0.5) factor - 0.5``); the division
        model's k1, k2 scale by ``factor^-2``, ``factor^-4``; OpenCV coefficients (normalised coordinates) do not
        change.  The board pose is kept (re-place it with :func:`~procam.simulate.with_board_pose` if the
        smaller margins matter)."""
        f = float(factor)
        if not f > 0:
            raise ValueError(f"factor must be positive, got {factor}")

        def K(M):
            M = np.array(M, float)
            M[0, 0] *= f
            M[1, 1] *= f
            M[0, 1] *= f
            M[:2, 2] = (M[:2, 2] + 0.5) * f - 0.5
            return M

        changes = {"cam_size": (round(self.cam_size[0] * f), round(self.cam_size[1] * f)), "K_cam": K(self.K_cam),
                   "proj_size": (round(self.proj_size[0] * f), round(self.proj_size[1] * f)), "K_proj": K(self.K_proj)}
        for dev in ("cam", "proj"):
            center = getattr(self, f"{dev}_dist_center")
            if center is not None:
                changes[f"{dev}_dist_center"] = tuple((np.array(center) + 0.5) * f - 0.5)
            if getattr(self, f"{dev}_distortion") == "division":
                k1, k2 = getattr(self, f"{dev}_dist_coeffs")
                changes[f"{dev}_dist_coeffs"] = (k1 / f ** 2, k2 / f ** 4)
        return self.replace(**changes)


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


