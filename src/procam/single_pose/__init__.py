"""The seed method: procam calibration from ONE pose of a planar chessboard (Lawal & Greenspan).

Pipeline per pose -- camera, then projector, then the procam extrinsics:

1. the camera (:mod:`.camera`): centre of distortion and division model, the principal point, the
   principal-axis LM, the joint refinement on the distorted corners;
2. the projector (:mod:`.projector`): ``f_p``, ``v0p`` and the pose with ``u0p`` fixed, ``alpha_p = 1``;
3. ``R = R_pb R_cb^T, T = t_pb - R t_cb`` (camera -> projector, as OpenCV ``stereoCalibrate``);
4. the verdict (:mod:`.rating`): pose angles, the paper's rule and the true degeneracy conditions, the
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

import contextlib
import warnings as _warnings
from dataclasses import replace

import numpy as np

from . import background as _background
from . import dense as _dense
from . import dense_result as _dense_result
from .. import models
from .. import uncertainty as unc
from .._threads import deterministic
from ..calibration import Calibration, Device, Distortion
from ..errors import CalibrationError, DegeneratePoseError, ModelErrorWarning
from ..residuals import pnp, stereo_pose
from ..stats import rms, robust_sigma
from ..verdict.gates import apply_gates
from ..board.labelling import canonical_points, canonical_view, given_labelling
from ._robust import RobustOptions, check_corners, clean, fit_robust, rejection_report
from .camera import COD_MODES, REFINE_MODES, CameraOptions, CameraSolution, calibrate_camera
from .misfit import misfit
from .projector import ProjectorOptions, ProjectorSolution, calibrate_projector, u0_cost
from .rating import Prediction, RatingOptions, judge, predict, rate_pose

__all__ = ["calibrate", "calibrate_camera_only", "calibrate_camera", "calibrate_projector", "known_camera_pose",
           "extrinsics", "rate_pose",
           "CameraOptions", "ProjectorOptions", "RobustOptions", "RatingOptions", "CameraSolution",
           "ProjectorSolution", "COD_MODES", "REFINE_MODES", "BACKGROUND_MODES", "robust_sigma"]

#: The background modes of :func:`calibrate` (:data:`procam.single_pose.background.MODES`).
BACKGROUND_MODES = _background.MODES


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


def _u0p_assumption(view, obj, proj_pts, proj: ProjectorSolution, options: ProjectorOptions,
                    rating_options: RatingOptions) -> dict:
    """What the paper's assumed ``u0p = W/2`` can cost ``f_p`` (:func:`.projector.u0_cost` over a real projector's
    range, ``rating_options.u0p_spread_fraction`` of W), for the rating: none when the user gave ``u0p`` or when the
    view carries a background (:mod:`.background` then checks the assumption against it, or lifts it)."""
    if options.u0 is not None or getattr(view, "background", None) is not None:
        return {}
    spread = rating_options.u0p_spread_fraction * proj.image_size[0]
    if not spread > 0:
        return {}
    cost = u0_cost(obj, proj_pts, proj, spread, view.name)
    return {"projector": (cost, f"the assumed u0p = W/2 (a real projector's u0p may sit {spread:.0f} px, "
                                f"{100 * rating_options.u0p_spread_fraction:g} % of W, off the centre)")}


def extrinsics(cam: CameraSolution, proj: ProjectorSolution):
    """Camera -> projector ``(R, T)`` from the two board poses: ``R = R_pb R_cb^T, T = t_pb - R t_cb``."""
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
        R_cb, t_cb = models.rvec_to_matrix(q[6:9]), q[9:12]
        R_pb, t_pb = models.rvec_to_matrix(q[n + 2:n + 5]), q[n + 5:n + 8]
        R = R_pb @ R_cb.T
        return np.concatenate([models.euler_deg(R), t_pb - R @ t_cb])

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


@contextlib.contextmanager
def _degenerate_if_unsolved(name, predicted: dict, o: RatingOptions):
    """A fit that finds no solution at a pose the stable prediction calls degenerate raises
    :class:`DegeneratePoseError` (the same verdict whatever the fit did), not a plain failure."""
    try:
        yield
    except CalibrationError as e:
        if isinstance(e, DegeneratePoseError):
            raise
        adv = rate_pose(predicted=predicted, options=o)
        bad = [adv[k]["message"] for k in ("camera", "projector")
               if isinstance(adv.get(k), dict) and adv[k]["level"] == "degenerate"]
        if bad:
            raise DegeneratePoseError(f"pose {name!r}: degenerate pose, no solution: " + "; ".join(bad)) from None
        raise


def _with_noise(pred: Prediction | None, sigma, device, o: RatingOptions) -> Prediction | None:
    """The stable prediction for the noise the fit measured, when that is larger than the typical one (the
    bound is linear in the noise)."""
    floor = o.camera_noise_px if device == "camera" else o.projector_noise_px
    if pred is None or sigma is None or not np.isfinite(sigma) or sigma <= floor:
        return pred
    return Prediction(pred.angles_deg, pred.rel_std_f * float(sigma) / pred.sigma_px, pred.f_nominal, float(sigma))


def known_camera_pose(obj_pts, cam_pts, device: Device, *, robust: RobustOptions = RobustOptions(),
                      name: str = "view") -> CameraSolution:
    """The board's pose in a camera whose intrinsics are known: PnP on the undistorted corners, refined on
    the distorted ones, with outlier rejection; the covariance covers the pose only (the intrinsics are
    given, their rows and columns are zero).

    Returns a :class:`CameraSolution` whose ``params`` keep the 12-vector layout (intrinsics and the
    division terms as given or zero; for an OpenCV-model camera the division terms are zero and
    ``distortion`` is the OpenCV one).
    """
    from scipy.optimize import least_squares

    obj, pts, finite = clean(obj_pts, cam_pts, f"pose {name!r}")
    check_corners(obj, finite, robust.min_points, name, "camera corners", "check the board detection")
    K = np.asarray(device.K, float)

    def predict(q, M):
        return device.distortion.distort(models.project(K, models.rvec_to_matrix(q[:3]), q[3:], M), K)

    def fit(used):
        M, m = obj[used], pts[used]
        with np.errstate(all="ignore"):
            und = device.distortion.undistort(m, K)
        ok = np.isfinite(und).all(1)
        try:
            R0, t0, _ = pnp(M[ok], und[ok], K)
        except CalibrationError:
            raise CalibrationError(f"pose {name!r}: no board pose in front of the given camera; are these its "
                                   "intrinsics?") from None
        q0 = np.concatenate([models.matrix_to_rvec(R0), t0])
        sol = least_squares(lambda q: (predict(q, M) - m).ravel(), q0, method="lm", x_scale="jac",
                            xtol=1e-12, ftol=1e-12, gtol=1e-12)
        q = sol.x
        res = predict(q, M) - m
        J = unc.jacobian(lambda v: (predict(v, M) - m).ravel(), q, typical=np.array([0.01, 0.01, 0.01, 1, 1, 1.0]))
        sigma = unc.sigma_from_residuals(res.ravel(), 6)
        cq = unc.covariance(J, sigma)
        R, t = models.rvec_to_matrix(q[:3]), q[3:]
        params = np.concatenate([[K[0, 0], K[1, 1] / K[0, 0], K[0, 2], K[1, 2], 0.0, 0.0], q])
        if device.distortion.model == "division":
            params[4:6] = [device.distortion.k1 * models.KAPPA_SCALE ** 2, device.distortion.k2 * models.KAPPA_SCALE ** 4]
        cov = np.zeros((12, 12))
        cov[6:, 6:] = cq
        residuals = np.full((len(obj), 2), np.nan)
        residuals[used] = -res
        sa = unc.std(unc.propagate(cq, lambda v: models.board_angles_deg(models.rvec_to_matrix(v[:3]), v[3:]), q,
                                   typical=1.0))
        std = {"f_c": 0.0, "alpha_c": 0.0, "fy_c": 0.0, "u0c": 0.0, "v0c": 0.0, "k1": 0.0, "k2": 0.0,
               "angles_deg": sa, "t": unc.std(cq)[3:]}
        return CameraSolution(K=K, distortion=device.distortion, R=R, t=t, rms_px=rms(res), residuals=residuals,
                              std=std, angles_deg=models.board_angles_deg(R, t), cost=float(sol.cost),
                              params=params, covariance=cov, mask=used, image_size=tuple(device.image_size),
                              info={"sigma_px": sigma, "refine": "pose only (intrinsics given)"},
                              principal_point_source="given")

    def predict_all(sol):
        return predict(np.concatenate([models.matrix_to_rvec(sol.R), sol.t]), obj)

    sol, used, thr, notes = fit_robust(fit, predict_all, pts, obj, finite, robust)
    return rejection_report(sol, predict_all, pts, finite, used, thr, notes, name, "camera", robust)


def _misfit(obj, sol, floor_px: float):
    """The misfit test (:mod:`procam.single_pose.misfit`) of a device solution's residuals on the corners it used."""
    res = np.where(sol.mask[:, None], sol.residuals, np.nan)
    return misfit(obj, res, device="camera" if isinstance(sol, CameraSolution) else "projector", floor_px=floor_px)


