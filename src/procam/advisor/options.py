"""The advisor's settings and what it says per frame: :class:`AdvisorOptions` (every threshold, checked at
construction), :class:`Advice` (one frame's verdict, with its JSON form), its :class:`Action` s and the
:class:`DeviceState` of each device.  Plain frozen dataclasses; nothing here computes a pose.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..board.corners import LIVE, DetectOptions
from ..errors import ProcamError
from ..single_pose.rating import RatingOptions

#: Advice states, from worst to best.
STATES = ("no-board", "adjust", "good", "ready")


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
    sigma_samples : with the camera known, the noise (projector px, per coordinate) of a decoded board sample (a
        window's mean; 0.035-0.06 px on the simulator's renders) the projector's bound assumes.
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
    paper_rule : a good pose must also pass the paper's rule as :func:`procam.single_pose.rate_pose` judges it
        (camera ``|psi_c| + |nu_c| > 10``, each ``>= 4`` deg; projector ``|nu_p| > 13`` deg; thresholds from
        ``advice``): the bounds cover the noise only, the rule keeps away from poses where a model error
        (``u0p = W/2``, a principal point off the centre of distortion) costs most.
    rating : :class:`procam.single_pose.RatingOptions` (the rule's thresholds).
    pp_prior_fraction : the solver's prior std of an assumed principal point, as a fraction of the
        larger image side (:class:`procam.single_pose.CameraOptions`).
    camera_f_pct, camera_pp_px : the camera mode's targets (:class:`procam.advisor.camera.CameraAdvisor`): enough
        photos when the fit's std of ``f_c`` is at most this % of ``f_c`` and that of the principal point at most
        this many px.
    min_new_deg : the camera mode takes a photo only this many degrees from every photo taken (half of it for a
        photo whose corners reach a region of the image not reached before).
    camera_min_coverage : the camera mode first asks for photos that cover more of the image until the boards
        cover this fraction (a margin over :func:`procam.multi_pose.calibrate_camera`'s 30 %, below which its
        fit is weak).
    min_photos : the camera mode says "enough" with at least this many photos (the covariance of fewer rests on
        a handful of residual degrees of freedom and on the lens model being right).
    """

    target_pct: float = 1.0
    projector_target_pct: float | None = None
    aim: float = 0.8
    sigma_camera: float = 0.1
    sigma_projector: float = 0.2
    sigma_samples: float = 0.05
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
    rating: RatingOptions = RatingOptions()
    pp_prior_fraction: float = 0.025
    camera_f_pct: float = 0.2
    camera_pp_px: float = 2.0
    min_new_deg: float = 10.0
    min_photos: int = 4
    camera_min_coverage: float = 0.35

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
        check("sigma_samples", 0, 100, open_lo=True)
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
        check("camera_f_pct", 0, 100, open_lo=True)
        check("camera_pp_px", 0, 1000, open_lo=True)
        check("min_new_deg", 0, 90)
        check("min_photos", 2, 100)
        check("camera_min_coverage", 0, 1)

    @property
    def projector_target(self) -> float:
        """The projector's target % of f."""
        return self.target_pct if self.projector_target_pct is None else self.projector_target_pct

    @property
    def detect_options(self) -> DetectOptions:
        """The detector's settings per frame: :data:`procam.board.corners.LIVE` with ``detect_width`` and
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
    frame : index of the frame (0, 1, ... per :class:`Advisor`); ``time_s`` its time, seconds since the advising
        session's first frame (:func:`procam.acquire.live.advise`).
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
