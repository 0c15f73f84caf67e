"""Blender: each device as Blender's own camera and render properties, its ``matrix_world``, and the calibration's
camera frame in Blender's world (``world_from_camera``), in one JSON document; :mod:`.blender_cameras` is the
script that creates the cameras in a scene from it.

Blender's camera model (``BKE_camera_params_compute_viewplane``, the model its renderers and
``bpy_extras.object_utils.world_to_camera_view`` share), with ``sensor_fit = 'HORIZONTAL'``:

* the image's width of ``resolution_x`` pixels spans ``sensor_width`` at the focal length ``lens`` (both mm):
  ``fx = lens resolution_x / sensor_width``;
* a pixel is ``ycor = pixel_aspect_y / pixel_aspect_x`` widths tall, so ``fy = fx / ycor``;
* the lens shift moves the frame by ``shift_x``, ``shift_y`` **widths** of the image (the fit axis's size), +x
  right, +y up;
* the camera looks down its local -z, y up; normalised frame coordinates run from (0, 0) at the bottom-left
  corner of the image to (1, 1) at the top-right corner (pixel edges).

procam's numbers (``K`` = [[fx, 0, u0], [0, fy, v0], [0, 0, 1]], image W x H, ``w`` the sensor width):
``lens = fx w / W``, ``pixel_aspect_x, pixel_aspect_y = (fy / fx, 1)`` if ``fy >= fx`` else ``(1, fx / fy)``
(Blender wants both >= 1), ``shift_x = ((W - 1)/2 - u0) / W``, ``shift_y = ycor (v0 - (H - 1)/2) / W``,
``sensor_height = w ycor H / W`` (the frame's height; unused with a horizontal fit).  ``shift_x`` is the
datasheet's horizontal lens shift as a fraction, ``shift_y`` the vertical one in units of the width.  The fit is
horizontal whatever the aspect ratio, so a portrait device keeps its numbers (with ``AUTO`` Blender would switch
to the vertical side, and the shifts' unit with it).

Pixel conventions: procam pixel ``(x, y)`` (origin at the centre of the top-left pixel) is Blender's normalised
frame point ``((x + 0.5) / W, 1 - (y + 0.5) / H)``.

The world: Blender's (x right, y forward, z up; metres) from the upright world device (:mod:`.frames`):
``X_blender = s B X_world`` with ``B`` taking OpenCV's (x right, y down, z forward) to (x, -z, y)
(:data:`BLENDER_FROM_CV`, a rotation) and ``s`` the metres per calibration unit.  ``world_from_camera`` (4x4,
scale included) takes the calibration's camera frame (OpenCV axes, its unit: point clouds from ``procam
reconstruct``) into Blender's world.  ``matrix_world`` of a device is rigid (det +1, no scale): its rotation
``B R_dw^T diag(1, -1, -1)`` turns Blender's camera axes into the device's, so nothing is mirrored.

Render settings are the scene's, not the camera's: the two devices differ in resolution, so the script sets the
scene's resolution and pixel aspect for the device it makes the scene camera (the projector, unless told).

Blender cameras are pinholes: lens distortion and skew are not held (the document says so per device; the
distortion maps of :mod:`.maps` carry the distortion).
"""

from __future__ import annotations

import numpy as np

from ..calibration import Calibration, Device
from ..io.formats import BLENDER_FORMAT
from .frames import device_poses, devices, metres_per_unit, rt4, skew_note

#: Blender's world (x right, y forward, z up) from an upright device's OpenCV frame (x right, y down, z forward).
BLENDER_FROM_CV = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
#: Blender's camera axes (x right, y up, looking down -z) from OpenCV's.
CAMERA_FROM_CV = np.diag([1.0, -1.0, -1.0])
#: Blender's default sensor width (mm): any width gives the same images.
SENSOR_WIDTH_MM = 36.0
#: Blender's default clipping distances (m), used when none are given.
DEFAULT_CLIP_M = (0.1, 1000.0)


def script_text() -> str:
    """The source of :mod:`.blender_cameras`, the script ``procam export --format blender`` writes beside its JSON."""
    from pathlib import Path

    from . import blender_cameras

    return Path(blender_cameras.__file__).read_text(encoding="utf-8")


def blender_camera(device: Device, sensor_width_mm: float = SENSOR_WIDTH_MM) -> dict:
    """Blender's camera (``bpy.types.Camera``) and render (``RenderSettings``) properties of ``device`` (module
    docstring): ``{"data": {lens, sensor_width, sensor_height, sensor_fit, shift_x, shift_y, type}, "render":
    {resolution_x, resolution_y, resolution_percentage, pixel_aspect_x, pixel_aspect_y}}``."""
    K = np.asarray(device.K, float)
    W, H = (float(v) for v in device.image_size)
    fx, fy, u0, v0 = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
    aspx, aspy = (fy / fx, 1.0) if fy >= fx else (1.0, fx / fy)
    ycor = aspy / aspx
    data = {"type": "PERSP", "sensor_fit": "HORIZONTAL", "lens": fx * sensor_width_mm / W,
            "sensor_width": sensor_width_mm, "sensor_height": sensor_width_mm * ycor * H / W,
            "shift_x": ((W - 1) / 2 - u0) / W, "shift_y": ycor * (v0 - (H - 1) / 2) / W}
    render = {"resolution_x": int(W), "resolution_y": int(H), "resolution_percentage": 100,
              "pixel_aspect_x": aspx, "pixel_aspect_y": aspy}
    return {"data": data, "render": render}