def _model_error(fits: dict, name, verdict: str, reasons: tuple, warnings: list):
    """Model error makes a good pose weak, with its reason, a warning line and a :class:`ModelErrorWarning`."""
    for mf in fits.values():
        if mf.model_error:
            msg = f"pose {name!r}: {mf.message}"
            warnings.append(msg)
            reasons = reasons + (msg,)
            verdict = "weak" if verdict == "good" else verdict
            _warnings.warn(msg, ModelErrorWarning, stacklevel=3)
    return verdict, reasons


def _pattern_words(fit) -> str:
    """Words for a given camera's residual pattern and what it moves the projector by (``fit.camera_pattern``)."""
    c = fit.camera_pattern
    moved = ", ".join(f"{k} {c[k]:+.3g}" for k in ("f_p", "u0p", "v0p"))
    said = c["message"].replace("; the ± does not cover this", "")
    return (f"{said}; with the camera given it counts by what it does to the projector: it moves {moved} px "
            f"(the ± includes that: f_p ± {fit.std('f_p'):.3g} px)")


def _misfit_dict(mf) -> dict:
    return {"model_error": mf.model_error, "field_rms_px": mf.field_rms_px, "rms_px": mf.rms_px,
            "explained": mf.explained, "p_value": mf.p_value}


def _rejected_list(sol) -> list:
    return [{"index": int(i), "residual_px": float(r)} for i, r in zip(sol.rejected, sol.rejected_residuals_px)]


