"""The plausibility gates every calibration passes: is it possible for a real rig?

A calibration (:func:`gate_failures`, :func:`apply_gates`) whose focal length is impossible for its image (or not positive), whose ``R`` is not a rotation, whose boards lie behind a device, whose stereo RMS is
far above the devices' own or whose baseline is absurd against the boards' distance is ``failed`` -- from every
method and every fallback (single-pose, multi-pose with or without the joint refinement, camera-only). The gates
read only what the calibration carries; they assume a real rig (a lens of 11-136 deg diagonal field of view,
boards in front of both devices).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Focal lengths outside this range x the image diagonal (diagonal fields of view of ~136 deg down to ~11 deg)
#: are impossible for a real device (the single-pose rating's ``plausible_f_range`` is this range).
FOCAL_RANGE = (0.2, 5.0)


@dataclass(frozen=True)
class GateOptions:
    """Thresholds of :func:`gate_failures`.

    Attributes
    ----------
    focal_range : a focal length outside this range x the image diagonal is impossible (:data:`FOCAL_RANGE`).
    stereo_ratio, stereo_floor_px : a stereo RMS above ``max(stereo_ratio x the devices' own RMS,
        stereo_floor_px)`` means the two devices' views of the boards disagree: ``R, T`` do not describe the rig.
    baseline_range : ``|T|`` outside this range x the boards' median distance from the camera is no real rig.
    """

    focal_range: tuple = FOCAL_RANGE
    stereo_ratio: float = 4.0
    stereo_floor_px: float = 1.0
    baseline_range: tuple = (1e-3, 20.0)


def focal_failure(key: str, f, size, focal_range=FOCAL_RANGE) -> str | None:
    """``"<key> = ... px is impossible for a WxH image (plausible ...)"`` when the focal length ``f`` is not
    positive or outside ``focal_range`` x the image diagonal; None when it is possible."""
    lo, hi = (focal_range[0] * float(np.hypot(*size)), focal_range[1] * float(np.hypot(*size)))
    if np.isfinite(f) and lo <= f <= hi:
        return None
    why = "not positive" if np.isfinite(f) and f <= 0 else f"plausible {lo:.0f}-{hi:.0f} px"
    return f"{key} = {f:.4g} px is impossible for a {size[0]}x{size[1]} image ({why})"


def _board_poses(calib):
    """``[(name, obj (N, 3), R_cb, t_cb, R_pb or None, t_pb or None)]``: the calibration's own board poses (a
    multi-pose calibration's ``R_cam, t_cam``; a single-pose one's device solutions); empty when it keeps none."""
    out = []
    views = list(calib.views)
    for k, p in enumerate(calib.poses):
        if "R_cam" in p and "t_cam" in p and k < len(views):
            R_cb, t_cb = np.asarray(p["R_cam"], float), np.asarray(p["t_cam"], float)
            obj = views[k].obj_pts[views[k].valid]
            out.append((str(p.get("name", f"pose{k + 1}")), obj, R_cb, t_cb, None, None))
    if out or len(views) != 1:
        return out
    cam, proj = calib.info.get("camera"), calib.info.get("projector")
    if getattr(cam, "R", None) is None:
        return out
    obj = views[0].obj_pts[np.isfinite(views[0].obj_pts).all(1)]
    R_pb = getattr(proj, "R", None)
    return [(str(views[0].name), obj, np.asarray(cam.R, float), np.asarray(cam.t, float),
             None if R_pb is None else np.asarray(R_pb, float), None if R_pb is None else np.asarray(proj.t, float))]


def gate_failures(calib, options: GateOptions = GateOptions()) -> list[str]:
    """What makes a calibration impossible for a real rig, one message each (empty: it passes).

    The gates, for every method: each focal length positive and possible for its image size
    (:func:`focal_failure`); ``R`` a rotation (``det R = +1``); every board in front of both devices; the stereo
    RMS not far above the devices' own RMS (the corners' noise); ``|T|`` neither zero nor absurd against the
    boards' distance. Reads only what the calibration carries (no refit).
    """
    from pathlib import Path

    msgs = []
    devices = [("camera", "c", calib.camera)]
    if calib.projector is not None:
        devices.append(("projector", "p", calib.projector))
    for device, d, dev in devices:
        K = np.asarray(dev.K, float)
        for key, f in ((f"f_{d}", K[0, 0]), (f"fy_{d}", K[1, 1])):
            why = focal_failure(key, float(f), tuple(dev.image_size), options.focal_range)
            if why:
                msgs.append(f"{device}: FAILED estimate: {why}")
    if calib.R is None or calib.T is None:
        return msgs
    R, T = np.asarray(calib.R, float), np.asarray(calib.T, float).ravel()
    det = float(np.linalg.det(R))
    if not (np.isfinite(det) and abs(det - 1.0) < 1e-3 and np.allclose(R @ R.T, np.eye(3), atol=1e-3)):
        msgs.append(f"FAILED estimate: R is not a rotation (det R = {det:+.3f}"
                    + ("; a mirror" if det < 0 else "") + "): no rig turns the camera into the projector so")
    dist = []
    for name, obj, R_cb, t_cb, R_pb, t_pb in _board_poses(calib):
        X = obj @ R_cb.T + t_cb
        dist.append(float(np.median(np.linalg.norm(X, axis=1))))
        Xp = X @ R.T + T if R_pb is None else obj @ R_pb.T + t_pb
        for device, P in (("camera", X), ("projector", Xp)):
            if not np.all(P[:, 2] > 0):
                msgs.append(f"pose {Path(name).name!r}: FAILED estimate: the board is behind the {device} ("
                            f"{int(np.sum(P[:, 2] <= 0))} of {len(P)} corners at z <= 0 in its frame): R, T put "
                            f"the {device} on the wrong side of the board")
    own = max((v for v in (calib.cam_rms, calib.proj_rms) if v is not None and np.isfinite(v)), default=np.nan)
    s = calib.stereo_rms
    if s is not None and np.isfinite(s) and np.isfinite(own) and s > max(options.stereo_ratio * own,
                                                                         options.stereo_floor_px):
        msgs.append(f"FAILED estimate: stereo RMS {s:.3g} px is {s / max(own, 1e-12):.0f} times the devices' own "
                    f"fits ({own:.2g} px, the corners' noise): the boards' poses seen by the camera and by the "
                    "projector disagree, so R, T do not describe the rig")
    if dist:
        d0, n = float(np.median(dist)), float(np.linalg.norm(T))
        lo, hi = options.baseline_range
        if not (np.isfinite(n) and lo * d0 <= n <= hi * d0):
            msgs.append(f"FAILED estimate: the baseline |T| = {n:.4g} is {n / d0:.3g} times the boards' distance "
                        f"from the camera ({d0:.4g}): no real rig (plausible {lo:g}-{hi:g} times)")
    return msgs


def apply_gates(calib, options: GateOptions = GateOptions(), *, over_degenerate: bool = True, stacklevel: int = 2):
    """The calibration with the verdict ``failed`` when a gate fails (:func:`gate_failures`): the failures lead
    its ``verdict_reasons``, join its ``warnings`` and are emitted as one
    :class:`~procam.errors.FailedEstimateWarning`. A calibration that passes is returned unchanged (as is a
    failure a solver already gave as a reason).

    ``over_degenerate=False`` keeps a ``degenerate`` verdict (the failures join only its warnings): where the
    stable prediction already says the numbers may be anything, where the optimiser stopped -- and so whether
    they are also impossible -- must not change the verdict (single-pose, :mod:`procam.single_pose.rating`).
    """
    import warnings as _warnings

    from ..errors import FailedEstimateWarning

    failures = [m for m in gate_failures(calib, options)
                if not any(m.split("FAILED estimate: ", 1)[-1] in r for r in calib.verdict_reasons)]
    if not failures:
        return calib
    warnings = tuple(calib.warnings) + tuple(w for w in failures if w not in calib.warnings)
    if calib.verdict == "degenerate" and not over_degenerate:
        return calib.replace(warnings=warnings)
    _warnings.warn("; ".join(failures), FailedEstimateWarning, stacklevel=stacklevel + 1)
    return calib.replace(verdict="failed", verdict_reasons=tuple(failures) + tuple(calib.verdict_reasons),
                         warnings=warnings)
