"""GenICam machine-vision cameras (GigE Vision / USB3 Vision) through a GenTL producer and ``harvesters``
(:class:`HarvestersCamera`, ``pip install 'procam[genicam]'``), and the cameras a producer finds
(:func:`list_genicam_cameras`).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ...errors import ProcamError
from .base import Frame, _Camera, _setting, to_gray


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
