"""A check in the world: does the calibration put projected light where it says it does?

With a calibration and the board in view, :func:`world_check`

1. grabs the board under the projector's white light and finds its corners (:func:`procam.board.corners.find_corners`);
2. takes the board's pose by PnP with the calibrated camera (its lens undistorted first,
   :func:`procam.residuals.pnp`);
3. puts one target on the board at the centre of every white square of the inner grid (see below), and maps it
   into the projector through ``R, T`` and the projector's intrinsics and distortion (:meth:`Device.project
   <procam.calibration.Device.project>`);
4. shows a Gaussian spot at each target's projector pixel, then a black frame, and grabs both;
5. finds each spot in the difference image near where the camera should see it (an intensity-weighted centroid
   in a window that follows the spot; a spot too faint to find is reported, never guessed);
6. reports the miss per target in camera pixels (found - predicted) and on the board in the board's unit (the
   camera ray of the found centroid meets the board plane), a verdict, what the pattern of the misses points to,
   and a picture (:func:`draw`).

Why the centres of the **white** squares: a spot on a uniform patch of paper is imaged without bias, while one
on a corner (half black, half white) has its centroid pulled into the white half by up to a fraction of its
width; a white square returns 8x the light of a black one, so the spot stands well above the camera's noise.
Which parity of squares is white is read off the white frame (the brighter of the two).

The device layer is one callable ``show_and_grab(projector_image) -> camera frame``: :func:`virtual_device`
(the simulator renders any projector image, :meth:`procam.simulate.Renderer.linear_image`) or
:func:`capture_device` (a projector window and a camera of :mod:`procam.acquire`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..board import Board
from ..errors import BoardNotFoundError, CalibrationError, ProcamError
from .spots import centroid, count_spots, spot_levels, spots_image
from .wall import WallCheck

__all__ = ["VERDICTS", "WALL_GRID_MAX", "WorldCheck", "WorldCheckOptions", "capture_device", "draw", "virtual_device",
           "white_square_centres", "world_check"]

#: The verdict words: the calibration holds in the world, is off, or the check cannot tell.
VERDICTS = ("holds", "off", "inconclusive")
#: The most spots a side of the wall's grid may have (``wall=(cols, rows)``).
WALL_GRID_MAX = 12


@dataclass(frozen=True)
class WorldCheckOptions:
    """Thresholds and marker size of :func:`world_check`.

    tolerance_px : the calibration holds when the RMS miss is at most this, camera px (default 0.5: about
        twice what a correct calibration misses by on a well-exposed board, see docs/world-check.md).
    tolerance : ... and at most this on the board, in the board's unit; None = 1/50 of a square.
    marker_sigma : the spots' Gaussian sigma in projector px; None = 8 % of a square's side in the projector
        (a spot then lies well inside its square; 3 sigma is a quarter of the square).
    min_snr : a spot is found when its peak in the smoothed difference image is this many times that image's
        noise (robust sigma).
    min_found : the check concludes only when at least this fraction of the targets (and at least 4) are found.
    """

    tolerance_px: float = 0.5
    tolerance: float | None = None
    marker_sigma: float | None = None
    min_snr: float = 8.0
    min_found: float = 0.6

    def __post_init__(self):
        for name, lo in (("tolerance_px", 0.0), ("min_snr", 0.0)):
            v = getattr(self, name)
            if not np.isfinite(v) or v <= lo:
                raise ProcamError(f"world check: {name} must be a finite number > {lo:g}, got {v!r}")
        for name in ("tolerance", "marker_sigma"):
            v = getattr(self, name)
            if v is not None and (not np.isfinite(v) or v <= 0):
                raise ProcamError(f"world check: {name} must be a finite number > 0 or None, got {v!r}")
        if not 0 < self.min_found <= 1:
            raise ProcamError(f"world check: min_found must be a fraction in (0, 1], got {self.min_found!r}")


@dataclass(frozen=True)
class WorldCheck:
    """The result of :func:`world_check` (N targets; pixels ``(x, y)``; lengths in the board's unit).

    verdict : ``"holds"``, ``"off"`` or ``"inconclusive"`` (:data:`VERDICTS`); reasons : its reasons in words.
    targets : (N, 2) the targets on the board (board frame x, y; z = 0).
    proj_pts : (N, 2) where the calibration puts them in the projector (the spots' centres), projector px.
    predicted : (N, 2) where the calibration says the camera sees them, camera px (distorted).
    found : (N, 2) the spots' centroids in the camera image, NaN where ``status`` is not ``"found"``.
    status : (N,) ``"found"``, ``"faint"`` (no spot above ``min_snr``) or ``"outside"`` (the target is off the
        projector's panel or the camera image: no spot shown).
    miss_px : (N, 2) found - predicted, camera px; miss : (N, 2) on the board (found - target), board unit.
    sd_px : (N,) the centroid's standard deviation from the image noise, camera px (NaN where not found).
    rms_px, max_px, rms, max : the RMS and largest miss over the found spots (camera px; board unit).
    noise_px : the median of ``sd_px``: what a perfect calibration would still miss by.
    pattern : what the misses look like in the projector (least squares ``d = shift + scale (q - pp)`` over the
        found spots, ``d`` the projector-pixel miss): ``{"shift": (dx, dy) px, "scale": fraction,
        "residual": RMS px, "total": RMS px}``, or None with fewer than 4 spots.
    diagnosis : the pattern in words (empty when the calibration holds).
    R_board, t_board : the board's pose (board -> camera) from the white frame.
    white : (H, W) the white frame (the picture's background); marker_sigma : the spots' sigma, projector px.
    tolerance_px, tolerance : the thresholds the verdict used.
    wall : the wall's targets (:class:`~procam.world_check.wall.WallCheck`; their verdict is in ``verdict`` and
        ``reasons``), or None when the check was asked for the board only.
    """

    verdict: str
    reasons: tuple
    targets: np.ndarray
    proj_pts: np.ndarray
    predicted: np.ndarray
    found: np.ndarray
    status: tuple
    miss_px: np.ndarray
    miss: np.ndarray
    sd_px: np.ndarray
    rms_px: float
    max_px: float
    rms: float
    max: float
    noise_px: float
    pattern: dict | None
    diagnosis: str
    R_board: np.ndarray
    t_board: np.ndarray
    white: np.ndarray = field(repr=False)
    marker_sigma: float = float("nan")
    tolerance_px: float = float("nan")
    tolerance: float = float("nan")
    wall: WallCheck | None = None

    def to_dict(self) -> dict:
        """The numbers as JSON-ready types (no image), ``"format": "procam-world-check"``."""
        from ..io.formats import WORLD_CHECK_FORMAT
        def arr(a):
            return [[None if not np.isfinite(v) else round(float(v), 4) for v in row] for row in np.asarray(a)]

        def num(v):
            return None if v is None or not np.isfinite(v) else round(float(v), 5)

        return {"format": WORLD_CHECK_FORMAT, "version": 1, "verdict": self.verdict, "reasons": list(self.reasons), "diagnosis": self.diagnosis,
                "rms_px": num(self.rms_px), "max_px": num(self.max_px), "rms": num(self.rms), "max": num(self.max),
                "noise_px": num(self.noise_px), "tolerance_px": num(self.tolerance_px),
                "tolerance": num(self.tolerance), "marker_sigma_proj_px": num(self.marker_sigma),
                "found": int(sum(s == "found" for s in self.status)), "targets": len(self.status),
                "pattern": None if self.pattern is None else {k: (list(map(num, v)) if isinstance(v, tuple)
                                                                  else num(v)) for k, v in self.pattern.items()},
                "markers": [{"target": [num(t[0]), num(t[1])], "projector": [num(q[0]), num(q[1])],
                             "predicted": [num(p[0]), num(p[1])], "status": s,
                             "found": arr([f])[0], "miss_px": arr([m])[0], "miss": arr([b])[0]}
                            for t, q, p, s, f, m, b in zip(self.targets, self.proj_pts, self.predicted, self.status,
                                                           self.found, self.miss_px, self.miss)],
                "wall": None if self.wall is None else self.wall.to_dict(num, arr)}


# --------------------------------------------------------------------------------------------
# the geometry
# --------------------------------------------------------------------------------------------

def white_square_centres(board: Board) -> tuple[np.ndarray, np.ndarray]:
    """The centres of the squares between the inner corners, (M, 3) board frame (``M = (cols-1)(rows-1)``), and
    their parity (M,) ``(i + j) % 2`` (the squares of one parity are white)."""
    obj = board.object_points().reshape(board.rows, board.cols, 3)
    centres = (obj[:-1, :-1] + obj[1:, 1:]) / 2.0
    j, i = np.mgrid[0:board.rows - 1, 0:board.cols - 1]
    return centres.reshape(-1, 3), ((i + j) % 2).ravel()


def _sample(image: np.ndarray, pts: np.ndarray, r: int = 1) -> np.ndarray:
    """Mean of ``image`` in the (2r+1)^2 block at each of ``pts`` (N, 2) (NaN outside)."""
    h, w = image.shape[:2]
    out = np.full(len(pts), np.nan)
    for k, (x, y) in enumerate(pts):
        if np.isfinite(x) and np.isfinite(y) and r <= x < w - r and r <= y < h - r:
            xi, yi = round(x), round(y)
            out[k] = float(image[yi - r:yi + r + 1, xi - r:xi + r + 1].mean())
    return out


def _on_board(calib, pts: np.ndarray, R_b: np.ndarray, t_b: np.ndarray) -> np.ndarray:
    """Board-frame points (N, 3) where the camera rays of distorted camera pixels ``pts`` (N, 2) meet the board."""
    from ..triangulate import rays

    d = rays(calib.camera, pts)
    n = R_b[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (n @ t_b) / (d @ n)
    X = d * s[:, None]
    return (X - t_b) @ R_b          # R_b^T (X - t_b), row-wise


def _pattern(calib, X_found: np.ndarray, q: np.ndarray, R_p: np.ndarray, t_p: np.ndarray):
    """The projector-pixel misses of the found spots and their fit ``d = shift + scale (q - pp)``."""
    q_back = calib.projector.project(R_p, t_p, X_found)
    d = q_back - q
    ok = np.isfinite(d).all(1)
    if ok.sum() < 4:
        return None
    pp = np.asarray(calib.projector.K, float)[:2, 2]
    r = q[ok] - pp
    n = int(ok.sum())
    A = np.zeros((2 * n, 3))
    A[0::2, 0] = 1.0
    A[1::2, 1] = 1.0
    A[0::2, 2] = r[:, 0]
    A[1::2, 2] = r[:, 1]
    sol, *_ = np.linalg.lstsq(A, d[ok].ravel(), rcond=None)
    res = d[ok].ravel() - A @ sol
    return {"shift": (float(sol[0]), float(sol[1])), "scale": float(sol[2]),
            "residual": float(np.sqrt(np.mean(res.reshape(-1, 2) ** 2) * 2)),
            "total": float(np.sqrt(np.mean(np.sum(d[ok] ** 2, 1)))),
            "scale_rms": float(abs(sol[2]) * np.sqrt(np.mean(np.sum(r ** 2, 1))))}


def _diagnosis(pattern: dict | None, calib) -> str:
    """The pattern of the misses in words: which parameter it points to (only parts that carry >= 1/3 of it)."""
    if pattern is None or not pattern["total"] > 0:
        return ""
    total = pattern["total"]
    parts = []
    s = pattern["scale"]
    if pattern["scale_rms"] >= total / 3:
        fp = float(np.asarray(calib.projector.K, float)[0, 0])
        parts.append(f"a scale of {s:+.2%} about the projector's principal point: the projector's focal length looks "
                     f"{'too long' if s > 0 else 'too short'} (f_p {fp:.1f} -> about {fp / (1 + s):.1f} px)")
    dx, dy = pattern["shift"]
    shift = float(np.hypot(dx, dy))
    if shift >= total / 3:
        fp = float(np.asarray(calib.projector.K, float)[0, 0])
        parts.append(f"a shift of ({dx:+.1f}, {dy:+.1f}) projector px, as from turning the projector by "
                     f"{np.degrees(np.arctan2(shift, fp)):.2f} deg: the rotation R or translation T, or the "
                     "projector's principal point")
    if pattern["residual"] >= total / 3:
        parts.append(f"{pattern['residual']:.1f} projector px RMS that is neither a scale nor a shift (distortion, "
                     "the camera's intrinsics, or a board that moved)")
    return f"the misses are {total:.1f} projector px RMS: " + "; ".join(parts) if parts else ""


# --------------------------------------------------------------------------------------------
# the check
# --------------------------------------------------------------------------------------------

def world_check(calib, board: Board, show_and_grab: Callable[[np.ndarray], np.ndarray], *,
                options: WorldCheckOptions = WorldCheckOptions(), wall: tuple[int, int] | None = None) -> WorldCheck:
    """Project spots where the calibration says the board's white squares are, and measure where they land.

    Parameters
    ----------
    calib : :class:`procam.calibration.Calibration` with a projector and ``R, T``.
    board : the :class:`~procam.board.Board` in view (its ``square`` is the unit of ``miss``).
    show_and_grab : ``f(image (Hp, Wp) uint8) -> (H, W) or (H, W, 3) uint8/uint16`` camera frame with ``image``
        on the projector (:func:`virtual_device`, :func:`capture_device`); called three times (white, spots,
        black), and once more per frame of the wall's spots.
    options : :class:`WorldCheckOptions`.
    wall : ``(cols, rows)``: also a grid of spots over the projector's panel, on the wall behind the board (the
        board's footprint left out), each checked against its epipolar curve in the camera
        (:mod:`procam.world_check.wall`: the wall's geometry is not known to the calibration); None: the board's
        targets only.

    Returns
    -------
    :class:`WorldCheck`.

    Raises
    ------
    CalibrationError : no projector in ``calib``, or no board pose.
    BoardNotFoundError : the board is not in the white frame.
    """
    from ..board import corners as _corners
    from ..residuals import pnp

    if calib.projector is None or calib.R is None or calib.T is None:
        raise CalibrationError("the calibration has no projector or no camera->projector R, T; the world check "
                               "needs a procam calibration with a projector")
    if wall is not None and not (isinstance(wall, (tuple, list)) and len(wall) == 2 and all(
            isinstance(v, (int, np.integer)) and 2 <= v <= WALL_GRID_MAX for v in wall)):
        raise ProcamError(f"world check: wall must be (cols, rows), each an integer from 2 to {WALL_GRID_MAX}, got "
                          f"{wall!r}")
    Wp, Hp = (int(v) for v in calib.projector.image_size)
    R, T = np.asarray(calib.R, float), np.asarray(calib.T, float).reshape(3)

    white = _gray(show_and_grab(np.full((Hp, Wp), 255, np.uint8)))
    h, w = white.shape
    if tuple(calib.camera.image_size) != (w, h):
        raise CalibrationError(f"the camera's frames are {w}x{h}, the calibration's camera is "
                               f"{calib.camera.image_size[0]}x{calib.camera.image_size[1]}; check the camera and "
                               "the calibration file (or --camera-size)")
    c, hint = _corners.find_corners([white], board.pattern_size)
    if c is None:
        why = _corners.size_hint_text(board.pattern_size, hint) if hint is not None else (
            "check --board (inner corners), the exposure, and that the whole board is in view and lit")
        raise BoardNotFoundError(f"world check: the {board.cols}x{board.rows} board is not in the camera's white "
                                 f"frame; {why}")
    obj = board.object_points()
    Kc = np.asarray(calib.camera.K, float)
    R_b, t_b, _ = pnp(obj, calib.camera.undistort(c), Kc)
    R_p, t_p = R @ R_b, R @ t_b + T          # board -> projector

    centres, parity = white_square_centres(board)
    cam_c = calib.camera.project(R_b, t_b, centres)
    bright = _sample(white.astype(np.float64), cam_c)
    means = [np.nanmean(bright[parity == k]) if np.isfinite(bright[parity == k]).any() else -np.inf for k in (0, 1)]
    targets = centres[parity == int(np.argmax(means))]
    predicted = calib.camera.project(R_b, t_b, targets)
    q = calib.projector.project(R_p, t_p, targets)

    # the spot size: a fraction of a square's side, in each device
    sq_proj = np.nanmedian(np.linalg.norm(np.diff(calib.projector.project(R_p, t_p, obj).reshape(
        board.rows, board.cols, 2), axis=1), axis=2))
    sq_cam = np.nanmedian(np.linalg.norm(np.diff(c.reshape(board.rows, board.cols, 2), axis=1), axis=2))
    sigma = options.marker_sigma or 0.08 * sq_proj
    sigma_cam = sigma * sq_cam / sq_proj
    m = 3 * sigma
    inside = (np.isfinite(q).all(1) & (q[:, 0] >= m) & (q[:, 0] <= Wp - 1 - m) & (q[:, 1] >= m)
              & (q[:, 1] <= Hp - 1 - m) & (predicted[:, 0] >= 0) & (predicted[:, 0] <= w - 1)
              & (predicted[:, 1] >= 0) & (predicted[:, 1] <= h - 1))

    lit = _gray(show_and_grab(spots_image((Wp, Hp), q[inside], sigma)))
    plan = _wall_plan(calib, board, wall, R_b, t_b, R_p, t_p, sigma, sigma_cam, sq_cam) if wall is not None else None
    wall_lit = [] if plan is None else [_gray(show_and_grab(spots_image((Wp, Hp), plan[0][plan[1] == f], sigma)))
                                        for f in range(int(plan[1].max()) + 1 if len(plan[1]) else 0)]
    dark = _gray(show_and_grab(np.zeros((Hp, Wp), np.uint8)))
    if any(f.shape != white.shape for f in (lit, dark, *wall_lit)):
        raise ProcamError("world check: the camera's frames changed size during the check")
    diff, smooth, noise, floor = spot_levels(lit, dark, sigma_cam, options.min_snr)

    n = len(targets)
    found = np.full((n, 2), np.nan)
    sd = np.full(n, np.nan)
    status = []
    for k in range(n):
        if not inside[k]:
            status.append("outside")
            continue
        got = centroid(diff, smooth, predicted[k], 0.5 * sq_cam, sigma_cam, floor, noise)
        if got is None:
            status.append("faint")
            continue
        found[k], sd[k] = got
        status.append("found")

    miss_px = found - predicted
    X_found = _on_board(calib, found, R_b, t_b)
    miss = X_found[:, :2] - targets[:, :2]
    ok = np.isfinite(miss_px).all(1)

    def rms(a):
        return float(np.sqrt(np.mean(np.sum(a[ok] ** 2, 1)))) if ok.any() else float("nan")

    def largest(a):
        return float(np.max(np.hypot(a[ok, 0], a[ok, 1]))) if ok.any() else float("nan")

    tol = options.tolerance if options.tolerance is not None else board.square / 50.0
    rms_px, rms_b = rms(miss_px), rms(miss)
    noise_px = float(np.nanmedian(sd)) if ok.any() else float("nan")
    pattern = _pattern(calib, X_found[ok], q[ok], R_p, t_p) if ok.sum() >= 4 else None
    shown = int(inside.sum())
    need = max(4, int(np.ceil(options.min_found * shown)))
    reasons = []
    few = shown < 4 or ok.sum() < need
    seen = count_spots(smooth, floor, sigma_cam) if few and shown >= 4 else 0
    if few and need <= seen <= 1.25 * shown + 2:  # more than that: changes that are not the spots
        verdict = "off"  # the camera saw the spots, elsewhere: not a dark board, a calibration of another rig
        reasons.append(f"only {int(ok.sum())} of {shown} spots shown on the board were found within half a square of "
                       f"where the calibration puts them, yet the camera sees {seen} spots elsewhere: the calibration "
                       "does not describe this camera and projector (another rig, a moved projector, R or T)")
    elif few:
        verdict = "inconclusive"
        reasons.append(f"only {int(ok.sum())} of {shown} spots shown on the board were found ({n} targets); light "
                       "the board better, or bring all of it into the projector's image")
    elif noise_px > options.tolerance_px / 3:
        verdict = "inconclusive"
        reasons.append(f"the spots' centroids are uncertain by {noise_px:.2f} px, too much for a tolerance of "
                       f"{options.tolerance_px:g} px: raise the exposure or the projector's brightness")
    elif rms_px <= options.tolerance_px and rms_b <= tol:
        verdict = "holds"
        reasons.append(f"the spots land {rms_px:.2f} px RMS ({rms_b:.3g} on the board) from where the calibration "
                       f"puts them: within {options.tolerance_px:g} px and {tol:.3g}")
    else:
        verdict = "off"
        reasons.append(f"the spots land {rms_px:.2f} px RMS, {largest(miss_px):.2f} px at most ({rms_b:.3g} RMS on "
                       f"the board) from where the calibration puts them: more than {options.tolerance_px:g} px or "
                       f"{tol:.3g}")
    diagnosis = _diagnosis(pattern, calib) if verdict == "off" else ""
    wall_check = None
    if plan is not None:
        wall_check = _wall_spots(calib, plan, wall_lit, dark, sigma_cam, options)
        verdict, why = _wall_verdict(verdict, wall_check, options)
        reasons.append(why)
        if wall_check.rms_px > options.tolerance_px:
            diagnosis = "; ".join(filter(None, [diagnosis, (
                f"the wall's spots lie {wall_check.rms_px:.2f} px RMS across the lines the calibration says they must "
                "fall on, wherever the wall is: the projector's rays are not where the calibration puts them (R, T, "
                "or the projector's intrinsics or distortion)")]))
    return WorldCheck(verdict, tuple(reasons), targets[:, :2].copy(), q, predicted, found, tuple(status), miss_px,
                      miss, sd, rms_px, largest(miss_px), rms_b, largest(miss), noise_px, pattern, diagnosis, R_b, t_b,
                      white, float(sigma), float(options.tolerance_px), float(tol), wall_check)


def _wall_plan(calib, board, shape, R_b, t_b, R_p, t_p, sigma, sigma_cam, sq_cam):
    """The wall's spots (:mod:`.wall`): (projector px (M, 2), frame per spot (M,), epipolar curves (M, n, 2), the
    board's footprint in the camera (4, 2), the search band's half-width, camera px)."""
    from . import wall as _wall

    qw = _wall.grid(calib.projector.image_size, shape, _wall.footprint(calib.projector, R_p, t_p, board), sigma * 3)
    curves = _wall.curves(calib, qw, float(t_p[2]))
    seen = np.isfinite(curves).all(2).any(1)        # rays the camera sees at some depth
    qw, curves = qw[seen], curves[seen]
    band = max(5.0, 0.5 * sq_cam)
    return qw, _wall.frames(curves, 2 * band + 6 * sigma_cam), curves, _wall.footprint(calib.camera, R_b, t_b,
                                                                                        board), band


def _wall_spots(calib, plan, wall_lit, dark, sigma_cam, options) -> WallCheck:
    """Find each wall spot near its epipolar curve in its frame's difference image and measure it (:mod:`.wall`)."""
    from . import wall as _wall

    qw, frame, curves, keep_out, band = plan
    M = len(qw)
    W, H = calib.camera.image_size
    m = 4 * sigma_cam + 1
    found, sd, status = np.full((M, 2), np.nan), np.full(M, np.nan), ["faint"] * M
    for f, lit in enumerate(wall_lit):
        diff, smooth, noise, floor = spot_levels(lit, dark, sigma_cam, options.min_snr)
        for k in np.flatnonzero(frame == f):
            peak = _wall.band_peak(smooth, curves[k], band)
            got = None if peak is None or not peak[1] > floor else centroid(
                diff, smooth, peak[0], 2 * sigma_cam + 1, sigma_cam, floor, noise)
            if got is None:
                continue
            if _wall.inside(keep_out, got[0][None], 3 * sigma_cam)[0]:
                status[k] = "board"
                continue
            if not (m <= got[0][0] <= W - 1 - m and m <= got[0][1] <= H - 1 - m):
                status[k] = "edge"          # cut by the image's border: its centroid is pulled inwards
                continue
            found[k], sd[k], status[k] = got[0], got[1], "found"
    nearest, points, gap = _wall.on_ray(calib, qw, found)
    miss = found - nearest
    ok = np.isfinite(miss).all(1)
    d = np.hypot(miss[:, 0], miss[:, 1])
    return WallCheck(qw, frame, found, tuple(status), miss, gap, points, sd,
                     float(np.sqrt(np.mean(d[ok] ** 2))) if ok.any() else float("nan"),
                     float(d[ok].max()) if ok.any() else float("nan"),
                     float(np.sqrt(np.mean(gap[ok] ** 2))) if ok.any() else float("nan"),
                     float(np.nanmedian(sd)) if ok.any() else float("nan"))


def _wall_verdict(verdict: str, wall, options) -> tuple[str, str]:
    """The verdict with the wall's spots (off if either part is off, else inconclusive if either is) and the
    wall's reason."""
    shown = sum(s not in ("board", "edge") for s in wall.status)
    need = max(4, int(np.ceil(options.min_found * shown)))
    if wall.n_found < need:
        part, why = "inconclusive", (f"the wall: only {wall.n_found} of {len(wall.status)} spots found on it; bring "
                                     "more of the wall into both views, or light it better")
    elif wall.noise_px > options.tolerance_px / 3:
        part, why = "inconclusive", (f"the wall: its spots' centroids are uncertain by {wall.noise_px:.2f} px, too "
                                     f"much for a tolerance of {options.tolerance_px:g} px")
    elif wall.rms_px <= options.tolerance_px:
        part, why = "holds", (f"the wall: {wall.n_found} spots lie {wall.rms_px:.2f} px RMS from their epipolar "
                              f"lines (rays {wall.rms_gap:.3g} apart): within {options.tolerance_px:g} px")
    else:
        part, why = "off", (f"the wall: {wall.n_found} spots lie {wall.rms_px:.2f} px RMS, {wall.max_px:.2f} px at "
                            f"most from their epipolar lines: more than {options.tolerance_px:g} px")
    order = ("off", "inconclusive", "holds")
    return min(verdict, part, key=order.index), why


def _gray(frame) -> np.ndarray:
    """A camera frame as (H, W) grey, its own dtype."""
    from ..board.corners import _gray as gray

    frame = np.asarray(frame)
    if frame.ndim not in (2, 3):
        raise ProcamError(f"world check: a camera frame must be (H, W) or (H, W, 3), got shape {frame.shape}")
    return gray(frame)


# --------------------------------------------------------------------------------------------
# the picture
# --------------------------------------------------------------------------------------------

#: Colour per verdict of the picture (the palette of :mod:`procam.style`).
_COLOURS = {"holds": "good", "off": "failed", "inconclusive": "weak"}


def draw(check: WorldCheck, magnify: float = 10.0, max_width: int = 1600) -> np.ndarray:
    """The picture: the white frame (dimmed), each target where the camera should see it (grey ring), the spot
    found (a dot in the verdict's colour) and its miss as a line ``magnify`` times as long; the wall's spots found
    (grey diamonds) with their miss across their epipolar lines likewise; the verdict on top.
    Returns (H', W', 3) uint8 BGR (at most ``max_width`` wide)."""
    import cv2

    from ..board.corners import to_gray8
    from ..style import NEUTRAL, VERDICT_COLOURS, bgr

    img = cv2.cvtColor((to_gray8(check.white) * 0.6).astype(np.uint8), cv2.COLOR_GRAY2BGR)
    scale = min(1.0, max_width / img.shape[1])
    if scale < 1:
        img = cv2.resize(img, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
    colour = bgr(VERDICT_COLOURS[_COLOURS[check.verdict]])
    grey = bgr(NEUTRAL)

    def pt(p):
        return round(p[0] * scale), round(p[1] * scale)

    for p, f, s in zip(check.predicted, check.found, check.status):
        if not np.isfinite(p).all():
            continue
        cv2.circle(img, pt(p), 6, grey if s == "found" else bgr(VERDICT_COLOURS["weak"]), 1, cv2.LINE_AA)
        if s == "found":
            cv2.line(img, pt(p), pt(p + magnify * (f - p)), colour, 2, cv2.LINE_AA)
            cv2.circle(img, pt(f), 2, colour, -1, cv2.LINE_AA)
    wall = check.wall
    for f, m, s in zip(*((wall.found, wall.miss_px, wall.status) if wall is not None else ((), (), ()))):
        if s == "found":        # the wall: a diamond at the spot, its miss across its epipolar line drawn magnified
            cv2.drawMarker(img, pt(f), grey, cv2.MARKER_DIAMOND, 10, 1, cv2.LINE_AA)
            cv2.line(img, pt(f - m), pt(f - m + magnify * m), colour, 2, cv2.LINE_AA)
    lines = [f"world check: {check.verdict}  {check.rms_px:.2f} px RMS, {check.rms:.3g} on the board"
             + (f"; wall {wall.rms_px:.2f} px RMS off its lines" if wall is not None else ""),
             f"misses drawn x{magnify:g}; ring: where the camera should see the spot"
             + ("; diamond: a wall spot" if wall is not None else "")]
    for k, t in enumerate(lines):
        cv2.putText(img, t, (10, 24 + 22 * k), cv2.FONT_HERSHEY_SIMPLEX, 0.6 if k == 0 else 0.45,
                    colour if k == 0 else (230, 230, 230), 1, cv2.LINE_AA)
    return img


# --------------------------------------------------------------------------------------------
# the devices
# --------------------------------------------------------------------------------------------

def virtual_device(scene, seed: int = 0) -> Callable[[np.ndarray], np.ndarray]:
    """``show_and_grab`` of the simulator: each projector image rendered as the camera sees it in ``scene``
    (:meth:`procam.simulate.Renderer.linear_image`, the camera's blur and noise from one generator seeded by
    ``seed``)."""
    from ..simulate import Renderer

    renderer = Renderer(scene)
    rng = np.random.default_rng(seed)

    def show_and_grab(image: np.ndarray) -> np.ndarray:
        return renderer.finish(renderer.linear_image(image), rng)

    return show_and_grab


def capture_device(projector, camera, settle_s: float = 0.25) -> Callable[[np.ndarray], np.ndarray]:
    """``show_and_grab`` of real devices: ``projector`` and ``camera`` open :mod:`procam.acquire` devices (a
    :class:`~procam.acquire.projector.ProjectorWindow`, a camera of :func:`~procam.acquire.cameras.open_camera`).
    Each image is shown, held ``settle_s`` seconds, and a frame grabbed after the camera's buffer is flushed; a
    streaming camera is grabbed until two frames agree (the capture loop's own rule)."""
    from ..acquire.session import steady_shooter

    return steady_shooter(projector, camera, settle_s)