def world_from_camera(calib: Calibration, world: str = "camera", metres: float = 1.0) -> np.ndarray:
    """4x4: the calibration's camera frame (OpenCV axes, calibration units) into Blender's world (metres)."""
    R_cw, t_cw = device_poses(calib, world)["camera"]          # world -> camera
    return np.diag([metres] * 3 + [1.0]) @ rt4(BLENDER_FROM_CV, np.zeros(3)) @ np.linalg.inv(rt4(R_cw, t_cw))


def matrix_world(R_dw, t_dw, metres: float = 1.0) -> np.ndarray:
    """A device's Blender ``matrix_world`` (4x4, rigid) from its pose ``(R_dw, t_dw)`` (world -> device, OpenCV
    axes, calibration units)."""
    R = np.asarray(R_dw, float)
    t = np.asarray(t_dw, float).reshape(3)
    return rt4(BLENDER_FROM_CV @ R.T @ CAMERA_FROM_CV, metres * (BLENDER_FROM_CV @ (-R.T @ t)))


def blender_document(calib: Calibration, *, world: str = "camera", unit: str = "mm", near_m: float | None = None,
                     far_m: float | None = None, sensor_width_mm: float = SENSOR_WIDTH_MM,
                     scene_camera: str = "projector") -> dict:
    """Both devices as Blender cameras (module docstring) in one JSON-able document.

    Parameters
    ----------
    calib : a camera-projector calibration.
    world : ``"camera"`` or ``"projector"``: the upright device whose frame is the world (:mod:`.frames`).
    unit : the calibration's length unit (``"mm"``, ``"cm"``, ``"m"``, ``"in"``), turned into metres.
    near_m, far_m : ``clip_start``, ``clip_end`` (m); default Blender's 0.1 and 1000.
    sensor_width_mm : the sensor width every device gets (any gives the same images).
    scene_camera : the device the script makes the scene's camera (its render settings become the scene's).
    """
    from ..mounting import mounting

    metres = metres_per_unit(unit)
    near, far = DEFAULT_CLIP_M if near_m is None else (float(near_m), float(far_m))
    doc = {"format": BLENDER_FORMAT, "version": 1, "world": world, "unit": unit, "metres_per_unit": metres,
           "scene_camera": scene_camera,
           "conventions": {
               "world": f"Blender world (x right, y forward, z up; metres) = {metres:g} x B of the procam {world} "
                        f"frame (OpenCV axes: x right, y down, z forward; {unit}), B = [[1, 0, 0], [0, 0, 1], "
                        "[0, -1, 0]]: the world device is upright",
               "world_from_camera": "4x4 from the calibration's camera frame (OpenCV axes, its unit; procam "
                                    "reconstruct's point clouds) into Blender's world, scale included",
               "matrix_world": "each device's object transform (rigid, no scale); Blender's camera looks down "
                               "its local -z with y up",
               "data": "bpy.types.Camera properties (mm; sensor_fit HORIZONTAL: the shifts are in units of the "
                       "image width, + = image right of / above the lens axis)",
               "render": "scene.render properties for this device; a scene has one set, so render each device "
                         "in its own scene or set them before rendering it",
               "pixel": "procam pixel (x, y) (origin: centre of the top-left pixel) = normalised frame point "
                        "((x + 0.5) / W, 1 - (y + 0.5) / H) (origin: bottom-left corner of the frame)",
               "distortion": "Blender cameras are pinholes: lens distortion and skew are not held (see each "
                             "device's distortion entry and the distortion maps)",
           },
           "world_from_camera": world_from_camera(calib, world, metres).tolist(),
           "mounting": mounting(calib).to_dict(), "devices": {}}
    poses = device_poses(calib, world)
    for name, dev in devices(calib).items():
        cam = blender_camera(dev, sensor_width_mm)
        cam["data"].update(clip_start=near, clip_end=far)
        notes = [n for n in (skew_note(dev.K),) if n]
        doc["devices"][name] = {**cam, "matrix_world": matrix_world(*poses[name], metres).tolist(),
                                "K": np.asarray(dev.K, float).tolist(),
                                "distortion": {**dev.distortion.to_dict(),
                                               "held_by_blender": dev.distortion.model == "none"},
                                "notes": notes}
    return doc
