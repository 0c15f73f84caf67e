"""Per-pose residuals of a calibration (for summaries and plots).

For every view: the board pose from PnP with the calibrated intrinsics, each device on its own
(METHOD §11.1), and the residual vectors observed - predicted in each device's pixels.
"""

from __future__ import annotations

import numpy as np


def pose_residuals(calib, views) -> list[dict]:
    """List of dicts per view: ``name, cam_pts, cam_res, proj_pts, proj_res`` (N, 2) arrays, NaN where a
    corner is missing; residuals in the device's own (distorted) pixels."""
    import cv2

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
            if ok.sum() < 4:
                continue
            und = dev.undistort(pts[ok])
            good, rvec, tvec = cv2.solvePnP(v.obj_pts[ok], und.reshape(-1, 1, 2), np.asarray(dev.K, float), None,
                                            flags=cv2.SOLVEPNP_ITERATIVE)
            if not good:
                continue
            R = cv2.Rodrigues(rvec)[0]
            pred = dev.project(R, tvec.ravel(), v.obj_pts[ok])
            res = np.full_like(pts, np.nan)
            res[ok] = pts[ok] - pred
            item[f"{key}_res"] = res
        out.append(item)
    return out
