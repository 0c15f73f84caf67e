"""The advisor: per camera frame, the board, its pose, the predicted uncertainty there and what to do
(:meth:`Advisor.update`, one named step per method).  See :mod:`procam.advisor` for the method.
"""

from __future__ import annotations

import math
import time
from collections import deque

import numpy as np

from .. import crlb, models
from ..board import Board
from ..calibration import Calibration, Device, Distortion
from ..board.corners import detect_corners
from ..errors import ProcamError
from .moves import ProjectorSide, axis_rotation, move_between, polygon_area, pose_pnp, projector_pose
from .options import Action, Advice, AdvisorOptions, DeviceState

_TURN_WORDS = {1: "right edge away", -1: "left edge away"}
_TILT_WORDS = {1: "top edge away", -1: "bottom edge away"}


def guessed_camera(image_size) -> Device:
    """The camera when nothing is known: ``f`` = the image diagonal (px; a ~53 deg diagonal field of
    view), the principal point at the image centre, square pixels, no distortion."""
    w, h = int(image_size[0]), int(image_size[1])
    f = float(math.hypot(w, h))
    return Device(models.intrinsic_matrix(f, (w - 1) / 2.0, (h - 1) / 2.0), (w, h), Distortion())


def distortion_for_bound(dev: Device):
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
    def set_camera(self, camera: Device | None, source: str = "", known: bool = False) -> None:
        """Use ``camera``'s intrinsics (None: the guess).  ``known``: the camera calibrated beforehand and held in
        the calibration to come (``procam calibrate POSE --camera FILE``): its terms leave the score, and the
        projector's ± is predicted for the fit with the camera known (:meth:`_projector_bound`)."""
        if camera is not None and tuple(int(v) for v in camera.image_size) != self.image_size:
            raise ProcamError(f"advisor: the camera intrinsics{' from ' + source if source else ''} are for "
                              f"{camera.image_size[0]}x{camera.image_size[1]} frames but the camera delivers "
                              f"{self.image_size[0]}x{self.image_size[1]}; use a calibration of this camera "
                              "at this resolution")
        if camera is None:
            if known:
                raise ProcamError("advisor: a known camera needs its intrinsics")
            self._camera = guessed_camera(self.image_size)
            self.intrinsics = (f"guessed f = image diagonal ({self._camera.K[0, 0]:.0f} px), principal point at "
                               "the image centre, no distortion")
            self.known_intrinsics = False
        else:
            self._camera = camera
            self.intrinsics = (("camera known (held in the calibration): " if known else "intrinsics ")
                               + (f"from {source}" if source else "given"))
            self.known_intrinsics = True
        self.camera_known = bool(known)
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
    def _camera_bound(self, R_cb, t_cb, prior: bool | None = None):
        """(std_f, std dict, used_prior) of the camera's single-pose bound at pose (R_cb, t_cb)."""
        o = self.options
        dev = self._camera
        c, k1, k2, _ = distortion_for_bound(dev)
        K = np.asarray(dev.K, float)
        sig_pp = o.pp_prior_fraction * max(self.image_size)
        # prior None: the solver's rule (the prior only where the corners do not pin the principal point)
        b = crlb.camera_bound(K, c, k1, k2, R_cb, t_cb, self.obj, o.sigma_camera, jacobian="central",
                              pp_prior_std=None if prior is False else sig_pp,
                              pp_prior_when="needed" if prior is None else "always")
        return b.std["f_c"], b.std, b.prior_used

    def _projector_bound(self, R_pb, t_pb, t_cb=None):
        """``(std f_p, std v0p)`` (px) predicted at the board's pose in the projector: from its corners (noise
        ``sigma_projector``), or with the camera known from the board samples the fit then uses
        (:meth:`_board_samples`, noise ``sigma_samples``: the decoded window means, every ``WINDOW`` camera px).
        ``f_p, v0p`` and the pose free, ``u0p, alpha_p`` held, no lens terms (:func:`procam.crlb.projector_bound`)."""
        if self.camera_known and t_cb is not None:
            b = crlb.projector_bound(self.projector.K, R_pb, t_pb, self._board_samples(t_cb),
                                     self.options.sigma_samples)
        else:
            b = crlb.projector_bound(self.projector.K, R_pb, t_pb, self.obj, self.options.sigma_projector)
        return b.std["f_p"], b.std["v0p"]

    def _board_samples(self, t_cb) -> np.ndarray:
        """(M, 3) board points where the decoded board samples fall: a grid over the corners' rectangle with the
        window's spacing (:data:`procam.correspond.samples.WINDOW` camera px at the board's distance)."""
        from ..correspond.samples import WINDOW

        b = self.board
        step = WINDOW * float(np.linalg.norm(t_cb)) / float(self._camera.K[0, 0])
        hx, hy = 0.5 * (b.cols - 1) * b.square, 0.5 * (b.rows - 1) * b.square
        xs = np.arange(-hx, hx + 1e-9, max(step, 1e-9 * b.square))
        ys = np.arange(-hy, hy + 1e-9, max(step, 1e-9 * b.square))
        X, Y = np.meshgrid(xs, ys)
        return np.c_[X.ravel(), Y.ravel(), np.zeros(X.size)]

    def _terms(self, ang_c, rel_c, ang_p, rel_p) -> dict:
        """The score's terms (each <= 1 when satisfied): ``f_c``/``f_p`` = predicted relative std / target,
        ``camera rule``/``projector rule`` = the paper's rule as a ratio (:mod:`procam.single_pose.rating`'s
        thresholds).  ``f_c`` only with known intrinsics, the projector's only with the projector side."""
        o, a = self.options, self.options.rating
        big = float("inf")

        def ratio(num, den):
            return num / den if den > 1e-12 else big

        terms = {}
        if self.known_intrinsics and not self.camera_known:
            terms["f_c"] = rel_c / (o.target_pct / 100.0) if math.isfinite(rel_c) else big
        if (o.paper_rule or not self.known_intrinsics) and not self.camera_known:
            psi, nu = abs(ang_c[0]), abs(ang_c[1])
            terms["camera rule"] = max(ratio(a.camera_rule_deg, psi + nu), ratio(a.weak_angle_deg, min(psi, nu)))
        if rel_p is not None:
            terms["f_p"] = rel_p / (o.projector_target / 100.0) if math.isfinite(rel_p) else big
            if o.paper_rule:
                terms["projector rule"] = ratio(a.projector_rule_deg, abs(ang_p[1]))
        return terms

    def _score(self, R_cb, t_cb, prior, stop_above: float | None = None) -> float:
        """The score (max of :meth:`_terms`) of the board at pose (R_cb, t_cb).

        The cheap terms (the rules, the projector's bound) come first: when they already exceed
        ``stop_above``, their maximum is returned without the camera's bound (the score is at least that).
        """
        ang_c = models.board_angles_deg(R_cb, t_cb)
        ang_p = rel_p = None
        if self.projector is not None:
            R_pb, t_pb = projector_pose(self.projector, R_cb, t_cb)
            rel_p = self._projector_bound(R_pb, t_pb, t_cb)[0] / float(self.projector.K[0, 0])
            ang_p = models.board_angles_deg(R_pb, t_pb)
        terms = self._terms(ang_c, 0.0, ang_p, rel_p)
        cheap = max(terms.values()) if terms else 0.0
        if not self.known_intrinsics or self.camera_known or (stop_above is not None and cheap > stop_above):
            return cheap
        std_c, _, _ = self._camera_bound(R_cb, t_cb, prior)
        rel_c = std_c / float(self._camera.K[0, 0])
        return max(cheap, rel_c / (self.options.target_pct / 100.0) if math.isfinite(rel_c) else float("inf"))

    def _within_limits(self, R_cb, t_cb) -> bool:
        a = models.board_angles_deg(R_cb, t_cb)
        return abs(a[0]) <= self.options.max_angle_deg and abs(a[1]) <= self.options.max_angle_deg

    def search_move(self, R_cb, t_cb, prior=True, rounds: int = 2):
        """The move (turn_deg, tilt_deg) towards a good pose from (R_cb, t_cb), and the score it reaches.

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
            return self._score(R, t_cb, prior, stop_above) if self._within_limits(R, t_cb) else float("inf")

        def log(v):
            return math.log(v) if 0 < v < float("inf") else (700.0 if v == float("inf") else -700.0)

        d = o.probe_deg
        R_now = R_cb
        s_now = self._score(R_cb, t_cb, prior)
        for _ in range(rounds):
            if s_now <= o.aim:
                break
            gains = []
            for axis in (0, 1):
                g = 0.0
                for sgn in (1.0, -1.0):
                    move = (sgn * d, 0.0) if axis == 0 else (0.0, sgn * d)
                    gain = log(s_now) - log(score_of(axis_rotation(*move) @ R_now, s_now))
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
                    R = axis_rotation(step * u[0], step * u[1]) @ R_now
                    v = score_of(R, max(best[0], o.aim))
                    if v < best[0]:
                        best = (v, R)
                    if v <= o.aim and (found is None or v < found[1]):
                        found = (step, v, u, R)
                if found is not None:
                    break
            if found is not None:
                step, v, u, R = found
                R_short = axis_rotation((step - d) * u[0], (step - d) * u[1]) @ R_now
                v_short = score_of(R_short, o.aim) if step - d > 0 else float("inf")
                R_now, s_now = (R_short, v_short) if v_short <= o.aim else (R, v)
                break
            if best[1] is None:
                break
            s_now, R_now = best
        turn, tilt = move_between(R_cb, R_now)
        return turn, tilt, s_now, s_now <= 1.0

    # -- the frame ----------------------------------------------------------------------------
    def reset_motion(self) -> None:
        """Forget the stillness history (e.g. after a capture)."""
        self._history.clear()

    def update(self, image: np.ndarray, t: float | None = None) -> Advice:
        """Advice for one camera frame ``image`` (H, W) taken at time ``t`` (s; default now).

        The steps: find the board (:meth:`_find_board`); its stillness (:meth:`_stillness`); its pose in the
        camera (:meth:`_camera_pose`) and in the image (:meth:`_placement`); the devices' bounds at that pose
        (:meth:`_camera_state`, :meth:`_projector_state`); the score (:meth:`_terms`); the actions
        (:meth:`_placement_actions`, :meth:`_move_actions`); the state (:meth:`_verdict`).  ``timings_ms``:
        ``detect`` the first step, ``bounds`` up to the score, ``search`` the move search.
        """
        t_start = time.perf_counter()
        t = time.monotonic() if t is None else float(t)
        img = self._checked_frame(image)
        k = self._frame
        self._frame += 1
        corners = self._find_board(img)
        t_det = time.perf_counter()
        phase = "target" if self.projector is not None else "first"
        common = self._common(k, t, phase)
        notes = self._notes()
        if corners is None:
            return self._no_board(notes, 1000 * (t_det - t_start), common)
        still, motion = self._stillness(t, corners)
        pose = self._camera_pose(corners)
        if pose is None:
            msg = "board found but its pose cannot be computed: show it whole and flatter to the camera"
            return Advice(state="adjust", message=msg, actions=(Action("find", msg),), notes=notes, corners=corners,
                          still=still, motion_px=motion,
                          timings_ms={"detect": 1000 * (t_det - t_start),
                                      "total": 1000 * (time.perf_counter() - t_start)}, **common)
        R_cb, t_cb = pose
        outline, fraction, edges = self._placement(corners, R_cb, t_cb)
        cam_state = self._camera_state(R_cb, t_cb)
        proj_state, outside = self._projector_state(R_cb, t_cb)
        terms = self._terms(cam_state.angles_deg, cam_state.rel_std_f,
                            None if proj_state is None else proj_state.angles_deg,
                            None if proj_state is None else proj_state.rel_std_f)
        score = max(terms.values()) if terms else 0.0
        limiting = self._limiting(terms, cam_state, proj_state) if score > 1.0 else ""
        t_bounds = time.perf_counter()

        actions = self._placement_actions(fraction, edges, outside)
        checks_ok = not actions
        search_ms = 0.0
        good_pose = score <= 1.0
        if not good_pose:
            t0 = time.perf_counter()
            acts, more = self._move_actions(R_cb, t_cb, t, phase)
            actions.extend(acts)
            notes = notes + tuple(more)
            search_ms = 1000 * (time.perf_counter() - t0)
        else:
            self._plan = None
        state, message = self._verdict(good_pose and checks_ok, still, phase, actions)
        t_end = time.perf_counter()
        timings = {"detect": 1000 * (t_det - t_start), "bounds": 1000 * (t_bounds - t_det), "search": search_ms,
                   "total": 1000 * (t_end - t_start)}
        return Advice(state=state, message=message, actions=tuple(actions), notes=notes, corners=corners,
                      outline=outline, camera=cam_state, projector=proj_state, score=score, limiting=limiting,
                      board_fraction=fraction, edge_px=min(edges.values()), outside_light=outside, still=still,
                      motion_px=motion, timings_ms=timings, **common)

    # -- the steps of a frame -------------------------------------------------------------------
    def _checked_frame(self, image) -> np.ndarray:
        """The frame as an array; a grey frame of the advisor's size, else :class:`ProcamError`."""
        img = np.asarray(image)
        if img.ndim != 2 or (img.shape[1], img.shape[0]) != self.image_size:
            raise ProcamError(f"advisor: frame of shape {img.shape}, expected a grey "
                              f"{self.image_size[0]}x{self.image_size[1]} image")
        return img

    def _find_board(self, img: np.ndarray) -> np.ndarray | None:
        """The board's (N, 2) full-resolution corners in canonical order, or None: the one detector
        (:func:`procam.board.corners.detect_corners`) with the live setting (:attr:`AdvisorOptions.detect_options`)."""
        return detect_corners(img, self.board.pattern_size, self.options.detect_options)

    def _common(self, frame: int, t: float, phase: str) -> dict:
        """The fields of :class:`Advice` every frame has, whatever was found."""
        o = self.options
        return dict(frame=frame, time_s=t, phase=phase, target_pct=o.target_pct,
                    projector_target_pct=o.projector_target, intrinsics=self.intrinsics, image_size=self.image_size)

    def _no_board(self, notes: tuple, detect_ms: float, common: dict) -> Advice:
        """The advice without a board: show it (the stillness history and the move plan are forgotten)."""
        self._history.clear()
        self._plan = None
        msg = (f"board not found: show the whole {self.board.cols}x{self.board.rows}-corner board to the "
               "camera, in focus and lit")
        return Advice(state="no-board", message=msg, actions=(Action("find", msg),), notes=notes,
                      timings_ms={"detect": detect_ms, "total": detect_ms}, **common)

    def _stillness(self, t: float, corners: np.ndarray) -> tuple[bool, float]:
        """``(still, motion_px)``: the largest corner motion over the last ``still_s`` seconds (this frame
        added to the history) and whether it is at most ``still_px`` over a history that spans ``still_s``."""
        o = self.options
        self._history.append((t, corners))
        while len(self._history) >= 2 and t - self._history[1][0] >= o.still_s - 1e-9:
            self._history.popleft()  # keep the newest frame at least still_s old: the window is covered
        motion = max(float(np.max(np.linalg.norm(c - corners, axis=1))) for _, c in self._history)
        span = t - self._history[0][0]
        return motion <= o.still_px and span >= o.still_s - 1e-9, motion

    def _camera_pose(self, corners: np.ndarray):
        """``(R_cb, t_cb)`` board -> camera by PnP on the undistorted corners with the camera's intrinsics,
        or None."""
        dev = self._camera
        return pose_pnp(self.obj, dev.undistort(corners), dev.K)

    def _placement(self, corners: np.ndarray, R_cb, t_cb):
        """Where the board is in the image: ``(outline, fraction, edges)`` -- the printed squares' outer
        corners (4, 2) projected, the area of the inner corners' quadrilateral / the image area, and the
        outline's distance (px) to each image border (``{"left": .., "right": .., "top": .., "bottom": ..}``)."""
        W, H = self.image_size
        b = self.board
        outline = self._camera.project(R_cb, t_cb, self.outer)
        quad = corners[[0, b.cols - 1, b.n_corners - 1, b.n_corners - b.cols]]
        fraction = polygon_area(quad) / (W * H)
        edges = {"left": float(np.min(outline[:, 0]) + 0.5), "right": float(W - 0.5 - np.max(outline[:, 0])),
                 "top": float(np.min(outline[:, 1]) + 0.5), "bottom": float(H - 0.5 - np.max(outline[:, 1]))}
        return outline, fraction, edges

    def _camera_state(self, R_cb, t_cb) -> DeviceState:
        """The board's angles in the camera and the camera's bound there (the solver's principal-point rule),
        with what the bound assumes in words."""
        o = self.options
        W, H = self.image_size
        dev = self._camera
        f_c = float(dev.K[0, 0])
        ang_c = tuple(float(a) for a in models.board_angles_deg(R_cb, t_cb))
        if self.camera_known:
            return DeviceState(ang_c, f_c, 0.0, 0.0, float(np.linalg.norm(t_cb)), None,
                               f"{self.intrinsics}: not estimated from this pose")
        std_c, _, prior = self._camera_bound(R_cb, t_cb)
        dist_note = distortion_for_bound(dev)[3]
        assumes_c = (f"corner noise {o.sigma_camera:g} px; f, alpha, k1, k2 and the pose fitted; "
                     + ("principal point assumed at the image centre ± "
                        f"{o.pp_prior_fraction * max(W, H):.0f} px (the corners do not pin it)" if prior
                        else "principal point = centre of distortion, from the corners")
                     + (f"; {dist_note}" if dist_note else ""))
        return DeviceState(ang_c, f_c, std_c, std_c / f_c, float(np.linalg.norm(t_cb)), None, assumes_c)

    def _projector_state(self, R_cb, t_cb):
        """``(state, outside)``: the board's angles in the projector and the projector's bound there
        (:class:`DeviceState`), and the projector-image sides the printed board crosses (``()`` when it is all
        in the light); ``(None, None)`` while the projector side is unknown."""
        if self.projector is None:
            return None, None
        o = self.options
        p = self.projector
        R_pb, t_pb = projector_pose(p, R_cb, t_cb)
        std_p, std_v = self._projector_bound(R_pb, t_pb, t_cb)
        f_p = float(p.K[0, 0])
        ang_p = tuple(float(a) for a in models.board_angles_deg(R_pb, t_pb))
        noise = (f"the camera known: board samples every 11 camera px, noise {o.sigma_samples:g} px"
                 if self.camera_known else f"corner noise {o.sigma_projector:g} px")
        state = DeviceState(ang_p, f_p, std_p, std_p / f_p, float(np.linalg.norm(t_pb)), std_v,
                            f"{noise}; f_p, v0p and the pose fitted, "
                            f"u0p and alpha_p held (R, T from {p.source or 'an earlier capture'})")
        footprint = models.project(p.K, R_pb, t_pb, self.outer)
        Wp, Hp = p.size
        outside = tuple(side for side, bad in (
            ("left", np.min(footprint[:, 0]) < -0.5), ("right", np.max(footprint[:, 0]) > Wp - 0.5),
            ("top", np.min(footprint[:, 1]) < -0.5), ("bottom", np.max(footprint[:, 1]) > Hp - 0.5)) if bad)
        return state, outside

    def _placement_actions(self, fraction: float, edges: dict, outside) -> list[Action]:
        """Actions that come before any turn: closer (the board covers less than ``min_board_fraction``),
        away from an image border nearer than ``edge_margin``, into the projector's light."""
        o = self.options
        W, H = self.image_size
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
        return actions

    @staticmethod
    def _verdict(good: bool, still: bool, phase: str, actions: list) -> tuple[str, str]:
        """``(state, message)`` of the frame; a good pose (and placement) gets its last action here: "capture"
        (first phase: it measures the projector side) or "hold" (appended to ``actions``)."""
        if not good:
            return "adjust", actions[0].text if actions else "adjust the board"
        state = "ready" if still else "good"
        if phase == "first":
            text = ("good for a first capture — hold still" + (" (steady)" if still else "")
                    + ": it measures the projector side (R, T)")
            actions.append(Action("capture", text))
        else:
            text = "good — hold still" + (" (steady)" if still else "")
            actions.append(Action("hold", text))
        return state, text

    # -- words and the move plan -------------------------------------------------------------
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
        o, a = self.options, self.options.rating
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

    def _stale(self, plan, R_cb, t_cb, t, phase) -> bool:
        """Does the move search have to run again?  Not while the user follows the proposed move (the remaining
        move to its pose is updated every frame): only without a plan, in another phase, after
        ``search_refresh_s``, or -- at most every ``search_interval_s`` -- when the board went the other way
        (the remaining move grew by 5 deg) or was moved by more than 15 % of its distance."""
        o = self.options
        if plan is None or plan["phase"] != phase or not 0 <= t - plan["t"] < o.search_refresh_s:
            return True
        if t - plan["t"] < o.search_interval_s:
            return False
        remaining = math.hypot(*move_between(R_cb, plan["R"]))
        moved = np.linalg.norm(np.asarray(t_cb) - plan["t_c"]) > 0.15 * np.linalg.norm(plan["t_c"])
        return remaining > plan["size"] + 5.0 or moved

    def _move_actions(self, R_cb, t_cb, t, phase):
        """Turn/tilt actions from the move search (:meth:`_stale` says when it runs), and notes."""
        o = self.options
        plan = self._plan
        for attempt in (0, 1):
            if attempt == 1 or self._stale(plan, R_cb, t_cb, t, phase):
                turn, tilt, after, reached = self.search_move(R_cb, t_cb)
                if turn == 0.0 and tilt == 0.0:
                    self._plan = None
                    return [Action("closer", f"no turn or tilt within {o.max_move_deg:g} deg improves this pose: move "
                                             "the board closer, or place it anew")], []
                plan = self._plan = {"t": t, "R": axis_rotation(turn, tilt) @ R_cb, "t_c": np.array(t_cb, float),
                                     "size": math.hypot(turn, tilt), "after": after, "phase": phase,
                                     "reached": reached}
                attempt = 1
            turn, tilt = move_between(R_cb, plan["R"])
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
