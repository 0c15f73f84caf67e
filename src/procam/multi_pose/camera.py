"""One camera alone from several photos of the board (Zhang / OpenCV ``calibrateCamera``), with the checks a
careful user makes, and the covariance of its intrinsics that its camera file carries (:func:`calibrate_camera`)."""

from __future__ import annotations

import warnings as _warnings
from typing import Sequence

import numpy as np

from .. import models
from ..board import board_region
from ..calibration import Calibration, Device, Distortion
from ..errors import CalibrationError, WeakPoseWarning
from ..view import View
from . import AUTO_MODELS, DIST_CHOICES, _canonical, check_distinct, undetermined_distortion
from .device import DIST_MODELS, _as_cv, _check_dist, _criteria, calibrate_device


def _covariance(dev, objs, free, fix_aspect_ratio: bool) -> dict | None:
    """The intrinsics' covariance of a camera-only fit (:func:`procam.crlb.views_bound` at the solution, scaled by
    the residual noise per coordinate, ``sum r^2 / (2 N - P)`` over every photo and parameter, as OpenCV's
    ``stdDeviationsIntrinsics``): ``{"params", "matrix", "sigma_px"}``, None with ``fx = fy`` tied."""
    if fix_aspect_ratio:
        return None
    from .. import crlb

    n = sum(len(o) for o in objs)
    dof = 2 * n - (4 + len(free) + 6 * len(objs))
    if dof <= 0 or not np.isfinite(dev.rms):
        return None
    sigma = float(dev.rms) * np.sqrt(n / dof)
    b = crlb.views_bound(dev.K, dev.coeffs, list(zip(dev.rvecs, dev.tvecs)), list(objs), sigma, tuple(free))
    return {"params": list(b.params), "matrix": b.cov, "sigma_px": sigma}


