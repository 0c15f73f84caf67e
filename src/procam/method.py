"""Which calibration method a set of views calls for, and the calibration by it.

procam has three methods (the result's :attr:`~procam.calibration.Calibration.method` names the one used):

* ``single-pose`` -- ONE view of the board seen by the camera and the projector: the seed method,
  :func:`procam.single_pose.calibrate`. With ``known_camera`` (intrinsics from an earlier calibration) the
  camera is fixed and the pose calibrates the projector and ``R, T`` (the result reads
  ``"single-pose, camera given"``);
* ``multi-pose`` -- two or more views: Zhang / Moreno-Taubin per device, the stereo pose and (by default) a
  joint refinement, :func:`procam.multi_pose.calibrate`;
* ``camera-only`` -- photos of the board without a projector: one photo by the single-pose camera solve
  (:func:`procam.single_pose.calibrate_camera_only`), several by Zhang with its checks
  (:func:`procam.multi_pose.calibrate_camera`).

:func:`choose` names the method before anything is decoded (a multi-pose pose needs fewer corners than a
single-pose one, so the decoding depends on it): the one asked for, else single-pose for one view and
multi-pose for several. Camera-only is never guessed: views without projector points are a failed decode,
not photos. :func:`check` is the one rule of what each method takes (the CLI and the rig path ask it too);
:func:`calibrate` runs the method, after checking that it can work with the views it is given.

The solvers are imported only when :func:`calibrate` runs them.
"""

from __future__ import annotations

from typing import Sequence

from .errors import CalibrationError
from . import choices

__all__ = ["METHODS", "choose", "check", "calibrate"]

#: The calibration methods.
METHODS = choices.METHODS


def choose(n_views: int, method: str | None = None) -> str:
    """The method for ``n_views`` views: ``method`` when given (one of :data:`METHODS`), else ``single-pose`` for
    one view and ``multi-pose`` for several.

    Raises
    ------
    CalibrationError
        An unknown method.
    """
    if method is None:
        return "single-pose" if n_views == 1 else "multi-pose"
    if method not in METHODS:
        raise CalibrationError(f"unknown calibration method {method!r}; choose one of {', '.join(METHODS)}")
    return method


def check(method: str, n: int, *, known_intrinsics: bool = False, unit: str = "view") -> None:
    """Raise :class:`CalibrationError` unless ``method`` can calibrate ``n`` inputs: the one method rule, worded
    once for every caller (``unit``: what the inputs are -- ``"view"``, ``"pose folder"``, ``"rig pose"``).

    single-pose takes exactly one; multi-pose at least two; known intrinsics (a camera's or a projector's) are for
    a single-pose calibration only.
    """
    if n < 1:
        raise CalibrationError(f"a calibration needs at least one {unit}")
    if method == "single-pose" and n != 1:
        raise CalibrationError(f"a single-pose calibration takes one {unit}, got {n}; calibrate several with the "
                               "multi-pose method (--method multi)")
    if method == "multi-pose" and n < 2:
        raise CalibrationError(f"a multi-pose calibration needs at least two {unit}s (three or more recommended)")
    if known_intrinsics and method != "single-pose":
        raise CalibrationError(f"known camera or projector intrinsics are for a single-pose calibration of one "
                               f"{unit}, not {method}")


def calibrate(views: Sequence, *, method: str | None = None, known_camera=None, camera=None, background=None,
              cam_dist: str = "auto", proj_dist: str = "auto", refine: bool = True, known_projector=None,
              dense=None):
    """Calibrate ``views`` by the method :func:`choose` names; the result's ``method`` says which it was.

    Parameters
    ----------
    views : :class:`procam.view.View` sequence, one per pose (camera-only: their camera points only).
    method : one of :data:`METHODS`, or None (by the number of views).
    known_camera : single-pose: the camera's intrinsics (:class:`~procam.calibration.Device`), fixed.
    camera : :class:`procam.single_pose.CameraOptions` of the single-pose camera solve (single-pose, and
        camera-only from one photo); default options when None.
    background : single-pose: :class:`procam.single_pose.background.BackgroundOptions` (default: mode ``free``).
    cam_dist, proj_dist : the OpenCV distortion models of a multi-pose calibration (``"auto"``: the richest the
        poses determine); ``cam_dist`` also of a camera-only calibration from several photos.
    refine : multi-pose: the joint refinement.
    known_projector : single-pose: the projector's intrinsics and distortion (a Device), fixed.
    dense : single-pose: :class:`procam.single_pose.dense.DenseOptions` (default options when None; a datasheet's
        priors go there).

    Returns
    -------
    :class:`procam.calibration.Calibration`

    Raises
    ------
    CalibrationError
        A method that cannot work with these views (single-pose on several, multi-pose on one, a known
        camera for anything but single-pose), and every error of the solver.
    """
    views = list(views)
    method = choose(len(views), method)
    check(method, len(views), known_intrinsics=known_camera is not None or known_projector is not None)
    if method == "multi-pose":
        from . import multi_pose

        return multi_pose.calibrate(views, cam_dist=cam_dist, proj_dist=proj_dist, refine=refine)
    if method == "camera-only" and len(views) > 1:
        from . import multi_pose

        return with_source(multi_pose.calibrate_camera(views, dist=cam_dist), views)
    from . import single_pose

    camera = single_pose.CameraOptions() if camera is None else camera
    view = views[0]
    if method == "single-pose":
        return single_pose.calibrate(view, camera=camera, known_camera=known_camera, background=background,
                                     known_projector=known_projector,
                                     dense=single_pose.dense.DenseOptions() if dense is None else dense)
    calib = single_pose.calibrate_camera_only(view.obj_pts, view.cam_pts, view.cam_size, name=view.name,
                                              camera=camera)
    return with_source(calib.replace(views=(view,)), views)


def with_source(calib, views):
    """``calib`` saying what it was calibrated from (``info["calibrated_from"]``: the views' names -- the photos'
    and pose folders' paths --, their count and the date, UTC): a camera file is reused long after it is made."""
    from datetime import datetime, timezone

    source = {"inputs": [{"name": str(v.name)} for v in views], "count": len(views),
              "date": datetime.now(timezone.utc).isoformat(timespec="seconds")}
    return calib.replace(info={**calib.info, "calibrated_from": source})
