"""OpenCV FileStorage files (YAML, XML, JSON): procam's calibration written with Moreno & Taubin's keys, and read
back; one camera's intrinsics read from the layouts other tools write.

* :func:`save_opencv_yaml` -- ``cam_K, cam_kc, proj_K, proj_kc, R, T`` (:data:`procam.io.formats.OPENCV`),
  the RMS errors, ``cam_size``/``proj_size``, method and verdict; YAML, or XML when the name ends in ``.xml``.
* :func:`read_calibration` -- the same keys from an open file (a missing ``cam_size``/``proj_size`` is assumed
  ``2 (u0, v0)`` and listed in ``info["image_size_assumed"]``).
* :func:`read_camera` -- one camera from any of :data:`CAMERA_LAYOUTS` (procam / Moreno-Taubin, OpenCV's
  calibration and stereo samples, kamino410).
* :func:`open_storage`, :func:`matrix`, :func:`real` -- the FileStorage plumbing the readers share (kamino410's
  too): a matrix may also stand as a sequence of numbers or one number (files written by hand); a file OpenCV
  cannot parse, or a node that is not numbers, gives one line naming the file and the key.

Every number is checked by :mod:`procam.io.validate`.  A distortion vector that is missing, empty or all zeros
is no distortion (the rules are in :mod:`procam.io.validate`).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ..calibration import Calibration, Device, Distortion
from ..distortion import opencv_from_division
from ..errors import CalibrationFileError
from .files import atomic_path
from .formats import FILESTORAGE_FORMATS, FILESTORAGE_KEY, KAMINO410, OPENCV, FileStorageLayout
from .procam import VERDICT_MEANING, verdict_level
from .validate import bad, check_K, check_rotation, check_size, check_translation, opencv_coeffs

#: FileStorage layouts of one camera's intrinsics, in the order they are looked for: (K key, distortion key, whose).
CAMERA_LAYOUTS = (
    (OPENCV.cam_K, OPENCV.cam_dist, "procam / Moreno-Taubin YAML"),
    ("camera_matrix", "distortion_coefficients", "OpenCV calibration sample"),
    (KAMINO410.cam_K, KAMINO410.cam_dist, "kamino410/procam-calibration"),
    ("M1", "D1", "OpenCV stereo_calib sample (first camera)"),
)


# --------------------------------------------------------------------------------------------------
# writing
# --------------------------------------------------------------------------------------------------

def device_coeffs(dev: Device) -> np.ndarray:
    """OpenCV distortion coefficients (1, n) of a device: its own; for the division model the OpenCV
    ``(k1, k2, p1, p2, k3)`` fit over the image (:func:`procam.distortion.opencv_from_division`); zeros (1, 5)
    without distortion."""
    d = dev.distortion
    if d.model == "opencv":
        return np.asarray(d.coeffs, float).reshape(1, -1)
    if d.model == "division":
        coeffs, _ = opencv_from_division(dev.K, d.center, d.k1, d.k2, dev.image_size)
        return np.asarray(coeffs, float).reshape(1, -1)
    return np.zeros((1, 5))


def write_devices(fs, keys: FileStorageLayout, calib) -> None:
    """Write procam's mark (:data:`~procam.io.formats.FILESTORAGE_KEY` naming the layout's format) and a layout's six
    keys into the open ``fs``: both devices' ``K`` and OpenCV distortion (:func:`device_coeffs`), ``R`` and ``T``
    (3x1)."""
    fs.write(FILESTORAGE_KEY, FILESTORAGE_FORMATS[keys.name])
    fs.write(keys.cam_K, np.asarray(calib.camera.K, float))
    fs.write(keys.cam_dist, device_coeffs(calib.camera))
    fs.write(keys.proj_K, np.asarray(calib.projector.K, float))
    fs.write(keys.proj_dist, device_coeffs(calib.projector))
    fs.write(keys.R, np.asarray(calib.R, float))
    fs.write(keys.T, np.asarray(calib.T, float).reshape(3, 1))


def save_opencv_yaml(calib, path) -> Path:
    """OpenCV FileStorage YAML with the keys ``cam_K, cam_kc, proj_K, proj_kc, R, T, cam_error,
    proj_error, stereo_error`` (as Moreno–Taubin's tool writes them), plus ``cam_size``/``proj_size``,
    atomically; the same keys as FileStorage XML when ``path`` ends in ``.xml``.

    ``cam_kc`` of a division-model camera is the OpenCV ``(k1, k2, p1, p2, k3)`` fit to it over the image
    (``distortion.opencv_from_division``); the division model itself is in the JSON file.
    """
    import cv2

    if calib.projector is None:
        raise CalibrationFileError(f"{path}: a camera-only calibration has no projector, so it has no OpenCV procam "
                                   "YAML form; write it as JSON (.json)")
    path = Path(path)
    with atomic_path(path) as tmp:
        fs = cv2.FileStorage(str(tmp), cv2.FILE_STORAGE_WRITE)
        write_devices(fs, OPENCV, calib)
        fs.write("cam_error", float(calib.cam_rms))
        fs.write("proj_error", float(calib.proj_rms))
        fs.write("stereo_error", float(calib.stereo_rms))
        fs.write("cam_size", np.array(calib.camera.image_size, np.int32).reshape(1, 2))
        fs.write("proj_size", np.array(calib.projector.image_size, np.int32).reshape(1, 2))
        fs.write("method", calib.method)
        fs.write("verdict", calib.verdict)
        fs.write("verdict_meaning", VERDICT_MEANING.get(calib.verdict, ""))
        fs.release()
    return path


# --------------------------------------------------------------------------------------------------
# reading: plumbing
# --------------------------------------------------------------------------------------------------

def cv_message(e: BaseException) -> str:
    """The useful part of an OpenCV error (also when wrapped in a SystemError): ``'Parsing error: ...'``."""
    seen = 0
    while isinstance(e, SystemError) and (e.__cause__ or e.__context__) and seen < 5:
        e, seen = e.__cause__ or e.__context__, seen + 1
    text = (str(e).strip().splitlines() or [""])[-1]
    m = re.search(r"error: \(-?\d+:([^)]*)\) (.*)$", text)
    return f"{m.group(1)}: {m.group(2)}" if m else text


def _top_level_keys(path) -> list[str]:
    """The top-level keys of a FileStorage YAML or XML file in the order written ([] for JSON, which
    :func:`procam.io.validate.load_json` checks, and for a file that does not parse: OpenCV then says why)."""
    try:
        text = Path(path).read_bytes().lstrip(b"\xef\xbb\xbf \t\r\n")
    except OSError:
        return []
    if text.startswith((b"<?xml", b"<opencv_storage")):
        import xml.etree.ElementTree as ET

        try:
            return [child.tag for child in ET.fromstring(text)]
        except (ET.ParseError, ValueError, RecursionError):
            return []
    if text.startswith(b"{"):
        return []
    keys = []
    for line in text.decode("utf-8", "replace").splitlines():
        m = re.match(r"([^\s#%\-\[\]{}:'\"][^:]*?)\s*:(\s|$)", line)      # a key at column 0
        if m:
            keys.append(m.group(1))
    return keys


def open_storage(path, hint: str):
    """``cv2.FileStorage`` of ``path`` open for reading (OpenCV tells YAML, XML and JSON apart by content), or a
    one-line :class:`CalibrationFileError` ending in ``hint`` (what the reader accepts).  A top-level key given
    twice is refused (OpenCV would silently read one of the two values)."""
    import cv2

    try:
        fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
        opened = fs.isOpened()
    except (cv2.error, SystemError) as e:   # a parse error surfaces as SystemError in some OpenCV builds
        msg = cv_message(e)
        raise CalibrationFileError(f"{path}: not a readable OpenCV FileStorage file ({msg}); {hint}") from None
    if not opened:
        raise CalibrationFileError(f"{path}: not a readable OpenCV FileStorage file; {hint}")
    seen = set()
    for key in _top_level_keys(path):
        if key in seen:
            fs.release()
            bad(path, key, "is given twice (procam cannot tell which one is meant)", fix="keep one")
        seen.add(key)
    return fs


def has(fs, key: str) -> bool:
    """Does the open file hold ``key``?"""
    return not fs.getNode(key).empty()


def matrix(fs, path, key: str):
    """The node ``key`` as a float array: an ``!!opencv-matrix`` (an empty one as (0,)), a sequence of numbers
    (as (n,)) or one number (as (1, 1)); None when the key is missing; a one-line error for anything else."""
    n = fs.getNode(key)
    if n.empty():
        return None
    if n.isMap():                                # ask for a matrix only of a map: OpenCV 5 asserts otherwise
        m = n.mat()
        if m is not None:
            return np.asarray(m, float)
        rows, cols = n.getNode("rows"), n.getNode("cols")
        if rows.isInt() and cols.isInt() and rows.real() * cols.real() == 0:
            return np.zeros(0)                   # an empty Mat: OpenCV writes one for "no coefficients"
    elif n.isSeq():
        items = [n.at(i) for i in range(n.size())]
        if all(it.isReal() or it.isInt() for it in items):
            return np.array([it.real() for it in items], float)
    elif n.isReal() or n.isInt():
        return np.array([[n.real()]])
    bad(path, key, "must be a matrix (!!opencv-matrix) of numbers")


def real(fs, path, key: str) -> float:
    """The number ``key`` (an RMS error in pixels); NaN when missing."""
    n = fs.getNode(key)
    if n.empty():
        return float("nan")
    if not (n.isReal() or n.isInt()):
        bad(path, key, "must be a number of pixels")
    return float(n.real())


def string(fs, key: str) -> str:
    """The string ``key``, or '' when it is missing or not a string."""
    n = fs.getNode(key)
    return n.string() if n.isString() else ""


def distortion(fs, path, key: str) -> Distortion:
    """The OpenCV distortion vector ``key``: missing, empty or all zeros is no distortion."""
    coeffs = opencv_coeffs(path, key, matrix(fs, path, key))
    return Distortion("opencv", coeffs=coeffs) if any(coeffs) else Distortion()


# --------------------------------------------------------------------------------------------------
# reading: procam's calibration, one camera of any layout
# --------------------------------------------------------------------------------------------------

def read_calibration(fs, path) -> Calibration:
    """procam's calibration (:data:`procam.io.formats.OPENCV` keys) from the open file ``fs`` of ``path``.

    A file without ``cam_size``/``proj_size`` gets ``2 (u0, v0)`` as the image size, and
    ``info["image_size_assumed"]`` lists the keys that were missing.  Not validated as a whole
    (:func:`procam.io.validate.validate_calibration` does that).
    """
    keys = OPENCV
    missing = [k for k in (keys.cam_K, keys.proj_K, keys.R, keys.T) if not has(fs, k)]
    if missing:
        raise CalibrationFileError(f"{path}: missing {', '.join(missing)}; expected the keys cam_K, cam_kc, "
                                   "proj_K, proj_kc, R, T")
    cK, pK = check_K(path, keys.cam_K, matrix(fs, path, keys.cam_K)), check_K(path, keys.proj_K,
                                                                             matrix(fs, path, keys.proj_K))
    assumed = []

    def size(k, K):
        m = matrix(fs, path, k)
        if m is not None:
            return check_size(path, k, m)
        assumed.append(k)
        return (max(1, round(2 * K[0, 2])), max(1, round(2 * K[1, 2])))

    return Calibration(
        camera=Device(cK, size("cam_size", cK), distortion(fs, path, keys.cam_dist)),
        projector=Device(pK, size("proj_size", pK), distortion(fs, path, keys.proj_dist)),
        R=check_rotation(path, keys.R, matrix(fs, path, keys.R)),
        T=check_translation(path, keys.T, matrix(fs, path, keys.T)),
        method=string(fs, "method") or "opencv-yaml", cam_rms=real(fs, path, "cam_error"),
        proj_rms=real(fs, path, "proj_error"), stereo_rms=real(fs, path, "stereo_error"),
        info={"image_size_assumed": assumed} if assumed else {}, verdict=verdict_level(string(fs, "verdict")))


def _camera_size(fs, path, K_key, K):
    """The camera's image size as its layout stores it (checked against its matrix ``K`` where the layout's order
    of width and height is easily mistaken), or None."""
    if K_key == OPENCV.cam_K:
        m = matrix(fs, path, "cam_size")
        return None if m is None else check_size(path, "cam_size", m)
    if K_key == "camera_matrix":
        if not (has(fs, "image_width") and has(fs, "image_height")):
            return None
        w, h = real(fs, path, "image_width"), real(fs, path, "image_height")
        return check_size(path, "image_width/image_height", (w, h))
    if K_key == KAMINO410.cam_K:
        from .kamino410 import camera_size

        m = matrix(fs, path, "img_shape")
        return None if m is None else camera_size(path, m, K)
    return None


def read_camera(fs, path) -> tuple[np.ndarray, Distortion, tuple[int, int] | None] | None:
    """One camera's ``(K, distortion, image size or None)`` from the first of :data:`CAMERA_LAYOUTS` the open
    file holds; None when it holds none."""
    for K_key, d_key, _ in CAMERA_LAYOUTS:
        if has(fs, K_key):
            K = check_K(path, K_key, matrix(fs, path, K_key))
            return K, distortion(fs, path, d_key), _camera_size(fs, path, K_key, K)
    return None
