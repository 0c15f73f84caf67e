"""Stereo rectification of the camera (first) and the projector (second) for any rig orientation: epipolar lines
become image rows whether the projector is beside, above or below the camera, and whatever either is rolled.

Method.  Both devices are turned into one common orientation whose x axis is the **baseline** (the line through
the two centres), so the epipolar planes (which all contain the baseline) cut both rectified images along rows:

* ``x`` = the unit baseline, signed so that the rectified rows run as close as possible to the camera's own rows
  (a beside-the-camera rig keeps its camera image unturned); for a baseline more vertical than horizontal in the
  camera image (a floor or ceiling rig) the rows run down the camera's columns: the rectified frame is **turned
  a quarter turn** (:func:`stereo_rectify` returns by how much, per device, in ``rows_along_deg``);
* ``z`` = the mean of the two viewing directions, made orthogonal to ``x``; ``y = z x x``;
* ``R1 = [x; y; z]`` (camera -> rectified), ``R2 = R1 R^T`` (projector -> rectified), so a point's rectified
  camera and projector coordinates differ by the baseline alone: ``X2 = X1 + (Tx, 0, 0)``, ``Tx = -/+|T|``.

This is Bouguet's construction (``cv2.stereoRectify``) without its two choices that fail procam's rigs: OpenCV
turns a vertical baseline onto the y axis (epipolar lines on columns), and splits a large relative roll (an
upside-down projector) half and half between the devices.

Framing: both rectified images share the focal length ``scale`` x the camera's (mean of fx, fy) and the principal
row; their rows span the band both devices see (the intersection of the two images' row ranges, from points
along each image's border, undistorted), each device's columns its own image.  ``P1 = [K1 | 0]``,
``P2 = [K2 | K2 (Tx, 0, 0)]`` (``P2[0, 3] = f Tx``, board units: OpenCV's layout), and ``Q`` turns
``(x1, y, x1 - x2 disparity, 1)`` into a 3-D point of the rectified camera frame.

Fails (``CalibrationError``) when the rectifying rotation turns part of an image behind its device (a baseline
nearly along a viewing direction, or devices looking in very different directions) or the images share no rows.
"""

from __future__ import annotations

import math

import numpy as np

from ..calibration import Calibration, Device
from ..errors import CalibrationError
from .frames import require_rig


def rectifying_rotations(calib: Calibration) -> tuple[np.ndarray, np.ndarray]:
    """``(R1, R2)``: camera -> rectified and projector -> rectified rotations (module docstring)."""
    require_rig(calib)
    R = np.asarray(calib.R, float)
    T = np.asarray(calib.T, float).reshape(3)
    centre = -R.T @ T                          # projector centre in the camera frame
    if not np.linalg.norm(centre) > 0:
        raise CalibrationError("the camera and the projector have the same centre: there is no baseline to rectify")
    x = centre / np.linalg.norm(centre)
    if abs(x[0]) >= abs(x[1]):                 # beside the camera: rows stay rows, left to right
        x = x if x[0] >= 0 else -x
    else:                                      # above or below: rows run down the camera's columns
        x = x if x[1] >= 0 else -x
    z = np.array([0.0, 0.0, 1.0]) + R.T @ np.array([0.0, 0.0, 1.0])
    z = z - (z @ x) * x
    if not np.linalg.norm(z) > 1e-6:
        raise CalibrationError("the baseline lies along the devices' mean viewing direction; rectification is not "
                               "possible for this camera-projector geometry")
    z /= np.linalg.norm(z)
    y = np.cross(z, x)
    R1 = np.vstack([x, y, z])
    return R1, R1 @ R.T


def rows_along_deg(R_rect) -> float:
    """The direction of the rectified rows (+x) in a device's own image, degrees from its +x axis towards its +y
    (clockwise on the screen): 0 unturned, 90 the rows run down the device's columns (its image turned a quarter
    turn counter-clockwise), 180 upside-down."""
    x = np.asarray(R_rect, float)[0]
    return math.degrees(math.atan2(x[1], x[0]))