@deterministic()  # one OpenCV and one BLAS thread: the same view gives the same bytes on any machine
def calibrate(view, proj_size=None, *, camera: CameraOptions = CameraOptions(),
              projector: ProjectorOptions = ProjectorOptions(), robust: RobustOptions = RobustOptions(),
              rating_options: RatingOptions = RatingOptions(), cam_size=None, strict: bool = False,
              known_camera: Device | None = None, background: _background.BackgroundOptions | None = None,
              dense: _dense.DenseOptions | None = _dense.DenseOptions(), known_projector: Device | None = None
              ) -> Calibration:
    """Single-pose procam calibration of one :class:`procam.view.View`.

    Parameters
    ----------
    view : View -- only corners with finite camera AND projector points (``view.valid``) are used.
    proj_size : (W, H) of the projector (default ``view.proj_size``).
    camera : :class:`CameraOptions` (principal point, distortion, refinement).
    projector : :class:`ProjectorOptions` (``u0``).
    robust : :class:`RobustOptions` -- minimum corners and outlier rejection, for both devices.
    rating_options : :class:`RatingOptions` -- the verdict's thresholds.
    cam_size : (W, H) of the camera (default ``view.cam_size``).
    known_camera : the camera's intrinsics (:class:`~procam.calibration.Device`, any distortion model), e.g. from
        a camera-only calibration of many photos (:func:`procam.io.load_camera_intrinsics` reads procam's,
        OpenCV's and kamino410's files): the camera is then fixed and the pose calibrates only its board pose,
        the projector and ``R, T`` (``camera`` options are not used).
    strict : raise :class:`~procam.errors.DegeneratePoseError` for a degenerate or failed pose instead of
        returning it with its verdict and a warning.
    background : :class:`procam.single_pose.background.BackgroundOptions` (default: mode ``free``): with dense
        samples, mode ``off`` leaves the background samples out of the dense fit (the board alone); without them
        (a view read from a correspondences file), the check of the paper projector's assumptions (u0p = W/2,
        alpha_p = 1) against ``view.background`` and, by its mode, the joint refinement that lifts them
        (:func:`procam.single_pose.background.apply`).
    dense : :class:`procam.single_pose.dense.DenseOptions` -- when the view carries dense samples
        (``view.board_samples``, from :mod:`procam.pipeline`), the projector is a real one: principal point, aspect,
        lens distortion chosen by evidence, the camera jointly, an honest ``±`` (:mod:`.dense`); None keeps the
        paper's projector model (u0p = W/2, alpha_p = 1, no distortion).
    known_projector : the projector's intrinsics and distortion (:class:`~procam.calibration.Device`) from an
        earlier calibration: held fixed, so the pose gives ``R, T`` (the twin of ``known_camera``; needs dense
        samples).

    Returns
    -------
    Calibration
        ``method="single-pose"``; camera with division distortion, projector without; ``R, T``
        camera -> projector; ``cam_rms, proj_rms`` (per-device PnP RMS on this pose, outliers excluded),
        ``stereo_rms`` (corners used by both devices); ``std`` with ``f_c, alpha_c, fy_c, u0c,
        v0c, k1, k2, f_p, v0p, R_euler_deg (3), T (3)`` and the board angles' std; one entry in
        ``poses`` with the angles, the rating (:func:`rate_pose`, key ``"advice"``), ``rejected_corners``
        (``{"camera": [{"index", "residual_px"}, ...], "projector": [...]}``, indices into the view's corners) and
        ``outlier_threshold_px``; ``info["camera"]``/``info["projector"]`` hold the full solutions;
        ``verdict`` (good / weak / degenerate / failed, :mod:`.rating`) and ``verdict_reasons`` -- a weak,
        degenerate or failed pose is also a :class:`~procam.errors.ProcamWarning`.

    Raises
    ------
    CalibrationError
        Too few usable corners (the message says how many are usable and needed), corners on one
        line, no valid solution (:class:`~procam.errors.DegeneratePoseError` when the pose is degenerate), or a
        degenerate or failed pose with ``strict``.
    """
    # no step may depend on how the board's corners were numbered: solve the canonical labelling (issue 24)
    given_view, (view, labelling) = view, canonical_view(view)
    cam_size = cam_size or view.cam_size
    proj_size = proj_size or view.proj_size
    name = view.name
    obj_all = view.obj_pts
    valid = view.valid & np.isfinite(obj_all).all(1)
    check_corners(obj_all, valid, robust.min_points, name,
                   "corners (with finite camera and projector coordinates)", "check the board detection and decoding")

    def only_valid(a):
        return np.where(valid[:, None], a, np.nan)

    # the verdict's stable part comes first: it does not depend on where the fits stop
    predicted = {"camera": None if known_camera is not None else
                 predict("camera", obj_all, only_valid(view.cam_pts), cam_size, rating_options.camera_noise_px),
                 "projector": predict("projector", obj_all, only_valid(view.proj_pts), proj_size,
                                      rating_options.projector_noise_px, u0=projector.u0)}
    # NaN for corners invalid in either device, so that both fits use the same corners and the
    # rejected corners' indices are the view's
    if known_camera is not None:
        if cam_size is not None and tuple(known_camera.image_size) != tuple(cam_size):
            raise CalibrationError(f"pose {name!r}: the given camera intrinsics are for {known_camera.image_size[0]}x"
                                   f"{known_camera.image_size[1]} images, this pose's are {cam_size[0]}x{cam_size[1]}")
    with _degenerate_if_unsolved(name, predicted, rating_options):
        if known_camera is not None:
            cam = known_camera_pose(obj_all, only_valid(view.cam_pts), known_camera, robust=robust, name=name)
        else:
            cam = calibrate_camera(obj_all, only_valid(view.cam_pts), cam_size, camera, robust=robust, name=name)
        proj = calibrate_projector(obj_all, only_valid(view.proj_pts), proj_size, projector, robust=robust,
                                   name=name)
    R, T = extrinsics(cam, proj)
    std = _std_dict(cam, proj)
    predicted = {k: _with_noise(v, d.info.get("sigma_px"), k, rating_options)
                 for (k, v), d in zip(predicted.items(), (cam, proj))}
    adv = rate_pose(None if known_camera is not None else cam.angles_deg, proj.angles_deg, std,
                    values={"f_c": cam.K[0, 0], "f_p": proj.K[0, 0]}, cam_size=cam.image_size,
                    proj_size=proj.image_size, predicted=predicted, options=rating_options,
                    assumed=_u0p_assumption(view, obj_all, only_valid(view.proj_pts), proj, projector, rating_options))
    if known_camera is not None:
        adv["camera"] = {"level": "good", "degenerate": False, "weak": False, "failed": False, "given": True,
                         "message": "camera: intrinsics given, not estimated from this pose"}
    # a real projector from the dense samples (single_pose.dense): it is rated by the ± it reports
    fit = _dense_fit(view, cam, proj, proj_size, dense, background, known_camera, known_projector)
    if fit is not None:
        adv["projector"] = _dense_result.projector_rating(fit, proj_size, known_projector, rating_options)
        _relevel(adv)
    warnings = list(cam.warnings) + list(proj.warnings)
    verdict, reasons = judge(adv, name, strict, warnings)
    fits = {"camera": _misfit(obj_all, cam, 0.1)}
    if fit is None:
        fits["projector"] = _misfit(obj_all, proj, 0.2)
    counted = dict(fits)
    if known_camera is not None and fit is not None:
        # the camera is given: its pattern counts by what it does to the projector and R, T (in their ±, rated by
        # the projector's rating), not by itself
        del counted["camera"]
        if fit.camera_pattern is not None:
            warnings.append(f"pose {name!r}: {_pattern_words(fit)}")
    verdict, reasons = _model_error(counted, name, verdict, reasons, warnings)
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
            "outlier_threshold_px": {"camera": cam.outlier_threshold_px, "projector": proj.outlier_threshold_px},
            "misfit": {k: _misfit_dict(v) for k, v in fits.items()}}
    cal = Calibration(camera=known_camera if known_camera is not None else
                      Device(cam.K, tuple(cam.image_size), cam.distortion),
                      projector=Device(proj.K, tuple(proj.image_size), Distortion()), R=R, T=T,
                      method="single-pose" if known_camera is None else "single-pose, camera given",
                      cam_rms=cam_rms, proj_rms=proj_rms, stereo_rms=stereo, std=std,
                      poses=(pose,), views=(view,), warnings=tuple(warnings),
                      info={"camera": cam, "projector": proj, "principal_point_source": cam.principal_point_source,
                            "cod_score": None if cam.cod is None else cam.cod.score,
                            "refine": cam.info["refine"]}, verdict=verdict, verdict_reasons=reasons)
    if fit is not None:
        cal = _dense_result.apply(cal, fit, view, known_camera=known_camera, known_projector=known_projector)
        return apply_gates(given_labelling(cal, given_view, labelling), over_degenerate=False, stacklevel=3)
    if known_projector is not None:
        raise CalibrationError(f"pose {name!r}: given projector intrinsics need the pose's dense samples (a pose "
                               "folder decoded by procam, not a correspondences file)")
    # the background behind the board (single_pose.background): the check, and the refinement, of the paper
    # projector's assumptions -- for a view with a background and no dense board samples
    bg = getattr(view, "background", None)
    if bg is not None:
        cal = _background.apply(cal, bg.cam_pts, bg.proj_pts, background or _background.BackgroundOptions())
    return apply_gates(given_labelling(cal, given_view, labelling), over_degenerate=False, stacklevel=3)


