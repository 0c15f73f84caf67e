"""Live pose advice: how to turn the board before a single-pose capture.

Per camera frame (:meth:`Advisor.update`):

1. the board: :func:`procam.corners.detect_corners` with its live setting (:data:`procam.corners.LIVE`,
   :attr:`AdvisorOptions.corner_options`): OpenCV's chessboard detector on a downscaled copy of the frame
   (``AdvisorOptions.detect_width``, ``CALIB_CB_FAST_CHECK`` so a frame without the board costs little),
   the corners refined with ``cornerSubPix`` in the full-resolution frame, in procam's canonical order
   (:func:`procam.corners.canonical_order`);
2. the board's pose in the camera by PnP (``SOLVEPNP_IPPE`` on the undistorted corners) with the camera's
   intrinsics: from a calibration (an earlier capture or a calibration file) when there is one, else a
   guess (``f`` = the image diagonal, the principal point at the image centre, no distortion) -- the advice
   says which (:attr:`Advice.intrinsics`);
3. the board's angles ``(psi_c, nu_c)`` (:func:`procam.models.board_angles_deg`) and the Cramér-Rao bound of
   ``f_c`` at that pose (:func:`procam.crlb.camera_bound`, the ``full`` model the single-pose solver fits:
   ``f, alpha``, the principal point = centre of distortion, ``k1, k2`` and the pose, corner noise
   ``sigma_camera`` px).  When the corners do not pin the principal point (its data-only bound above
   the solver's prior, 2.5 % of the larger image side), the bound is the one with the solver's Gaussian
   prior on it (the image centre), as :func:`procam.single_pose.calibrate` then does;
4. with an earlier capture's calibration (its ``R, T, K_p``), the board in the projector frame
   (``R_p = R R_c, t_p = R t_c + T``), ``(psi_p, nu_p)`` and the bound of ``f_p, v0p``
   (:func:`procam.crlb.projector_bound`: ``u0p`` and ``alpha_p`` held, corner noise ``sigma_projector``);
   the printed board's footprint in the projector image tells whether it is all in the projector's light;
5. the advice (:class:`Action` s): move into view / closer / into the light first, then which way to turn
   and tilt the board and roughly how far (:meth:`Advisor.search_move`), then "good — hold still" until the
   corners have been still for ``still_s``: the state ``ready``.

The score of a pose is the largest of its terms, each ``<= 1`` when satisfied: ``std(f_c) / f_c / target``
(with known intrinsics), ``std(f_p) / f_p / target`` (with the projector side) and the paper's rule as
:func:`procam.single_pose.advice` applies it (``|psi_c| + |nu_c| > 10``, each ``>= 4`` deg; ``|nu_p| > 13``
deg), as a ratio.  The bounds cover the noise only; the rule keeps clear of poses where the method's
assumptions (``u0p = W/2``, the principal point at the centre of distortion) cost most.  Before the
projector side is known and with guessed intrinsics, the camera's bound is only indicative (no distortion
is known) and the camera rule alone judges the pose: enough for the one quick capture that measures
``R, T``.  The move search (:meth:`Advisor.search_move`) probes a turn and a tilt each way, then walks
along the pure turns/tilts and their gradient-weighted combination until a pose scores below ``aim``
(a margin under 1); camera angles beyond ``max_angle_deg`` are not proposed (the detector and the corner
accuracy suffer).

Moves are rotations of the board about its own centre, about the **camera's** axes (the user's vertical
and horizontal): a *turn* of ``+d`` degrees is about the vertical axis with the board's right edge (as the
camera sees it) going away from the camera, a *tilt* of ``+d`` degrees about the horizontal axis with the
top edge going away (:func:`apply_move`).

Nothing here opens a window or prints: :class:`Advice` is a frozen dataclass per frame with its JSON
form (:meth:`Advice.to_dict`).
"""

from __future__ import annotations

import json
import math
import time
from collections import deque
from dataclasses import dataclass, field, replace

import numpy as np

from . import crlb, models
from .board import Board
from .corners import LIVE, CornerOptions, detect_corners
from .calibration import Calibration, Device, Distortion
from .errors import ProcamError
from .single_pose.advice import AdviceOptions

__all__ = ["AdvisorOptions", "Action", "DeviceState", "Advice", "ProjectorSide", "Advisor", "apply_move",
           "move_between", "guessed_camera", "STATES"]

#: Advice states, from worst to best.
STATES = ("no-board", "adjust", "good", "ready")

_TURN_WORDS = {1: "right edge away", -1: "left edge away"}
_TILT_WORDS = {1: "top edge away", -1: "bottom edge away"}


