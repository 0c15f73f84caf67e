"""Multi-pose (Zhang-style) procam calibration: the baseline the paper compares against.

Pipeline (Moreno & Taubin's reference, plus an optional joint refinement):

1. :func:`calibrate_device` for the camera and for the projector separately: OpenCV
   ``calibrateCamera`` with a selectable OpenCV distortion model.  Two starts are tried and the one
   with the lower RMS is kept: OpenCV's own initialisation (principal point at the image centre) and
   a zero-skew Zhang closed form.  A lens-shifted projector has its principal point outside the
   image, which OpenCV refuses as an initial guess; the guess is then applied in a translated pixel
   frame whose (virtual) image contains the principal point, and the result translated back (exact:
   every OpenCV distortion model is a function of ``(x - c) / f`` only).
2. ``stereoCalibrate`` with ``CALIB_FIX_INTRINSIC`` for ``(R, T)`` (the "frozen" step every peer
   tool ships: the intrinsics are not improved by the stereo constraint).
3. ``refine=True`` (default): a joint least-squares refinement of both intrinsics, both distortion
   vectors, ``(R, T)`` and every board pose (scipy ``least_squares``, robust loss, analytic Jacobian
   from ``cv2.projectPoints`` and ``cv2.composeRT``).

Conventions as in :mod:`procam.calibration`: board poses map board -> camera, ``x_p = R x_c + T``.
"""

from __future__ import annotations

import warnings as _warnings
from typing import Sequence

import numpy as np

from .. import choices, models
from .. import uncertainty as unc
from .._threads import deterministic
from ..calibration import Calibration, Device, Distortion
from ..errors import CalibrationError, DegeneratePoseError, DegeneratePoseWarning, WeakPoseWarning
from ..stats import rms
from ..verdict import LEVELS
from ..view import View
from .device import DIST_MODELS, DeviceCalibration, _as_cv, _check_dist, _criteria, calibrate_device, zhang_intrinsics
from .refine import StereoRefinement, refine_stereo

__all__ = ["calibrate", "calibrate_camera", "calibrate_models", "refit_without", "check_distinct", "undetermined_distortion", "calibrate_device",
           "AUTO_MODELS", "DIST_CHOICES", "refine_stereo", "zhang_intrinsics", "DIST_MODELS", "DeviceCalibration",
           "StereoRefinement", "MIN_CORNERS_PER_POSE", "check_counts"]

#: Fewest corners a pose needs in a multi-pose calibration: four give its board homography (the Zhang
#: start); how many poses are needed then depends on the distortion models (:func:`check_counts`).
MIN_CORNERS_PER_POSE = 4

#: OpenCV's names of the distortion coefficients, in its order.
_COEFF_NAMES = ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6")


def check_counts(obj_list, cam_dist: str = "k1k2p1p2k3", proj_dist: str = "k1k2p1p2k3", names=None) -> None:
    """Raise :class:`CalibrationError` when poses with these usable board points ``obj_list`` ((N_j, 3) each)
    cannot determine a multi-pose calibration with these distortion models.

    Each pose needs :data:`MIN_CORNERS_PER_POSE` corners, not all on one line of the board (its homography).
    Each device's fit has 6 unknowns per pose, 4 intrinsics and the model's distortion terms; each corner
    gives 2 equations, and there must be more equations than unknowns (else the fit passes exactly through
    the noise).  The message says how many equations and unknowns there are, which distortion terms need
    them, and what model would do.
    """
    counts = [len(o) for o in obj_list]
    names = list(names) if names is not None else [f"pose {k + 1}" for k in range(len(counts))]
    for n, c, o in zip(names, counts, obj_list):
        if c < MIN_CORNERS_PER_POSE:
            raise CalibrationError(f"pose {n!r}: only {c} corners have both camera and projector points; a "
                                   f"multi-pose calibration needs {MIN_CORNERS_PER_POSE} per pose (its board "
                                   "homography); re-capture or drop this pose")
        xy = np.asarray(o, float)[:, :2]
        sv = np.linalg.svd(xy - xy.mean(axis=0), compute_uv=False)
        if sv[1] <= 1e-6 * max(sv[0], 1e-300):
            raise CalibrationError(f"pose {n!r}: its {c} usable corners lie on one line of the board; a multi-pose "
                                   "calibration needs corners spread over at least 2 rows and 2 columns per pose; "
                                   "re-capture or drop this pose")
    eq = 2 * sum(counts)
    for option, dist in (("--cam-dist", cam_dist), ("--proj-dist", proj_dist)):
        free = _check_dist(dist)[2]
        unknowns = 6 * len(counts) + 4 + len(free)
        if eq > unknowns:
            continue
        terms = ", ".join(_COEFF_NAMES[i] for i in free)
        fits = [m for m, (_, f) in DIST_MODELS.items() if eq > 6 * len(counts) + 4 + len(f)]
        simpler = (f"or a model with fewer terms ({option} {fits[-1]})" if fits else "")
        raise CalibrationError(
            f"{len(counts)} poses with {sum(counts)} usable corners give {eq} equations per device, not more than "
            f"the {unknowns} unknowns of a fit with the {dist} model (6 per pose, 4 intrinsics"
            + (f", {len(free)} distortion terms {terms}" if free else "") + "): so few points cannot determine "
            + ("the distortion" if free else "the intrinsics") + "; use more poses or a larger board"
            + (f", {simpler}" if simpler else ""))


