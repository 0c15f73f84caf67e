"""The camera interface the capture loop needs, and what every backend shares.

Every camera is a context manager with

``grab() -> Frame``
    the next frame as a grey (H, W) uint8/uint16 image (colour converted with BT.601 luma, as
    :func:`procam.io.read_image` does: :func:`to_gray`), its time stamp and backend details;
``arm()``
    called right after a new pattern is shown: "whatever comes from now on belongs to it";
``flush()``
    called after the settle time, just before :meth:`grab`: drop frames the camera buffered;
``describe() -> dict``
    backend, device, size, and for each requested setting what was asked, what was set and
    whether it took effect (:func:`_setting`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from .._device import Device


@dataclass(frozen=True)
class Frame:
    """One camera frame: ``image`` (H, W) uint8/uint16 grey, ``timestamp`` (s, ``time.monotonic``
    clock unless ``meta['clock']`` says otherwise) and backend details in ``meta``."""

    image: np.ndarray
    timestamp: float
    meta: dict = field(default_factory=dict)


@runtime_checkable
class Camera(Protocol):
    """What the capture loop needs from a camera (see the module docstring)."""

    def open(self) -> "Camera": ...
    def close(self) -> None: ...
    def __enter__(self) -> "Camera": ...
    def __exit__(self, *exc) -> bool: ...
    def arm(self) -> None: ...
    def flush(self) -> None: ...
    def grab(self) -> Frame: ...
    def describe(self) -> dict: ...


def to_gray(image: np.ndarray, order: str = "bgr") -> np.ndarray:
    """(H, W), (H, W, 1), (H, W, 3) or (H, W, 4) -> (H, W) grey (BT.601 luma), dtype kept.

    ``order`` is the channel order of colour images: ``"bgr"`` (OpenCV) or ``"rgb"``.
    """
    import cv2

    image = np.asarray(image)
    if image.ndim == 2:
        return image
    if image.ndim == 3 and image.shape[2] == 1:
        return image[:, :, 0]
    if image.ndim == 3 and image.shape[2] in (3, 4):
        code = {("bgr", 3): cv2.COLOR_BGR2GRAY, ("bgr", 4): cv2.COLOR_BGRA2GRAY,
                ("rgb", 3): cv2.COLOR_RGB2GRAY, ("rgb", 4): cv2.COLOR_RGBA2GRAY}[(order, image.shape[2])]
        return cv2.cvtColor(image, code)
    raise ValueError(f"cannot convert an image of shape {image.shape} to grey")


def _setting(requested, device_value=None, read_back=None, took_effect: bool | None = None, note: str = "") -> dict:
    d = {"requested": requested, "device_value": device_value, "read_back": read_back, "took_effect": took_effect}
    if note:
        d["note"] = note
    return d


class _Camera(Device):
    """Default no-op ``arm``/``flush`` (and the context manager of :class:`~procam.acquire._device.Device`).

    ``streaming`` is True for cameras that deliver frames continuously (a second grab costs a
    frame period); False for ones where each frame is a shot (the folder watch), so the capture
    loop grabs no extra frames from them.
    """

    name = "camera"
    streaming = True
    _settings: dict = {}  # a backend's settings, by name (:func:`_setting`): what was asked and what took effect

    def arm(self) -> None:
        pass

    def flush(self) -> None:
        pass

    @property
    def exposure_ms(self) -> float | None:
        """The exposure in effect (ms) when the backend set it and it took effect, else None (for exposure
        advice)."""
        s = self._settings.get("exposure_ms")
        return s["requested"] if s and s["took_effect"] else None
