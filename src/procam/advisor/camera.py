"""The advisor's camera mode: photos of the board for a camera calibrated once (then each projector from one pose
with the camera known, ``procam calibrate POSE --camera cam.json``).

Per camera frame (:meth:`CameraAdvisor.update`):

1. the board, by the live detector (:attr:`AdvisorOptions.detect_options`), and its pose by PnP with the camera as
   known so far: the fit of the photos taken (two or more), else the guess (:func:`procam.advisor.guessed_camera`);
2. where the photos' corners have been seen so far: the image cut in 3 x 3 regions, each reached or not
   (:attr:`CameraAdvice.coverage`, the regions still empty by name);
3. the predicted ± of ``f_c``, ``fy_c``, the principal point and the distortion coefficients with the photos taken,
   and with this frame added: the covariance of the calibration :func:`procam.multi_pose.calibrate_camera` makes
   (:func:`procam.crlb.views_bound`: each photo's information with its board pose marginalised, summed), at the
   camera as fitted so far, with the fit's own residual noise (before two photos, ``sigma_camera`` and the guessed
   camera with ``k1, k2``);
4. which tilt to take next: among turns and tilts of the board about its centre (about the camera's axes, as
   :func:`procam.advisor.apply_move`; every ``±20``, ``±35`` deg and their combinations, the board staying in the
   image), the one whose photo lowers the predicted score most, as a move from the board's current pose;
5. the verdict: ``"take"`` when this frame is new (``min_new_deg`` from every photo taken; the next tilt is chosen
   new too) and gains at least half
   of what the best next tilt would (in the score's logarithm), ``"adjust"`` with the move otherwise, and
   ``"enough"`` when the photos taken determine the camera to the targets (``camera_f_pct`` % of ``f_c`` and
   ``camera_pp_px`` px of the principal point, by the fit's own covariance).

The score of a set of photos is ``max(std(f_c) / f_c / camera_f_pct %, max(std(u0c), std(v0c)) / camera_pp_px)``
(<= 1: enough); to rank photos before the camera is determined it is taken with a weak prior (``f`` within 50 %,
the principal point within a quarter of the image, each coefficient within 1), which the numbers reported never
include.  :meth:`CameraAdvisor.take` adds a photo (detected at full quality), :meth:`CameraAdvisor.set_fit` gives
the fit of the photos taken (the session above the advisor refits: :func:`procam.acquire.live.advise_camera`, which
also writes the camera file).  Nothing here prints or opens a window.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

import numpy as np

from .. import crlb, models
from ..board import Board
from ..calibration import Calibration, Device
from ..errors import ProcamError
from .advisor import guessed_camera
from .moves import axis_rotation, move_between, pose_pnp
from .options import Action, AdvisorOptions

#: The camera-mode states, from worst to best.
CAMERA_STATES = ("no-board", "adjust", "take", "enough")
#: The 3 x 3 regions of the image, row by row.
REGIONS = ("top-left", "top", "top-right", "left", "centre", "right", "bottom-left", "bottom", "bottom-right")
#: The turns and tilts (deg) the next photo is chosen among (each combination, the fronto-parallel one excepted).
CANDIDATE_DEG = (-35.0, -20.0, 0.0, 20.0, 35.0)


def _rvec(R) -> np.ndarray:
    """The Rodrigues vector of a rotation (OpenCV's: the per-candidate hot path)."""
    import cv2

    return cv2.Rodrigues(np.asarray(R, float))[0].ravel()


def _angle_deg(R1, R2) -> float:
    """The angle (deg) of the rotation between two board orientations."""
    return math.degrees(float(np.linalg.norm(_rvec(np.asarray(R1) @ np.asarray(R2).T))))


def _std_dict(b: crlb.ViewsBound, f: float) -> dict | None:
    """The predicted ± by name (``f_c_pct`` in % of ``f_c``, the rest in their units), None when undetermined."""
    if not b.determined:
        return None
    out = {"f_c_pct": 100.0 * b.std["f_c"] / f}
    out.update(b.std)
    return out


@dataclass(frozen=True)
class CameraAdvice:
    """The camera mode's verdict on one frame.

    ``state``: one of :data:`CAMERA_STATES`; ``message`` the headline; ``actions`` (:class:`Action` s: ``find``,
    ``turn``/``tilt`` -- the move to the next photo's pose --, ``move`` towards an empty region, ``take``,
    ``done``); ``photos`` taken so far; ``coverage`` the fraction of :data:`REGIONS` their corners reach and
    ``uncovered`` the others; ``now`` and ``with_this`` the predicted ± (``f_c_pct`` % and per parameter of
    :data:`procam.crlb.VIEW_PARAMS`, px or OpenCV's units) with the photos taken and with this frame added (None:
    undetermined); ``next_move`` ``(turn_deg, tilt_deg)`` from the board's pose to the best next photo's and
    ``next_shift`` (3,) the move of its centre (camera frame, board units; towards a region not yet reached);
    ``angles_deg`` the board's ``(psi, nu, phi)`` in the camera; ``corners`` (N, 2) or None; ``enough`` the
    photos taken determine the camera to the targets ``f_target_pct``, ``pp_target_px``.
    """

    frame: int
    state: str
    message: str
    actions: tuple = ()
    photos: int = 0
    coverage: float = 0.0
    uncovered: tuple = REGIONS
    now: dict | None = None
    with_this: dict | None = None
    next_move: tuple | None = None
    next_shift: tuple | None = None
    angles_deg: tuple | None = None
    corners: np.ndarray | None = None
    enough: bool = False
    f_target_pct: float = 0.2
    pp_target_px: float = 2.0

    def to_dict(self) -> dict:
        """JSON-ready dict (non-finite numbers become null; the corners left out)."""
        def num(v, nd=4):
            return None if v is None or not math.isfinite(v) else round(float(v), nd)

        def stds(d):
            return None if d is None else {k: num(v, 6) for k, v in d.items()}

        return {"frame": self.frame, "mode": "camera", "state": self.state, "message": self.message,
                "actions": [a.to_dict() for a in self.actions], "photos": self.photos,
                "coverage": num(self.coverage, 3), "uncovered": list(self.uncovered), "now": stds(self.now),
                "with_this": stds(self.with_this),
                "next_move": None if self.next_move is None else [num(v, 1) for v in self.next_move],
                "next_shift": None if self.next_shift is None else [num(v, 2) for v in self.next_shift],
                "angles_deg": None if self.angles_deg is None else [num(v, 2) for v in self.angles_deg],
                "enough": self.enough, "f_target_pct": self.f_target_pct, "pp_target_px": self.pp_target_px}

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), separators=(",", ":"), allow_nan=False)


