"""A projector's intrinsics in the words of its datasheet: throw ratio, lens shift, field of view.

Projector datasheets (and the people who set up projection mapping) do not give ``K``: they give a **throw
ratio** and a **lens shift**. The conventions, which forums argue about, are fixed here once (see the figure
in ``docs/datasheet.md``); every number procam reads from a user or prints for one goes through this module.

Conventions (pixels as everywhere in procam: ``(x, y)`` = (column, row), the origin at the centre of the top-left
pixel, so the panel spans ``[-0.5, W - 0.5] x [-0.5, H - 0.5]`` and its centre is ``((W - 1) / 2, (H - 1) / 2)``;
a projector as seen from behind it, facing the screen, not mirrored):

* **throw ratio** = throw distance / image width = ``f_x / W`` (the distance along the lens axis to a screen square
  to it, over the width of the image there). ``f_x`` is the focal length in panel pixels.
* **vertical lens shift** = how far the image centre sits above the lens axis, in percent of the image height:
  ``shift_v = 100 (v0 - (H - 1) / 2) / H``. 0 % is an image centred on the axis; +50 % puts the image's bottom
  edge on the axis (the usual table-top projector: the image above the lens); above 50 % the whole image is above
  the axis (``v0`` beyond the panel's last row); negative values put the image below the axis (a ceiling mount
  flips the sign of what the room sees, not of this number, which is in the panel's own frame).
* **horizontal lens shift** = how far the image centre sits to the right of the lens axis, in percent of the image
  width: ``shift_h = 100 ((W - 1) / 2 - u0) / W``.
* **offset** (some datasheets): the same displacement in percent of the HALF height, ``offset = 2 shift_v`` (an
  offset of 100 % is a shift of 50 %: the bottom edge on the axis).
* **field of view**: the full angles the panel spans, horizontal and vertical, degrees (``atan`` of each edge's
  distance from the principal point over the focal length, summed).

A calibration's datasheet view (:func:`calibration_datasheet`) carries a ``±`` for each number, propagated to
first order from the ``±`` of ``f``, ``fy``, ``u0``, ``v0`` the calibration reports (:mod:`procam.uncertainty`),
taken as independent: it is 1 sigma, assumes what those assume (the model is right, the corner noise i.i.d.), and
a number whose inputs have no ``±`` (a single-pose projector's assumed ``u0p = W/2``) has none.

>>> K = intrinsic_matrix(1920, 1080, throw_ratio=1.5, shift_h=0.0, shift_v=50.0)
>>> float(K[0, 0]), float(K[0, 2]), float(K[1, 2])
(2880.0, 959.5, 1079.5)
>>> view = datasheet_view(K, (1920, 1080))
>>> round(view.throw_ratio, 3), round(view.shift_v_pct, 3), round(view.offset_pct, 3)
(1.5, 50.0, 100.0)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class DatasheetView:
    """A projector's intrinsics as its datasheet would print them (module docstring for the conventions).

    ``throw_ratio`` (``f_x / W``), ``shift_h_pct`` / ``shift_v_pct`` (lens shift, % of the image width / height,
    positive = image right of / above the lens axis), ``offset_pct`` (``2 shift_v``), ``fov_h_deg`` / ``fov_v_deg``
    (full field of view, degrees), ``aspect`` (``fy / fx``: 1 for square pixels); ``std``: the 1-sigma ``±`` of
    those that have one (:func:`calibration_datasheet`), by the same names.
    """

    throw_ratio: float
    shift_h_pct: float
    shift_v_pct: float
    offset_pct: float
    fov_h_deg: float
    fov_v_deg: float
    aspect: float
    std: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        out = {k: float(getattr(self, k)) for k in self.__dataclass_fields__ if k != "std"}
        out["std"] = {k: float(v) for k, v in self.std.items()}
        return out


def datasheet_view(K, size) -> DatasheetView:
    """The datasheet numbers of intrinsics ``K`` (3, 3) of a panel of ``size`` = (W, H) pixels."""
    K = np.asarray(K, float)
    W, H = float(size[0]), float(size[1])
    fx, fy, u0, v0 = (float(v) for v in (K[0, 0], K[1, 1], K[0, 2], K[1, 2]))
    shift_v = 100.0 * (v0 - (H - 1) / 2) / H
    fov_h = math.degrees(math.atan((u0 + 0.5) / fx) + math.atan((W - 0.5 - u0) / fx))
    fov_v = math.degrees(math.atan((v0 + 0.5) / fy) + math.atan((H - 0.5 - v0) / fy))
    return DatasheetView(throw_ratio=fx / W, shift_h_pct=100.0 * ((W - 1) / 2 - u0) / W, shift_v_pct=shift_v,
                         offset_pct=2.0 * shift_v, fov_h_deg=fov_h, fov_v_deg=fov_v, aspect=fy / fx)


def focal_from_throw_ratio(throw_ratio: float, width: int) -> float:
    """``f_x`` (panel pixels) of a throw ratio for a panel ``width`` pixels wide."""
    return float(throw_ratio) * float(width)


def principal_point_from_shift(shift_h_pct: float, shift_v_pct: float, size) -> tuple[float, float]:
    """``(u0, v0)`` (panel pixels) of a lens shift in percent (module docstring)."""
    W, H = float(size[0]), float(size[1])
    return (W - 1) / 2 - shift_h_pct / 100.0 * W, (H - 1) / 2 + shift_v_pct / 100.0 * H


def intrinsic_matrix(width: int, height: int, *, throw_ratio: float, shift_h: float = 0.0, shift_v: float = 0.0,
                     aspect: float = 1.0) -> np.ndarray:
    """``K`` (3, 3) of a datasheet's throw ratio and lens shift (``shift_h``, ``shift_v`` in percent)."""
    f = focal_from_throw_ratio(throw_ratio, width)
    u0, v0 = principal_point_from_shift(shift_h, shift_v, (width, height))
    return np.array([[f, 0.0, u0], [0.0, aspect * f, v0], [0.0, 0.0, 1.0]])