def _std_dict(ref: StereoRefinement, n_cam_dist: int, n_proj_dist: int) -> dict:
    """Standard deviations from the refinement covariance, named as every procam result
    (:mod:`procam.parameters`): ``f_c, fy_c, u0c, v0c, f_p, fy_p, u0p, v0p`` (px), ``cam_dist``,
    ``proj_dist`` (one per coefficient; 0 for a coefficient the model fixes), ``R_euler_deg`` (3,) (delta
    method through the Euler angles) and ``T`` (3,)."""
    sd = unc.std(ref.cov)
    names = list(ref.names)
    out = {n: float(sd[names.index(n)]) for n in ("f_c", "fy_c", "u0c", "v0c", "f_p", "fy_p", "u0p", "v0p")}
    for key, n in (("cam_dist", n_cam_dist), ("proj_dist", n_proj_dist)):
        out[key] = [float(sd[names.index(f"{key}[{i}]")]) if f"{key}[{i}]" in names else 0.0 for i in range(n)]
    i = names.index("R_rx")
    ce = unc.propagate(ref.cov[i:i + 3, i:i + 3], lambda r: models.euler_deg(models.rvec_to_matrix(r)),
                       ref.x[i:i + 3])
    out["R_euler_deg"] = unc.std(ce).tolist()
    out["T"] = sd[i + 3:i + 6].tolist()
    return out


#: Distortion models tried by ``"auto"``, richest first: a device steps down while the poses do not
#: determine all its terms (:func:`undetermined_distortion`).
AUTO_MODELS = ("k1k2p1p2k3", "k1k2p1p2", "k1k2", "k1", "none")
#: The choices of ``cam_dist`` / ``proj_dist``.
DIST_CHOICES = choices.DIST_CHOICES


