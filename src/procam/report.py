"""Per-pose residuals of a calibration (for summaries and plots).

For every view: the board pose from PnP with the calibrated intrinsics, each device on its own
(METHOD §11.1, :func:`procam.residuals.pnp`, the same PnP as ``Calibration.cam_rms`` and
``procam evaluate``), and the residual vectors **observed - predicted** in each device's own
(distorted) pixels.
"""

from __future__ import annotations

import numpy as np

from .errors import CalibrationError
from .residuals import pnp


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
