"""UVC/V4L2 webcams through OpenCV's ``cv2.VideoCapture`` (:class:`OpenCVCamera`), and the video devices
there are (:func:`list_opencv_cameras`).
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

from ...errors import ProcamError
from .base import Frame, _Camera, _setting, to_gray


class OpenCVCamera(_Camera):
    """A camera through ``cv2.VideoCapture`` (V4L2 on Linux, the default API elsewhere).

    Parameters
    ----------
    source : device index (``/dev/videoN`` on Linux), a device path, or a video file (for tests).
    size : requested (width, height) in pixels, or None for the driver's default.
    exposure_ms : manual exposure in milliseconds (auto exposure is switched off), or None to
        leave the camera's setting.  Converted to the API's unit: V4L2 100-microsecond steps,
        MSMF/DSHOW log2(seconds); elsewhere passed as is (the driver's unit, noted).
    gain : gain in the driver's unit, or None.
    api : an OpenCV ``cv2.CAP_*`` constant, or None for V4L2 for a device on Linux and ``CAP_ANY``
        otherwise.
    flush_frames : frames grabbed and dropped by :meth:`flush` (default: the driver's buffer count
        plus one).

    Every setting is read back: :meth:`describe` says which took effect (many webcams ignore some).
    Autofocus is switched off where the driver allows (a focus change mid-sequence moves the image).
    """

    def __init__(self, source=0, size=None, exposure_ms: float | None = None, gain: float | None = None,
                 api: int | None = None, flush_frames: int | None = None):
        self.source = source
        self.size = None if size is None else (int(size[0]), int(size[1]))
        self.exposure_request = exposure_ms
        self.gain_request = gain
        self.api = api
        self.flush_frames = flush_frames
        self.name = f"opencv:{source}"
        self._cap = None
        self._settings: dict = {}
        self._notes: list[str] = []
        self._frame_size = None

    def open(self):
        import cv2

        if self._cap is not None:
            return self
        device = isinstance(self.source, int) or str(self.source).startswith("/dev/")
        api = self.api if self.api is not None else (
            cv2.CAP_V4L2 if device and sys.platform.startswith("linux") else cv2.CAP_ANY)
        cap = cv2.VideoCapture(self.source, api)
        if not cap.isOpened():
            cap.release()
            raise ProcamError(f"camera {self.name}: cannot be opened; check that it is connected and not in use by "
                              "another program (procam capture --list-devices lists the cameras)")
        self._cap = cap
        try:
            self._configure()
            ok, img = cap.read()
            if not ok or img is None:
                raise ProcamError(f"camera {self.name}: opened but delivers no frames; check the cable and that "
                                  "no other program uses it")
        except BaseException:
            self.close()
            raise
        self._frame_size = (int(img.shape[1]), int(img.shape[0]))
        if self.size is not None:
            ok = self._frame_size == self.size
            self._settings["size"] = _setting(list(self.size), list(self.size), list(self._frame_size), ok)
            if not ok:
                self._notes.append(f"size {self.size[0]}x{self.size[1]} not accepted; the driver delivers "
                                   f"{self._frame_size[0]}x{self._frame_size[1]}")
        return self

    def _set(self, prop: int, value: float, tol: float = 1e-3):
        ok = bool(self._cap.set(prop, value))
        back = float(self._cap.get(prop))
        return ok, back, ok and abs(back - value) <= max(tol, 1e-3 * abs(value))

    def _configure(self):
        import cv2

        cap = self._cap
        backend = cap.getBackendName()
        self._set(cv2.CAP_PROP_BUFFERSIZE, 1)  # fewer stale frames where the API supports it
        _, back, eff = self._set(cv2.CAP_PROP_AUTOFOCUS, 0)
        self._settings["autofocus"] = _setting("off", 0, back, eff,
                                               "" if eff else "autofocus could not be switched off (or the camera has none)")
        if self.size is not None:
            self._set(cv2.CAP_PROP_FRAME_WIDTH, self.size[0])
            self._set(cv2.CAP_PROP_FRAME_HEIGHT, self.size[1])
        if self.exposure_request is not None:
            manual = False
            for value in (1, 0.25):  # V4L2_EXPOSURE_MANUAL; some builds map 0.25 to manual
                _, _, eff = self._set(cv2.CAP_PROP_AUTO_EXPOSURE, value)
                if eff:
                    manual = True
                    break
            ms = float(self.exposure_request)
            if backend == "V4L2":
                value, unit = ms * 10.0, "100 us"
            elif backend in ("MSMF", "DSHOW"):
                value, unit = float(round(math.log2(ms / 1000.0))), "log2(s)"
            else:
                value, unit = ms, "driver unit"
            _, back, eff = self._set(cv2.CAP_PROP_EXPOSURE, value, tol=0.5 if unit != "driver unit" else 1e-3)
            note = [] if manual else ["auto exposure could not be switched off"]
            if not eff:
                note.append(f"{backend} did not accept exposure {value:g} ({unit}); it reads back {back:g}")
            self._settings["exposure_ms"] = _setting(ms, value, back, eff and manual, "; ".join(note))
            if note:
                self._notes.append(f"exposure: {'; '.join(note)}")
        if self.gain_request is not None:
            _, back, eff = self._set(cv2.CAP_PROP_GAIN, float(self.gain_request))
            self._settings["gain"] = _setting(float(self.gain_request), float(self.gain_request), back, eff,
                                              "" if eff else f"{backend} did not accept the gain; it reads back {back:g}")
            if not eff:
                self._notes.append(f"gain {self.gain_request:g} not accepted (reads back {back:g})")

    def close(self):
        if self._cap is not None:
            self._cap.release()
            self._cap = None

    def flush(self):
        import cv2

        n = self.flush_frames
        if n is None:
            buffers = int(self._cap.get(cv2.CAP_PROP_BUFFERSIZE) or 4)
            n = max(1, buffers) + 1
        for _ in range(n):
            self._cap.grab()

    def grab(self) -> Frame:
        ok, img = self._cap.read()
        if not ok or img is None:
            raise ProcamError(f"camera {self.name}: no frame (disconnected?); check the cable and re-run")
        return Frame(to_gray(img, "bgr"), time.monotonic(), {"source": self.name})

    def describe(self) -> dict:
        d = {"backend": "opencv", "source": self.source}
        if self._cap is not None:
            d["api"] = self._cap.getBackendName()
        d["size"] = list(self._frame_size) if self._frame_size else None
        d["settings"] = self._settings
        d["notes"] = list(self._notes)
        return d


def list_opencv_cameras(max_index: int = 8) -> list[dict]:
    """Video devices: on Linux ``/dev/video*`` with their V4L2 names (nothing is opened); elsewhere the
    indices ``0 .. max_index-1`` that ``cv2.VideoCapture`` can open."""
    out = []
    if sys.platform.startswith("linux"):
        for dev in sorted(Path("/dev").glob("video*"), key=lambda p: int("0" + "".join(filter(str.isdigit, p.name)))):
            name_file = Path("/sys/class/video4linux") / dev.name / "name"
            try:
                name = name_file.read_text().strip()
            except OSError:
                name = ""
            idx = "".join(filter(str.isdigit, dev.name))
            out.append({"spec": f"opencv:{idx}", "device": str(dev), "name": name})
        return out
    import cv2

    for i in range(max_index):
        cap = cv2.VideoCapture(i)
        if cap.isOpened():
            out.append({"spec": f"opencv:{i}", "device": str(i), "name": cap.getBackendName()})
        cap.release()
    return out
