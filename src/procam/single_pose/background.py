"""The background behind the board: a check, and a refinement, of the single-pose projector model.

One plane gives two constraints on a device's intrinsics, so the single-pose projector model assumes
``u0p`` (default ``W / 2``) and ``alpha_p = 1``: with them fixed, ``K_p`` and the board pose have exactly
the board homography's 8 degrees of freedom, so **any** ``u0p`` fits the board perfectly and the board
alone cannot reveal a wrong one. Every capture also decodes the wall or table behind the board, and
board + background are not coplanar: the calibration predicts the camera-projector epipolar geometry,
and the background's correspondences must agree with it.

Given both devices' board homographies, a calibration is free only in the projector's epipole (2
degrees of freedom of the fundamental matrix): a wrong ``u0p`` moves the epipole, and the background
points, off the board's plane, then leave their epipolar lines by an amount that grows with their
parallax. The single-pose camera is itself uncertain (its ``f_c`` is often known to only +-20-40 px
from one pose), and that uncertainty moves the epipole too, so the size of the disagreement alone says
nothing; this module compares two fits of the same data instead:

* **assumed**: the paper's projector model (``u0p`` fixed, ``alpha_p`` 1), with the background;
* **free**: ``u0p`` (and optionally ``alpha_p``) estimated from the background;

both jointly over the camera (the parameters its single-pose fit estimates, on its board corners, with
its principal-point prior if it used one), the projector's ``f_p, v0p`` and board pose, on the projector's
board corners (pixels) and the background points' distances to their epipolar lines (projector pixels).
Twice the cost difference is the likelihood-ratio statistic of the assumption: chi-square with one
degree of freedom per freed parameter when the assumption holds, so a threshold at a false-alarm
probability (default 1e-4) is the **model-error** test (:func:`epipolar_check`). The free fit is the
refinement (:func:`refine_projector`): ``f_p, u0p, v0p`` (and ``alpha_p``) from ONE pose, with a
covariance that includes the camera's uncertainty. Where the background pins ``u0p`` only loosely, the
test cannot tell a wrong ``u0p`` from the camera's own uncertainty; the free fit's ``+-`` then says so,
which is why lifting the assumptions is the default (:data:`MODES`). Either fit with the background also
pins the camera's focal length, the single pose's weakest parameter.

While ``alpha_p`` is not freed it is ``1 +- 0.003`` (a prior) rather than exactly 1, so that the ``+-``
of ``f_p`` covers square-ish projector pixels (the paper's simulated projector has 1.002).

Robustness (the background is arbitrary: partly unlit, shadowed, with interreflections that decode
wrong):

* the noise is measured, not assumed: first from each point's difference to the median of its
  neighbours (a model error is a smooth field, decoding errors are not), then as the robust scale
  (median absolute deviation) of the inliers' residuals;
* points that disagree with their neighbours are left out, a first fit uses a graduated Cauchy loss on
  the background (the corners stay quadratic), and points beyond ``outlier_k`` noise sigmas are left
  out of the final fits;
* a background that does not follow one epipolar geometry (``u0p`` fitted per quadrant of the points
  disagrees: a reflective or moving surface, interreflections that decode consistently wrong) is no
  check;
* too few points off the board's plane, or a background that does not pin ``u0p`` (too small, nearly
  coplanar with the board): no check, with the reason, never a false alarm.

The points come from the decoded maps (:func:`procam.correspond.background_points`, re-exported here);
:mod:`procam.pipeline` keeps them in ``View.background`` and :func:`procam.single_pose.calibrate` applies
:func:`apply` after its projector fit.
"""

from __future__ import annotations

import warnings as _warnings
from dataclasses import dataclass, field
from itertools import pairwise

import numpy as np

from .. import models
from ..calibration import Calibration
from ..correspond import background_points
from ..errors import CalibrationError, ModelErrorWarning
from ..parameters import ALPHA_PRIOR_STD
from ..stats import robust_sigma
from . import joint as J
from .background_fit import BackgroundFit, PaperFits, _single_pose_parts, epipolar
from .. import choices

__all__ = ["FREEABLE", "MODES", "BackgroundCheck", "BackgroundFit", "BackgroundOptions", "apply", "background_points",
           "epipolar_check", "epipolar_distances", "parallax", "refine_projector"]