class CameraAdvisor:
    """The camera mode of the live advisor (see the module docstring).

    Parameters
    ----------
    board : the printed :class:`~procam.board.Board`.
    image_size : (W, H) of the camera frames.
    options : :class:`AdvisorOptions` (``camera_f_pct``, ``camera_pp_px``, ``min_new_deg``, ``sigma_camera``, the
        detector's settings, ``max_angle_deg``).
    """

    def __init__(self, board: Board, image_size, options: AdvisorOptions = AdvisorOptions()):
        w, h = int(image_size[0]), int(image_size[1])
        if w < 16 or h < 16:
            raise ProcamError(f"advisor: camera frames of {w}x{h} px are too small")
        self.board, self.image_size, self.options = board, (w, h), options
        self.obj = board.object_points()
        hx, hy = 0.5 * (board.cols + 1) * board.square, 0.5 * (board.rows + 1) * board.square
        #: the printed squares' outer corners (board frame)
        self.outer = np.array([[-hx, -hy, 0.0], [hx, -hy, 0.0], [hx, hy, 0.0], [-hx, hy, 0.0]])
        self.views: list = []
        self.fit: Calibration | None = None
        self._frame = 0

    # -- the camera as known so far -------------------------------------------------------------
    @property
    def camera(self) -> Device:
        """The camera as fitted from the photos taken (two or more), else the guess."""
        return self.fit.camera if self.fit is not None else guessed_camera(self.image_size)

    def _model(self):
        """``(K, coeffs, free, sigma)`` the predictions are taken at."""
        if self.fit is None:
            return np.asarray(self.camera.K, float), np.zeros(5), (0, 1), self.options.sigma_camera
        cov = self.fit.info["covariance"]
        sigma = cov.get("sigma_px")
        sigma = max(sigma if sigma is not None and np.isfinite(sigma) else 0.0, self.options.sigma_camera)
        free = tuple(crlb.VIEW_PARAMS.index(n) - 4 for n in cov["params"][4:])  # the fit's free coefficients
        return (np.asarray(self.fit.camera.K, float), np.asarray(self.fit.camera.distortion.coeffs, float), free,
                float(sigma))

    def _pose(self, corners):
        """``(R, t)`` board -> camera by PnP with the camera as known so far, or None."""
        cam = self.camera
        return pose_pnp(self.obj, cam.undistort(corners), cam.K)

    def _prior(self, K, free) -> np.ndarray:
        """The weak prior (information per parameter) that ranks photos while the camera is undetermined."""
        W, H = self.image_size
        sd = np.r_[0.5 * K[0, 0], 0.5 * K[1, 1], 0.25 * W, 0.25 * H, np.ones(len(free))]
        return np.diag(1.0 / sd ** 2)

    def _score(self, b: crlb.ViewsBound, f: float) -> float:
        o = self.options
        if not b.determined:
            return float("inf")
        return max(b.std["f_c"] / f / (o.camera_f_pct / 100.0), max(b.std["u0c"], b.std["v0c"]) / o.camera_pp_px)

    # -- the photos -------------------------------------------------------------------------------
    def _photo_information(self, K, coeffs, free) -> tuple[np.ndarray, list]:
        """The summed information of the photos taken (their poses by PnP at the current camera) and their
        rotations."""
        P = 4 + len(free)
        total, rotations = np.zeros((P, P)), []
        for v in self.views:
            pose = self._pose(v.cam_pts)
            if pose is None:
                continue
            rotations.append(pose[0])
            total += crlb.view_information(K, coeffs, _rvec(pose[0]), pose[1], self.obj, free)
        return total, rotations

    def _now(self):
        """``(bound, score, rotations, information, model)`` of the photos taken."""
        K, coeffs, free, sigma = model = self._model()
        before, rotations = self._photo_information(K, coeffs, free)
        b = crlb.views_bound(K, coeffs, [], self.obj, sigma, free, extra=before)
        return b, self._score(b, float(K[0, 0])), rotations, before, model

    @property
    def enough(self) -> bool:
        """At least ``min_photos`` photos, their fit rated good (no photo out of line, the boards covering enough
        of the image, the distortion determined: :func:`procam.multi_pose.calibrate_camera`'s checks) and the
        predicted ± within the targets (with the fit's residual noise, never below ``sigma_camera``)."""
        if self.fit is None or len(self.views) < self.options.min_photos or self.fit.verdict != "good":
            return False
        return self._now()[1] <= 1.0

    def take(self, image=None, *, corners=None, name: str | None = None):
        """Add a photo (an image, its board found at full quality; or its ``corners`` (N, 2) in canonical order)
        named ``name``; returns its :class:`~procam.view.View`.  The camera is refitted by the caller
        (:meth:`set_fit`; :func:`procam.acquire.live.advise_camera` does it after each photo).

        Raises :class:`~procam.errors.BoardNotFoundError` when the image shows no board."""
        from ..view import View

        name = name or f"photo{len(self.views) + 1:02d}"
        if corners is None:
            from ..board import corners as _corners
            from ..errors import BoardNotFoundError

            c, _ = _corners.find_corners([np.asarray(image)], self.board.pattern_size)
            if c is None:
                raise BoardNotFoundError(f"{name}: the {self.board.cols}x{self.board.rows}-corner board is not "
                                         "in the photo")
            corners = c
        corners = np.asarray(corners, float).reshape(-1, 2)
        view = View(self.obj, corners, np.full_like(corners, np.nan), name, self.image_size, None, board=self.board)
        self.views.append(view)
        return view

    def set_fit(self, calib: Calibration | None) -> None:
        """The camera-only calibration of the photos taken (:func:`procam.multi_pose.calibrate_camera`, with its
        covariance): the camera the predictions are taken at, and the fit ``enough`` judges."""
        if calib is not None and (calib.info.get("covariance") is None or calib.projector is not None):
            raise ProcamError("advisor: the camera mode needs a camera-only calibration of several photos "
                              "(procam.multi_pose.calibrate_camera), with its covariance")
        self.fit = calib

    # -- one frame --------------------------------------------------------------------------------
    def _area(self, extra=None, base=None) -> tuple[float, np.ndarray]:
        """(fraction of the image inside the photos' boards (each board's corners' convex hull, as
        :func:`procam.multi_pose.calibrate_camera` measures its coverage; on a 1/8-scale grid), the grid) with
        ``extra``'s corners added to the photos' (or to the grid ``base``)."""
        from ..board import board_region

        W, H = self.image_size
        small = (max(2, W // 8), max(2, H // 8))
        if base is None:
            base = np.zeros((small[1], small[0]), bool)
            for v in self.views:
                base |= board_region(v.cam_pts / 8.0, small)
        grid = base if extra is None else base | board_region(np.asarray(extra) / 8.0, small)
        return float(grid.mean()), grid

    def _coverage(self, extra=None) -> tuple[float, tuple]:
        """(fraction of :data:`REGIONS` reached by the photos' corners (and ``extra``'s), the others)."""
        W, H = self.image_size
        hit = np.zeros(9, bool)
        for pts in [v.cam_pts for v in self.views] + ([] if extra is None else [extra]):
            ok = np.isfinite(pts).all(1)
            i = np.clip((pts[ok, 0] * 3 // W).astype(int), 0, 2)
            j = np.clip((pts[ok, 1] * 3 // H).astype(int), 0, 2)
            hit[j * 3 + i] = True
        return float(hit.mean()), tuple(r for r, h in zip(REGIONS, hit) if not h)

    def _inside(self, R, t) -> np.ndarray | None:
        """The corners (N, 2) of the board at ``(R, t)`` when they all fall in the image, else None."""
        W, H = self.image_size
        m = 0.02 * math.hypot(W, H)  # the printed board's outer squares, and a margin
        cam = self.camera
        out = models.project(cam.K, R, t, self.outer)  # pinhole: the margin covers the lens's few pixels
        if not (np.all(np.isfinite(out)) and out[:, 0].min() > m and out[:, 1].min() > m
                and out[:, 0].max() < W - 1 - m and out[:, 1].max() < H - 1 - m):
            return None
        return cam.project(R, t, self.obj)

    def _goals(self, t_cb) -> list:
        """Where the board's centre may go: where it is, under the centre of each of :data:`REGIONS` at the same
        distance, and under the image's centre a quarter farther away (room to turn the board in view)."""
        W, H = self.image_size
        K = np.asarray(self.camera.K, float)
        out = [np.asarray(t_cb, float)]
        for k in range(9):
            ray = np.linalg.solve(K, [(k % 3 + 0.5) * W / 3, (k // 3 + 0.5) * H / 3, 1.0])
            out.append(ray * t_cb[2] / ray[2])
        ray = np.linalg.solve(K, [(W - 1) / 2.0, (H - 1) / 2.0, 1.0])
        out.append(ray * 1.25 * t_cb[2] / ray[2])
        return out

    def _candidates(self, R_cb, t_cb):
        """``(R, t, corners)`` of the next photo: :data:`CANDIDATE_DEG` turns and tilts of the board made
        fronto-parallel (its turn in its own plane kept), its normal within ``max_angle_deg`` of the camera's
        axis, its centre where it is or moved towards each region (the whole way, 3/4, 1/2 or 1/4: as far as the
        printed board stays in the image)."""
        n = np.asarray(R_cb, float)[:, 2]
        z = np.array([0.0, 0.0, 1.0 if n[2] >= 0 else -1.0])
        axis = np.cross(n, z)
        w = axis / max(np.linalg.norm(axis), 1e-12) * math.acos(float(np.clip(n @ z, -1.0, 1.0)))
        front = models.rvec_to_matrix(w) @ R_cb
        cos_max = math.cos(math.radians(self.options.max_angle_deg))
        goals = self._goals(t_cb)
        for turn in CANDIDATE_DEG:
            for tilt in CANDIDATE_DEG:
                R = axis_rotation(turn, tilt) @ front
                if (turn == 0.0 and tilt == 0.0) or abs(R[2, 2]) < cos_max:
                    continue
                for goal in goals:
                    for frac in (1.0, 0.75, 0.5, 0.25):
                        t = t_cb + frac * (goal - t_cb)
                        px = self._inside(R, t)
                        if px is not None:
                            yield R, t, px
                            break

    def update(self, image) -> CameraAdvice:
        """The advice for one grey frame (see the module docstring)."""
        from ..board.corners import detect_corners

        img = np.asarray(image)
        if img.ndim != 2 or (img.shape[1], img.shape[0]) != self.image_size:
            raise ProcamError(f"advisor: frame of shape {img.shape}, expected a grey "
                              f"{self.image_size[0]}x{self.image_size[1]} image")
        o = self.options
        frame = self._frame
        self._frame += 1
        common = dict(frame=frame, photos=len(self.views), f_target_pct=o.camera_f_pct, pp_target_px=o.camera_pp_px)
        now, _, rotations, before, (K, coeffs, free, sigma) = self._now()
        f = float(K[0, 0])
        coverage, uncovered = self._coverage()
        common.update(now=_std_dict(now, f), coverage=coverage, uncovered=uncovered)
        if self.enough:
            msg = (f"enough: {len(self.views)} photos determine the camera to f_c ± {now.std['f_c'] / f:.2%} "
                   f"(target {o.camera_f_pct:g} %), principal point ± {max(now.std['u0c'], now.std['v0c']):.1f} px "
                   f"(target {o.camera_pp_px:g} px): write the camera file")
            return CameraAdvice(state="enough", message=msg, actions=(Action("done", msg),), enough=True, **common)
        corners = detect_corners(img, self.board.pattern_size, o.detect_options)
        pose = None if corners is None else self._pose(corners)
        if pose is None:
            msg = (f"board not found: show the whole {self.board.cols}x{self.board.rows}-corner board to the camera, "
                   "in focus and lit")
            return CameraAdvice(state="no-board", message=msg, actions=(Action("find", msg),), **common)
        R_cb, t_cb = pose
        prior = self._prior(K, free)

        def score(info):
            return self._score(crlb.views_bound(K, coeffs, [], self.obj, sigma, free, extra=before + info + prior), f)

        def information(R, t):
            return crlb.view_information(K, coeffs, _rvec(R), t, self.obj, free)

        # while the boards cover too little of the image (the fit's check), a photo that covers more comes first
        area, grid = self._area()
        wants_area = area < o.camera_min_coverage
        this = information(R_cb, t_cb)
        with_this = crlb.views_bound(K, coeffs, [], self.obj, sigma, free, extra=before + this)
        ranked = []
        for k, (R, t, px) in enumerate(self._candidates(R_cb, t_cb)):
            gained = self._area(px, grid)[0] - area
            if gained < 0.02 and any(_angle_deg(R, Q) < o.min_new_deg for Q in rotations):
                continue  # a photo taken already: the next one must be new
            ranked.append((-round(gained, 2) if wants_area else 0.0, score(information(R, t)), k, R, t))
        ranked.sort(key=lambda c: c[:3])
        s_now, s_this = score(0.0), score(this)
        best = ranked[0] if ranked else None
        next_move = None if best is None else move_between(R_cb, best[3])
        shift = None if best is None else best[4] - t_cb
        newest = min((_angle_deg(R_cb, R) for R in rotations), default=180.0)
        adds = self._area(corners, grid)[0] - area
        gain = math.log(s_now / s_this) if s_this < s_now else 0.0
        best_gain = math.log(s_now / best[1]) if best is not None and best[1] < s_now else 0.0
        angles = tuple(float(a) for a in models.board_angles_deg(R_cb, t_cb))
        common.update(with_this=_std_dict(with_this, f), next_move=next_move, angles_deg=angles, corners=corners,
                      next_shift=None if shift is None else tuple(float(v) for v in shift))
        if len(self.views) < 2:
            common.update(now=None)
        more = best is not None and wants_area and adds >= max(0.02, -0.5 * best[0])
        new = newest >= o.min_new_deg or (adds >= 0.02 and newest >= 0.5 * o.min_new_deg)
        if new and ((gain > 0 and gain >= 0.5 * best_gain) or more):
            pred = _std_dict(with_this, f)
            msg = ("take this photo" + (f": f_c ± {pred['f_c_pct']:.2f} %, principal point ± "
                                        f"{max(pred['u0c'], pred['v0c']):.1f} px with it" if pred else
                                        " (the camera is determined from two or more)"))
            return CameraAdvice(state="take", message=msg, actions=(Action("take", msg),), **common)
        actions = []
        if shift is not None and np.linalg.norm(shift) > 0.05 * t_cb[2]:
            why = (f"corners not yet seen in the image's {', '.join(uncovered)}" if uncovered else
                   "the next tilt there covers more of the image")
            x, y = (K[:2, :2] @ shift[:2]) / t_cb[2]
            sides = [(("right" if x > 0 else "left"), abs(x)), (("down" if y > 0 else "up"), abs(y))]
            words = [w for w, v in sides if v > 0.03 * max(self.image_size)]
            if abs(shift[2]) > 0.1 * t_cb[2]:
                words.append("farther from the camera" if shift[2] > 0 else "closer")
            main = max(sides, key=lambda v: v[1])
            actions.append(Action("move", f"move the board {' and '.join(words)} (about {abs(x):.0f}, {abs(y):.0f} px "
                                          f"in the image): {why}",
                                  direction=main[0] if main[1] > 0.03 * max(self.image_size) else None))
        if next_move is not None:
            from .advisor import Advisor

            actions += [Advisor._action(n, d) for n, d in sorted((("turn", next_move[0]), ("tilt", next_move[1])),
                                                                 key=lambda v: -abs(v[1])) if abs(d) >= 1.5]
        why = (f"a photo within {newest:.0f} deg of this one was taken" if not new else "this pose adds little")
        if not actions:  # no new pose fits in view from here
            actions = [Action("move", "move the board back towards the image's centre and farther from the camera",
                              direction=None)]
        msg = f"{why}: {actions[0].text}"
        return CameraAdvice(state="adjust", message=msg, actions=tuple(actions), **common)