@deterministic()
def calibrate(views: Sequence[View], *, cam_dist: str = "auto", proj_dist: str = "auto", refine: bool = True,
              strict: bool = False, leave_one_out: bool = True, judge_pose_set: bool = True,
              **options) -> Calibration:
    """Multi-pose procam calibration (Zhang / Moreno–Taubin, optionally jointly refined), with the distortion
    models the poses can determine, and its verdict from the evidence.

    ``cam_dist`` / ``proj_dist``: an OpenCV distortion model of :data:`DIST_MODELS`, or ``"auto"`` (default):
    start from ``"k1k2p1p2k3"`` (OpenCV's and Moreno & Taubin's) and, for a device whose poses do not determine
    all its terms (a large term with a standard deviation over half its value: :func:`undetermined_distortion`),
    step down :data:`AUTO_MODELS` until they do. Without the joint refinement there is no covariance to judge
    by, and ``"auto"`` is ``"k1k2p1p2k3"``. The models used are in ``info["cam_dist_model"]`` /
    ``info["proj_dist_model"]``, the steps taken in ``info["auto_dist"]``. Other options: :func:`calibrate_models`.

    The verdict (worst first): ``failed`` when the result is impossible for a real rig
    (:func:`procam.verdict.gates.gate_failures`); ``degenerate`` when the pose set cannot determine the
    intrinsics, judged before the fit (:func:`procam.multi_pose.poseset.check_pose_set`, in
    ``info["pose_set"]``), or when a parameter moves far more than its ``±`` as each pose is left out
    (``leave_one_out``, with 4 or more poses: :mod:`procam.multi_pose.evidence`, in ``info["leave_one_out"]``;
    the refits are kept in ``info["leave_one_out_refits"]`` for :func:`procam.verify.leave_one_out`); ``weak``
    with warnings (or fewer than 3 poses); else ``good``. A verdict other than good is also a procam warning.

    ``strict`` raises :class:`~procam.errors.DegeneratePoseError` for a degenerate pose set without fitting it;
    otherwise the set is fitted and the result marked (and a fit that finds no solution raises that error,
    with the reason).

    ``judge_pose_set=False`` judges the set only when the fit finds no solution (for the error's reason): the
    leave-one-out refits, whose parameters are all that is read of them, skip the judgment a refit's verdict
    alone would use (a third of a refit's time; the parameters are the same to the bit).
    """
    from . import evidence, poseset
    from ..verdict import gates

    given = list(views)
    views, labellings = _canonical(given)  # no step may depend on how each board's corners were numbered
    for name, d in (("cam_dist", cam_dist), ("proj_dist", proj_dist)):
        if d not in DIST_CHOICES:
            raise CalibrationError(f"unknown distortion model {d!r} for {name}; choose one of {', '.join(DIST_CHOICES)}")
    cam_size = options.get("cam_size") or (views[0].cam_size if views else None)
    proj_size = options.get("proj_size") or (views[0].proj_size if views else None)
    def judged():
        return poseset.check_pose_set(views, cam_size, proj_size) if len(views) >= 2 and cam_size else None

    pre = judged() if judge_pose_set or strict else None
    degenerate_set = pre is not None and pre.level == "degenerate"
    if strict and degenerate_set:
        raise DegeneratePoseError("; ".join(pre.reasons))
    try:
        calib = _calibrate_auto(views, cam_dist, proj_dist, refine, options)
    except CalibrationError as e:
        if pre is None:
            pre = judged()
            degenerate_set = pre is not None and pre.level == "degenerate"
        if degenerate_set and not isinstance(e, DegeneratePoseError):
            raise DegeneratePoseError("; ".join(pre.reasons) + f" (the fit found no solution: {e})") from None
        raise
    info = dict(calib.info)
    level, reasons = calib.verdict, list(calib.verdict_reasons)
    if pre is not None:
        info["pose_set"] = pre.to_dict()
        if degenerate_set:
            level, reasons = "degenerate", list(pre.reasons) + reasons
    if leave_one_out and len(views) >= evidence.MIN_POSES:
        warm = (lambda i: refit_without(calib, i)) if refine else None  # from the solution: a few steps each
        refits = evidence.refit_each(views, calibrate, warm, cam_dist=info["cam_dist_model"],
                                     proj_dist=info["proj_dist_model"], refine=refine, leave_one_out=False,
                                     judge_pose_set=False, **options)
        lvl, why, details = evidence.judge_spread(calib, refits, info["pose_names"])
        info["leave_one_out"] = details
        info["leave_one_out_refits"] = tuple(refits)
        if not degenerate_set:  # a set already called degenerate before the fit: the spread only confirms it
            reasons = [r for r in why if lvl == "degenerate"] + reasons + [r for r in why if lvl != "degenerate"]
            level = max(level, lvl, key=LEVELS.index)
    calib = calib.replace(info=info, verdict=level, verdict_reasons=tuple(reasons),
                          warnings=tuple(calib.warnings) + tuple(r for r in reasons if r not in calib.warnings))
    calib = gates.apply_gates(_given(calib, given, labellings), stacklevel=2)
    if calib.verdict in ("weak", "degenerate"):
        category = WeakPoseWarning if calib.verdict == "weak" else DegeneratePoseWarning
        _warnings.warn("; ".join(calib.verdict_reasons), category, stacklevel=2)
    return calib


def _canonical(views):
    """Each view in the canonical labelling of its board (:func:`procam.board.labelling.canonical_view`)."""
    from ..board.labelling import canonical_view

    out = [canonical_view(v) for v in views]
    return [v for v, _ in out], [lab for _, lab in out]