#: What :func:`apply` does: ``off`` (nothing), ``check`` (warn on a model error; numbers unchanged),
#: ``free`` (the default: the warning, and the assumptions lifted with the background whenever it is
#: informative), ``auto`` (the warning; the assumptions kept, with the background, when the check finds them
#: consistent, lifted when it does not -- more precise when they hold, but a weak background then keeps a
#: wrong assumption with a too small +-; see ``benchmarks/background.py``).
MODES = choices.BACKGROUND_MODES
#: Projector parameters the background can free.
FREEABLE = ("u0p", "alpha_p")



@dataclass(frozen=True)
class BackgroundOptions:
    """Options of the background check and refinement.

    Attributes
    ----------
    mode : one of :data:`MODES` (default ``free``).
    free : the projector parameters the background may free, in the order they are freed (nested models:
        assumed, ``u0p``, ``u0p+alpha_p``); default ``("u0p",)`` (``alpha_p`` then has the prior
        ``alpha_prior_std``). The check tests the assumed model against the freest one; a further parameter
        is freed only when it improves the fit significantly.
    false_alarm : probability that the check reports a model error when the assumptions hold (the
        likelihood-ratio test's level; default 1e-4).
    min_points : fewer background points off the board's plane than this: no check.
    min_parallax_px : a point counts as off the board's plane when it is at least this far (projector
        pixels) from where the board's plane would put it.
    outlier_k : points whose epipolar distance exceeds this many noise sigmas (after the robust fit) are
        left out (wrong decoding, interreflections).
    max_std_fraction : no check when the background pins ``u0p`` no better than this fraction of the
        projector width (1 sigma): it is too small or too flat.
    noise_floor_px : the smallest noise (projector px) the test assumes, whatever the data say.
    max_points : at most this many background points are used (a regular subsample).
    alpha_prior_std : while ``alpha_p`` is not freed, it is ``1 +- alpha_prior_std`` (a Gaussian prior: square
        projector pixels to within a few tenths of a percent) rather than exactly 1, so that the ``+-`` of
        ``f_p`` includes that assumption; 0 fixes it at 1.
    """

    mode: str = "free"
    free: tuple = ("u0p",)
    false_alarm: float = 1e-4
    min_points: int = 200
    min_parallax_px: float = 2.0
    outlier_k: float = 4.0
    max_std_fraction: float = 0.05
    noise_floor_px: float = 0.05
    max_points: int = 4000
    alpha_prior_std: float = ALPHA_PRIOR_STD

    def __post_init__(self):
        if self.mode not in MODES:
            raise ValueError(f"background mode must be one of {', '.join(MODES)}, got {self.mode!r}")
        free = tuple(self.free)
        if not free or any(f not in FREEABLE for f in free) or len(set(free)) != len(free):
            raise ValueError(f"background free parameters must be distinct names from {', '.join(FREEABLE)}, "
                             f"got {self.free!r}")
        object.__setattr__(self, "free", tuple(p for p in FREEABLE if p in free))
        for name, lo, hi in (("false_alarm", 0.0, 0.5), ("min_parallax_px", 0.0, 1e4), ("outlier_k", 2.0, 100.0),
                             ("max_std_fraction", 0.0, 10.0), ("noise_floor_px", 0.0, 100.0),
                             ("alpha_prior_std", 0.0, 0.5)):
            v = getattr(self, name)
            ok = isinstance(v, (int, float, np.number)) and np.isfinite(v) and lo <= v <= hi
            if not ok or (name == "false_alarm" and v == 0) or (name == "max_std_fraction" and v == 0):
                raise ValueError(f"background {name} must be a finite number from {lo:g} to {hi:g}, got {v!r}")
        for name in ("min_points", "max_points"):
            v = getattr(self, name)
            if not (isinstance(v, (int, np.integer)) and 10 <= v <= 10 ** 7):
                raise ValueError(f"background {name} must be an integer from 10 to 1e7, got {v!r}")


