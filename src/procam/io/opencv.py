"""OpenCV FileStorage files (YAML, XML, JSON): procam's calibration written with Moreno & Taubin's keys, and read
back; one camera's intrinsics read from the layouts other tools write.

* :func:`save_opencv_yaml` -- ``cam_K, cam_kc, proj_K, proj_kc, R, T`` (:data:`procam.io.formats.OPENCV`),
  the RMS errors, ``cam_size``/``proj_size``, method and verdict; YAML, or XML when the name ends in ``.xml``.
* :func:`read_calibration` -- the same keys from an open file (a missing ``cam_size``/``proj_size`` is assumed
  ``2 (u0, v0)`` and listed in ``info["image_size_assumed"]``).
* :func:`read_layout` -- a calibration in any of other tools' layouts (:data:`procam.io.layouts.RESULT_LAYOUTS`:
  structured-light ``CamMat/ProMat``, SLStudio, OpenCV stereo / MATLAB export), by the table, one code path.
* :func:`read_camera` -- one camera from any of :data:`CAMERA_LAYOUTS` (procam / Moreno-Taubin, OpenCV's
  calibration sample, kamino410) or of the result layouts.
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
from .layouts import RESULT_LAYOUTS, ResultLayout
from .validate import bad, check_K, check_rotation, check_size, check_translation, off_centre, opencv_coeffs

#: FileStorage layouts of one camera's intrinsics besides :data:`procam.io.layouts.RESULT_LAYOUTS` (whose camera
#: is read too): (K key, distortion key, whose).
CAMERA_LAYOUTS = (
    (OPENCV.cam_K, OPENCV.cam_dist, "procam / Moreno-Taubin YAML"),
    ("camera_matrix", "distortion_coefficients", "OpenCV calibration sample"),
    (KAMINO410.cam_K, KAMINO410.cam_dist, "kamino410/procam-calibration"),
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


def camera_size(path, shape, K) -> tuple[int, int]:
    """The camera's (width, height) from kamino410's ``img_shape`` (``[height, width]``), checked against the
    camera matrix ``K``: a shape written as ``[width, height]`` puts the principal point off the centre of the image
    it describes (by 10-40 % of a side for 16:10 to 4:3 images) and at the centre of the transposed one.  Such a
    file is refused (one line naming ``img_shape`` and both readings), never read as a camera turned a quarter
    turn."""
    size = check_size(path, "img_shape", np.asarray(shape).ravel()[::-1])
    w, h = size
    if w != h:
        here, there = off_centre(K, (w, h)), off_centre(K, (h, w))
        if here > 0.08 and there < here / 2:
            bad(path, "img_shape", f"[{h}, {w}] reads as a {w}x{h} camera (kamino410's img_shape is [height, width]),"
                                   f" but the principal point ({K[0, 2]:.0f}, {K[1, 2]:.0f}) of {KAMINO410.cam_K} is "
                                   f"that of a {h}x{w} camera (the centre of a {w}x{h} image is "
                                   f"({(w - 1) / 2:.0f}, {(h - 1) / 2:.0f}))",
                fix=f"write img_shape as [{w}, {h}] (height, width) if the camera is {h}x{w}")
    return size


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
        m = matrix(fs, path, "img_shape")
        return None if m is None else camera_size(path, m, K)
    return None


def read_camera(fs, path) -> tuple[np.ndarray, Distortion, tuple[int, int] | None] | None:
    """One camera's ``(K, distortion, image size or None)`` from the layout of :data:`CAMERA_LAYOUTS` or
    :data:`procam.io.layouts.RESULT_LAYOUTS` whose camera matrix the open file holds; None when it holds none.  A
    file holding the camera matrices of two layouts is refused (which one is meant?)."""
    hits = [(K_key, d_key) for K_key, d_key, _ in CAMERA_LAYOUTS if has(fs, K_key)]
    hits += [layout for layout in RESULT_LAYOUTS if any(has(fs, k) for k in layout.cam_K)]
    if len(hits) > 1:
        names = [h[0] if isinstance(h, tuple) else _present(fs, h.cam_K)[0] for h in hits]
        raise CalibrationFileError(f"{path}: holds the camera matrices of {len(hits)} layouts ({', '.join(names)}); "
                                   "procam cannot tell which one is meant: keep one")
    if not hits:
        return None
    if isinstance(hits[0], ResultLayout):
        return _layout_device(fs, path, hits[0], "camera")
    K_key, d_key = hits[0]
    K = check_K(path, K_key, matrix(fs, path, K_key))
    return K, distortion(fs, path, d_key), _camera_size(fs, path, K_key, K)


# --------------------------------------------------------------------------------------------------
# reading: other tools' result files, by the table of layouts
# --------------------------------------------------------------------------------------------------

def _present(fs, keys: tuple[str, ...]) -> list[str]:
    return [k for k in keys if has(fs, k)]


def _key(fs, path, layout: ResultLayout, keys: tuple[str, ...]) -> str | None:
    """The one of ``keys`` (names of one field) the file holds, None when none; two at once are refused."""
    present = _present(fs, keys)
    if len(present) > 1:
        bad(path, " and ".join(present), f"are two names of one field of the {layout.name} layout "
                                         "(procam cannot tell which one is meant)", fix="keep one")
    return present[0] if present else None


def _pair_size(path, key: str, v, order: str, K) -> tuple[int, int]:
    """A size stored as one pair: ``[width, height]``, or (order ``"either"``) the order the principal point of
    ``K`` tells: the reading that puts it at most half as far from the image centre as the other does (in fractions
    of the side, :func:`procam.io.validate.off_centre`); refused when neither does."""
    a = np.asarray(v, float).ravel()
    w, h = check_size(path, key, a)
    if order == "wh" or w == h:
        return w, h
    here, there = off_centre(K, (w, h)), off_centre(K, (h, w))
    if here <= there / 2:
        return w, h
    if there <= here / 2:
        return h, w
    bad(path, key, f"[{w}, {h}] may be [width, height] (OpenCV) or [height, width] (MATLAB's ImageSize), and the "
                   f"principal point ({K[0, 2]:.0f}, {K[1, 2]:.0f}) does not tell which",
        fix="write image_width and image_height instead")


def _layout_size(fs, path, specs, K) -> tuple[int, int] | None:
    """A device's image size from the first of ``specs`` (:class:`procam.io.layouts.SizeKeys`) the file holds;
    None when it holds none (a size of two zeros, SLStudio's unset projector, is none)."""
    for spec in specs:
        if not all(has(fs, k) for k in spec.keys()):
            continue
        if spec.height is None:
            return _pair_size(path, spec.width, matrix(fs, path, spec.width), spec.order, K)
        w, h = real(fs, path, spec.width), real(fs, path, spec.height)
        if w == 0 and h == 0:
            return None
        return check_size(path, f"{spec.width}/{spec.height}", (w, h))
    return None


def _layout_device(fs, path, layout: ResultLayout, which: str):
    """``(K, distortion, size or None)`` of the ``which`` device (``"camera"``, ``"projector"``) of ``layout``."""
    K_keys, d_keys, sizes = ((layout.cam_K, layout.cam_dist, layout.cam_size) if which == "camera" else
                             (layout.proj_K, layout.proj_dist, layout.proj_size))
    K_key = _key(fs, path, layout, K_keys)
    K = check_K(path, K_key, matrix(fs, path, K_key))
    d_key = _key(fs, path, layout, d_keys)
    return K, distortion(fs, path, d_key) if d_key else Distortion(), _layout_size(fs, path, sizes, K)


def layout_of(fs) -> list[ResultLayout]:
    """The layouts of :data:`procam.io.layouts.RESULT_LAYOUTS` whose camera or projector matrix the open file
    holds."""
    return [lay for lay in RESULT_LAYOUTS if _present(fs, lay.cam_K + lay.proj_K)]


def read_layout(fs, path, layout: ResultLayout) -> Calibration:
    """The calibration in ``layout``'s keys (a row of :data:`procam.io.layouts.RESULT_LAYOUTS`) from the open file
    ``fs`` of ``path``.  ``R, T`` are read as the layout stores them (``x_projector = R x_camera + T``).  A size
    the layout does not store (or this file lacks) is assumed ``2 (u0, v0)``, listed in
    ``info["image_size_assumed"]`` and said in a warning (the commands that read a pose take the real one:
    :func:`procam.io.complete_sizes`).  Not validated as a whole (:func:`procam.io.validate.validate_calibration`
    does that)."""
    path = Path(path)
    missing = ["/".join(keys) for keys in (layout.cam_K, layout.proj_K, layout.R, layout.T)
               if _key(fs, path, layout, keys) is None]
    if missing:
        raise CalibrationFileError(f"{path}: missing {', '.join(missing)}; the {layout.name} layout has the keys "
                                   f"{layout.keys()} (? optional)")
    devices, assumed, warnings = {}, [], []
    for which, key in (("camera", "cam_size"), ("projector", "proj_size")):
        K, dist, size = _layout_device(fs, path, layout, which)
        if size is None:
            size = (max(1, round(2 * K[0, 2])), max(1, round(2 * K[1, 2])))
            assumed.append(key)
            warnings.append(f"{path.name} does not store the {which} size; assumed {size[0]}x{size[1]} from its "
                            "principal point: give the real size")
        devices[which] = Device(K, size, dist)
    R_key, T_key = _key(fs, path, layout, layout.R), _key(fs, path, layout, layout.T)
    cam_rms, proj_rms, stereo_rms = (real(fs, path, k) if k else float("nan") for k in layout.rms)
    info = {"source": str(path), "layout": layout.name, **({"image_size_assumed": assumed} if assumed else {})}
    return Calibration(devices["camera"], devices["projector"], check_rotation(path, R_key, matrix(fs, path, R_key)),
                       check_translation(path, T_key, matrix(fs, path, T_key)), layout.method, cam_rms=cam_rms,
                       proj_rms=proj_rms, stereo_rms=stereo_rms, warnings=tuple(warnings), info=info,
                       verdict="unknown")