# --------------------------------------------------------------------------------------------
# options and results
# --------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class AdvisorOptions:
    """Thresholds and settings of the advisor (every one checked at construction).

    Attributes
    ----------
    target_pct : a pose is good when the predicted std of ``f_c`` and of ``f_p`` are at most this % of
        the focal length.
    projector_target_pct : the projector's target when it differs (None: ``target_pct``).
    aim : the move search aims at ``aim * target`` (a margin, so that a good pose stays good).
    sigma_camera, sigma_projector : corner noise (px, per coordinate) the bounds assume.
    still_s, still_px : the board is still when no corner moved more than ``still_px`` (full-resolution
        px) over the last ``still_s`` seconds.
    detect_width : the frame is downscaled to at most this width for the detection (px); 0 = never.
    refine_window : ``cornerSubPix`` half-window at full resolution (px; clamped to half the corner spacing).
    min_board_fraction : the board's quadrilateral must cover at least this fraction of the image.
    edge_margin : the printed board's outer squares must keep this fraction of the image diagonal from
        the image border.
    max_angle_deg : no move is proposed that tilts or turns the board beyond this in the camera frame.
    probe_deg, max_move_deg : the move search's step and longest move (degrees).
    search_interval_s, search_refresh_s : the move search (10-50 bound evaluations) runs again when the board
        went the other way or was moved (checked at most every ``search_interval_s``), when it reached the
        proposed pose and that is not good, and every ``search_refresh_s``; in between, the remaining move to
        the proposed pose is updated every frame.
    paper_rule : a good pose must also pass the paper's rule as :func:`procam.single_pose.advice` judges it
        (camera ``|psi_c| + |nu_c| > 10``, each ``>= 4`` deg; projector ``|nu_p| > 13`` deg; thresholds from
        ``advice``): the bounds cover the noise only, the rule keeps away from poses where a model error
        (``u0p = W/2``, a principal point off the centre of distortion) costs most.
    advice : :class:`procam.single_pose.AdviceOptions` (the rule's thresholds).
    pp_prior_fraction : the solver's prior std of an assumed principal point, as a fraction of the
        larger image side (:class:`procam.single_pose.CameraOptions`).
    """

    target_pct: float = 1.0
    projector_target_pct: float | None = None
    aim: float = 0.8
    sigma_camera: float = 0.1
    sigma_projector: float = 0.2
    still_s: float = 0.5
    still_px: float = 1.0
    detect_width: int = 640
    refine_window: int = 11
    min_board_fraction: float = 0.05
    edge_margin: float = 0.01
    max_angle_deg: float = 40.0
    probe_deg: float = 5.0
    max_move_deg: float = 40.0
    search_interval_s: float = 0.25
    search_refresh_s: float = 2.0
    paper_rule: bool = True
    advice: AdviceOptions = AdviceOptions()
    pp_prior_fraction: float = 0.025

    def __post_init__(self):
        def check(name, lo, hi, *, open_lo=False, allow_none=False):
            v = getattr(self, name)
            if v is None and allow_none:
                return
            ok = isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool) \
                and math.isfinite(v) and (v > lo if open_lo else v >= lo) and v <= hi
            if not ok:
                low = f"> {lo:g}" if open_lo else f">= {lo:g}"
                raise ProcamError(f"advisor option {name} must be a finite number {low} and <= {hi:g}, got {v!r}")

        check("target_pct", 0, 100, open_lo=True)
        check("projector_target_pct", 0, 100, open_lo=True, allow_none=True)
        check("aim", 0, 1, open_lo=True)
        check("sigma_camera", 0, 100, open_lo=True)
        check("sigma_projector", 0, 100, open_lo=True)
        check("still_s", 0, 60)
        check("still_px", 0, 1000)
        check("detect_width", 0, 100000)
        if 0 < self.detect_width < 160:
            raise ProcamError(f"advisor option detect_width must be 0 (no downscaling) or >= 160 px, "
                              f"got {self.detect_width}")
        check("refine_window", 0, 100)
        check("min_board_fraction", 0, 1)
        check("edge_margin", 0, 0.5)
        check("max_angle_deg", 1, 80)
        check("probe_deg", 0.5, 30)
        check("max_move_deg", 1, 90)
        check("search_interval_s", 0, 60)
        check("search_refresh_s", 0, 3600)
        check("pp_prior_fraction", 0, 1, open_lo=True)

    @property
    def projector_target(self) -> float:
        """The projector's target % of f."""
        return self.target_pct if self.projector_target_pct is None else self.projector_target_pct

    @property
    def corner_options(self) -> CornerOptions:
        """The detector's settings per frame: :data:`procam.corners.LIVE` with ``detect_width`` and
        ``refine_window``."""
        return replace(LIVE, max_width=self.detect_width, refine_window=self.refine_window)


@dataclass(frozen=True)
class Action:
    """One thing to do.

    ``kind``: ``"find"`` (bring the board into view), ``"closer"``, ``"move"`` (``direction`` left /
    right / up / down: away from an image border or into the projector's light), ``"turn"`` (about the
    vertical axis, ``degrees > 0``: right edge away), ``"tilt"`` (about the horizontal axis,
    ``degrees > 0``: top edge away), ``"capture"`` (first capture: measure the projector side), ``"hold"``
    (good: hold still).  ``text`` is the sentence shown to the user.
    """

    kind: str
    text: str
    degrees: float | None = None
    direction: str | None = None

    def to_dict(self) -> dict:
        d = {"kind": self.kind, "text": self.text}
        if self.degrees is not None:
            d["degrees"] = round(float(self.degrees), 1)
        if self.direction is not None:
            d["direction"] = self.direction
        return d