def calibrate_camera(views: Sequence[View], *, dist: str = "auto", fix_aspect_ratio: bool = False,
                     min_corners: int = 6, max_view_rms_ratio: float = 3.0, min_coverage: float = 0.3) -> Calibration:
    """Camera-only calibration from several photos of the board (Zhang / OpenCV ``calibrateCamera``), with the
    checks a careful user would make (mrcal-style): the residual RMS and the worst photo, photos that fit much
    worse than the rest, the image area the corners cover, and distortion terms the photos do not determine.

    Use it once with many photos; then ``single_pose.calibrate(view, known_camera=calib.camera)`` (``procam
    calibrate POSE --camera cam.json``) calibrates the projector and ``R, T`` from one pose.

    Parameters
    ----------
    views : two or more :class:`~procam.view.View` (camera points only are used); the image size from the first.
    dist : an OpenCV distortion model (:data:`DIST_MODELS`) or ``"auto"`` (the richest of :data:`AUTO_MODELS`
        whose terms the photos determine).
    fix_aspect_ratio : fx = fy.
    max_view_rms_ratio : a photo whose RMS exceeds this times the median (and 0.3 px) is named in a warning.
    min_coverage : below this fraction of the image covered by the boards' outlines, a warning.

    Returns
    -------
    :class:`~procam.calibration.Calibration` with ``method="camera-only"``, ``projector=None``, ``std`` (``f_c,
    fy_c, u0c, v0c, cam_dist``, from OpenCV's ``stdDeviationsIntrinsics``), a pose entry per photo (its RMS and
    board angles), ``verdict`` good or weak with its reasons.
    """
    import cv2

    given = list(views)
    views, labellings = _canonical(given)  # independent of how each board's corners were numbered
    if len(views) < 2:
        raise CalibrationError(f"camera-only calibration from photos needs at least 2 (5-20 recommended), got "
                               f"{len(views)}; one photo: the single-pose method (procam.single_pose)")
    if dist not in DIST_CHOICES:
        raise CalibrationError(f"unknown distortion model {dist!r}; choose one of {', '.join(DIST_CHOICES)}")
    check_distinct(views)
    size = tuple(int(v) for v in views[0].cam_size)
    objs, imgs, names = [], [], []
    for v in views:
        if tuple(v.cam_size) != size:
            raise CalibrationError(f"{v.name}: {v.cam_size[0]}x{v.cam_size[1]} pixels, the first photo is "
                                   f"{size[0]}x{size[1]}: calibrate one camera at one resolution")
        ok = np.isfinite(v.cam_pts).all(1)
        if ok.sum() < min_corners:
            raise CalibrationError(f"{v.name}: only {int(ok.sum())} corners (need {min_corners})")
        objs.append(v.obj_pts[ok])
        imgs.append(v.cam_pts[ok])
        names.append(v.name)
    model = AUTO_MODELS[0] if dist == "auto" else dist
    steps = []
    while True:
        dev = calibrate_device(objs, imgs, size, model, fix_aspect_ratio=fix_aspect_ratio)
        flags, ncoef, _ = _check_dist(model)
        flags |= cv2.CALIB_USE_INTRINSIC_GUESS | (cv2.CALIB_FIX_ASPECT_RATIO if fix_aspect_ratio else 0)
        o32, i32 = _as_cv(objs, imgs)
        try:
            ext = cv2.calibrateCameraExtended(o32, i32, size, dev.K.copy(), dev.coeffs.copy(), flags=flags,
                                              criteria=_criteria(30))
            sd_int, per_view = ext[5].ravel(), ext[7].ravel()
        except cv2.error:  # a principal point outside the image: no extended statistics
            sd_int, per_view = np.full(4 + ncoef, np.nan), np.full(len(objs), np.nan)
        sd_dist = np.zeros(ncoef)
        free = DIST_MODELS[model][1]
        sd_dist[list(free)] = sd_int[4:4 + ncoef][list(free)]
        msgs, bad = undetermined_distortion(dev.K, dev.coeffs, sd_dist, size, model, "camera", "--cam-dist", imgs)
        if not bad or dist != "auto" or model == AUTO_MODELS[-1]:
            break
        nxt = AUTO_MODELS[AUTO_MODELS.index(model) + 1]
        steps.append(f"{model} -> {nxt} ({', '.join(bad)} undetermined)")
        model = nxt
    warnings = list(msgs)
    med = float(np.nanmedian(per_view)) if np.any(np.isfinite(per_view)) else float("nan")
    for n, r in zip(names, per_view):
        if np.isfinite(r) and r > max(max_view_rms_ratio * med, 0.3):
            warnings.append(f"photo {n}: RMS {r:.2f} px against a median of {med:.2f}: blurred, moved during the "
                            "exposure, or a wrong detection? Leave it out and calibrate again")
    hull = np.zeros((size[1], size[0]), bool)
    for m in imgs:
        hull |= board_region(m, size)
    coverage = float(hull.mean())
    if coverage < min_coverage:
        warnings.append(f"the boards cover only {coverage:.0%} of the image: the lens distortion near the edges and "
                        "corners is extrapolated; add photos with the board near the edges and in the corners")
    std = {"f_c": float(sd_int[1] if fix_aspect_ratio else sd_int[0]), "fy_c": float(sd_int[1]), "u0c": float(sd_int[2]), "v0c": float(sd_int[3]),
           "cam_dist": [float(v) for v in sd_dist]}
    poses = []
    for j, n in enumerate(names):
        R = models.rvec_to_matrix(dev.rvecs[j]) @ (labellings[j].G if labellings[j] is not None else np.eye(3))
        poses.append({"name": n, "n_corners": int(len(objs[j])), "cam_rms": float(per_view[j]),
                      "camera_angles_deg": models.board_angles_deg(R, dev.tvecs[j]).tolist(),
                      "projector_angles_deg": None})
    verdict = "weak" if warnings else "good"
    if warnings:
        _warnings.warn("; ".join(warnings), WeakPoseWarning, stacklevel=2)
    cov = _covariance(dev, objs, free, fix_aspect_ratio)
    info = {"cam_dist_model": model, "auto_dist": steps, "coverage": coverage, "init": dev.init,
            "photos": len(views), "covariance": cov}
    own = None if cov is None else (tuple(cov["params"]), np.asarray(cov["matrix"], float))
    return Calibration(camera=Device(dev.K, size, Distortion("opencv", coeffs=tuple(float(c) for c in dev.coeffs)),
                                     covariance=own),
                       projector=None, R=None, T=None, method="camera-only", cam_rms=dev.rms, std=std,
                       poses=tuple(poses), views=tuple(given), warnings=tuple(warnings), info=info, verdict=verdict,
                       verdict_reasons=tuple(warnings))