@dataclass(frozen=True)
class BackgroundCheck:
    """Result of :func:`epipolar_check`.

    Attributes
    ----------
    status : ``"model error"``, ``"consistent"`` or ``"no check"``.
    model_error : True only for ``"model error"``.
    message : one line for the user (says ``model error``, the size in projector pixels and the assumption).
    reason : why there is no check (empty otherwise).
    n_points : background points given (finite); ``n_off_plane`` of them at least ``min_parallax_px`` off
        the board's plane; ``n_used`` kept after outlier rejection; ``inlier_fraction = n_used / n_points``.
    size_px : median |distance| (projector px) of the background points to their epipolar lines under the
        calibration as it was given: the size of the disagreement.
    p90_px : 90th percentile of that |distance|.
    noise_px : robust noise of the distances after the free fit (px).
    parallax_px : median distance of the points from where the board's plane would put them (px).
    statistic, threshold, dof : the likelihood-ratio statistic, its threshold and degrees of freedom.
    assumed : dict of the assumed values (``u0p``, ``alpha_p``) and ``estimate`` / ``estimate_std`` the
        free fit's values of the same parameters.
    fits : name -> :class:`BackgroundFit` of the nested models: ``"assumed"``, ``"u0p"``, ``"u0p+alpha_p"``
        (as ``options.free``; empty for most ``no check`` cases).
    selected : the model the background supports: ``"assumed"`` when consistent, else the smallest freed
        model that the next freed parameter does not improve significantly (forward selection); empty for
        ``no check``.
    """

    status: str
    message: str
    reason: str = ""
    n_points: int = 0
    n_off_plane: int = 0
    n_used: int = 0
    inlier_fraction: float = float("nan")
    size_px: float = float("nan")
    p90_px: float = float("nan")
    noise_px: float = float("nan")
    parallax_px: float = float("nan")
    statistic: float = float("nan")
    threshold: float = float("nan")
    dof: int = 0
    assumed: dict = field(default_factory=dict)
    estimate: dict = field(default_factory=dict)
    estimate_std: dict = field(default_factory=dict)
    fits: dict = field(default_factory=dict, compare=False, repr=False)
    selected: str = ""

    @property
    def model_error(self) -> bool:
        return self.status == "model error"

    def to_dict(self) -> dict:
        """JSON-able summary (no fits)."""
        out = {}
        for k in ("status", "message", "reason", "selected", "n_points", "n_off_plane", "n_used", "inlier_fraction", "size_px",
                  "p90_px", "noise_px", "parallax_px", "statistic", "threshold", "dof"):
            v = getattr(self, k)
            out[k] = v if isinstance(v, str) else (int(v) if isinstance(v, (int, np.integer)) else float(v))
        for k in ("assumed", "estimate", "estimate_std"):
            out[k] = {n: float(v) for n, v in getattr(self, k).items()}
        out["model_error"] = self.model_error
        return out


# --------------------------------------------------------------------------------------------------
# geometry
# --------------------------------------------------------------------------------------------------

def _stereo(calibration):
    if calibration.projector is None or calibration.R is None or calibration.T is None:
        raise CalibrationError("the background check needs a procam calibration (camera, projector, R and T)")
    return np.asarray(calibration.R, float), np.asarray(calibration.T, float).reshape(3)


def _points(cam_pts, proj_pts):
    cam = np.asarray(cam_pts, float).reshape(-1, 2)
    proj = np.asarray(proj_pts, float).reshape(-1, 2)
    if len(cam) != len(proj):
        raise ValueError(f"background camera and projector points differ in number: {len(cam)} vs {len(proj)}")
    ok = np.isfinite(cam).all(1) & np.isfinite(proj).all(1)
    return cam[ok], proj[ok]


def epipolar_distances(calibration, cam_pts, proj_pts) -> np.ndarray:
    """Signed distance (projector px) of each projector point to the epipolar line of its camera point.

    Parameters
    ----------
    calibration : :class:`~procam.calibration.Calibration` with a projector and ``(R, T)`` (the projector's
        distortion, if any, is removed from ``proj_pts`` first).
    cam_pts : (M, 2) distorted camera pixels; proj_pts : (M, 2) projector pixels.

    Returns
    -------
    (M,) float: ``l . p / |l[:2]|`` with ``l = F m``, ``F = K_p^-T [T]x R K_c^-1`` on undistorted pixels;
    NaN where a point is NaN.
    """
    R, T = _stereo(calibration)
    cam = np.asarray(cam_pts, float).reshape(-1, 2)
    proj = calibration.projector.undistort(np.asarray(proj_pts, float).reshape(-1, 2))
    und = calibration.camera.undistort(cam)
    return epipolar(calibration.camera.K, und, np.asarray(calibration.projector.K, float), R, T, proj)