def _given(calib, views, labellings) -> Calibration:
    """A calibration of canonical views as the given ``views``': each pose's board pose and angles in its given
    board frame, ``views`` the given ones."""
    if all(lab is None or lab.identity for lab in labellings):
        return calib.replace(views=tuple(views))
    poses = []
    for p, lab in zip(calib.poses, labellings):
        p = dict(p)
        if lab is not None and "R_cam" in p:
            R_cb, t_cb = np.asarray(p["R_cam"], float) @ lab.G, np.asarray(p["t_cam"], float)
            p["R_cam"] = R_cb.tolist()
            p["camera_angles_deg"] = models.board_angles_deg(R_cb, t_cb).tolist()
            if calib.R is not None and p.get("projector_angles_deg") is not None:
                p["projector_angles_deg"] = models.board_angles_deg(*models.compose(calib.R, calib.T, R_cb, t_cb)).tolist()
        poses.append(p)
    return calib.replace(views=tuple(views), poses=tuple(poses))


def _calibrate_auto(views, cam_dist, proj_dist, refine, options) -> Calibration:
    """:func:`calibrate_models` with ``"auto"`` distortion models stepped down while undetermined."""
    models_ = {"camera": cam_dist, "projector": proj_dist}
    auto = {k: v == "auto" for k, v in models_.items()}
    # "auto" starts at the richest model the corner count can determine at all (check_counts)
    counts = [int(np.asarray(v.valid).sum()) for v in views]
    first = next((m for m in AUTO_MODELS if 2 * sum(counts) > 6 * len(counts) + 4 + len(_check_dist(m)[2])),
                 AUTO_MODELS[-1])
    steps = [] if first == AUTO_MODELS[0] else [f"{first} (fewer terms than {AUTO_MODELS[0]}: {sum(counts)} corners)"]
    models_ = {k: (first if v == "auto" else v) for k, v in models_.items()}
    while True:
        calib = calibrate_models(views, cam_dist=models_["camera"], proj_dist=models_["projector"], refine=refine,
                                 **options)
        bad = [d for d in ("camera", "projector") if auto[d] and calib.info.get("undetermined", {}).get(d)]
        if not bad or not refine:
            break
        for d in bad:
            i = AUTO_MODELS.index(models_[d])
            steps.append(f"{d}: {models_[d]} -> {AUTO_MODELS[min(i + 1, len(AUTO_MODELS) - 1)]} "
                         f"({', '.join(calib.info['undetermined'][d])} undetermined)")
            models_[d] = AUTO_MODELS[min(i + 1, len(AUTO_MODELS) - 1)]
    if any(auto.values()):
        calib = calib.replace(info={**calib.info, "auto_dist": steps})
    return calib


