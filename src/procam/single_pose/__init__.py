"""The seed method: procam calibration from ONE pose of a planar chessboard (Lawal & Greenspan).

Pipeline per pose -- camera, then projector, then the procam extrinsics:

1. the camera (:mod:`.camera`): centre of distortion and division model, the principal point, the
   principal-axis LM, the joint refinement on the distorted corners;
2. the projector (:mod:`.projector`): ``f_p``, ``v0p`` and the pose with ``u0p`` fixed, ``alpha_p = 1``;
3. ``R = R_p R_c^T, T = t_p - R t_c`` (camera -> projector, as OpenCV ``stereoCalibrate``);
4. the verdict (:mod:`.advice`): pose angles, the paper's rule and the true degeneracy conditions, the
   standard deviation of every parameter from the Jacobian at the solution (:mod:`procam.uncertainty`),
   and whether a focal length is plausible at all.

Both devices' fits use only corners a robust rule keeps (:mod:`._robust`): outliers are rejected,
reported and refitted without; too few or collinear corners raise
:class:`~procam.errors.CalibrationError` saying how many are usable and needed.

Board frame: corner k at ``(i s, j s, 0) - centroid``; pose ``(R, t)`` maps board -> device. Angles are
reported in degrees, in a board frame whose z axis points away from the device (fronto-parallel <=>
psi = nu = 0).
"""

from __future__ import annotations

import numpy as np

from .. import background as _background
from .. import models
from .. import uncertainty as unc
from ..calibration import Calibration, Device, Distortion
from ..errors import CalibrationError
from ..residuals import pnp, rms, stereo_pose
from ._robust import RobustOptions, check_corners, clean, robust_sigma
from .advice import AdviceOptions, advice, judge
from .camera import COD_MODES, REFINE_MODES, CameraOptions, CameraSolution, calibrate_camera
from .projector import ProjectorOptions, ProjectorSolution, calibrate_projector

__all__ = ["calibrate", "calibrate_camera_only", "calibrate_camera", "calibrate_projector", "extrinsics", "advice",
           "CameraOptions", "ProjectorOptions", "RobustOptions", "AdviceOptions", "CameraSolution",
           "ProjectorSolution", "COD_MODES", "REFINE_MODES", "robust_sigma"]


def _pnp_rms(obj, pts, K) -> float:
    """RMS (px) (the per-device PnP reprojection error) of undistorted ``pts`` with ``K`` fixed (:func:`procam.residuals.pnp`);
    NaN if PnP finds no pose in front of the device."""
    try:
        return rms(pnp(obj, pts, K)[2])
    except CalibrationError:
        return float("nan")


def _stereo_rms(obj, cam_und, proj, Kc, Kp, R, T, R0, t0) -> float:
    """Stereo RMS (px) over camera and projector points (:func:`procam.residuals.stereo_pose`)."""
    _, _, rc, rp = stereo_pose(obj, cam_und, proj, Kc, Kp, R, T, R0, t0)
    return rms([rc, rp])


def extrinsics(cam: CameraSolution, proj: ProjectorSolution):
    """Camera -> projector ``(R, T)`` from the two board poses: ``R = R_p R_c^T, T = t_p - R t_c``."""
    R = proj.R @ cam.R.T
    return R, proj.t - R @ cam.t


def _extrinsics_std(cam: CameraSolution, proj: ProjectorSolution):
    """Delta-method std of (Euler XYZ deg of R, T) from the two independent parameter covariances."""
    pc, pp = cam.params, proj.params
    n = len(pc)
    cov = np.zeros((n + len(pp), n + len(pp)))
    cov[:n, :n] = cam.covariance
    cov[n:, n:] = proj.covariance

    def g(q):
        Rc, tc = models.rvec_to_matrix(q[6:9]), q[9:12]
        Rp, tp = models.rvec_to_matrix(q[n + 2:n + 5]), q[n + 5:n + 8]
        R = Rp @ Rc.T
        return np.concatenate([models.euler_deg(R), tp - R @ tc])

    C = unc.propagate(cov, g, np.concatenate([pc, pp]), typical=np.r_[np.ones(n), np.ones(len(pp))])
    s = np.sqrt(np.abs(np.diag(C)))
    return s[:3], s[3:]