def _plane_homography(Kc, Rc, tc, Kp, R, T):
    """Undistorted camera pixels -> projector pixels of points on the board plane (board -> camera pose)."""
    n = Rc[:, 2]
    dist = float(n @ tc)
    return Kp @ (R + np.outer(T, n) / dist) @ np.linalg.inv(Kc)


def parallax(calibration, cam_pts, proj_pts, R_board=None, t_board=None) -> np.ndarray:
    """Distance (projector px, (M,)) of each projector point from where the board's plane would put it.

    Zero for a point on the board's plane (it says nothing about the epipolar geometry); the background's
    information grows with it. ``R_board, t_board``: the board -> camera pose (default: the single-pose
    camera solution's, ``calibration.info["camera"]``).
    """
    R, T = _stereo(calibration)
    if R_board is None:
        cs = calibration.info.get("camera")
        if cs is None:
            raise CalibrationError("parallax needs the board pose (R_board, t_board)")
        R_board, t_board = cs.R, cs.t
    H = _plane_homography(np.asarray(calibration.camera.K, float), np.asarray(R_board, float),
                          np.asarray(t_board, float).reshape(3), np.asarray(calibration.projector.K, float), R, T)
    und = calibration.camera.undistort(np.asarray(cam_pts, float).reshape(-1, 2))
    proj = calibration.projector.undistort(np.asarray(proj_pts, float).reshape(-1, 2))
    return np.linalg.norm(models.apply_homography(H, und) - proj, axis=1)


def _local_noise(cam, d):
    """Robust noise scale of ``d`` that ignores a smooth field and outliers: each value minus the median of
    its 8 nearest neighbours (camera image), MAD-scaled for that difference's variance (about 1.2 sigma^2).

    Returns (scale, the differences (M,)).
    """
    from scipy.spatial import cKDTree

    if len(d) < 20:
        return float("nan"), np.zeros(len(d))
    _, idx = cKDTree(cam).query(cam, k=9)
    e = d - np.median(d[idx[:, 1:]], axis=1)
    return robust_sigma(e) / float(np.sqrt(1.2)), e



# --------------------------------------------------------------------------------------------------
# check and refinement
# --------------------------------------------------------------------------------------------------

def _assumption_words(cal, ps) -> tuple[str, dict]:
    W = cal.projector.image_size[0]
    u0 = float(ps.u0)
    where = f"u0p = W/2 = {u0:g} px" if abs(u0 - W / 2) < 1e-9 else f"u0p = {u0:g} px (given)"
    return f"{where}, alpha_p = 1", {"u0p": u0, "alpha_p": 1.0}


def _no_check(reason, **kw) -> BackgroundCheck:
    return BackgroundCheck(status="no check", message=f"background check not possible: {reason}", reason=reason, **kw)


