"""Reprojection residuals shared by the solvers, the evaluation and the reports.

One implementation of each measure, so that a calibration's own ``cam_rms`` / ``stereo_rms`` and
``procam evaluate`` on the same pose agree (every RMS is :func:`procam.stats.rms`):

* :func:`pnp` -- board pose from undistorted pixels with the intrinsics fixed;
* :func:`stereo_pose` -- board pose with both devices' intrinsics and ``(R, T)`` fixed;
* :func:`pose_residuals` -- every view's residual vectors under a calibration, each device on its own
  (PnP with the calibrated intrinsics), in the device's own distorted pixels;
* :func:`calibration_residuals` -- the residuals behind a calibration's own ``cam_rms`` / ``proj_rms``
  (outliers the solver rejected marked), for the figures and the report.

Sign convention: every residual is **observed - predicted** (pixels).

This module is below :mod:`procam.single_pose`, :mod:`procam.multi_pose` and
:mod:`procam.evaluate`; it imports only :mod:`procam.models`, :mod:`procam.stats` and :mod:`procam.errors`.
"""

from __future__ import annotations

import numpy as np

from . import models
from .errors import CalibrationError

#: Termination of the final ``cv2.solvePnPRefineLM`` step of :func:`pnp`: at most this many iterations,
#: or a step below this epsilon.
PNP_REFINE_ITERATIONS, PNP_REFINE_EPS = 100, 1e-15


def pnp(obj, pts, K, *, refine: bool = True):
    """Board pose from undistorted pixels with fixed ``K``: ``(R (3, 3), t (3,), residuals (N, 2))``.

    ``cv2.solvePnP`` with ``SOLVEPNP_ITERATIVE`` (OpenCV's default, as used by the paper); if that
    fails or puts the board behind the device (a rare planar failure of its start), an IPPE start
    refined by the iterative method.  ``refine`` polishes the pose with ``cv2.solvePnPRefineLM``
    (:data:`PNP_REFINE_ITERATIONS`, :data:`PNP_REFINE_EPS`) so the RMS is that of the converged minimum.

    Parameters
    ----------
    obj : (N, 3) board points; pts : (N, 2) undistorted pixels (finite, N >= 4); K : (3, 3).

    Returns
    -------
    R, t : board -> device pose; residuals : (N, 2) observed - predicted pixels.

    Raises
    ------
    CalibrationError
        No pose with the board in front of the device.
    """
    import cv2

    obj = np.ascontiguousarray(np.asarray(obj, float).reshape(-1, 3))
    pts = np.asarray(pts, float).reshape(-1, 2)
    K = np.asarray(K, float)
    img = np.ascontiguousarray(pts.reshape(-1, 1, 2))

    def bad(ok, tvec):
        return not ok or not np.all(np.isfinite(tvec)) or tvec.ravel()[2] <= 0

    ok, rvec, tvec = cv2.solvePnP(obj, img, K, None, flags=cv2.SOLVEPNP_ITERATIVE)
    if bad(ok, tvec):
        ok, rvec, tvec = cv2.solvePnP(obj, img, K, None, flags=cv2.SOLVEPNP_IPPE)
        if ok:
            ok, rvec, tvec = cv2.solvePnP(obj, img, K, None, rvec, tvec, True, cv2.SOLVEPNP_ITERATIVE)
    if bad(ok, tvec):
        raise CalibrationError("solvePnP found no pose with the board in front of the device")
    if refine:
        rv, tv = cv2.solvePnPRefineLM(obj, img, K, None, rvec.copy(), tvec.copy(),
                                     (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, PNP_REFINE_ITERATIONS,
                                      PNP_REFINE_EPS))
        if not bad(True, tv) and np.all(np.isfinite(rv)):
            rvec, tvec = rv, tv
    R = models.rvec_to_matrix(rvec)
    t = np.asarray(tvec, float).ravel()
    return R, t, pts - models.project(K, R, t, obj)


