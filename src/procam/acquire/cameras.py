"""Camera input behind one small interface, for the capture loop.

Every camera is a context manager with

``grab() -> Frame``
    the next frame as a grey (H, W) uint8/uint16 image (colour converted with BT.601 luma, as
    :func:`procam.io.read_image` does), its time stamp and backend details;
``arm()``
    called right after a new pattern is shown: "whatever comes from now on belongs to it";
``flush()``
    called after the settle time, just before :meth:`grab`: drop frames the camera buffered;
``describe() -> dict``
    backend, device, size, and for each requested setting what was asked, what was set and
    whether it took effect.

Backends: :class:`OpenCVCamera` (UVC/V4L2 webcams through ``cv2.VideoCapture``),
:class:`HarvestersCamera` (GenICam machine-vision cameras through a GenTL producer, ``harvesters``),
:class:`FolderWatchCamera` (cameras whose own software saves files: DSLRs, vendor apps) and
:class:`VirtualCamera` (the simulator renders what the camera sees of the pattern a projector
shows, with stale frames, a dead projector, saturation and exposure changes injectable).
:func:`open_camera` builds one from a ``--camera`` spec.
"""

from __future__ import annotations

import hashlib
import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol, runtime_checkable

import numpy as np

from ..errors import ProcamError

CAMERA_SPECS = "opencv:INDEX, opencv:/dev/videoN, genicam:PRODUCER.cti[#DEVICE], folder:PATH or virtual"


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


class _Camera:
    """Context manager plumbing and default no-op ``arm``/``flush``.

    ``streaming`` is True for cameras that deliver frames continuously (a second grab costs a
    frame period); False for ones where each frame is a shot (the folder watch), so the capture
    loop grabs no extra frames from them.
    """

    name = "camera"
    streaming = True

    def __enter__(self):
        self.open()
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def open(self):
        return self

    def close(self) -> None:
        pass

    def arm(self) -> None:
        pass

    def flush(self) -> None:
        pass

    @property
    def exposure_ms(self) -> float | None:
        """The exposure in effect (ms) when the backend knows it, else None (for exposure advice)."""
        return None


# --------------------------------------------------------------------------------------------
# OpenCV VideoCapture (UVC / V4L2 webcams)
# --------------------------------------------------------------------------------------------

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

    @property
    def exposure_ms(self):
        s = self._settings.get("exposure_ms")
        return s["requested"] if s and s["took_effect"] else None

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


# --------------------------------------------------------------------------------------------
# GenICam through harvesters
# --------------------------------------------------------------------------------------------

_BAYER = {"BayerRG": "COLOR_BayerRG2GRAY", "BayerGR": "COLOR_BayerGR2GRAY", "BayerBG": "COLOR_BayerBG2GRAY",
          "BayerGB": "COLOR_BayerGB2GRAY"}