def calibrate_models(views: Sequence[View], *, cam_size=None, proj_size=None, cam_dist: str = "k1k2p1p2k3",
                     proj_dist: str = "k1k2p1p2k3", refine: bool = True, loss: str = "soft_l1",
                     loss_scale: float = 1.0, balance: bool = True, init: str = "auto", fix_aspect_ratio: bool = False,
                     iterations: int = 100, stereo_iterations: int = 150,
                     min_corners: int = MIN_CORNERS_PER_POSE) -> Calibration:
    """Multi-pose procam calibration with given distortion models (Zhang / Moreno–Taubin, optionally jointly
    refined).

    Parameters
    ----------
    views : two or more :class:`procam.view.View` (three or more recommended); NaN corners are
        dropped per view (``view.valid``).
    cam_size, proj_size : (width, height) in pixels; default: taken from the views.
    cam_dist, proj_dist : OpenCV distortion model of each device (:data:`DIST_MODELS`); the default
        ``"k1k2p1p2k3"`` is OpenCV's (and Moreno & Taubin's).
    refine : run the joint refinement after the frozen-intrinsics stereo step.
    loss, loss_scale : robust loss of the refinement and its soft threshold in camera pixels.
    balance : weight the projector residuals by ``rms_cam / rms_proj`` of the per-device step
        (maximum likelihood when each device has its own Gaussian noise; projector corners are
        usually noisier).  ``False`` weights both equally, as ``stereoCalibrate`` does.
    init, fix_aspect_ratio, iterations : passed to :func:`calibrate_device`.
    stereo_iterations : iteration cap of ``stereoCalibrate`` (Moreno & Taubin: 150).
    min_corners : poses with fewer valid corners are an error (at least :data:`MIN_CORNERS_PER_POSE`); the
        total must also determine the distortion models (:func:`check_counts`).

    OpenCV and BLAS run on one thread inside (:func:`procam._threads.deterministic`): the same views give
    the same bytes.

    Returns
    -------
    :class:`procam.calibration.Calibration` with ``method="multi-pose"``, OpenCV distortion on both
    devices, ``cam_rms``/``proj_rms`` (per-device RMS of the final model), ``stereo_rms`` (RMS over
    all camera and projector points of the final stereo model), ``std`` (from the refinement's
    covariance, keys as :func:`_std_dict`; empty without refinement), ``poses`` (per-pose angles and RMS) and ``info`` with the
    frozen-step result under ``"frozen"`` (K, dist, R, T, RMS) for comparison.

    Raises
    ------
    CalibrationError
        Fewer than two poses, missing image sizes, too few corners, or no solution.
    """
    import cv2

    views = list(views)
    if len(views) < 2:
        raise CalibrationError(f"multi-pose calibration needs at least 2 poses (3 or more recommended), "
                               f"got {len(views)}; use --method single for one pose")
    check_distinct(views)
    cam_size = cam_size or views[0].cam_size
    proj_size = proj_size or views[0].proj_size
    if cam_size is None or proj_size is None:
        raise CalibrationError("multi-pose calibration needs the camera and projector image sizes "
                               "(set View.cam_size/proj_size or pass cam_size=, proj_size=)")
    sizes = ((int(cam_size[0]), int(cam_size[1])), (int(proj_size[0]), int(proj_size[1])))
    cam_size, proj_size = sizes
    data = _pose_data(views, min_corners)
    objs, cams, projs, names = data
    check_counts(objs, cam_dist, proj_dist, names)
    cal_c = calibrate_device(objs, cams, cam_size, cam_dist, init=init, fix_aspect_ratio=fix_aspect_ratio,
                             iterations=iterations)
    cal_p = calibrate_device(objs, projs, proj_size, proj_dist, init=init, fix_aspect_ratio=fix_aspect_ratio,
                             iterations=iterations)
    Kc, dc, rvc, tvc, rms_c = cal_c.K, cal_c.coeffs, cal_c.rvecs, cal_c.tvecs, cal_c.rms
    Kp, dp, rms_p = cal_p.K, cal_p.coeffs, cal_p.rms
    o32, c32 = _as_cv(objs, cams)
    _, p32 = _as_cv(objs, projs)
    try:
        out = cv2.stereoCalibrate(o32, c32, p32, Kc, dc, Kp, dp, cam_size, flags=cv2.CALIB_FIX_INTRINSIC,
                                  criteria=_criteria(stereo_iterations))
    except cv2.error as e:
        raise CalibrationError(f"stereo step failed: {str(e).strip().splitlines()[-1]}") from None
    rms_s, R0, T0 = float(out[0]), np.asarray(out[5], float), np.asarray(out[6], float).ravel()
    frozen = {"cam_K": Kc.tolist(), "cam_dist": dc.tolist(), "proj_K": Kp.tolist(), "proj_dist": dp.tolist(),
              "R": R0.tolist(), "T": T0.tolist(), "cam_rms": rms_c, "proj_rms": rms_p, "stereo_rms": rms_s,
              "cam_init": cal_c.init, "proj_init": cal_p.init}
    info = {"frozen": frozen, "cam_dist_model": cam_dist, "proj_dist_model": proj_dist, "refined": bool(refine),
            "pose_names": names}
    if refine:
        floor = 1e-3  # px: noise-free data have RMS ~ 0; keep the weight finite
        w_proj = max(rms_c, floor) / max(rms_p, floor) if balance else 1.0

        def diverged():
            return _without_refinement(views, cam_size, proj_size, cam_dist, proj_dist, init, fix_aspect_ratio,
                                       iterations, stereo_iterations, min_corners)

        return _refined(views, data, sizes, (Kc, dc, Kp, dp, R0, T0, rvc, tvc), cam_dist, proj_dist, loss,
                        loss_scale, w_proj, info, diverged)
    cam_res, proj_res = [], []
    for j in range(len(objs)):
        pc = models.project(Kc, models.rvec_to_matrix(rvc[j]), tvc[j], objs[j])
        cam_res.append(cams[j] - Distortion("opencv", coeffs=tuple(dc)).distort(pc, Kc))
        R_pb, t_pb = models.compose(R0, T0, models.rvec_to_matrix(rvc[j]), tvc[j])
        pp = Distortion("opencv", coeffs=tuple(dp)).distort(models.project(Kp, R_pb, t_pb, objs[j]), Kp)
        proj_res.append(projs[j] - pp)
    return _assemble(views, data, sizes, (Kc, dc, Kp, dp, R0, T0, rvc, tvc), (cam_res, proj_res),
                     (rms_c, rms_p, rms_s), {}, info, [], (cam_dist, proj_dist))