@dataclass(frozen=True)
class DeviceState:
    """The board seen by one device, and the predicted single-pose uncertainty there.

    ``angles_deg`` (psi, nu, phi) of the board in the device frame; ``f`` (px) the focal length the bound
    was evaluated at; ``std_f`` (px) its predicted std, ``rel_std_f`` = ``std_f / f``; ``std_v0`` (px, the
    projector's ``v0p``; None for the camera); ``distance`` (board units) of the board centre;
    ``assumes`` what the bound assumes.
    """

    angles_deg: tuple
    f: float
    std_f: float
    rel_std_f: float
    distance: float
    std_v0: float | None = None
    assumes: str = ""

    def to_dict(self) -> dict:
        def num(v, nd=3):
            return None if v is None or not math.isfinite(v) else round(float(v), nd)

        d = {"psi": num(self.angles_deg[0], 2), "nu": num(self.angles_deg[1], 2), "phi": num(self.angles_deg[2], 2),
             "f": num(self.f, 1), "std_f": num(self.std_f, 2), "rel_std_f_pct": num(100 * self.rel_std_f, 3),
             "distance": num(self.distance, 1)}
        if self.std_v0 is not None:
            d["std_v0"] = num(self.std_v0, 2)
        d["assumes"] = self.assumes
        return d


@dataclass(frozen=True)
class Advice:
    """The advisor's verdict on one camera frame.

    Attributes
    ----------
    frame : index of the frame (0, 1, ... per :class:`Advisor`); ``time_s`` its time stamp (s).
    state : ``"no-board"``, ``"adjust"``, ``"good"`` (good — hold still) or ``"ready"`` (good and still).
    message : the headline shown to the user.
    actions : :class:`Action` s, most urgent first.
    notes : other lines worth showing (the projector side unknown, which intrinsics ...).
    phase : ``"first"`` (no projector side yet: the goal is one quick capture) or ``"target"``.
    corners : (N, 2) full-resolution corners in canonical order, or None; ``outline`` (4, 2) the printed
        squares' outer corners in the image (clockwise from the top-left), or None.
    camera, projector : :class:`DeviceState` or None.
    score : the largest of the pose's terms, each <= 1 when satisfied: ``std(f) / f / target`` per known device
        and the paper's rule as a ratio (:meth:`Advisor._terms`); <= 1: good, inf: undetermined.
    limiting : what keeps the score above 1, in words ("" when good).
    target_pct, projector_target_pct : the targets (% of f).
    board_fraction : area of the board's quadrilateral / image area; ``edge_px`` its smallest distance to
        the image border (px).
    outside_light : projector-image sides the printed board crosses (``"left"``, ...; empty: all lit);
        None when the projector side is unknown.
    still : the corners moved at most ``still_px`` over the last ``still_s``; ``motion_px`` the largest move.
    intrinsics : where the camera's intrinsics come from (``"intrinsics from FILE"`` or ``"guessed f = image
        diagonal (1510 px), principal point at the image centre, no distortion"``).
    image_size : (W, H) of the frame.
    timings_ms : ``detect``, ``bounds``, ``search`` and ``total`` (ms).
    """

    frame: int
    time_s: float
    state: str
    message: str
    actions: tuple = ()
    notes: tuple = ()
    phase: str = "first"
    corners: np.ndarray | None = None
    outline: np.ndarray | None = None
    camera: DeviceState | None = None
    projector: DeviceState | None = None
    score: float = float("inf")
    limiting: str = ""
    target_pct: float = 1.0
    projector_target_pct: float = 1.0
    board_fraction: float = 0.0
    edge_px: float = float("nan")
    outside_light: tuple | None = None
    still: bool = False
    motion_px: float = float("nan")
    intrinsics: str = ""
    image_size: tuple = (0, 0)
    timings_ms: dict = field(default_factory=dict)

    @property
    def found(self) -> bool:
        """The board was found in the frame."""
        return self.corners is not None

    @property
    def good(self) -> bool:
        """The pose is good (``good`` or ``ready``)."""
        return self.state in ("good", "ready")

    @property
    def ready(self) -> bool:
        """Good and still: the moment to capture."""
        return self.state == "ready"

    def to_dict(self, corners: bool = False) -> dict:
        """JSON-ready dict (``corners=True`` adds the (N, 2) corners; non-finite numbers become null)."""
        def num(v, nd=3):
            return None if v is None or not math.isfinite(v) else round(float(v), nd)

        d = {"frame": self.frame, "time_s": num(self.time_s, 4), "state": self.state, "message": self.message,
             "phase": self.phase, "actions": [a.to_dict() for a in self.actions], "notes": list(self.notes),
             "score": num(self.score, 4), "limiting": self.limiting, "target_pct": self.target_pct,
             "projector_target_pct": self.projector_target_pct,
             "camera": None if self.camera is None else self.camera.to_dict(),
             "projector": None if self.projector is None else self.projector.to_dict(),
             "board_fraction": num(self.board_fraction, 4), "edge_px": num(self.edge_px, 1),
             "outside_light": None if self.outside_light is None else list(self.outside_light),
             "still": self.still, "motion_px": num(self.motion_px, 2), "intrinsics": self.intrinsics,
             "image_size": list(self.image_size),
             "outline": None if self.outline is None else np.round(self.outline, 2).tolist(),
             "timings_ms": {k: round(float(v), 2) for k, v in self.timings_ms.items()}}
        if corners:
            d["corners"] = None if self.corners is None else np.round(self.corners, 3).tolist()
        return d

    def to_json(self, corners: bool = False) -> str:
        """One line of JSON (:meth:`to_dict`)."""
        return json.dumps(self.to_dict(corners), separators=(",", ":"), allow_nan=False)


@dataclass(frozen=True)
class ProjectorSide:
    """What an earlier capture tells about the projector: ``K`` (3, 3), ``size`` (W, H), the extrinsics
    ``R, T`` (camera -> projector, ``x_p = R x_c + T``, board units) and ``source`` (where they come from)."""

    K: np.ndarray
    size: tuple
    R: np.ndarray
    T: np.ndarray
    source: str = ""