def stereo_pose(obj, cam_u, proj_u, Kc, Kp, R, T, R0, t0, *, tol: float = 1e-12):
    """Board pose (camera frame) minimising camera + projector residuals with everything else fixed.

    Parameters
    ----------
    obj : (N, 3) board points; cam_u, proj_u : (N, 2) undistorted camera / projector pixels.
    Kc, Kp : (3, 3) intrinsics; R, T : camera -> projector; R0, t0 : start (camera PnP pose).
    tol : ftol = xtol = gtol of ``least_squares`` (LM).

    Returns
    -------
    R_cb (3, 3), t_cb (3,), cam residuals (N, 2), proj residuals (N, 2) (observed - predicted, pixels)
    """
    from scipy.optimize import least_squares

    obj = np.asarray(obj, float).reshape(-1, 3)
    cam_u = np.asarray(cam_u, float).reshape(-1, 2)
    proj_u = np.asarray(proj_u, float).reshape(-1, 2)
    R = np.asarray(R, float)
    T = np.asarray(T, float).reshape(3)

    def res(x):
        R_cb = models.rvec_to_matrix(x[:3])
        Xc = obj @ R_cb.T + x[3:]
        rc = cam_u - models.project(Kc, np.eye(3), np.zeros(3), Xc)
        rp = proj_u - models.project(Kp, R, T, Xc)
        return np.concatenate([rc.ravel(), rp.ravel()])

    x0 = np.concatenate([models.matrix_to_rvec(R0), np.ravel(t0)])
    sol = least_squares(res, x0, method="lm", x_scale="jac", ftol=tol, xtol=tol, gtol=tol)
    r = sol.fun
    n = len(obj)
    return (models.rvec_to_matrix(sol.x[:3]), sol.x[3:].copy(), r[:2 * n].reshape(-1, 2),
            r[2 * n:].reshape(-1, 2))


def pose_residuals(calib, views, *, min_points: int = 4) -> list[dict]:
    """Per-view residuals of ``calib``.

    Parameters
    ----------
    calib : :class:`procam.calibration.Calibration` (camera-only calibrations give camera residuals only).
    views : :class:`procam.view.View` sequence.
    min_points : a device with fewer usable corners in a view gets no residuals (all NaN).

    Returns
    -------
    list of dict, one per view: ``name``, ``cam_pts``, ``cam_res``, ``proj_pts``, ``proj_res``
    ((N, 2) arrays, NaN where a corner is missing or PnP failed; ``proj_*`` None without a
    projector); residuals observed - predicted, in the device's own distorted pixels.
    """
    out = []
    for v in views:
        ok = v.valid if calib.projector is not None else np.isfinite(v.cam_pts).all(1)
        item = {"name": v.name, "cam_pts": v.cam_pts, "cam_res": np.full_like(v.cam_pts, np.nan),
                "proj_pts": v.proj_pts if calib.projector is not None else None,
                "proj_res": np.full_like(v.proj_pts, np.nan) if calib.projector is not None else None}
        devices = [("cam", calib.camera, v.cam_pts)]
        if calib.projector is not None:
            devices.append(("proj", calib.projector, v.proj_pts))
        for key, dev, pts in devices:
            und = np.full_like(pts, np.nan, dtype=float)
            if ok.any():
                with np.errstate(all="ignore"):
                    und[ok] = dev.undistort(pts[ok])
            use = ok & np.isfinite(und).all(1)
            if use.sum() < min_points:
                continue
            try:
                R, t, _ = pnp(v.obj_pts[use], und[use], dev.K)
            except CalibrationError:
                continue
            res = np.full_like(pts, np.nan, dtype=float)
            res[use] = pts[use] - dev.project(R, t, v.obj_pts[use])
            item[f"{key}_res"] = res
        out.append(item)
    return out


def _rejected_mask(pose: dict, device: str, n: int) -> np.ndarray:
    """(n,) bool of the corners a single-pose solver rejected as outliers for ``device``."""
    out = np.zeros(n, bool)
    for r in (pose.get("rejected_corners") or {}).get(device) or []:
        i = int(r["index"]) if isinstance(r, dict) else int(r)
        if 0 <= i < n:
            out[i] = True
    return out


def _pnp_device(obj, pts_und, used, K):
    """Residuals (N, 2) of undistorted points under the PnP pose fitted to the ``used`` corners (NaN
    elsewhere, and everywhere when PnP fails)."""
    res = np.full_like(pts_und, np.nan, dtype=float)
    if used.sum() < 4:
        return res
    try:
        R, t, _ = pnp(obj[used], pts_und[used], K)
    except CalibrationError:
        return res
    ok = np.isfinite(pts_und).all(1)
    res[ok] = pts_und[ok] - models.project(K, R, t, obj[ok])
    return res


def _same_views(calib, views) -> bool:
    """Are ``views`` the calibration's own poses (same count, same names in order)?"""
    poses = list(calib.poses)
    if len(poses) != len(views):
        return False
    return all(str(p.get("name", "")) == str(v.name) or (not v.name and str(p.get("name", "")) == f"pose{k + 1}")
               for k, (p, v) in enumerate(zip(poses, views)))