def _pose_data(views, min_corners: int) -> tuple:
    """``(objs, cams, projs, names)``: per view its board points (N, 3) and camera and projector pixels (N, 2) where
    both devices have the corner, and its name; a view with too few such corners is a :class:`CalibrationError`."""
    objs, cams, projs, names = [], [], [], []
    for k, v in enumerate(views):
        m = v.valid
        if m.sum() < max(min_corners, MIN_CORNERS_PER_POSE):
            raise CalibrationError(f"pose {v.name!r}: only {int(m.sum())} corners have both camera and "
                                   f"projector points (need {max(min_corners, MIN_CORNERS_PER_POSE)}); re-capture or "
                                   "drop this pose")
        objs.append(v.obj_pts[m])
        cams.append(v.cam_pts[m])
        projs.append(v.proj_pts[m])
        names.append(v.name if v.name else f"pose{k + 1}")
    return objs, cams, projs, names


def _refined(views, data, sizes, start, cam_dist, proj_dist, loss, loss_scale, w_proj, info, diverged) -> Calibration:
    """The calibration of ``views`` by the joint refinement (:func:`refine_stereo`) from ``start`` = ``(Kc, dc, Kp,
    dp, R, T, board rvecs, board tvecs)``, the projector's residuals weighted by ``w_proj``; ``data`` and ``sizes`` as
    :func:`calibrate_models` makes them, ``info`` its info so far, ``diverged()`` the advice when the refinement
    diverges."""
    objs, cams, projs, _ = data
    ref = refine_stereo(objs, cams, projs, *start, cam_dist=cam_dist, proj_dist=proj_dist, loss=loss,
                        loss_scale=loss_scale, proj_weight=w_proj)
    res = ref.residuals
    cam_res = [r[0] for r in res]
    proj_res = [r[1] for r in res]
    rmss = (rms(cam_res), rms(proj_res), rms(cam_res + proj_res))
    info["refinement"] = {"loss": loss, "loss_scale": loss_scale, "proj_weight": w_proj, "status": ref.status,
                          "nfev": ref.nfev, "cost": ref.cost}
    warnings = []
    if ref.status <= 0:
        warnings.append("joint refinement stopped at its evaluation limit; the result may not be converged")
    if not (ref.Kc[0, 0] > 0 and ref.Kc[1, 1] > 0 and ref.Kp[0, 0] > 0 and ref.Kp[1, 1] > 0):
        raise CalibrationError("joint refinement diverged (non-positive focal length); " + diverged())
    return _assemble(views, data, sizes, (ref.Kc, ref.dc, ref.Kp, ref.dp, ref.R, ref.T, ref.rvecs, ref.tvecs),
                     (cam_res, proj_res), rmss, _std_dict(ref, len(ref.dc), len(ref.dp)), info, warnings,
                     (cam_dist, proj_dist))


def _assemble(views, data, sizes, solution, residuals, rmss, std, info, warnings, dist_models) -> Calibration:
    """The :class:`Calibration` of a solution ``(Kc, dc, Kp, dp, R, T, board rvecs, board tvecs)``: per-pose angles
    and RMS from ``residuals`` (per pose camera and projector, observed - predicted px), ``rmss`` (camera,
    projector, both), the distortion terms the poses do not determine (from ``std``), its verdict from
    ``warnings``."""
    objs, cams, projs, names = data
    cam_size, proj_size = sizes
    Kc, dc, Kp, dp, R, T, rv_board, tv_board = solution
    cam_res, proj_res = residuals
    cam_rms, proj_rms, stereo_rms = rmss
    cam_dist, proj_dist = dist_models
    warnings = list(warnings)
    poses = []
    for j in range(len(objs)):
        R_cb = models.rvec_to_matrix(rv_board[j])
        R_pb, t_pb = models.compose(R, T, R_cb, tv_board[j])
        poses.append({"name": names[j], "n_corners": int(len(objs[j])),
                      "camera_angles_deg": models.board_angles_deg(R_cb, tv_board[j]).tolist(),
                      "projector_angles_deg": models.board_angles_deg(R_pb, t_pb).tolist(),
                      "R_cam": R_cb.tolist(), "t_cam": np.asarray(tv_board[j], float).tolist(),
                      "cam_rms": rms([cam_res[j]]), "proj_rms": rms([proj_res[j]]),
                      "stereo_rms": rms([cam_res[j], proj_res[j]])})
    if len(views) < 3:
        warnings.append("only 2 poses: the multi-pose intrinsics are weakly constrained; use 3 or more")
    info["undetermined"] = {}
    if std:
        for device, K, d, sd, size, model, option, pts in (
                ("camera", Kc, dc, std.get("cam_dist"), cam_size, cam_dist, "--cam-dist", cams),
                ("projector", Kp, dp, std.get("proj_dist"), proj_size, proj_dist, "--proj-dist", projs)):
            msg, terms = undetermined_distortion(K, d, sd, size, model, device, option, pts)
            warnings += msg
            info["undetermined"][device] = terms
    camera = Device(Kc, cam_size, Distortion("opencv", coeffs=tuple(float(c) for c in dc)))
    projector = Device(Kp, proj_size, Distortion("opencv", coeffs=tuple(float(c) for c in dp)))
    verdict = "weak" if warnings else "good"
    return Calibration(camera=camera, projector=projector, R=np.asarray(R, float), T=np.asarray(T, float).ravel(),
                       method="multi-pose", cam_rms=cam_rms, proj_rms=proj_rms, stereo_rms=stereo_rms, std=std,
                       poses=tuple(poses), views=tuple(views), warnings=tuple(warnings), info=info, verdict=verdict,
                       verdict_reasons=tuple(warnings))