def guessed_camera(image_size) -> Device:
    """The camera when nothing is known: ``f`` = the image diagonal (px; a ~53 deg diagonal field of
    view), the principal point at the image centre, square pixels, no distortion."""
    w, h = int(image_size[0]), int(image_size[1])
    f = float(math.hypot(w, h))
    return Device(models.intrinsic_matrix(f, (w - 1) / 2.0, (h - 1) / 2.0), (w, h), Distortion())


# --------------------------------------------------------------------------------------------
# moves
# --------------------------------------------------------------------------------------------

def _axis_rotation(turn_deg: float, tilt_deg: float) -> np.ndarray:
    """The rotation (camera frame) of a turn then a tilt (see :func:`apply_move` for the signs)."""
    ry = models.rvec_to_matrix([0.0, -math.radians(turn_deg), 0.0])
    rx = models.rvec_to_matrix([-math.radians(tilt_deg), 0.0, 0.0])
    return rx @ ry


def apply_move(R_b, t_b, turn_deg: float = 0.0, tilt_deg: float = 0.0):
    """The board pose after a move: a turn about the camera's vertical axis and a tilt about its
    horizontal axis, both through the board's centre (the corners' centroid, ``t_b``).

    ``turn_deg > 0``: the board's right edge (larger image x) goes away from the camera;
    ``tilt_deg > 0``: its top edge (smaller image y) goes away.  Returns ``(R_b', t_b)`` (board -> camera).

    >>> R, t = apply_move(np.eye(3), [0.0, 0.0, 500.0], turn_deg=10.0)
    >>> bool((R @ [100.0, 0, 0] + t)[2] > 500.0)   # the right edge is farther
    True
    """
    R_b = np.asarray(R_b, float)
    return _axis_rotation(turn_deg, tilt_deg) @ R_b, np.asarray(t_b, float).reshape(3).copy()


def move_between(R_from, R_to) -> tuple[float, float]:
    """``(turn_deg, tilt_deg)`` that take the board from rotation ``R_from`` to ``R_to`` (camera frame;
    the small-angle split of ``R_to R_from^T`` into the two axes of :func:`apply_move`)."""
    w = models.matrix_to_rvec(np.asarray(R_to, float) @ np.asarray(R_from, float).T)
    return -math.degrees(w[1]), -math.degrees(w[0])


def _pose_pnp(obj, pts_und, K):
    """Board -> camera pose by IPPE on undistorted pixels (None when PnP fails)."""
    import cv2

    ok, rvec, tvec = cv2.solvePnP(obj.astype(np.float64), pts_und.reshape(-1, 1, 2).astype(np.float64),
                                  np.asarray(K, float), None, flags=cv2.SOLVEPNP_IPPE)
    if not ok or not np.all(np.isfinite(tvec)) or tvec[2, 0] <= 0:
        return None
    return models.rvec_to_matrix(rvec.ravel()), tvec.ravel()


