"""How the devices of a calibration are mounted, in words: a projector upside-down (ceiling-mounted) or turned a
quarter turn (portrait) relative to the camera, a portrait panel or sensor, and where the projector sits.

A calibration knows the two devices relative to each other, not relative to gravity.  The words are therefore
relative to the camera, taken as upright (the usual rig; if it is the camera that hangs upside-down, "the
projector is upside-down relative to the camera" is still true, and the engine exports take the projector as
the upright device with ``world="projector"``).

Method: the projector's roll relative to the camera is the angle, in the camera's image, of the projector's own
x axis (its panel's rows, left to right) seen from the camera: ``atan2(r_y, r_x)`` of ``r = R^T e_x`` (degrees,
positive clockwise on the camera's screen, whose y runs down).  Near 0 the projector is upright relative to the
camera, near 180 upside-down (a ceiling mount: the panel's rows run right to left, its top at the bottom), near
+-90 turned a quarter turn (a portrait installation of a landscape panel).  The words take the nearest quarter turn;
the number is exact.  A panel or sensor with more rows than columns is a portrait device of its own.  The
projector's position is its centre ``-R^T T`` in the camera frame (x right, y down, z forward), in the
calibration's length unit.

Every rotation here is proper (``R`` of a calibration is a rotation, det +1, which :mod:`procam.io.validate`
checks when a file is read): a mirrored rig is not a mounting, it is a wrong solution.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: The words of the projector's quarter turns relative to the camera (index = quarter turns clockwise).
TURNS = ("upright relative to the camera", "turned a quarter turn clockwise relative to the camera (portrait)",
         "upside-down relative to the camera (a ceiling mount, if the camera is upright)",
         "turned a quarter turn counter-clockwise relative to the camera (portrait)")


@dataclass(frozen=True)
class Mounting:
    """The rig's mounting (module docstring).

    Attributes
    ----------
    roll_deg : the projector's roll relative to the camera, degrees in (-180, 180], + clockwise on the camera's
        screen; NaN for a camera-only calibration.
    turn : the nearest quarter turn in words (:data:`TURNS`); "" for a camera-only calibration.
    camera_portrait, projector_portrait : the image has more rows than columns.
    position : the projector's centre in the camera frame (x right, y down, z forward), calibration units; None
        for a camera-only calibration.
    """

    roll_deg: float
    turn: str
    camera_portrait: bool
    projector_portrait: bool
    position: tuple | None

    @property
    def upside_down(self) -> bool:
        return self.turn == TURNS[2]

    def where(self) -> str:
        """Where the projector sits relative to the camera, in words (calibration units)."""
        if self.position is None:
            return ""
        x, y, z = self.position
        parts = [f"{abs(x):.0f} {'right of' if x >= 0 else 'left of'}",
                 f"{abs(y):.0f} {'below' if y >= 0 else 'above'}",
                 f"{abs(z):.0f} {'in front of' if z >= 0 else 'behind'}"]
        return "the projector is " + ", ".join(parts) + " the camera (calibration units; camera axes)"

    def lines(self) -> list[str]:
        """The mounting in sentences (the text summary and the report)."""
        out = []
        if self.position is not None:
            out.append(f"projector {self.turn} (roll {self.roll_deg:+.1f} deg)")
            out.append(self.where())
        for name, portrait in (("camera", self.camera_portrait), ("projector", self.projector_portrait)):
            if portrait and (name == "camera" or self.position is not None):
                out.append(f"the {name}'s image is portrait (more rows than columns)")
        return out

    def to_dict(self) -> dict:
        return {"projector_roll_deg": None if math.isnan(self.roll_deg) else float(self.roll_deg),
                "projector_turn": self.turn, "projector_upside_down": self.upside_down,
                "camera_portrait": self.camera_portrait, "projector_portrait": self.projector_portrait,
                "projector_position": None if self.position is None else [float(v) for v in self.position],
                "relative_to": "the camera, taken as upright (a calibration does not know gravity)"}


def mounting(calib) -> Mounting:
    """The :class:`Mounting` of a calibration (module docstring)."""
    W, H = calib.camera.image_size
    cam_portrait = H > W
    if calib.projector is None or calib.R is None or calib.T is None:
        return Mounting(float("nan"), "", cam_portrait, False, None)
    R = np.asarray(calib.R, float)
    r = R.T @ np.array([1.0, 0.0, 0.0])          # the projector's x axis in the camera frame
    roll = math.degrees(math.atan2(r[1], r[0]))
    roll = 180.0 if roll <= -180.0 + 1e-12 else roll
    turn = TURNS[int(round(roll / 90.0)) % 4]
    Wp, Hp = calib.projector.image_size
    pos = -R.T @ np.asarray(calib.T, float).reshape(3)
    return Mounting(roll, turn, cam_portrait, Hp > Wp, tuple(float(v) for v in pos))