def epipolar_check(calibration, cam_pts, proj_pts, options: BackgroundOptions = BackgroundOptions()) -> BackgroundCheck:
    """Does the background agree with a single-pose calibration's epipolar geometry?

    Parameters
    ----------
    calibration : a :func:`procam.single_pose.calibrate` result (its camera and projector solutions and
        its view are used).
    cam_pts : (M, 2) distorted camera pixels of the background; proj_pts : (M, 2) projector pixels
        decoded there (:func:`background_points`). Rows with a NaN are ignored.
    options : :class:`BackgroundOptions`.

    Returns
    -------
    :class:`BackgroundCheck`. ``model error`` when the likelihood-ratio test of the projector's assumptions
    (module docstring) rejects them at ``options.false_alarm``; its message gives the disagreement in
    projector pixels and where the background puts ``u0p``. ``no check`` (with the reason) when the
    calibration is not a single-pose one, the background has fewer than ``min_points`` points off the
    board's plane, or it does not pin ``u0p`` (too small or too flat).
    """
    cam, proj = _points(cam_pts, proj_pts)
    n = len(cam)
    parts, why = _single_pose_parts(calibration)
    if parts is None:
        return _no_check(why, n_points=n)
    cs, ps = parts
    words, assumed = _assumption_words(calibration, ps)
    if n > options.max_points:
        step = int(np.ceil(n / options.max_points))
        cam, proj = cam[::step], proj[::step]
        n = len(cam)
    if n == 0:
        return _no_check("no decoded background (nothing off the board is lit and decoded in column and row)",
                         assumed=assumed)
    d0 = epipolar_distances(calibration, cam, proj)
    with np.errstate(all="ignore"):
        par = parallax(calibration, cam, proj)
    off = np.isfinite(par) & (par >= options.min_parallax_px)
    base = {"n_points": n, "n_off_plane": int(off.sum()), "size_px": float(np.median(np.abs(d0))),
            "p90_px": float(np.percentile(np.abs(d0), 90)), "parallax_px": float(np.median(par)), "assumed": assumed}
    if off.sum() < options.min_points:
        return _no_check(f"only {int(off.sum())} of {n} background points are {options.min_parallax_px:g} px or "
                         f"more off the board's plane (need {options.min_points}); the background is too small or "
                         "too flat", **base)
    # 1. a robust fit of the freest model with the local noise, 2. the noise from its residuals, outliers
    # out, 3. every nested model on the same points with the same noise
    sigma0, local = _local_noise(cam, d0)
    sigma0 = max(sigma0, options.noise_floor_px) if np.isfinite(sigma0) else max(robust_sigma(d0), options.noise_floor_px)
    nested = [options.free[:k] for k in range(len(options.free) + 1)]
    top = PaperFits(calibration, cs, ps, cam, proj, nested[-1], sigma0, options.alpha_prior_std)
    # a model error is a smooth field: points that disagree with their neighbours are decoding errors
    top.keep = np.abs(local) <= options.outlier_k * sigma0
    warm = top.solve(top.start(), robust=True)
    r = top.distances(warm)
    sigma_n = max(robust_sigma(r), options.noise_floor_px)
    keep = np.abs(r - np.median(r)) <= options.outlier_k * sigma_n
    if keep.sum() > 20:     # the MAD of a sample with outliers overstates the inliers' noise: once more on them
        sigma_n = max(robust_sigma(r[keep]), options.noise_floor_px)
        keep = np.abs(r - np.median(r[keep])) <= options.outlier_k * sigma_n
    base.update(n_used=int(keep.sum()), inlier_fraction=float(keep.mean()), noise_px=sigma_n)
    if (keep & off).sum() < options.min_points:
        return _no_check(f"only {int((keep & off).sum())} background points off the board's plane agree with any "
                         f"epipolar geometry within {options.outlier_k:g} x the noise ({sigma_n:.2f} px); the "
                         "decoded background is unreliable", **base)
    fits, solved = {}, {}
    for free in nested:
        joint = PaperFits(calibration, cs, ps, cam, proj, free, sigma_n, options.alpha_prior_std)
        joint.keep = keep
        # the assumed model from the single-pose solution too: an unconverged fit would inflate the statistic
        p = joint.solve_best([joint.start(), joint.start(warm)] if not free else [joint.start(warm)])
        solved[free] = (joint, p)
        fits[_model_name(free)] = joint.fit_result(p, _model_name(free))
    # a background that does not follow ONE epipolar geometry (interreflections, a reflective or moving
    # surface) must not raise an alarm: u0p fitted separately on the quadrants of the points must agree
    split = _inconsistent_quadrants(calibration, cs, ps, cam, proj, keep, sigma_n, options, warm,
                                    solved.get(("u0p",)))
    if split:
        return _no_check(split, **base)
    first = fits[_model_name(nested[1])]
    W = calibration.projector.image_size[0]
    name0 = nested[1][0]
    s0 = first.std[name0]
    limit = options.max_std_fraction * (W if name0 == "u0p" else 1.0)
    last = fits[_model_name(nested[-1])]
    est = {k: float(last.params[J.IDX[k]]) for k in nested[-1]}
    est_std = {k: last.std[k] for k in nested[-1]}
    base.update(estimate=est, estimate_std=est_std, fits=fits)
    if not (np.isfinite(s0) and s0 <= limit):
        return _no_check(f"the background pins {name0} only to +-{s0:.3g} (need {limit:.3g}); it is too small or "
                         "too flat", **base)
    held = fits["assumed"]
    dof = len(nested[-1])
    stat = max(held.cost - last.cost, 0.0)
    thr = _chi2_isf(options.false_alarm, dof)
    base.update(statistic=stat, threshold=thr, dof=dof)
    where = ", ".join(f"{k} = {est[k]:.{0 if k == 'u0p' else 4}f} +- {est_std[k]:.{0 if k == 'u0p' else 4}f}"
                      + (" px" if k == "u0p" else "") for k in est)
    if stat > thr:
        msg = (f"model error: the background ({int(keep.sum())} points) disagrees with the calibration's epipolar "
               f"geometry by {base['size_px']:.1f} px (median distance to the epipolar lines, projector pixels; "
               f"decoding noise {sigma_n:.2f} px), beyond what the calibration's uncertainty allows (likelihood "
               f"ratio {stat:.0f} > {thr:.0f}); the projector assumption {words} is probably wrong (the background "
               f"puts {where}), so the single-pose f_p = {calibration.projector.K[0, 0]:.1f} +- "
               f"{calibration.std.get('f_p', float('nan')):.1f} px, v0p and R, T are biased beyond their +-")
        return BackgroundCheck(status="model error", message=msg, selected=_select(fits, nested, options), **base)
    msg = (f"background check: {int(keep.sum())} points agree with the calibration's epipolar geometry within its "
           f"uncertainty (median distance {base['size_px']:.2f} px, noise {sigma_n:.2f} px; likelihood ratio "
           f"{stat:.1f} <= {thr:.0f}); the projector assumption {words} is consistent with them ({where})")
    return BackgroundCheck(status="consistent", message=msg, selected="assumed", **base)


