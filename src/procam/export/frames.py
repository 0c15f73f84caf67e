"""The rig's geometry as the engine exports need it: each device's pose in a chosen world frame, length units.

Every export places both devices in one **world**: the procam camera frame (``world="camera"``, default) or the
projector frame (``world="projector"``), with OpenCV's axes (x right, y down, z forward) and the calibration's
length unit (the unit of ``--square``).  The world device is taken as **upright**: its image's up (-y) is the
engine's up, its viewing direction the engine's forward.  Choose as world the device that is mounted upright
(:mod:`procam.mounting` says how the other one is turned relative to it).

A pose ``(R_dw, t_dw)`` maps world points to device points, ``X_dev = R_dw X_world + t_dw`` (OpenCV's
``rvec``/``tvec`` sense); a device's centre in the world is ``-R_dw^T t_dw`` and its axes (as columns) are
``R_dw^T``.  Both are rigid (det +1): nothing here mirrors a frame, so an engine frame built from them
is never a mirror image of the rig.

Engines work in metres: :data:`LENGTH_UNITS` gives the metres of each calibration unit a user can name
(:data:`procam.choices.LENGTH_UNITS`).
"""

from __future__ import annotations

import numpy as np

from ..calibration import Calibration
from ..errors import CalibrationError
from .. import choices

#: Metres per calibration length unit (the unit of the board's ``--square``).
LENGTH_UNITS = {"mm": 1e-3, "cm": 1e-2, "m": 1.0, "in": 0.0254}
assert tuple(LENGTH_UNITS) == choices.LENGTH_UNITS
#: The devices of a camera-projector calibration, in export order.
DEVICES = ("camera", "projector")


def rt4(R, t) -> np.ndarray:
    """The 4x4 homogeneous matrix ``[[R, t], [0, 1]]``."""
    M = np.eye(4)
    M[:3, :3] = np.asarray(R, float)
    M[:3, 3] = np.asarray(t, float).reshape(3)
    return M


def require_rig(calib: Calibration) -> None:
    """Raise :class:`CalibrationError` for a calibration without a projector or extrinsics."""
    if calib.projector is None or calib.R is None or calib.T is None:
        raise CalibrationError("the calibration has no projector or no camera->projector extrinsics")


#: The clipping range an export accepts: ``0 < near < far <= MAX_FAR``, ``far / near`` from :data:`MIN_DEPTH_RATIO`
#: (a thinner range makes the projection's depth terms, ~ 1 / (far - near), explode) to :data:`MAX_DEPTH_RATIO` (a
#: depth buffer has no precision left beyond).
MAX_FAR = 1e12
MIN_DEPTH_RATIO = 1.0001
MAX_DEPTH_RATIO = 1e7


def check_clip(near, far) -> tuple[float, float]:
    """``(near, far)`` clipping distances (any one length unit) as floats, or a :class:`CalibrationError` saying
    which bound they break and what to change."""
    try:
        near, far = float(near), float(far)
    except (TypeError, ValueError):
        raise CalibrationError(f"near and far must be numbers, got {near!r} and {far!r}") from None
    if not (np.isfinite(near) and np.isfinite(far) and 0 < near < far <= MAX_FAR):
        raise CalibrationError(f"near and far must be finite with 0 < near < far <= {MAX_FAR:g}, got near={near:g}, "
                               f"far={far:g}")
    if far / near > MAX_DEPTH_RATIO:
        raise CalibrationError(f"far / near is {far / near:.3g}; at most {MAX_DEPTH_RATIO:g} (a depth buffer has no "
                               "precision left beyond), so raise near")
    if far < near * MIN_DEPTH_RATIO:
        raise CalibrationError(f"far {far:g} is hardly beyond near {near:g}: the depth range must reach at least "
                               f"{MIN_DEPTH_RATIO:g} x near (a thinner one makes a degenerate projection matrix); "
                               "lower near or raise far")
    return near, far


def check_world(world: str) -> str:
    if world not in choices.WORLDS:
        raise ValueError(f"world must be one of {', '.join(choices.WORLDS)}, got {world!r}")
    return world


def metres_per_unit(unit: str) -> float:
    """Metres per calibration unit ``unit`` (:data:`LENGTH_UNITS`); ``ValueError`` for another word."""
    if unit not in LENGTH_UNITS:
        raise ValueError(f"unknown length unit {unit!r}; choose one of {', '.join(LENGTH_UNITS)}")
    return LENGTH_UNITS[unit]


def device_poses(calib: Calibration, world: str = "camera") -> dict:
    """``{"camera": (R_dw, t_dw), "projector": (R_dw, t_dw)}``: each device's pose (world -> device, OpenCV axes,
    calibration units) in the world frame ``world`` (``"camera"`` or ``"projector"``)."""
    require_rig(calib)
    check_world(world)
    R = np.asarray(calib.R, float)
    T = np.asarray(calib.T, float).reshape(3)
    if world == "camera":
        return {"camera": (np.eye(3), np.zeros(3)), "projector": (R, T)}
    return {"camera": (R.T, -R.T @ T), "projector": (np.eye(3), np.zeros(3))}


def devices(calib: Calibration) -> dict:
    """``{"camera": Device, "projector": Device}``."""
    require_rig(calib)
    return {"camera": calib.camera, "projector": calib.projector}


def skew_note(K) -> str | None:
    """A note when ``K`` has a skew an engine camera cannot hold (None when it has none)."""
    s = float(np.asarray(K, float)[0, 1])
    if abs(s) > 1e-9 * abs(float(np.asarray(K, float)[0, 0])):
        return f"K has a skew of {s:.4g} px, which an engine camera cannot hold; it is left out"
    return None
