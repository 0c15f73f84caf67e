"""Unity: each device as a Physical Camera (focal length, sensor size, lens shift, gate fit) and a transform in
Unity's left-handed, y-up world, in metres.

Unity's physical camera, as its documentation states it (``Camera.focalLength``, ``sensorSize``, ``lensShift``,
``gateFit``, ``Camera.FocalLengthToFieldOfView``, ``Camera.GateFitMode.None``, ``Camera.worldToCameraMatrix``,
``Camera.WorldToScreenPoint``):

* the field of view along a sensor side is ``2 atan(side / (2 focalLength))``;
* ``lensShift`` is in units of the sensor size: a shift of 0.5 moves the frame by half the sensor's side, so
  the frustum's window at the near plane ``n`` is ``[(-1/2 + shift) side n / focalLength]`` to ``[(+1/2 + shift)
  side n / focalLength]`` along each side;
* ``gateFit = None`` stretches the sensor gate onto the resolution gate: the sensor's width spans the image's
  width and its height the image's height, whatever their aspect ratios, which is how a calibration's
  ``fx != fy`` is held (:func:`unity_projection` builds the matrix from exactly these rules);
* camera space is OpenGL's (forward is -z): ``worldToCameraMatrix = scale(1, 1, -1) * transform.worldToLocalMatrix``;
* screen coordinates are pixels from the **bottom-left corner** of the bottom-left pixel: procam pixel
  ``(x, y)`` (origin at the centre of the top-left pixel) is screen ``(x + 0.5, H - y - 0.5)``.

procam's numbers: with a sensor width ``w`` (mm, :data:`SENSOR_WIDTH_MM` unless given), ``focalLength = fx w / W``,
``sensorSize = (w, focalLength H / fy)``, ``lensShift = (((W - 1)/2 - u0) / W, (v0 - (H - 1)/2) / H)``, which
are the datasheet lens shifts of :mod:`procam.datasheet` as fractions (positive: the image right of / above the
lens axis).

The world: Unity's ``(x, y, z) = s (x, -y, z)`` of the upright world device's OpenCV frame (``world``, see
:mod:`.frames`), ``s`` the metres per calibration unit.  A device's local frame (Unity camera axes: x right, y up,
z forward) is ``diag(1, -1, 1)`` of its OpenCV frame, so its rotation is ``S R_dw^T S`` (``S = diag(1, -1, 1)``),
a proper rotation (det +1) of Unity's left-handed frame; nothing is mirrored.  Unity's ``eulerAngles`` are
its ZXY order (z, then x, then y about the world axes).

Lens distortion and skew cannot be held by a Unity camera: the document says so per device, and the distortion
maps of :mod:`.maps` warp a pinhole render into what the real projector must show.
"""

from __future__ import annotations

import numpy as np

from ..calibration import Calibration, Device
from ..io.formats import UNITY_FORMAT
from .frames import device_poses, devices, metres_per_unit, skew_note
from .opengl import opengl_projection

#: Unity's left-handed world (x right, y up, z forward) from an upright device's OpenCV frame (x right, y down).
UNITY_FROM_CV = np.diag([1.0, -1.0, 1.0])
#: The sensor width of the exported physical cameras (mm): any width gives the same images, this is Unity's
#: default 36 mm (full frame) so the focal lengths read like a photographer's.
SENSOR_WIDTH_MM = 36.0
#: Unity's default clipping planes (m), used when none are given.
DEFAULT_CLIP_M = (0.3, 1000.0)


def physical_camera(device: Device, sensor_width_mm: float = SENSOR_WIDTH_MM) -> dict:
    """Unity's Physical Camera properties of ``device`` (module docstring): ``focalLength`` (mm), ``sensorSize``
    ([w, h] mm), ``lensShift`` ([x, y], fractions of the sensor size), ``gateFit`` ``"None"``."""
    K = np.asarray(device.K, float)
    W, H = (float(v) for v in device.image_size)
    fx, fy, u0, v0 = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
    focal = fx * sensor_width_mm / W
    return {"usePhysicalProperties": True, "focalLength": focal, "sensorSize": [sensor_width_mm, focal * H / fy],
            "lensShift": [((W - 1) / 2 - u0) / W, (v0 - (H - 1) / 2) / H], "gateFit": "None"}


def unity_projection(physical: dict, near: float, far: float) -> np.ndarray:
    """Unity's projection matrix of a physical camera with ``gateFit`` None, from its documented rules (module
    docstring): the frustum's window at the near plane from the focal length, sensor size and lens shift, then
    ``Matrix4x4.Frustum`` (OpenGL's ``glFrustum``)."""
    f = float(physical["focalLength"])
    sx, sy = (float(v) for v in physical["sensorSize"])
    lx, ly = (float(v) for v in physical["lensShift"])
    left, right = (-0.5 + lx) * sx * near / f, (0.5 + lx) * sx * near / f
    bottom, top = (-0.5 + ly) * sy * near / f, (0.5 + ly) * sy * near / f
    return np.array([[2 * near / (right - left), 0, (right + left) / (right - left), 0],
                     [0, 2 * near / (top - bottom), (top + bottom) / (top - bottom), 0],
                     [0, 0, -(far + near) / (far - near), -2 * far * near / (far - near)],
                     [0, 0, -1, 0]])