def _inconsistent_quadrants(calibration, cs, ps, cam, proj, keep, sigma_n, options, warm, one=None) -> str:
    """A reason when u0p differs between the quadrants of the background (split at the medians along the
    principal directions of the points in the camera image) beyond ``false_alarm`` (likelihood ratio of one
    u0p per quadrant against one for all, 3 degrees of freedom); "" otherwise. ``one``: the solved
    (joint, x) with one u0p, if at hand."""
    pts = cam[keep]
    _, _, Vt = np.linalg.svd(pts - pts.mean(0), full_matrices=False)
    s = cam @ Vt.T
    groups = (s[:, 0] > np.median(s[keep, 0])).astype(int) + 2 * (s[:, 1] > np.median(s[keep, 1]))
    if one is None:
        base = PaperFits(calibration, cs, ps, cam, proj, ("u0p",), sigma_n, options.alpha_prior_std)
        base.keep = keep
        one = (base, base.solve(base.start(warm)))
    base, p1 = one
    four = PaperFits(calibration, cs, ps, cam, proj, ("u0p",), sigma_n, options.alpha_prior_std, groups=groups)
    four.keep = keep
    p4 = four.solve(four.start(p1))
    stat = base.cost(p1) - four.cost(p4)
    thr = _chi2_isf(options.false_alarm, 3)
    if stat > thr:
        u0 = [p4[J.IDX["u0p"]], *p4[len(J.NAMES):]]
        return (f"the background's quadrants do not fit one epipolar geometry: one u0p per quadrant fits their "
                f"epipolar distances better than one for all by a likelihood ratio of {stat:.0f} (threshold {thr:.0f} "
                f"for noise {sigma_n:.2f} px; the quadrants' u0p are {', '.join(f'{u:.1f}' for u in u0)} px): "
                "interreflections, a reflective or moving surface, or a lens the paper's projector model does not "
                "describe (the dense fit models the projector's distortion)")
    return ""


def _model_name(free) -> str:
    return "+".join(free) if free else "assumed"