def turn_words(angle_deg: float) -> str:
    """The rectification's turn of one device's image in words (:func:`rows_along_deg`)."""
    q = int(round(angle_deg / 90.0)) % 4
    return ("not turned", "turned a quarter turn counter-clockwise (rows along its columns, downwards)",
            "turned upside-down", "turned a quarter turn clockwise (rows along its columns, upwards)")[q]


def _border_rays(device: Device, R_rect, n: int = 64) -> np.ndarray:
    """Normalised rectified coordinates (M, 2) of points along the device image's border."""
    W, H = (int(v) for v in device.image_size)
    t = np.linspace(0.0, 1.0, n)
    xs = np.concatenate([t * (W - 1), np.full(n, W - 1.0), (1 - t) * (W - 1), np.zeros(n)])
    ys = np.concatenate([np.zeros(n), t * (H - 1), np.full(n, H - 1.0), (1 - t) * (H - 1)])
    und = device.undistort(np.column_stack([xs, ys]))
    und = und[np.isfinite(und).all(1)]
    Kinv = np.linalg.inv(np.asarray(device.K, float))
    ray = np.column_stack([und, np.ones(len(und))]) @ Kinv.T @ np.asarray(R_rect).T
    if np.any(ray[:, 2] <= 1e-6):
        raise CalibrationError("the rectifying rotation turns part of the image behind the device; "
                               "rectification is not possible for this camera-projector geometry")
    return ray[:, :2] / ray[:, 2:3]


def stereo_rectify(calib: Calibration, *, scale: float = 1.0, max_size: int = 8192) -> dict:
    """Rectification of camera (first) and projector (second): epipolar lines become image rows, for any rig
    orientation (module docstring).

    Returns
    -------
    dict with ``R1, R2`` (3, 3), ``P1, P2`` (3, 4) (``P2[0, 3] = f * Tx``, the rectified baseline in board
    units), ``Q`` (4, 4), ``size1``, ``size2`` ((width, height) of each rectified image), ``baseline`` (``Tx``),
    ``rows_along_deg`` (``{"camera": deg, "projector": deg}``, :func:`rows_along_deg`); the maps are
    ``undistort_maps(calib.camera, new_K=P1[:, :3], R=R1, size=size1)`` and likewise with ``P2, R2, size2`` for
    the projector (:mod:`procam.export.maps`).
    """
    if not (np.isfinite(scale) and scale > 0):
        raise CalibrationError(f"scale must be a positive number, got {scale}")
    R1, R2 = rectifying_rotations(calib)
    T = np.asarray(calib.T, float).reshape(3)
    Tx = float((R2 @ T)[0])
    f = scale * 0.5 * float(calib.camera.K[0, 0] + calib.camera.K[1, 1])
    b1, b2 = _border_rays(calib.camera, R1), _border_rays(calib.projector, R2)
    y0 = max(b1[:, 1].min(), b2[:, 1].min())
    y1 = min(b1[:, 1].max(), b2[:, 1].max())
    if not y1 > y0:
        raise CalibrationError("the camera and the projector see no common rows after rectification")
    cy = -f * y0
    height = int(np.ceil(f * (y1 - y0))) + 1
    out = {"R1": R1, "R2": R2, "baseline": Tx,
           "rows_along_deg": {"camera": rows_along_deg(R1), "projector": rows_along_deg(R2)}}
    for k, b in (("1", b1), ("2", b2)):
        x0, x1 = b[:, 0].min(), b[:, 0].max()
        width = int(np.ceil(f * (x1 - x0))) + 1
        if width > max_size or height > max_size:
            raise CalibrationError(f"the rectified images would be {width}x{height} px (more than {max_size}); "
                                   "lower scale")
        P = np.zeros((3, 4))
        P[:, :3] = [[f, 0, -f * x0], [0, f, cy], [0, 0, 1]]
        out["P" + k] = P
        out["size" + k] = (width, height)
    out["P2"][0, 3] = f * Tx
    c1, c2 = out["P1"][0, 2], out["P2"][0, 2]
    out["Q"] = np.array([[1.0, 0, 0, -c1], [0, 1.0, 0, -cy], [0, 0, 0, f], [0, 0, -1.0 / Tx, (c1 - c2) / Tx]])
    return out