class HarvestersCamera(_Camera):
    """A GenICam (GigE Vision / USB3 Vision) camera through a GenTL producer and ``harvesters``.

    Parameters
    ----------
    producer : path of the vendor's GenTL producer (``.cti`` file).
    device : index into the producer's device list or a serial number (str); None = the first.
    exposure_ms : ``ExposureTime`` (SFNC, microseconds on the device) with ``ExposureAuto`` off.
    gain : ``Gain`` (SFNC, usually dB) with ``GainAuto`` off.
    timeout_s : how long :meth:`grab` waits for a frame.
    software_trigger : acquire each frame on a software trigger when the camera supports it (then no
        frame is ever stale); otherwise free-running with :meth:`flush` dropping queued buffers.
    """

    def __init__(self, producer, device=None, exposure_ms: float | None = None, gain: float | None = None,
                 timeout_s: float = 5.0, software_trigger: bool = True):
        self.producer = Path(producer)
        self.device = device
        self.exposure_request = exposure_ms
        self.gain_request = gain
        self.timeout_s = float(timeout_s)
        self.software_trigger = software_trigger
        self.name = f"genicam:{self.producer}"
        self._h = self._ia = None
        self._trigger = False
        self._settings: dict = {}
        self._notes: list[str] = []
        self._info: dict = {}

    def open(self):
        if self._ia is not None:
            return self
        try:
            from harvesters.core import Harvester
        except ImportError:
            raise ProcamError("GenICam cameras need the 'harvesters' package, which is not installed; install it "
                              "with: pip install 'procam[genicam]'") from None
        if not self.producer.is_file():
            raise ProcamError(f"{self.producer}: no such GenTL producer (.cti) file; give the path of the camera "
                              "vendor's producer, e.g. --camera genicam:/opt/vendor/lib/producer.cti")
        h = Harvester()
        try:
            h.add_file(str(self.producer), check_existence=True, check_validity=True)
            h.update()
            if not h.device_info_list:
                raise ProcamError(f"{self.producer}: the producer finds no camera; check the cable, the network "
                                  "settings (GigE) and that no other program holds the camera")
            key = self.device
            if isinstance(key, str):
                key = int(key) if key.isdigit() else {"serial_number": key}
            key = 0 if key is None else key
            infos = [d.property_dict for d in h.device_info_list]
            if isinstance(key, int) and not 0 <= key < len(infos):
                raise ProcamError(f"{self.name}#{key}: the producer lists {len(infos)} camera(s); use #0 .. "
                                  f"#{len(infos) - 1} or #SERIAL")
            ia = h.create(key)
        except ProcamError:
            h.reset()
            raise
        except Exception as e:  # harvesters/GenTL errors have many types
            h.reset()
            raise ProcamError(f"{self.name}: cannot open the camera ({type(e).__name__}: {e})") from None
        self._h, self._ia = h, ia
        info = infos[key] if isinstance(key, int) else next(
            (d for d in infos if str(d.get("serial_number")) == key["serial_number"]), {})
        self._info = {k: str(info.get(k, "")) for k in ("vendor", "model", "serial_number")}
        try:
            self._configure()
            ia.start()
        except BaseException:
            self.close()
            raise
        return self

    def _node_set(self, names, value) -> tuple[str | None, object, bool]:
        nm = self._ia.remote_device.node_map
        for name in names:
            try:
                node = getattr(nm, name)
                node.value = value
                back = node.value
            except Exception:
                continue
            if isinstance(value, str):
                ok = back == value
            else:
                ok = abs(float(back) - float(value)) <= 1e-3 * max(1.0, abs(float(value)))
            return name, back, ok
        return None, None, False

    def _configure(self):
        if self.exposure_request is not None:
            self._node_set(["ExposureAuto"], "Off")
            us = float(self.exposure_request) * 1000.0
            node, back, ok = self._node_set(["ExposureTime", "ExposureTimeAbs"], us)
            self._settings["exposure_ms"] = _setting(float(self.exposure_request), us, back, ok,
                                                     f"node {node} (us)" if node else "no ExposureTime node")
            if not ok:
                self._notes.append(f"exposure {self.exposure_request:g} ms not accepted (reads back {back})")
        if self.gain_request is not None:
            self._node_set(["GainAuto"], "Off")
            node, back, ok = self._node_set(["Gain", "GainRaw"], float(self.gain_request))
            self._settings["gain"] = _setting(float(self.gain_request), float(self.gain_request), back, ok,
                                              f"node {node}" if node else "no Gain node")
            if not ok:
                self._notes.append(f"gain {self.gain_request:g} not accepted (reads back {back})")
        if self.software_trigger:
            self._node_set(["TriggerSelector"], "FrameStart")
            _, _, mode = self._node_set(["TriggerMode"], "On")
            _, _, src = self._node_set(["TriggerSource"], "Software")
            self._trigger = mode and src
            if not self._trigger:
                self._node_set(["TriggerMode"], "Off")
                self._notes.append("no software trigger: free-running, buffered frames are flushed before each grab")
        self._settings["trigger"] = _setting("software" if self.software_trigger else "free-running",
                                             None, "software" if self._trigger else "free-running",
                                             self._trigger == self.software_trigger)

    @property
    def exposure_ms(self):
        s = self._settings.get("exposure_ms")
        return s["requested"] if s and s["took_effect"] else None

    def close(self):
        if self._ia is not None:
            try:
                self._ia.stop()
                self._ia.destroy()
            finally:
                self._ia = None
        if self._h is not None:
            self._h.reset()
            self._h = None

    def flush(self):
        if self._trigger:
            return
        for _ in range(64):
            buf = self._ia.try_fetch(timeout=0.001)
            if buf is None:
                return
            buf.queue()

    def grab(self) -> Frame:
        import cv2

        if self._trigger:
            self._ia.remote_device.node_map.TriggerSoftware.execute()
        try:
            buf = self._ia.fetch(timeout=self.timeout_s)
        except Exception as e:
            raise ProcamError(f"{self.name}: no frame within {self.timeout_s:g} s ({type(e).__name__}); check the "
                              "camera's trigger settings and the cable") from None
        try:
            comp = buf.payload.components[0]
            fmt = str(getattr(comp, "data_format", ""))
            h, w = int(comp.height), int(comp.width)
            data = np.asarray(comp.data)
            n = data.size // (h * w)
            img = data.reshape(h, w, n).copy() if n > 1 else data.reshape(h, w).copy()
            ts = float(buf.timestamp_ns) * 1e-9 if hasattr(buf, "timestamp_ns") else time.monotonic()
        finally:
            buf.queue()
        bayer = next((v for k, v in _BAYER.items() if fmt.startswith(k)), None)
        if bayer is not None and img.ndim == 2:
            img = cv2.cvtColor(img, getattr(cv2, bayer))
        elif img.ndim == 3:
            img = to_gray(img, "bgr" if fmt.startswith("BGR") else "rgb")
        return Frame(img, ts, {"source": self.name, "pixel_format": fmt, "clock": "device"})

    def describe(self) -> dict:
        return {"backend": "genicam", "producer": str(self.producer), "device": self.device, **self._info,
                "settings": self._settings, "notes": list(self._notes)}