#: The names of each device's intrinsics in a calibration's ``std`` (:mod:`procam.parameters`).
_STD_NAMES = {"camera": ("f_c", "fy_c", "u0c", "v0c"), "projector": ("f_p", "fy_p", "u0p", "v0p")}


def calibration_datasheet(calib, device: str = "projector") -> DatasheetView | None:
    """The datasheet view of a calibration's ``device`` (``"projector"`` or ``"camera"``) with the ``±`` of its
    numbers (module docstring); None when the calibration has no such device."""
    dev = getattr(calib, device, None)
    if dev is None:
        return None
    view = datasheet_view(dev.K, dev.image_size)
    K = np.asarray(dev.K, float)
    W, H = (float(v) for v in dev.image_size)
    fx, fy, u0, v0 = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
    sd = {}
    for k, name in zip(("fx", "fy", "u0", "v0"), _STD_NAMES[device]):
        v = calib.std.get(name)
        try:
            v = float(v)
        except (TypeError, ValueError):
            v = float("nan")
        if math.isfinite(v) and v > 0:
            sd[k] = v
    std = {}
    if "fx" in sd:
        std["throw_ratio"] = sd["fx"] / W
    if "u0" in sd:
        std["shift_h_pct"] = 100.0 * sd["u0"] / W
    if "v0" in sd:
        std["shift_v_pct"] = 100.0 * sd["v0"] / H
        std["offset_pct"] = 2.0 * std["shift_v_pct"]
    for key, f, sf, c, sc, side in (("fov_h_deg", fx, "fx", u0, "u0", W), ("fov_v_deg", fy, "fy", v0, "v0", H)):
        if sf not in sd:
            continue
        a, b = c + 0.5, side - 0.5 - c
        d_f = -(a / (f * f + a * a) + b / (f * f + b * b))         # d fov / d f (rad per px)
        d_c = f / (f * f + a * a) - f / (f * f + b * b)             # d fov / d centre
        var = (d_f * sd[sf]) ** 2 + ((d_c * sd[sc]) ** 2 if sc in sd else 0.0)
        std[key] = math.degrees(math.sqrt(var))
    if "fx" in sd and "fy" in sd:
        std["aspect"] = float(fy / fx) * math.hypot(sd["fx"] / fx, sd["fy"] / fy)
    return DatasheetView(**{k: getattr(view, k) for k in view.__dataclass_fields__ if k != "std"}, std=std)