def refit_without(calib: Calibration, i: int) -> Calibration:
    """``calib`` (a jointly refined multi-pose calibration) refitted without its pose ``i``, from its own solution.

    The leave-one-pose-out refit of :mod:`procam.multi_pose.evidence`, warm-started: the joint refinement alone
    (no per-device calibrations, no stereo step), from ``calib``'s intrinsics, distortion, ``(R, T)`` and the other
    poses' boards, with ``calib``'s robust loss and projector weight (the weight a refit from scratch estimates
    again from its own poses: the refits differ from those by a small fraction of their spread). It converges in a
    few steps to the minimum a refit from scratch finds wherever the other poses determine the parameters; where
    they do not, where it stops along what they leave free says little (the cost is almost flat there, and the
    gradient at the start has no component along it), and its own ``±`` says so
    (:func:`procam.multi_pose.evidence.refit_each` then refits from scratch).
    Raises :class:`CalibrationError` when the refinement diverges.
    """
    keep = [j for j in range(len(calib.views)) if j != i]
    views = [calib.views[j] for j in keep]
    data = _pose_data(views, MIN_CORNERS_PER_POSE)
    cd, pd = calib.info["cam_dist_model"], calib.info["proj_dist_model"]
    r = calib.info["refinement"]
    start = (calib.camera.K, np.asarray(calib.camera.distortion.coeffs, float), calib.projector.K,
             np.asarray(calib.projector.distortion.coeffs, float), calib.R, calib.T,
             [models.matrix_to_rvec(np.asarray(calib.poses[j]["R_cam"], float)) for j in keep],
             [np.asarray(calib.poses[j]["t_cam"], float) for j in keep])
    info = {"cam_dist_model": cd, "proj_dist_model": pd, "refined": True, "pose_names": data[3], "warm_start": True}
    return _refined(views, data, (calib.camera.image_size, calib.projector.image_size), start, cd, pd, r["loss"],
                    r["loss_scale"], r["proj_weight"], info, lambda: "refit from scratch")


def _without_refinement(views, cam_size, proj_size, cam_dist, proj_dist, init, fix_aspect_ratio, iterations,
                        stereo_iterations, min_corners) -> str:
    """What to do when the joint refinement diverges: ``--no-refine`` only when its result passes the plausibility
    gates (:func:`procam.verdict.gates.gate_failures`) -- advice never points at a failed result."""
    from ..verdict import gates

    try:
        frozen = calibrate_models(views, cam_size=cam_size, proj_size=proj_size, cam_dist=cam_dist,
                                  proj_dist=proj_dist, refine=False, init=init, fix_aspect_ratio=fix_aspect_ratio,
                                  iterations=iterations, stereo_iterations=stereo_iterations, min_corners=min_corners)
        failures = gates.gate_failures(frozen)
    except CalibrationError as e:
        failures = [str(e)]
    if not failures:
        return ("the calibration without it (--no-refine) passes the plausibility checks: use it, or capture more "
                "varied poses")
    return (f"without it (--no-refine) the result is impossible too ({failures[0].split('FAILED estimate: ')[-1]}): "
            "these poses do not determine a calibration; capture 3 or more poses tilted 15-30 deg about different "
            "axes")