def _polygon_area(p) -> float:
    x, y = p[:, 0], p[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def _distortion_for_bound(dev: Device):
    """(centre or None, k1, k2, note) of a device's distortion for the division-model bound."""
    d = dev.distortion
    if d.model == "division":
        return (None if d.center is None else tuple(d.center)), float(d.k1), float(d.k2), ""
    if d.model == "opencv" and d.coeffs:
        f2 = float(dev.K[0, 0]) * float(dev.K[1, 1])
        # first order: OpenCV's x_d = x_u (1 + k1 r_n^2) ~ the division model's with k1_div = k1 / f^2
        k1 = float(d.coeffs[0]) / f2
        k2 = float(d.coeffs[1]) / f2 ** 2 if len(d.coeffs) > 1 else 0.0
        return None, k1, k2, "OpenCV distortion approximated by the division model"
    return None, 0.0, 0.0, ""


# --------------------------------------------------------------------------------------------
# the advisor
# --------------------------------------------------------------------------------------------

class Advisor:
    """Stateful per-frame pose advice for single-pose calibration (see the module docstring).

    Parameters
    ----------
    board : the printed :class:`~procam.board.Board`.
    image_size : (W, H) of the camera frames.
    options : :class:`AdvisorOptions`.
    camera : the camera's intrinsics (:class:`~procam.calibration.Device`), or None for the guess
        (:func:`guessed_camera`); ``camera_source`` says where they come from (a file name).
    projector : :class:`ProjectorSide` from an earlier capture, or None (the projector side unknown).

    :meth:`set_calibration` takes both from a :class:`~procam.calibration.Calibration` (e.g. the quick
    single-pose calibration of the last capture).  :meth:`update` takes one frame.
    """

    def __init__(self, board: Board, image_size, options: AdvisorOptions = AdvisorOptions(), *,
                 camera: Device | None = None, camera_source: str = "", projector: ProjectorSide | None = None):
        self.board = board
        w, h = int(image_size[0]), int(image_size[1])
        if w < 16 or h < 16:
            raise ProcamError(f"advisor: camera frames of {w}x{h} px are too small")
        self.image_size = (w, h)
        self.options = options
        self.obj = board.object_points()
        s = board.square
        hx = 0.5 * (board.cols - 1) * s + s
        hy = 0.5 * (board.rows - 1) * s + s
        #: the printed squares' outer corners (board frame), clockwise in the image from the top-left
        self.outer = np.array([[-hx, -hy, 0.0], [hx, -hy, 0.0], [hx, hy, 0.0], [-hx, hy, 0.0]])
        self._camera: Device | None = None
        self.set_camera(camera, camera_source)
        self.projector = projector
        self._frame = 0
        self._history: deque = deque()
        self._plan: dict | None = None  # the move search's last proposal (see _move_actions)

    # -- configuration ----------------------------------------------------------------------
    def set_camera(self, camera: Device | None, source: str = "") -> None:
        """Use ``camera``'s intrinsics (None: the guess)."""
        if camera is not None and tuple(int(v) for v in camera.image_size) != self.image_size:
            raise ProcamError(f"advisor: the camera intrinsics{' from ' + source if source else ''} are for "
                              f"{camera.image_size[0]}x{camera.image_size[1]} frames but the camera delivers "
                              f"{self.image_size[0]}x{self.image_size[1]}; use a calibration of this camera "
                              "at this resolution")
        if camera is None:
            self._camera = guessed_camera(self.image_size)
            self.intrinsics = (f"guessed f = image diagonal ({self._camera.K[0, 0]:.0f} px), principal point at "
                               "the image centre, no distortion")
            self.known_intrinsics = False
        else:
            self._camera = camera
            self.intrinsics = f"intrinsics from {source}" if source else "intrinsics given"
            self.known_intrinsics = True
        self._plan = None

    def set_projector(self, projector: ProjectorSide | None) -> None:
        """Use ``projector`` (None: unknown)."""
        self.projector = projector
        self._plan = None

    def set_calibration(self, calib: Calibration, source: str = "") -> None:
        """Camera intrinsics and (when it has them) the projector side from a calibration."""
        self.set_camera(calib.camera, source)
        if calib.projector is not None and calib.R is not None and calib.T is not None:
            self.set_projector(ProjectorSide(np.asarray(calib.projector.K, float), tuple(calib.projector.image_size),
                                             np.asarray(calib.R, float), np.asarray(calib.T, float).reshape(3),
                                             source))
        else:
            self.set_projector(None)

    @property
    def camera(self) -> Device:
        return self._camera

    # -- per-pose quantities ------------------------------------------------------------------
    def _camera_bound(self, R_c, t_c, prior: bool | None = None):
        """(std_f, std dict, used_prior) of the camera's single-pose bound at pose (R_c, t_c)."""
        o = self.options
        dev = self._camera
        c, k1, k2, _ = _distortion_for_bound(dev)
        K = np.asarray(dev.K, float)
        sig_pp = o.pp_prior_fraction * max(self.image_size)
        # prior None: the solver's rule (the prior only where the corners do not pin the principal point)
        b = crlb.camera_bound(K, c, k1, k2, R_c, t_c, self.obj, o.sigma_camera, jacobian="central",
                              pp_prior_std=None if prior is False else sig_pp,
                              pp_prior_when="needed" if prior is None else "always")
        return b.std["f_c"], b.std, b.prior_used

    def _projector_pose(self, R_c, t_c):
        p = self.projector
        return p.R @ R_c, p.R @ t_c + p.T

    def _projector_bound(self, R_p, t_p):
        b = crlb.projector_bound(self.projector.K, R_p, t_p, self.obj, self.options.sigma_projector)
        return b.std["f_p"], b.std["v0p"]

    def _terms(self, ang_c, rel_c, ang_p, rel_p) -> dict:
        """The score's terms (each <= 1 when satisfied): ``f_c``/``f_p`` = predicted relative std / target,
        ``camera rule``/``projector rule`` = the paper's rule as a ratio (:mod:`procam.single_pose.advice`'s
        thresholds).  ``f_c`` only with known intrinsics, the projector's only with the projector side."""
        o, a = self.options, self.options.advice
        big = float("inf")

        def ratio(num, den):
            return num / den if den > 1e-12 else big

        terms = {}
        if self.known_intrinsics:
            terms["f_c"] = rel_c / (o.target_pct / 100.0) if math.isfinite(rel_c) else big
        if o.paper_rule or not self.known_intrinsics:
            psi, nu = abs(ang_c[0]), abs(ang_c[1])
            terms["camera rule"] = max(ratio(a.camera_rule_deg, psi + nu), ratio(a.weak_angle_deg, min(psi, nu)))
        if rel_p is not None:
            terms["f_p"] = rel_p / (o.projector_target / 100.0) if math.isfinite(rel_p) else big
            if o.paper_rule:
                terms["projector rule"] = ratio(a.projector_rule_deg, abs(ang_p[1]))
        return terms

    def _score(self, R_c, t_c, prior, stop_above: float | None = None) -> float:
        """The score (max of :meth:`_terms`) of the board at pose (R_c, t_c).

        The cheap terms (the rules, the projector's bound) come first: when they already exceed
        ``stop_above``, their maximum is returned without the camera's bound (the score is at least that).
        """
        ang_c = models.board_angles_deg(R_c, t_c)
        ang_p = rel_p = None
        if self.projector is not None:
            R_p, t_p = self._projector_pose(R_c, t_c)
            rel_p = self._projector_bound(R_p, t_p)[0] / float(self.projector.K[0, 0])
            ang_p = models.board_angles_deg(R_p, t_p)
        terms = self._terms(ang_c, 0.0, ang_p, rel_p)
        cheap = max(terms.values()) if terms else 0.0
        if not self.known_intrinsics or (stop_above is not None and cheap > stop_above):
            return cheap
        std_c, _, _ = self._camera_bound(R_c, t_c, prior)
        rel_c = std_c / float(self._camera.K[0, 0])
        return max(cheap, rel_c / (self.options.target_pct / 100.0) if math.isfinite(rel_c) else float("inf"))

    def _within_limits(self, R_c, t_c) -> bool:
        a = models.board_angles_deg(R_c, t_c)
        return abs(a[0]) <= self.options.max_angle_deg and abs(a[1]) <= self.options.max_angle_deg

    def search_move(self, R_c, t_c, prior=True, rounds: int = 2):
        """The move (turn_deg, tilt_deg) towards a good pose from (R_c, t_c), and the score it reaches.

        Per round: probe a turn and a tilt of ``probe_deg`` each way; the candidate directions are the four
        pure turns/tilts and their combination weighted by how much each probe lowers the log score.  Along
        each direction, poses every ``2 probe_deg`` up to ``max_move_deg`` are scored (walking on across the
        degenerate lines ``psi = 0``, ``nu = 0`` where the score peaks) until one scores ``<= aim``; the
        shortest such move wins (then tried ``probe_deg`` shorter), else the best pose seen, from where a
        second round starts.  Camera angles beyond ``max_angle_deg`` are never proposed.  The camera's bound
        is taken with the solver's principal-point prior throughout (``prior=True``: one bound per pose, smooth
        across the poses where the corners stop pinning the principal point; at most a few % below the
        data-only bound where they do); the pose reached is judged exactly when it is seen.

        Returns ``(turn, tilt, score_after, reached)`` (``reached``: score <= 1); ``(0, 0, score, ...)`` when
        nothing probed lowers the score.
        """
        o = self.options

        def score_of(R, stop_above=None):
            return self._score(R, t_c, prior, stop_above) if self._within_limits(R, t_c) else float("inf")

        def log(v):
            return math.log(v) if 0 < v < float("inf") else (700.0 if v == float("inf") else -700.0)

        d = o.probe_deg
        R_now = R_c
        s_now = self._score(R_c, t_c, prior)
        for _ in range(rounds):
            if s_now <= o.aim:
                break
            gains = []
            for axis in (0, 1):
                g = 0.0
                for sgn in (1.0, -1.0):
                    move = (sgn * d, 0.0) if axis == 0 else (0.0, sgn * d)
                    gain = log(s_now) - log(score_of(_axis_rotation(*move) @ R_now, s_now))
                    if gain > abs(g) + 1e-9:
                        g = sgn * gain
                gains.append(g)
            dirs = [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)]
            if gains[0] and gains[1]:
                g = np.array(gains)
                dirs.insert(0, tuple(g / np.linalg.norm(g)))
            best = (s_now, None)
            found = None
            steps = list(np.arange(2 * d, o.max_move_deg + 1e-9, 2 * d)) or [o.max_move_deg]
            for step in steps:              # breadth first: the shortest move that reaches the aim wins
                for u in dirs:
                    R = _axis_rotation(step * u[0], step * u[1]) @ R_now
                    v = score_of(R, max(best[0], o.aim))
                    if v < best[0]:
                        best = (v, R)
                    if v <= o.aim and (found is None or v < found[1]):
                        found = (step, v, u, R)
                if found is not None:
                    break
            if found is not None:
                step, v, u, R = found
                R_short = _axis_rotation((step - d) * u[0], (step - d) * u[1]) @ R_now
                v_short = score_of(R_short, o.aim) if step - d > 0 else float("inf")
                R_now, s_now = (R_short, v_short) if v_short <= o.aim else (R, v)
                break
            if best[1] is None:
                break
            s_now, R_now = best
        turn, tilt = move_between(R_c, R_now)
        return turn, tilt, s_now, s_now <= 1.0

    # -- the frame ----------------------------------------------------------------------------
    def reset_motion(self) -> None:
        """Forget the stillness history (e.g. after a capture)."""
        self._history.clear()

    def update(self, image: np.ndarray, t: float | None = None) -> Advice:
        """Advice for one camera frame ``image`` (H, W) taken at time ``t`` (s; default now)."""
        t_start = time.perf_counter()
        o = self.options
        t = time.monotonic() if t is None else float(t)
        img = np.asarray(image)
        if img.ndim != 2 or (img.shape[1], img.shape[0]) != self.image_size:
            raise ProcamError(f"advisor: frame of shape {img.shape}, expected a grey "
                              f"{self.image_size[0]}x{self.image_size[1]} image")
        k = self._frame
        self._frame += 1
        corners = detect_corners(img, self.board.pattern_size, o.corner_options)
        t_det = time.perf_counter()
        phase = "target" if self.projector is not None else "first"
        common = dict(frame=k, time_s=t, phase=phase, target_pct=o.target_pct,
                      projector_target_pct=o.projector_target, intrinsics=self.intrinsics,
                      image_size=self.image_size)
        notes = self._notes()
        if corners is None:
            self._history.clear()
            self._plan = None
            msg = (f"board not found: show the whole {self.board.cols}x{self.board.rows}-corner board to the "
                   "camera, in focus and lit")
            return Advice(state="no-board", message=msg, actions=(Action("find", msg),), notes=notes,
                          timings_ms={"detect": 1000 * (t_det - t_start), "total": 1000 * (t_det - t_start)},
                          **common)

        # stillness: the largest corner motion over the last still_s seconds
        self._history.append((t, corners))
        while len(self._history) >= 2 and t - self._history[1][0] >= o.still_s - 1e-9:
            self._history.popleft()  # keep the newest frame at least still_s old: the window is covered
        motion = max(float(np.max(np.linalg.norm(c - corners, axis=1))) for _, c in self._history)
        span = t - self._history[0][0]
        still = motion <= o.still_px and span >= o.still_s - 1e-9

        # pose in the camera
        dev = self._camera
        und = dev.undistort(corners)
        pose = _pose_pnp(self.obj, und, dev.K)
        if pose is None:
            msg = "board found but its pose cannot be computed: show it whole and flatter to the camera"
            return Advice(state="adjust", message=msg, actions=(Action("find", msg),), notes=notes, corners=corners,
                          still=still, motion_px=motion,
                          timings_ms={"detect": 1000 * (t_det - t_start),
                                      "total": 1000 * (time.perf_counter() - t_start)}, **common)
        R_c, t_c = pose
        W, H = self.image_size
        outline = dev.project(R_c, t_c, self.outer)
        quad = corners[[0, self.board.cols - 1, self.board.n_corners - 1, self.board.n_corners - self.board.cols]]
        fraction = _polygon_area(quad) / (W * H)
        edges = {"left": float(np.min(outline[:, 0]) + 0.5), "right": float(W - 0.5 - np.max(outline[:, 0])),
                 "top": float(np.min(outline[:, 1]) + 0.5), "bottom": float(H - 0.5 - np.max(outline[:, 1]))}
        edge_px = min(edges.values())

        # bounds at this pose
        std_c, _, prior = self._camera_bound(R_c, t_c)
        f_c = float(dev.K[0, 0])
        ang_c = tuple(float(a) for a in models.board_angles_deg(R_c, t_c))
        dist_note = _distortion_for_bound(dev)[3]
        assumes_c = (f"corner noise {o.sigma_camera:g} px; f, alpha, k1, k2 and the pose fitted; "
                     + ("principal point assumed at the image centre ± "
                        f"{o.pp_prior_fraction * max(W, H):.0f} px (the corners do not pin it)" if prior
                        else "principal point = centre of distortion, from the corners")
                     + (f"; {dist_note}" if dist_note else ""))
        cam_state = DeviceState(ang_c, f_c, std_c, std_c / f_c, float(np.linalg.norm(t_c)), None, assumes_c)
        proj_state, outside, ang_p = None, None, None
        if self.projector is not None:
            p = self.projector
            R_p, t_p = self._projector_pose(R_c, t_c)
            std_p, std_v = self._projector_bound(R_p, t_p)
            f_p = float(p.K[0, 0])
            ang_p = tuple(float(a) for a in models.board_angles_deg(R_p, t_p))
            proj_state = DeviceState(ang_p, f_p, std_p, std_p / f_p, float(np.linalg.norm(t_p)), std_v,
                                     f"corner noise {o.sigma_projector:g} px; f_p, v0p and the pose fitted, "
                                     f"u0p and alpha_p held (R, T from {p.source or 'an earlier capture'})")
            footprint = models.project(p.K, R_p, t_p, self.outer)
            Wp, Hp = p.size
            outside = tuple(side for side, bad in (
                ("left", np.min(footprint[:, 0]) < -0.5), ("right", np.max(footprint[:, 0]) > Wp - 0.5),
                ("top", np.min(footprint[:, 1]) < -0.5), ("bottom", np.max(footprint[:, 1]) > Hp - 0.5)) if bad)
        terms = self._terms(ang_c, cam_state.rel_std_f, ang_p, None if proj_state is None else proj_state.rel_std_f)
        score = max(terms.values()) if terms else 0.0
        limiting = self._limiting(terms, cam_state, proj_state) if score > 1.0 else ""
        t_bounds = time.perf_counter()

        # what to do
        actions: list[Action] = []
        margin = o.edge_margin * math.hypot(W, H)
        if fraction < o.min_board_fraction:
            actions.append(Action("closer", f"move the board closer: it covers {100 * fraction:.0f} % of the image "
                                            f"(aim for >= {100 * o.min_board_fraction:.0f} %)"))
        near = [s for s in ("left", "right", "top", "bottom") if edges[s] < margin]
        opposite = {"left": "right", "right": "left", "top": "down", "bottom": "up"}
        for side in near:
            actions.append(Action("move", f"move the board {opposite[side]}: it is {max(0.0, edges[side]):.0f} px "
                                          f"from the image's {side} edge", direction=opposite[side]))
        if outside:
            for side in outside:
                actions.append(Action("move", f"move the board {opposite[side]}: it is partly outside the "
                                              f"projector's light ({side} side)", direction=opposite[side]))
        checks_ok = not actions

        search_ms = 0.0
        good_pose = score <= 1.0
        if not good_pose:
            t0 = time.perf_counter()
            acts, more = self._move_actions(R_c, t_c, t, phase)
            actions.extend(acts)
            notes = notes + tuple(more)
            search_ms = 1000 * (time.perf_counter() - t0)
        else:
            self._plan = None

        if not good_pose or not checks_ok:
            state = "adjust"
            message = actions[0].text if actions else "adjust the board"
        else:
            state = "ready" if still else "good"
            if phase == "first":
                text = ("good for a first capture — hold still" + (" (steady)" if still else "")
                        + ": it measures the projector side (R, T)")
                actions.append(Action("capture", text))
            else:
                text = "good — hold still" + (" (steady)" if still else "")
                actions.append(Action("hold", text))
            message = text
        t_end = time.perf_counter()
        timings = {"detect": 1000 * (t_det - t_start), "bounds": 1000 * (t_bounds - t_det), "search": search_ms,
                   "total": 1000 * (t_end - t_start)}
        return Advice(state=state, message=message, actions=tuple(actions), notes=notes, corners=corners,
                      outline=outline, camera=cam_state, projector=proj_state, score=score, limiting=limiting,
                      board_fraction=fraction, edge_px=edge_px, outside_light=outside, still=still,
                      motion_px=motion, timings_ms=timings, **common)

    def _notes(self) -> tuple:
        notes = [self.intrinsics]
        if self.projector is None:
            notes.append("projector side unknown: capture one pose (even a weak one); its R, T then give the "
                         "board's angles in the projector and the predicted std of f_p")
            if not self.known_intrinsics:
                notes.append("until then the camera's std assumes no distortion (indicative only) and a pose is "
                             "judged by the paper's camera rule")
        else:
            notes.append(f"projector side from {self.projector.source or 'an earlier capture'}")
        return tuple(notes)

    def _limiting(self, terms, cam, proj) -> str:
        """What keeps the pose from being good: the largest term in words."""
        o, a = self.options, self.options.advice
        name = max(terms, key=terms.get)
        if name == "f_c":
            return f"f_c ± {100 * cam.rel_std_f:.2g} % (target {o.target_pct:g} %)"
        if name == "f_p":
            return f"f_p ± {100 * proj.rel_std_f:.2g} % (target {o.projector_target:g} %)"
        if name == "camera rule":
            psi, nu = abs(cam.angles_deg[0]), abs(cam.angles_deg[1])
            return (f"camera: |psi_c| = {psi:.0f}, |nu_c| = {nu:.0f} deg (the rule: sum > {a.camera_rule_deg:g}, "
                    f"each >= {a.weak_angle_deg:g})")
        return f"projector: |nu_p| = {abs(proj.angles_deg[1]):.0f} deg (the rule: > {a.projector_rule_deg:g})"

    @staticmethod
    def _action(name: str, degrees: float) -> Action:
        deg = float(degrees)
        amount = max(1, int(round(abs(deg))))
        sgn = 1 if deg >= 0 else -1
        if name == "turn":
            return Action("turn", f"turn the board ~{amount} deg about the vertical axis, {_TURN_WORDS[sgn]}",
                          degrees=deg)
        return Action("tilt", f"tilt the board ~{amount} deg about the horizontal axis, {_TILT_WORDS[sgn]}",
                      degrees=deg)

    def _stale(self, plan, R_c, t_c, t, phase) -> bool:
        """Does the move search have to run again?  Not while the user follows the proposed move (the remaining
        move to its pose is updated every frame): only without a plan, in another phase, after
        ``search_refresh_s``, or -- at most every ``search_interval_s`` -- when the board went the other way
        (the remaining move grew by 5 deg) or was moved by more than 15 % of its distance."""
        o = self.options
        if plan is None or plan["phase"] != phase or not 0 <= t - plan["t"] < o.search_refresh_s:
            return True
        if t - plan["t"] < o.search_interval_s:
            return False
        remaining = math.hypot(*move_between(R_c, plan["R"]))
        moved = np.linalg.norm(np.asarray(t_c) - plan["t_c"]) > 0.15 * np.linalg.norm(plan["t_c"])
        return remaining > plan["size"] + 5.0 or moved

    def _move_actions(self, R_c, t_c, t, phase):
        """Turn/tilt actions from the move search (:meth:`_stale` says when it runs), and notes."""
        o = self.options
        plan = self._plan
        for attempt in (0, 1):
            if attempt == 1 or self._stale(plan, R_c, t_c, t, phase):
                turn, tilt, after, reached = self.search_move(R_c, t_c)
                if turn == 0.0 and tilt == 0.0:
                    self._plan = None
                    return [Action("closer", f"no turn or tilt within {o.max_move_deg:g} deg improves this pose: move "
                                             "the board closer, or place it anew")], []
                plan = self._plan = {"t": t, "R": _axis_rotation(turn, tilt) @ R_c, "t_c": np.array(t_c, float),
                                     "size": math.hypot(turn, tilt), "after": after, "phase": phase,
                                     "reached": reached}
                attempt = 1
            turn, tilt = move_between(R_c, plan["R"])
            acts = [self._action(name, deg) for name, deg in sorted((("turn", turn), ("tilt", tilt)),
                                                                   key=lambda v: -abs(v[1])) if abs(deg) >= 1.5]
            if acts or attempt == 1:
                break
            # at the proposed pose already, yet not good: search again from here
        if not acts:
            name, deg = ("turn", turn) if abs(turn) >= abs(tilt) else ("tilt", tilt)
            acts = [self._action(name, math.copysign(max(abs(deg), 1.0), deg if deg else 1.0))]
        notes = []
        if not plan["reached"]:
            notes.append(f"turning and tilting alone do not make this pose good (the best within {o.max_move_deg:g} "
                         f"deg scores {plan['after']:.2g}, good is <= 1): after the move, bring the board closer")
        return acts, notes