def _std_dict(cam: CameraSolution, proj: ProjectorSolution | None) -> dict:
    s = {"f_c": cam.std["f_c"], "alpha_c": cam.std["alpha_c"], "fy_c": cam.std["fy_c"], "u0c": cam.std["u0c"],
         "v0c": cam.std["v0c"], "k1": cam.std["k1"], "k2": cam.std["k2"],
         "camera_angles_deg": [float(v) for v in cam.std["angles_deg"]]}
    if proj is not None:
        s.update({"f_p": proj.std["f_p"], "v0p": proj.std["v0p"],
                  "projector_angles_deg": [float(v) for v in proj.std["angles_deg"]]})
        r, t = _extrinsics_std(cam, proj)
        s["R_euler_deg"] = [float(v) for v in r]
        s["T"] = [float(v) for v in t]
    return s


def _rejected_list(sol) -> list:
    return [{"index": int(i), "residual_px": float(r)} for i, r in zip(sol.rejected, sol.rejected_residuals_px)]


def calibrate(view, proj_size=None, *, camera: CameraOptions = CameraOptions(),
              projector: ProjectorOptions = ProjectorOptions(), robust: RobustOptions = RobustOptions(),
              advice_options: AdviceOptions = AdviceOptions(), cam_size=None, strict: bool = False,
              on_failure: str = "raise", background: _background.BackgroundOptions | None = None) -> Calibration:
    """Single-pose procam calibration of one :class:`procam.view.View`.

    Parameters
    ----------
    view : View -- only corners with finite camera AND projector points (``view.valid``) are used.
    proj_size : (W, H) of the projector (default ``view.proj_size``).
    camera : :class:`CameraOptions` (principal point, distortion, refinement).
    projector : :class:`ProjectorOptions` (``u0``).
    robust : :class:`RobustOptions` -- minimum corners and outlier rejection, for both devices.
    advice_options : :class:`AdviceOptions` -- the verdict's thresholds.
    cam_size : (W, H) of the camera (default ``view.cam_size``).
    strict : raise :class:`CalibrationError` on a degenerate pose instead of warning.
    on_failure : ``"raise"`` (default: raise :class:`CalibrationError` when an estimated focal length is
        impossible, see :func:`advice`) or ``"warn"`` (return it, flagged ``failed`` in the advice, with a
        warning).
    background : :class:`procam.background.BackgroundOptions` (default: mode ``free``) -- used only when
        ``view.background`` holds decoded points off the board: the check of the projector's assumptions
        against them (a ``model error`` warning) and, by its mode, the joint refinement
        (:func:`procam.background.apply`). Without ``view.background`` the result is the paper's method alone.

    Returns
    -------
    Calibration
        ``method="single-pose"``; camera with division distortion, projector without; ``R, T``
        camera -> projector; ``cam_rms, proj_rms`` (per-device PnP RMS on this pose, outliers excluded),
        ``stereo_rms`` (corners used by both devices); ``std`` with ``f_c, alpha_c, fy_c, u0c,
        v0c, k1, k2, f_p, v0p, R_euler_deg (3), T (3)`` and the board angles' std; one entry in
        ``poses`` with the angles, :func:`advice`, ``rejected_corners`` (``{"camera": [{"index",
        "residual_px"}, ...], "projector": [...]}``, indices into the view's corners) and
        ``outlier_threshold_px``; ``info["camera"]``/``info["projector"]`` hold the full solutions.

    Raises
    ------
    CalibrationError
        Too few usable corners (the message says how many are usable and needed), corners on one
        line, no valid solution, an impossible focal length (``on_failure="raise"``), or a degenerate
        pose with ``strict``.
    """
    cam_size = cam_size or view.cam_size
    proj_size = proj_size or view.proj_size
    name = view.name
    obj_all = view.obj_pts
    valid = view.valid & np.isfinite(obj_all).all(1)
    check_corners(obj_all, valid, robust.min_points, name,
                   "corners (with finite camera and projector coordinates)", "check the board detection and decoding")

    def only_valid(a):
        return np.where(valid[:, None], a, np.nan)

    # NaN for corners invalid in either device, so that both fits use the same corners and the
    # rejected corners' indices are the view's
    cam = calibrate_camera(obj_all, only_valid(view.cam_pts), cam_size, camera, robust=robust, name=name)
    proj = calibrate_projector(obj_all, only_valid(view.proj_pts), proj_size, projector, robust=robust, name=name)
    R, T = extrinsics(cam, proj)
    std = _std_dict(cam, proj)
    adv = advice(cam.angles_deg, proj.angles_deg, std, values={"f_c": cam.K[0, 0], "f_p": proj.K[0, 0]},
                 camera_size=cam.image_size, projector_size=proj.image_size, options=advice_options)
    warnings = list(cam.warnings) + list(proj.warnings)
    judge(adv, name, strict, on_failure, warnings)
    cin, pin = cam.mask, proj.mask
    both = cin & pin
    with np.errstate(all="ignore"):
        cam_und = cam.distortion.undistort(only_valid(view.cam_pts), cam.K)
    proj_pts = view.proj_pts
    cam_rms = _pnp_rms(obj_all[cin], cam_und[cin], cam.K)
    proj_rms = _pnp_rms(obj_all[pin], proj_pts[pin], proj.K)
    stereo = _stereo_rms(obj_all[both], cam_und[both], proj_pts[both], cam.K, proj.K, R, T, cam.R, cam.t)
    pose = {"name": name, "camera_angles_deg": [float(a) for a in cam.angles_deg],
            "projector_angles_deg": [float(a) for a in proj.angles_deg], "advice": adv,
            "cam_rms": cam_rms, "proj_rms": proj_rms, "stereo_rms": stereo, "n_corners": int(valid.sum()),
            "n_used": {"camera": int(cin.sum()), "projector": int(pin.sum())},
            "rejected_corners": {"camera": _rejected_list(cam), "projector": _rejected_list(proj)},
            "outlier_threshold_px": {"camera": cam.outlier_threshold_px, "projector": proj.outlier_threshold_px}}
    cal = Calibration(camera=Device(cam.K, tuple(cam.image_size), cam.distortion),
                      projector=Device(proj.K, tuple(proj.image_size), Distortion()), R=R, T=T,
                      method="single-pose", cam_rms=cam_rms, proj_rms=proj_rms, stereo_rms=stereo, std=std,
                      poses=(pose,), views=(view,), warnings=tuple(warnings),
                      info={"camera": cam, "projector": proj, "principal_point_source": cam.principal_point_source,
                            "cod_score": None if cam.cod is None else cam.cod.score,
                            "refine": cam.info["refine"]})
    # the background behind the board (procam.background): the check, and the refinement, of the projector's
    # assumptions -- only when the view carries decoded background points
    bg = getattr(view, "background", None)
    if bg is not None:
        cal = _background.apply(cal, bg.cam_pts, bg.proj_pts, background or _background.BackgroundOptions())
    return cal