def calibration_residuals(calib, views=None) -> list[dict]:
    """Per-view residuals measured as the calibration measured its own ``cam_rms`` / ``proj_rms``.

    The figures and tables show these, so that the RMS a figure prints is the RMS the calibration
    reports (:attr:`~procam.calibration.Calibration.cam_rms`, ``proj_rms``):

    * **single-pose** and **camera-only** (its one pose, with ``rejected_corners``): each device's
      PnP pose with the calibrated intrinsics fitted to the corners the solver kept, residuals in
      **undistorted** pixels (the single-pose RMS is defined there); the corners it rejected as
      outliers get their residual under the same pose and ``*_used`` False;
    * **multi-pose** with a joint refinement (poses with ``R_cam``, ``t_cam``): the residuals of the
      refined model at its own board poses, in distorted pixels (their pooled RMS is ``cam_rms`` /
      ``proj_rms``);
    * otherwise (other views, a multi-pose calibration without refinement, a file without poses):
      :func:`pose_residuals` (PnP per device), every corner used.

    Parameters
    ----------
    calib : :class:`procam.calibration.Calibration`.
    views : :class:`procam.view.View` sequence (default ``calib.views``).

    Returns
    -------
    list of dict, one per view, with the keys of :func:`pose_residuals` plus ``cam_used`` and
    ``proj_used`` ((N,) bool: counted in the RMS; a finite residual with ``used`` False is a rejected
    corner; ``proj_used`` None without a projector) and ``source`` (how they were measured, one of
    ``"single-pose"``, ``"multi-pose"``, ``"pnp"``).
    """
    own = views is None
    views = list(calib.views if views is None else views)
    own = own or _same_views(calib, views)
    poses = list(calib.poses)
    has_proj = calib.projector is not None
    out = []
    single = own and calib.method in ("single-pose", "camera-only") and len(views) == 1 and len(poses) == 1
    multi = (own and calib.method == "multi-pose" and calib.info.get("refined", True)
             and all("R_cam" in p and "t_cam" in p for p in poses)
             and all(int(p.get("n_corners", -1)) == int(v.valid.sum()) for p, v in zip(poses, views)))
    if single:
        v, pose = views[0], poses[0]
        n = len(v.obj_pts)
        valid = (v.valid if has_proj else np.isfinite(v.cam_pts).all(1)) & np.isfinite(v.obj_pts).all(1)
        item = {"name": v.name, "source": "single-pose"}
        devices = [("cam", "camera", calib.camera, v.cam_pts)]
        if has_proj:
            devices.append(("proj", "projector", calib.projector, v.proj_pts))
        for key, device, dev, pts in devices:
            und = np.full((n, 2), np.nan)
            with np.errstate(all="ignore"):
                und[valid] = dev.undistort(pts[valid])
            used = valid & ~_rejected_mask(pose, device, n)
            item[f"{key}_pts"], item[f"{key}_res"] = pts, _pnp_device(v.obj_pts, und, used, dev.K)
            item[f"{key}_used"] = used & np.isfinite(item[f"{key}_res"]).all(1)
        if not has_proj:
            item.update(proj_pts=None, proj_res=None, proj_used=None)
        return [item]
    if multi:
        for p, v in zip(poses, views):
            m = v.valid
            R_cb, t_cb = np.asarray(p["R_cam"], float), np.asarray(p["t_cam"], float)
            R_pb, t_pb = models.compose(calib.R, calib.T, R_cb, t_cb)
            cam_res = np.full_like(v.cam_pts, np.nan)
            proj_res = np.full_like(v.proj_pts, np.nan)
            cam_res[m] = v.cam_pts[m] - calib.camera.project(R_cb, t_cb, v.obj_pts[m])
            proj_res[m] = v.proj_pts[m] - calib.projector.project(R_pb, t_pb, v.obj_pts[m])
            out.append({"name": v.name, "cam_pts": v.cam_pts, "cam_res": cam_res, "cam_used": m.copy(),
                        "proj_pts": v.proj_pts, "proj_res": proj_res, "proj_used": m.copy(), "source": "multi-pose"})
        return out
    for item in pose_residuals(calib, views):
        item["cam_used"] = np.isfinite(item["cam_res"]).all(1)
        item["proj_used"] = None if item["proj_res"] is None else np.isfinite(item["proj_res"]).all(1)
        item["source"] = "pnp"
        out.append(item)
    return out