def unity_transform(R_dw, t_dw, metres: float = 1.0) -> dict:
    """A device's Unity transform from its pose ``(R_dw, t_dw)`` (world -> device, OpenCV axes, calibration units;
    :func:`procam.export.frames.device_poses`): ``position`` (m), ``rotation`` quaternion ``[x, y, z, w]``,
    ``eulerAngles`` (degrees, Unity's ZXY order), ``rotation_matrix`` and ``localToWorldMatrix`` (4x4)."""
    from scipy.spatial.transform import Rotation

    S = UNITY_FROM_CV
    R = np.asarray(R_dw, float)
    t = np.asarray(t_dw, float).reshape(3)
    M = S @ R.T @ S                      # device local -> Unity world rotation
    pos = metres * (S @ (-R.T @ t))
    rot = Rotation.from_matrix(M)
    ey, ex, ez = rot.as_euler("YXZ", degrees=True)    # intrinsic Y, X, Z = Unity's extrinsic z, x, y
    L = np.eye(4)
    L[:3, :3], L[:3, 3] = M, pos
    return {"position": pos.tolist(), "rotation": rot.as_quat().tolist(),
            "eulerAngles": [float(np.mod(a, 360.0)) for a in (ex, ey, ez)], "rotation_matrix": M.tolist(),
            "localToWorldMatrix": L.tolist()}


def world_to_camera_matrix(transform: dict) -> np.ndarray:
    """Unity's ``worldToCameraMatrix`` of a transform of :func:`unity_transform`:
    ``scale(1, 1, -1) @ inverse(localToWorldMatrix)``."""
    return np.diag([1.0, 1.0, -1.0, 1.0]) @ np.linalg.inv(np.asarray(transform["localToWorldMatrix"], float))


def unity_document(calib: Calibration, *, world: str = "camera", unit: str = "mm", near_m: float | None = None,
                   far_m: float | None = None, sensor_width_mm: float = SENSOR_WIDTH_MM) -> dict:
    """Both devices as Unity physical cameras with their transforms (module docstring) in one JSON-able document.

    Parameters
    ----------
    calib : a camera-projector calibration.
    world : ``"camera"`` or ``"projector"``: the upright device whose frame is the world (:mod:`.frames`).
    unit : the calibration's length unit (``"mm"``, ``"cm"``, ``"m"``, ``"in"``), turned into metres.
    near_m, far_m : clipping planes (m); default Unity's 0.3 and 1000.
    sensor_width_mm : the sensor width every device gets (any gives the same images).
    """
    from ..mounting import mounting

    metres = metres_per_unit(unit)
    near, far = DEFAULT_CLIP_M if near_m is None else (float(near_m), float(far_m))
    doc = {"format": UNITY_FORMAT, "version": 1, "world": world, "unit": unit, "metres_per_unit": metres,
           "conventions": {
               "world": f"Unity world (left-handed: x right, y up, z forward, metres) = {metres:g} x diag(1, -1, 1) "
                        f"of the procam {world} frame (OpenCV axes: x right, y down, z forward; {unit})",
               "physical_camera": "Camera.usePhysicalProperties = true; focalLength (mm), sensorSize (mm), "
                                  "lensShift (fractions of the sensor size; + = image right of / above the lens "
                                  "axis), gateFit = None (the sensor stretched onto the image: fx and fy both held)",
               "resolution": "render at exactly resolution (width, height) pixels (the Game view / target texture)",
               "pixel": "procam pixel (x, y) (origin: centre of the top-left pixel) = Unity screen point "
                        "(x + 0.5, H - y - 0.5) (origin: bottom-left corner of the bottom-left pixel)",
               "transform": "transform.position (m), transform.rotation = Quaternion(x, y, z, w), or eulerAngles "
                            "(degrees, Unity's order z, x, y); no scale",
               "projectionMatrix": "the same camera as a matrix (OpenGL form, Camera.projectionMatrix), for "
                                   "pipelines that set it directly",
               "distortion": "Unity cameras are pinholes: lens distortion and skew are not held (see each "
                             "device's distortion entry and the distortion maps)",
           },
           "mounting": mounting(calib).to_dict()}
    poses = device_poses(calib, world)
    for name, dev in devices(calib).items():
        phys = physical_camera(dev, sensor_width_mm)
        notes = [n for n in (skew_note(dev.K),) if n]
        doc[name] = {"resolution": [int(v) for v in dev.image_size], "physical": phys, "nearClipPlane": near,
                     "farClipPlane": far, "transform": unity_transform(*poses[name], metres),
                     "projectionMatrix": opengl_projection(dev.K, dev.image_size, near, far).tolist(),
                     "distortion": {**dev.distortion.to_dict(), "held_by_unity": dev.distortion.model == "none"},
                     "notes": notes}
    return doc