def list_genicam_cameras(producer) -> list[dict]:
    """The cameras a GenTL producer finds: ``spec``, ``vendor``, ``model``, ``serial_number``."""
    try:
        from harvesters.core import Harvester
    except ImportError:
        raise ProcamError("GenICam cameras need the 'harvesters' package, which is not installed; install it "
                          "with: pip install 'procam[genicam]'") from None
    producer = Path(producer)
    if not producer.is_file():
        raise ProcamError(f"{producer}: no such GenTL producer (.cti) file")
    h = Harvester()
    try:
        h.add_file(str(producer), check_existence=True, check_validity=True)
        h.update()
        infos = [d.property_dict for d in h.device_info_list]
    except Exception as e:
        raise ProcamError(f"{producer}: cannot list its cameras ({type(e).__name__}: {e})") from None
    finally:
        h.reset()
    return [{"spec": f"genicam:{producer}#{i}", **{k: str(d.get(k, "")) for k in ("vendor", "model", "serial_number")}}
            for i, d in enumerate(infos)]


# --------------------------------------------------------------------------------------------
# folder watch (DSLRs, vendor software that saves files)
# --------------------------------------------------------------------------------------------

_PARTIAL_SUFFIXES = {".part", ".partial", ".tmp", ".crdownload", ".download", ".filepart"}


