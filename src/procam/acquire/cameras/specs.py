"""``--camera`` specs: ``opencv:INDEX``, ``genicam:PRODUCER.cti[#DEVICE]``, ``folder:PATH``, ``virtual``
checked (:func:`parse_camera_spec`) and turned into a camera (:func:`open_camera`).
"""

from __future__ import annotations

from ...errors import ProcamError
from .folder import FolderWatchCamera
from .genicam import HarvestersCamera
from .opencv import OpenCVCamera
from .virtual import VirtualCamera


CAMERA_SPECS = "opencv:INDEX, opencv:/dev/videoN, genicam:PRODUCER.cti[#DEVICE], folder:PATH or virtual"


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
