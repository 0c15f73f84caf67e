"""Rigs: several projectors and cameras, one calibration, their agreement and their blend.

A rig's capture is one **rig pose folder** per board pose (:mod:`procam.capture.rig`): one ordinary pose folder
per (camera, projector) pair, the projectors shown in turn.  This package turns them into one calibration of
every device in the reference camera's frame (the first camera; ``x_dev = R x_ref + T``):

* :mod:`~procam.rig.calibrate` - :func:`calibrate_rig`: single-pose per pair with the shared camera (one rig
  pose), or per-pair multi-pose initialisation then a joint refinement of every device and pose
  (:mod:`~procam.rig.joint`, sparse least squares); every relative pose with its std (:class:`~procam.calibration.RigCalibration`).
* :mod:`procam.io.rig` - the rig calibration file (JSON, OpenCV YAML); each pair also an ordinary procam
  calibration (:func:`procam.io.load_calibration` with ``pair=``).
* :mod:`~procam.rig.verify` - where two projectors light the same corners, their triangulated points agree
  (mm and % of depth).
* :mod:`~procam.rig.blend` - per projector, alpha per projector pixel: smooth ramps summing to 1 where the
  projectors overlap on the surface the camera sees.
"""

from __future__ import annotations

from .calibrate import RigPoseViews, calibrate_rig, rig_views_from_folders  # noqa: F401
from ..calibration import RelativePose, RigCalibration, RigDevice  # noqa: F401

__all__ = ["RigPoseViews", "calibrate_rig", "rig_views_from_folders", "RigCalibration", "RigDevice", "RelativePose"]