def _relevel(adv: dict) -> None:
    """The pose's level, ``ok``, ``degenerate`` and ``failed`` of a rating whose device entries changed."""
    from ..verdict import LEVELS

    subs = [adv[k] for k in ("camera", "projector") if isinstance(adv.get(k), dict)]
    adv["level"] = max((s["level"] for s in subs), key=LEVELS.index, default="good")
    adv["degenerate"] = any(s["degenerate"] for s in subs)
    adv["failed"] = any(s["failed"] for s in subs)
    adv["ok"] = adv["level"] == "good"


def _dense_fit(view, cam, proj, proj_size, dense, background, known_camera, known_projector):
    """The dense projector fit of the view (:mod:`.dense`), or None (no dense options or samples)."""
    if dense is None or getattr(view, "board_samples", None) is None:
        return None
    if background is not None and background.mode == "off":
        dense = replace(dense, use_background=False)
    if known_projector is not None and tuple(known_projector.image_size) != tuple(proj_size):
        w, h = known_projector.image_size
        raise CalibrationError(f"pose {view.name!r}: the given projector intrinsics are for {w}x{h}, this pose's "
                               f"projector is {proj_size[0]}x{proj_size[1]}")
    return _dense.fit(view, cam, proj, proj_size, dense, known_camera=known_camera, known_projector=known_projector)