def check_distinct(views: Sequence[View], min_px: float = 1.0) -> None:
    """Raise :class:`CalibrationError` when two views are the same pose (their camera corners within
    ``min_px`` pixels RMS): a pose given twice adds no constraint, only weight, and skews every parameter."""
    for i in range(len(views)):
        for j in range(i + 1, len(views)):
            a, b = views[i], views[j]
            if a.cam_pts.shape != b.cam_pts.shape:
                continue
            d = a.cam_pts - b.cam_pts
            ok = np.isfinite(d).all(1)
            if ok.sum() >= 4 and rms(d[ok]) < min_px:
                raise CalibrationError(f"poses {a.name!r} and {b.name!r} are the same pose (their board corners lie "
                                       f"within {min_px:g} px of each other): give every pose once -- a pose given "
                                       "twice counts twice and skews the calibration")


def undetermined_distortion(K, coeffs, std, image_size, model: str, device: str, option: str, points,
                            max_px: float = 10.0) -> tuple[list[str], list[str]]:
    """The distortion coefficients the poses do not determine: ``(warnings, names)``.

    A coefficient is undetermined when its standard deviation exceeds half its value while the distortion it
    alone adds at the image's farthest corner exceeds ``max_px`` pixels: a large term that correlated terms
    cancel where the corners are and that nobody knows beyond them (e.g. k3 = 37 with k2 = -2.2 from poses
    that cover only the image's centre). The message names the terms and a model without them.

    Parameters
    ----------
    K : (3, 3); coeffs : OpenCV distortion vector; std : its standard deviations (same length) or None.
    image_size : (W, H); model : the :data:`DIST_MODELS` name in use; device, option : for the message.
    points : per-pose (N, 2) pixels of the corners, for the coverage in the message.
    """
    if std is None:
        return [], []
    coeffs = np.asarray(coeffs, float).ravel()
    std = np.asarray(std, float).ravel()
    W, H = image_size
    fx, fy, cx, cy = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
    corners = np.array([[-0.5, -0.5], [W - 0.5, -0.5], [-0.5, H - 0.5], [W - 0.5, H - 0.5]])
    xn = (corners[:, 0] - cx) / fx
    yn = (corners[:, 1] - cy) / fy
    r2 = float(np.max(xn * xn + yn * yn))
    r = np.sqrt(r2)
    f = max(fx, fy)
    # displacement (px) at radius r of each coefficient alone (radial: k r^(2i+1); tangential: ~3 p r^2)
    effect = {0: r ** 3, 1: r ** 5, 4: r ** 7, 5: r ** 3, 6: r ** 5, 7: r ** 7, 2: 3 * r2, 3: 3 * r2}
    bad, names = [], []
    for i, (c, s) in enumerate(zip(coeffs, std)):
        if s == 0 or not np.isfinite(c):
            continue
        moves = abs(c) * effect.get(i, r ** 3) * f
        if (not np.isfinite(s) or s > 0.5 * abs(c)) and moves > max_px:
            bad.append(f"{_COEFF_NAMES[i]} = {c:.3g} ± {s:.2g} (alone it would move the image corners by {moves:.0f} px)")
            names.append(_COEFF_NAMES[i])
    if not bad:
        return [], []
    pts = np.vstack([np.asarray(q, float).reshape(-1, 2) for q in points]) if len(points) else np.zeros((0, 2))
    pts = pts[np.isfinite(pts).all(1)]
    covered = ""
    if len(pts):
        rr = np.sqrt(((pts[:, 0] - cx) / fx) ** 2 + ((pts[:, 1] - cy) / fy) ** 2)
        covered = f"; the corners reach {100 * rr.max() / r:.0f} % of the way to the image corners"
    simpler = {"rational": "k1k2p1p2k3", "k1k2p1p2k3": "k1k2p1p2", "k1k2p1p2": "k1k2", "k1k2": "k1"}.get(model, "k1")
    return [f"{device}: the poses do not determine {', '.join(bad)}: the distortion model '{model}' has more terms "
            f"than these poses can fix{covered}; use {option} {simpler} (or auto) or poses that reach the image's "
            "edges and corners (the calibration is unreliable away from where the corners were)"], names


# the camera alone from photos (multi_pose/camera.py); imported last: it uses the helpers above
from .camera import calibrate_camera  # noqa: E402