class FolderWatchCamera(_Camera):
    """A camera whose own software saves each shot into a folder.

    After each pattern is shown (:meth:`arm`) every file already in the folder is old; :meth:`grab`
    waits for the next new image file (extensions as :data:`procam.io.IMAGE_EXTS`), lets it grow
    until its size stays the same for ``stable_s`` and it decodes, and returns it.  Hidden files,
    ``~`` files and download/partial suffixes are ignored.  The files are left where they are.

    Parameters
    ----------
    folder : the folder the camera software saves into (must exist).
    timeout_s : how long :meth:`grab` waits for a new file.
    poll_s : polling period.
    stable_s : the time a file's size must stay unchanged before it is read.
    """

    def __init__(self, folder, timeout_s: float = 60.0, poll_s: float = 0.05, stable_s: float = 0.2):
        self.folder = Path(folder)
        self.timeout_s = float(timeout_s)
        self.poll_s = float(poll_s)
        self.stable_s = float(stable_s)
        self.name = f"folder:{self.folder}"
        self.streaming = False
        self._seen: set[str] = set()
        self._taken: list[str] = []

    def _candidates(self) -> list[Path]:
        from ..io.files import IMAGE_EXTS

        try:
            entries = list(self.folder.iterdir())
        except OSError as e:
            raise ProcamError(f"{self.name}: cannot read the folder ({e.strerror or e})") from None
        out = []
        for p in entries:
            n = p.name
            if n.startswith((".", "~")) or p.suffix.lower() in _PARTIAL_SUFFIXES or p.suffix.lower() not in IMAGE_EXTS:
                continue
            out.append(p)
        return out

    def open(self):
        if not self.folder.is_dir():
            raise ProcamError(f"{self.name}: no such folder; give the folder your camera software saves into")
        self.arm()
        return self

    def arm(self):
        self._seen = {p.name for p in self._candidates()}

    def grab(self) -> Frame:
        from ..io.files import read_image

        deadline = time.monotonic() + self.timeout_s
        sizes: dict[str, tuple[int, float]] = {}
        while True:
            now = time.monotonic()
            new = []
            for p in self._candidates():
                if p.name in self._seen:
                    continue
                try:
                    st = p.stat()
                except OSError:
                    continue
                new.append((st.st_mtime, p, st.st_size))
            for _, p, size in sorted(new, key=lambda t: (t[0], t[1].name)):
                prev = sizes.get(p.name)
                if prev is None or prev[0] != size:
                    sizes[p.name] = (size, now)
                    continue
                if size == 0 or now - prev[1] < self.stable_s:
                    continue
                try:
                    img = read_image(p)
                except ProcamError:
                    continue  # still being written, or not an image: wait for the next poll
                self._seen.add(p.name)
                self._taken.append(p.name)
                return Frame(to_gray(img), now, {"source": self.name, "file": str(p)})
            if now >= deadline:
                raise ProcamError(f"{self.name}: no new image within {self.timeout_s:g} s; check that the camera "
                                  "software saves every shot into this folder as JPEG/PNG/TIFF (files already there "
                                  "are ignored)")
            time.sleep(self.poll_s)

    def describe(self) -> dict:
        return {"backend": "folder", "folder": str(self.folder), "timeout_s": self.timeout_s,
                "files": list(self._taken), "settings": {},
                "notes": ["exposure and gain are set in the camera's own software"]}


# --------------------------------------------------------------------------------------------
# the simulator as a camera
# --------------------------------------------------------------------------------------------

def _digest(image: np.ndarray) -> bytes:
    return hashlib.blake2b(np.ascontiguousarray(image).tobytes(), digest_size=16).digest()