def _chi2_isf(p: float, dof: int) -> float:
    """The chi-square quantile exceeded with probability ``p`` (``dof`` degrees of freedom)."""
    from scipy.special import chdtri

    return float(chdtri(dof, p))


def _select(fits, nested, options) -> str:
    """Forward selection among the freed models: free the next parameter while its likelihood ratio (1 degree
    of freedom) passes the threshold; at least the first freed model."""
    thr1 = _chi2_isf(options.false_alarm, 1)
    chosen = _model_name(nested[1])
    for a, b in pairwise(nested[1:]):
        if fits[_model_name(a)].cost - fits[_model_name(b)].cost > thr1:
            chosen = _model_name(b)
        else:
            break
    return chosen


def refine_projector(calibration, cam_pts, proj_pts, *, free=("u0p",), options: BackgroundOptions | None = None):
    """Lift the single-pose projector assumptions with the background: the joint fit with ``free`` freed.

    ``f_p, v0p``, the parameters ``free`` (``u0p``, and ``alpha_p`` with care: it needs a background that pins
    it), the projector's board pose and the camera from both devices' board corners and the background's
    epipolar distances (module docstring), robustly.

    Returns
    -------
    (:class:`BackgroundFit` or None, :class:`BackgroundCheck`): the fit (its ``calibration``, ``std`` with
    the camera's uncertainty included) is None -- keep the paper's assumption -- when the background is too
    small or too flat (the check says why).
    """
    o = options or BackgroundOptions()
    o = BackgroundOptions(**{**o.__dict__, "free": tuple(free)})
    check = epipolar_check(calibration, cam_pts, proj_pts, o)
    fit = check.fits.get(_model_name(o.free)) if check.status != "no check" else None
    return fit, check


def apply(calibration, cam_pts, proj_pts, options: BackgroundOptions = BackgroundOptions()) -> Calibration:
    """A single-pose calibration with the background's verdict (and, by ``options.mode``, its refinement).

    ``info["background"]`` holds the :class:`BackgroundCheck` and ``info["background_model"]`` which model the
    result is (``"single-pose"`` = unchanged, or a :class:`BackgroundFit` model name); the first pose's
    dict gets ``"background"`` (:meth:`BackgroundCheck.to_dict`). A model error adds its message to ``warnings``
    (and, when the result lifts the assumptions, the refined values). See :data:`MODES`.
    """
    if options.mode == "off":
        return calibration
    check = epipolar_check(calibration, cam_pts, proj_pts, options)
    warnings = list(calibration.warnings)
    chosen = "single-pose"
    out = calibration
    if check.status != "no check" and options.mode in ("auto", "free"):
        chosen = check.selected
        if options.mode == "free" and chosen == "assumed":
            chosen = _select(check.fits, [options.free[:k] for k in range(len(options.free) + 1)], options)
        out = check.fits[chosen].calibration
    if check.model_error:
        msg = check.message
        if chosen not in ("single-pose", "assumed"):
            Kp = out.projector.K
            msg += (f"; refined with {chosen.replace('+', ' and ')} from the background: f_p = {Kp[0, 0]:.1f} +- "
                    f"{out.std['f_p']:.1f}, u0p = {Kp[0, 2]:.1f} +- {out.std.get('u0p', 0.0):.1f}, v0p = "
                    f"{Kp[1, 2]:.1f} +- {out.std['v0p']:.1f} px")
            if "alpha_p" in chosen:
                msg += f", alpha_p = {Kp[1, 1] / Kp[0, 0]:.4f} +- {out.std['alpha_p']:.4f}"
        warnings.append(msg)
    verdict, reasons = out.verdict, tuple(out.verdict_reasons)
    if check.model_error and chosen in ("single-pose", "assumed"):
        # the assumptions do not hold and the result keeps them: its +- does not cover that
        reasons = reasons + (msg,)
        verdict = "weak" if verdict == "good" else verdict
        _warnings.warn(msg, ModelErrorWarning, stacklevel=3)
    info = dict(out.info)
    info.update(background=check, background_model=chosen)
    poses = tuple({**p, "background": check.to_dict()} if k == 0 else p for k, p in enumerate(out.poses))
    return out.replace(warnings=tuple(warnings), info=info, poses=poses, verdict=verdict, verdict_reasons=reasons)