def calibrate_camera_only(obj_pts, cam_pts, image_size, *, camera: CameraOptions = CameraOptions(),
                          robust: RobustOptions = RobustOptions(), advice_options: AdviceOptions = AdviceOptions(),
                          name: str = "view", strict: bool = False, on_failure: str = "raise") -> Calibration:
    """Camera-only single-pose calibration (one photo of a chessboard, no projector): K and division distortion.

    Options as :func:`calibrate`. Returns a :class:`Calibration` with ``projector=None, R=T=None``, ``cam_rms``
    (PnP RMS on this pose, outliers excluded), ``std`` and one pose entry (with
    ``rejected_corners``).
    """
    cam = calibrate_camera(obj_pts, cam_pts, image_size, camera, robust=robust, name=name)
    std = _std_dict(cam, None)
    adv = advice(cam.angles_deg, None, std, values={"f_c": cam.K[0, 0]}, camera_size=cam.image_size,
                 options=advice_options)
    warnings = list(cam.warnings)
    judge(adv, name, strict, on_failure, warnings)
    obj, pts, finite = clean(obj_pts, cam_pts, name)
    mask = cam.mask
    cam_rms = _pnp_rms(obj[mask], cam.distortion.undistort(pts[mask], cam.K), cam.K)
    pose = {"name": name, "camera_angles_deg": [float(a) for a in cam.angles_deg], "projector_angles_deg": None,
            "advice": adv, "cam_rms": cam_rms, "n_corners": int(finite.sum()),
            "n_used": {"camera": int(mask.sum())}, "rejected_corners": {"camera": _rejected_list(cam)},
            "outlier_threshold_px": {"camera": cam.outlier_threshold_px}}
    return Calibration(camera=Device(cam.K, tuple(cam.image_size), cam.distortion), projector=None, R=None, T=None,
                       method="camera-only", cam_rms=cam_rms, std=std, poses=(pose,), warnings=tuple(warnings),
                       info={"camera": cam, "principal_point_source": cam.principal_point_source,
                             "cod_score": None if cam.cod is None else cam.cod.score, "refine": cam.info["refine"]})