class VirtualCamera(_Camera):
    """The simulator as a camera: returns the rendered view of the pattern a projector shows.

    The pose's whole sequence is rendered once (:func:`procam.simulate.render`); :meth:`grab`
    identifies the image the projector shows (by its hash among the sequence's patterns) and
    returns the rendered frame of it.

    Parameters
    ----------
    projector : anything with ``current`` (the image shown) and ``shown`` (a counter), e.g.
        :class:`~procam.acquire.projector.VirtualProjector` or a real window.
    scene : :class:`procam.simulate.Scene`; its ``proj_size`` must be the projector's size.
    order, seed : the sequence order and noise seed of the render.
    stack : the rendered stack of ``scene`` in ``order`` (skips the render; e.g. shared by tests).
    latency : frames the camera has buffered: the first ``latency`` grabs after a new pattern
        return the frame of the pattern shown before it (stale), unless :meth:`flush` drained them.
    flush_works : whether :meth:`flush` drains the buffered frames.
    stale_grabs : grab numbers (0-based, counting every grab) that return the previous pattern's frame.
    dead_projector : every frame is the black frame (the projector's light never arrives).
    gain : a digital gain on every frame (values clipped at full scale: saturation).
    exposure_change_at, exposure_factor : from grab number ``exposure_change_at`` on, frames are
        multiplied by ``exposure_factor`` (auto exposure kicking in mid-sequence).
    """

    def __init__(self, projector, scene, *, order: str = "opencv", seed: int = 0, stack: np.ndarray | None = None,
                 latency: int = 0, flush_works: bool = True, stale_grabs=(), dead_projector: bool = False,
                 gain: float = 1.0, exposure_change_at: int | None = None, exposure_factor: float = 0.5):
        self.projector = projector
        self.scene = scene
        self.order = order
        self.seed = int(seed)
        self.stack = stack
        self.latency = int(latency)
        self.flush_works = flush_works
        self.stale_grabs = frozenset(int(i) for i in stale_grabs)
        self.dead_projector = dead_projector
        self.gain = float(gain)
        self.exposure_change_at = exposure_change_at
        self.exposure_factor = float(exposure_factor)
        self.name = "virtual"
        self.grabs = 0
        self._index: dict[bytes, int] = {}
        self._seen_show = None
        self._cur = self._prev = None
        self._pending = 0
        self._ps = None

    def open(self):
        from .. import patterns

        if self._ps is not None:
            return self
        if tuple(self.projector.size) != tuple(self.scene.proj_size):
            raise ProcamError(f"virtual camera: the scene's projector is {self.scene.proj_size[0]}x"
                              f"{self.scene.proj_size[1]} but the patterns are {self.projector.size[0]}x"
                              f"{self.projector.size[1]}")
        w, h = self.scene.proj_size
        self._ps = patterns.pattern_set(w, h, self.order)
        if self.stack is None:
            from .. import simulate

            self.stack, _ = simulate.render(self.scene, order=self.order, seed=self.seed)
        expected = (self._ps.count, self.scene.cam_size[1], self.scene.cam_size[0])
        if self.stack.shape != expected:
            raise ValueError(f"stack must be {expected} for this scene and order, got {self.stack.shape}")
        self._index = {_digest(img): k for k, img in enumerate(patterns.generate(w, h, self.order))}
        return self

    def _identify(self, image) -> int:
        if image is None:
            return self._ps.black  # nothing shown yet: the projector is dark
        k = self._index.get(_digest(image))
        if k is None:
            raise ProcamError("virtual camera: the projector shows an image that is not one of the sequence's "
                              f"patterns (order {self.order}, step 1); the simulator renders only those")
        return k

    def _update(self):
        if self.projector.shown != self._seen_show:
            self._seen_show = self.projector.shown
            k = self._identify(self.projector.current)
            if k != self._cur:  # showing the same image again changes nothing on the screen
                self._prev = self._cur if self._cur is not None else self._ps.black
                self._cur = k
                self._pending = self.latency

    def flush(self):
        self._update()
        if self.flush_works:
            self._pending = 0

    def grab(self) -> Frame:
        self._update()
        n = self.grabs
        self.grabs += 1
        stale = self._pending > 0 or n in self.stale_grabs
        if self._pending > 0:
            self._pending -= 1
        k = self._prev if stale else self._cur
        if self.dead_projector:
            k = self._ps.black
        img = self.stack[k]
        factor = self.gain
        if self.exposure_change_at is not None and n >= self.exposure_change_at:
            factor *= self.exposure_factor
        if factor != 1.0:
            top = np.iinfo(img.dtype).max
            img = np.clip(np.rint(img.astype(np.float32) * factor), 0, top).astype(img.dtype)
        else:
            img = img.copy()
        return Frame(img, time.monotonic(), {"source": "virtual", "pattern": int(k), "stale": bool(stale)})

    def describe(self) -> dict:
        s = self.scene
        return {"backend": "virtual", "scene": s.name, "size": list(s.cam_size), "projector_size": list(s.proj_size),
                "order": self.order, "seed": self.seed, "latency": self.latency,
                "stale_grabs": sorted(self.stale_grabs), "dead_projector": self.dead_projector,
                "settings": {"gain": _setting(self.gain, self.gain, self.gain, True)},
                "notes": ["frames rendered by procam.simulate"]}