@deterministic()
def calibrate_camera_only(obj_pts, cam_pts, image_size, *, camera: CameraOptions = CameraOptions(),
                          robust: RobustOptions = RobustOptions(), rating_options: RatingOptions = RatingOptions(),
                          name: str = "view", strict: bool = False) -> Calibration:
    """Camera-only single-pose calibration (one photo of a chessboard, no projector): K and division distortion.

    Options as :func:`calibrate`. Returns a :class:`Calibration` with ``projector=None, R=T=None``, ``cam_rms``
    (PnP RMS on this pose, outliers excluded), ``std`` and one pose entry (with
    ``rejected_corners``).
    """
    obj_pts, cam_pts, labelling = canonical_points(obj_pts, cam_pts)  # independent of the corners' numbering
    obj, pts, finite = clean(obj_pts, cam_pts, name)
    # too few or collinear corners are that error, whatever the prediction (the first thing the fit checks)
    check_corners(obj, finite, robust.min_points, name, "camera corners", "check the board detection")
    predicted = {"camera": predict("camera", obj, pts, image_size, rating_options.camera_noise_px)
                 if image_size is not None else None}
    with _degenerate_if_unsolved(name, predicted, rating_options):
        cam = calibrate_camera(obj_pts, cam_pts, image_size, camera, robust=robust, name=name)
    std = _std_dict(cam, None)
    predicted["camera"] = _with_noise(predicted["camera"], cam.info.get("sigma_px"), "camera", rating_options)
    adv = rate_pose(cam.angles_deg, None, std, values={"f_c": cam.K[0, 0]}, cam_size=cam.image_size,
                    predicted=predicted, options=rating_options)
    warnings = list(cam.warnings)
    verdict, reasons = judge(adv, name, strict, warnings)
    fits = {"camera": _misfit(obj, cam, 0.1)}
    verdict, reasons = _model_error(fits, name, verdict, reasons, warnings)
    mask = cam.mask
    cam_rms = _pnp_rms(obj[mask], cam.distortion.undistort(pts[mask], cam.K), cam.K)
    pose = {"name": name, "camera_angles_deg": [float(a) for a in cam.angles_deg], "projector_angles_deg": None,
            "advice": adv, "cam_rms": cam_rms, "n_corners": int(finite.sum()),
            "n_used": {"camera": int(mask.sum())}, "rejected_corners": {"camera": _rejected_list(cam)},
            "outlier_threshold_px": {"camera": cam.outlier_threshold_px},
            "misfit": {k: _misfit_dict(v) for k, v in fits.items()}}
    cal = Calibration(camera=Device(cam.K, tuple(cam.image_size), cam.distortion), projector=None, R=None, T=None,
                      method="camera-only", cam_rms=cam_rms, std=std, poses=(pose,), warnings=tuple(warnings),
                      info={"camera": cam, "principal_point_source": cam.principal_point_source,
                            "cod_score": None if cam.cod is None else cam.cod.score, "refine": cam.info["refine"]},
                      verdict=verdict, verdict_reasons=reasons)
    return apply_gates(given_labelling(cal, None, labelling), over_degenerate=False, stacklevel=3)