def demo_scene(projector_size=None, pose=None, preset: str = "ideal"):
    """A simulator scene for ``procam capture --virtual``: the ``preset`` rig with its projector
    resized to ``projector_size`` (same horizontal field of view, intrinsics scaled by W / 1920) and
    the board at ``pose`` (psi, nu, phi) degrees in the camera frame (default: the recommended pose)."""
    from .. import simulate

    scene = simulate.preset(preset)
    if projector_size is not None and tuple(projector_size) != tuple(scene.proj_size):
        w, h = int(projector_size[0]), int(projector_size[1])
        s = w / scene.proj_size[0]
        scene = scene.replace(proj_size=(w, h), K_proj=np.diag([s, s, 1.0]) @ scene.K_proj)
    if pose is not None or projector_size is not None:
        scene = simulate.with_board_pose(scene, simulate.RECOMMENDED_POSE if pose is None else pose)
    return scene


# --------------------------------------------------------------------------------------------
# --camera specs
# --------------------------------------------------------------------------------------------

def parse_camera_spec(spec: str) -> tuple[str, str]:
    """``--camera`` text -> (kind, argument), checked without opening anything.

    Kinds: ``opencv`` (argument: an index or a device path; default 0), ``genicam`` (the producer
    path, optionally ``#DEVICE``), ``folder`` (the folder) and ``virtual``.  Raises
    :class:`ProcamError` naming the option.
    """
    text = (spec or "").strip()
    kind, _, arg = text.partition(":")
    kind = kind.lower()
    if kind == "virtual" and not arg:
        return "virtual", ""
    if kind == "opencv":
        arg = arg or "0"
        if arg.isdigit() or arg.startswith("/"):
            return "opencv", arg
        raise ProcamError(f"--camera {spec}: opencv takes a device index or path, e.g. opencv:0 or opencv:/dev/video2")
    if kind == "genicam":
        if not arg.split("#")[0].lower().endswith(".cti"):
            raise ProcamError(f"--camera {spec}: genicam takes the GenTL producer file, e.g. "
                              "genicam:/opt/vendor/lib/producer.cti (optionally #SERIAL or #INDEX)")
        return "genicam", arg
    if kind == "folder":
        if not arg:
            raise ProcamError(f"--camera {spec}: folder takes the folder the camera software saves into, e.g. folder:shots/")
        return "folder", arg
    raise ProcamError(f"--camera {spec!r}: unknown camera; use {CAMERA_SPECS}")


def open_camera(spec: str, *, size=None, exposure_ms=None, gain=None, timeout_s: float = 60.0, projector=None,
                scene=None, **virtual_options):
    """Build (not open) the camera a ``--camera`` spec names (see :func:`parse_camera_spec`).

    ``projector`` and ``scene`` are needed by ``virtual``; ``virtual_options`` go to
    :class:`VirtualCamera`.  ``size`` is used by OpenCV only, ``timeout_s`` by the folder watch.
    """
    kind, arg = parse_camera_spec(spec)
    if kind == "opencv":
        return OpenCVCamera(int(arg) if arg.isdigit() else arg, size=size, exposure_ms=exposure_ms, gain=gain)
    if kind == "genicam":
        producer, _, device = arg.partition("#")
        return HarvestersCamera(producer, device or None, exposure_ms=exposure_ms, gain=gain)
    if kind == "folder":
        return FolderWatchCamera(arg, timeout_s=timeout_s)
    if projector is None or scene is None:
        raise ValueError("the virtual camera needs a projector and a simulator scene")
    return VirtualCamera(projector, scene, gain=1.0 if gain is None else gain, **virtual_options)
