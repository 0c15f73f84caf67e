"""One calibration file, whatever its format: :func:`save_calibration` picks the format by the file's suffix,
:func:`load_calibration` and :func:`load_camera_intrinsics` recognise it by its content (the suffix is only a
hint).

A camera-projector calibration is read from

* procam's calibration JSON (``"format": "procam-calibration"``; :mod:`procam.io.procam`), also camera-only;
* procam's OpenCV FileStorage YAML or XML, Moreno & Taubin's keys ``cam_K, cam_kc, proj_K, proj_kc, R, T``
  (:mod:`procam.io.opencv`);
* kamino410/procam-calibration's ``calibration_result.xml`` (``cam_int, cam_dist, proj_int, proj_dist, rotation,
  translation``), theirs or procam's export (:mod:`procam.io.kamino410`);
* other tools' result files, each layout a row of one table (:data:`procam.io.layouts.RESULT_LAYOUTS`: the
  structured-light ``CamMat, ProMat, R, T``, SLStudio's ``Kc, kc, Kp, kp, Rp, Tp``, OpenCV's stereo ``K1, D1,
  K2, D2, R, T`` and its variants, MATLAB's stereo parameters exported so), read by one code path
  (:func:`procam.io.opencv.read_layout`);

one camera's intrinsics from those and from OpenCV's calibration sample (``camera_matrix``) and kamino410's
``camera_config.json``.

Recognition: a file that starts with ``%YAML``, ``<?xml`` or ``<opencv_storage>`` is a FileStorage file; one that
starts with ``{`` is JSON (procam's, kamino410's camera file, or a FileStorage JSON holding one of the layouts'
keys); for anything else the suffix decides (``.json`` JSON; ``.yml``, ``.yaml``, ``.xml`` FileStorage), so the
error says what is wrong with that kind of file.  In a FileStorage file the layout is the one whose device
matrices the file holds (procam's, kamino410's or a row of the table); a file holding those of two layouts is
refused as ambiguous, one holding none names the keys it has and the layouts read.  Every field is checked by the
one validator set (:mod:`procam.io.validate`), and a file that cannot be read is refused with one line that names
it and the formats read.
"""

from __future__ import annotations

from pathlib import Path

from ..calibration import Calibration, Device, Distortion, RigCalibration
from ..errors import CalibrationFileError
from . import kamino410, opencv, procam
from .formats import CALIBRATION_FORMAT, KAMINO410, OPENCV, RIG_CALIBRATION_FORMAT
from .layouts import RESULT_LAYOUTS
from .rig import HINT as RIG_HINT
from .rig import load_rig_document, rig_devices
from .validate import bad, check_size, load_json, validate_calibration

#: The FileStorage layouts of a camera-projector calibration :func:`load_calibration` reads: (name, keys).
STORAGE_LAYOUTS = ((OPENCV.name, "cam_K, cam_kc, proj_K, proj_kc, R, T"),
                   (KAMINO410.name, "cam_int, cam_dist, proj_int, proj_dist, rotation, translation"),
                   *((lay.name, lay.keys()) for lay in RESULT_LAYOUTS))
#: What :func:`load_calibration` reads, as its errors say it.
CALIBRATION_FORMATS = ("procam reads procam calibration JSON and OpenCV FileStorage YAML/XML/JSON in the layouts "
                       + "; ".join(f"{name} ({keys})" for name, keys in STORAGE_LAYOUTS))
#: What :func:`load_camera_intrinsics` reads, as its errors say it.
CAMERA_FORMATS = ("procam reads a camera from procam calibration JSON, kamino410's camera_config.json and OpenCV "
                  "FileStorage YAML/XML/JSON with " + ", ".join(
                      [f"{k}/{d}" for k, d, _ in opencv.CAMERA_LAYOUTS]
                      + [f"{'/'.join(lay.cam_K)} ({lay.name})" for lay in RESULT_LAYOUTS]))

#: The keys that make a JSON document a FileStorage file (``cv2.FileStorage`` writes JSON too).
_STORAGE_KEYS = (OPENCV.cam_K, OPENCV.proj_K, KAMINO410.cam_K, KAMINO410.proj_K,
                 *(k for k, _, _ in opencv.CAMERA_LAYOUTS),
                 *(k for lay in RESULT_LAYOUTS for k in lay.cam_K + lay.proj_K))


def save_calibration(calib: Calibration, path) -> Path:
    """Write ``calib`` as procam's JSON (``.json`` or any other suffix) or OpenCV FileStorage (``.yml``/``.yaml``
    YAML, ``.xml`` XML, procam's keys: :func:`procam.io.opencv.save_opencv_yaml`), atomically."""
    path = Path(path)
    if path.suffix.lower() in (".yml", ".yaml", ".xml"):
        return opencv.save_opencv_yaml(calib, path)
    return procam.save_calibration_json(calib, path)


def _kind(path: Path) -> str | None:
    """``"filestorage"`` or ``"json"`` by the file's first bytes, else by its suffix; None when neither tells."""
    try:
        with open(path, "rb") as f:
            head = f.read(256)
    except OSError as e:
        raise CalibrationFileError(f"{path}: cannot be read ({e.strerror or e}); check its permissions") from None
    text = head.lstrip(b"\xef\xbb\xbf \t\r\n")
    if text.startswith((b"%YAML", b"<?xml", b"<opencv_storage")):
        return "filestorage"
    if text.startswith(b"{"):
        return "json"
    return {".json": "json", ".yml": "filestorage", ".yaml": "filestorage", ".xml": "filestorage"}.get(
        path.suffix.lower())


def _json(path: Path, what: str, hint: str):
    return load_json(path, what, hint)


def _is_storage(doc) -> bool:
    """Is the JSON document a ``cv2.FileStorage`` file of one of the layouts?"""
    return isinstance(doc, dict) and any(k in doc for k in _STORAGE_KEYS)


def _read_storage(path: Path, hint: str, read):
    """``read(fs, path)`` of the FileStorage file ``path``; OpenCV's own errors become one line."""
    import cv2

    fs = opencv.open_storage(path, hint)
    try:
        return read(fs, path)
    except (cv2.error, SystemError) as e:
        raise CalibrationFileError(f"{path}: not a readable OpenCV calibration ({opencv.cv_message(e)})") from None
    finally:
        fs.release()


def _storage_calibration(fs, path) -> Calibration:
    """The calibration of the one layout whose device matrices the open file holds (procam's, kamino410's or a
    row of :data:`procam.io.layouts.RESULT_LAYOUTS`); none or two are refused, naming the keys found."""
    hits = [(name, read) for name, keys, read in (
        (OPENCV.name, (OPENCV.cam_K, OPENCV.proj_K), opencv.read_calibration),
        (KAMINO410.name, (KAMINO410.cam_K, KAMINO410.proj_K), kamino410.read_calibration))
        if any(opencv.has(fs, k) for k in keys)]
    hits += [(lay.name, lambda fs, path, lay=lay: opencv.read_layout(fs, path, lay)) for lay in opencv.layout_of(fs)]
    if len(hits) == 1:
        return hits[0][1](fs, path)
    root = fs.root()
    found = ", ".join(root.keys()) if root.isMap() else ""
    found = (found[:200] + " ...") if len(found) > 200 else found or "none"
    if hits:
        raise CalibrationFileError(f"{path}: ambiguous: holds the device matrices of {len(hits)} layouts "
                                   f"({', '.join(n for n, _ in hits)}; keys found: {found}); keep one layout's keys; "
                                   f"{CALIBRATION_FORMATS}")
    raise CalibrationFileError(f"{path}: holds no camera-projector calibration of a known layout (keys found: "
                               f"{found}); {CALIBRATION_FORMATS}")


def _rig_pair(path: Path, doc: dict, pair: str | None) -> tuple[str, dict]:
    """``(key, document)``: the procam calibration document of one pair of a rig calibration
    (``procam-rig-calibration``): ``pair`` is ``"camera/projector"`` or a device name that is in one pair only; None
    for a rig of one pair."""
    pairs = doc.get("pairs")
    if not isinstance(pairs, dict) or not pairs:
        raise CalibrationFileError(f"{path}: a rig calibration without pairs")
    if pair is None and len(pairs) == 1:
        hits = list(pairs)
    else:
        hits = [k for k in pairs if pair is not None and (k == pair or pair in k.split("/"))]
    if len(hits) != 1:
        what = "names no pair" if pair is not None and not hits else "is ambiguous" if pair is not None else ""
        raise CalibrationFileError(f"{path}: a rig calibration of {len(pairs)} pairs ({', '.join(pairs)})"
                                   + (f"; pair {pair!r} {what}" if what else "") + "; name one pair "
                                   "(camera/projector or a device's name: procam export --pair, "
                                   "load_calibration(path, pair=...))")
    if not isinstance(pairs[hits[0]], dict) or pairs[hits[0]].get("format") != CALIBRATION_FORMAT:
        raise CalibrationFileError(f"{path}: pair {hits[0]!r} is not a procam calibration document")
    return hits[0], pairs[hits[0]]


def load_calibration(path, pair: str | None = None) -> Calibration:
    """Read a calibration in any format procam writes or reads (module docstring), recognised by content.

    A rig calibration (``procam-rig-calibration``, :mod:`procam.io.rig`) holds one calibration per
    (camera, projector) pair: ``pair`` names it (``"camera/projector"``, or a device name in one pair only); it
    is required for a rig of several pairs and refused for any other file.

    Every field is checked (:func:`procam.io.validate.validate_calibration`): shapes, finiteness, positive focal
    lengths, plausible magnitudes, a rotation ``R`` and non-zero ``T``, a known distortion model (an unknown one
    is refused, not read as none).  A procam YAML/XML without ``cam_size``/``proj_size`` gets ``2 (u0, v0)`` as
    the image size, and ``info["image_size_assumed"]`` lists the keys that were missing; a kamino410 file from
    their tool (no projector size) gets ``2 (u0, v0)`` for the projector and a warning
    (:func:`procam.io.load_kamino410` takes the real size).

    Raises :class:`~procam.errors.CalibrationFileError` naming the file and the field.
    """
    path = Path(path)
    if not path.is_file():
        what = ("a folder, not a calibration file" if path.is_dir() else "not a regular file" if path.exists() else
                "no such file")
        raise CalibrationFileError(f"{path}: {what}; give a calibration written by 'procam calibrate'")
    kind = _kind(path)
    if kind == "json":
        doc = _json(path, "not a procam calibration JSON file", CALIBRATION_FORMATS)
        if isinstance(doc, dict) and doc.get("format") == RIG_CALIBRATION_FORMAT:
            rig_devices(path, doc)          # the whole rig checked: a file is read whole or refused
            key, pair_doc = _rig_pair(path, doc, pair)
            where = f"{path} (pair {key})"  # the errors name the pair
            return validate_calibration(procam.calibration_from_json(where, pair_doc), where)
        if pair is not None:
            raise CalibrationFileError(f"{path}: not a rig calibration, so it has no pair {pair!r}")
        if isinstance(doc, dict) and doc.get("format") == CALIBRATION_FORMAT:
            return validate_calibration(procam.calibration_from_json(path, doc), path)
        if not _is_storage(doc):
            why = f"missing format: {CALIBRATION_FORMAT}" if isinstance(doc, dict) else "the top level is not an object"
            raise CalibrationFileError(f"{path}: not a procam calibration JSON file ({why}); {CALIBRATION_FORMATS}")
    elif kind is None:
        raise CalibrationFileError(f"{path}: unknown file type {path.suffix!r}; {CALIBRATION_FORMATS}")
    elif pair is not None:
        raise CalibrationFileError(f"{path}: an OpenCV file holds the rig's reference pair only; read pair {pair!r} "
                                   "from the rig's JSON file")
    return validate_calibration(_read_storage(path, CALIBRATION_FORMATS, _storage_calibration), path)


def complete_sizes(calib: Calibration, cam_size=None, proj_size=None) -> Calibration:
    """``calib`` with the image sizes its file did not store (``info["image_size_assumed"]``: ``2 (u0, v0)`` was
    assumed) replaced by the sizes a capture tells (``cam_size``, ``proj_size``: (width, height) or None); a size
    the file stored is kept (a mismatch is the caller's to report).  The warning about the assumed size goes with
    it.  Used by the commands that read a pose with a calibration (kamino410's own files store no projector size)."""
    assumed = list((calib.info or {}).get("image_size_assumed", ()))
    kw = {}
    for key, name, size in (("cam_size", "camera", cam_size), ("proj_size", "projector", proj_size)):
        dev = getattr(calib, name)
        if size is not None and key in assumed and dev is not None:
            kw[name] = Device(dev.K, tuple(int(v) for v in size), dev.distortion)
            assumed.remove(key)
    if not kw:
        return calib
    info = {**calib.info, "image_size_assumed": assumed} if assumed else \
        {k: v for k, v in calib.info.items() if k != "image_size_assumed"}
    warnings = tuple(w for w in calib.warnings if not any(f"does not store the {name} size" in w for name in kw))
    return calib.replace(info=info, warnings=warnings, **kw)


def load_camera_intrinsics(path, image_size=None) -> Device:
    """One camera's intrinsics (K, distortion, image size) from the files people have: :func:`load_calibration`'s
    reader asking for the camera only.

    Reads, by content:

    * procam calibration JSON (``procam calibrate``, also camera-only): the ``camera`` block, any
      distortion model, and its ``covariance`` block where it has one (``Device.covariance``);
    * kamino410's camera JSON (``{"camera": {"P": [9 numbers], "distortion": [...], "width", "height"}}``);
    * ``cv2.FileStorage`` YAML/XML/JSON with ``cam_K``/``cam_kc`` (procam, Moreno-Taubin's
      scan3d-capture; size from ``cam_size``), ``camera_matrix``/``distortion_coefficients`` (OpenCV's
      calibration sample; size from ``image_width``/``image_height``), ``cam_int``/``cam_dist``
      (kamino410; size from ``img_shape``) or ``M1``/``D1`` (OpenCV's stereo sample: the first camera).

    Parameters
    ----------
    path : the file.
    image_size : (width, height) of the images the intrinsics will be used with.  Required when the
        file has no size; when it has one they must agree.

    Raises
    ------
    CalibrationFileError
        Missing file, unknown layout, a malformed matrix (naming the field), no image size, or a
        size that differs from ``image_size``.
    """
    path = Path(path)
    if not path.is_file():
        raise CalibrationFileError(f"{path}: no such file; give a camera calibration file")
    kind = _kind(path)
    found = covariance = None
    if kind == "json":
        doc = _json(path, "not valid JSON", CAMERA_FORMATS)
        if isinstance(doc, dict) and doc.get("format") == CALIBRATION_FORMAT:
            cam = procam.device_from_json(path, doc, "camera")
            found = cam.K, cam.distortion, cam.image_size
            if "covariance" in doc and cam.distortion.model in ("opencv", "none"):  # OpenCV's parameters: its model's
                c = procam._covariance_from_json(path, doc["covariance"])
                covariance = (c["params"], c["matrix"])
        elif isinstance(doc, dict) and isinstance(doc.get("camera"), dict) and "P" in doc["camera"]:
            found = kamino410.camera_from_config(path, doc)
        elif not _is_storage(doc):
            raise CalibrationFileError(f"{path}: no camera calibration found; {CAMERA_FORMATS}")
    elif kind is None:
        raise CalibrationFileError(f"{path}: unknown file type {path.suffix!r}; {CAMERA_FORMATS}")
    if found is None:
        found = _read_storage(path, CAMERA_FORMATS, opencv.read_camera)
        if found is None:
            keys = ", ".join([f"{k}/{d} ({what})" for k, d, what in opencv.CAMERA_LAYOUTS]
                             + [f"{'/'.join(lay.cam_K)} ({lay.name})" for lay in RESULT_LAYOUTS])
            raise CalibrationFileError(f"{path}: no camera matrix found; expected one of {keys}")
    K, dist, size = found
    if image_size is not None:
        want = check_size(path, "the image size", image_size)
        if size is not None and size != want:
            raise CalibrationFileError(f"{path}: the intrinsics are for {size[0]}x{size[1]} images, the images are "
                                       f"{want[0]}x{want[1]}; use the calibration of this camera at this resolution")
        size = want
    if size is None:
        raise CalibrationFileError(f"{path}: the file does not say the image size the intrinsics belong to; "
                                   "give it (width x height)")
    return Device(K, size, dist if dist is not None else Distortion(), covariance=covariance)


def load_projector_intrinsics(path, image_size=None) -> Device:
    """A projector's intrinsics and distortion (a :class:`~procam.calibration.Device`) from a procam calibration
    in any format :func:`load_calibration` reads (procam JSON, OpenCV FileStorage YAML/XML with procam's keys,
    kamino410's XML, other tools' result files): the file's ``projector``.

    ``image_size``: the projector (width, height) the intrinsics will be used with; they must agree.  A file that
    does not store the projector's size (``info["image_size_assumed"]``) takes it (:func:`complete_sizes`).

    Raises :class:`~procam.errors.CalibrationFileError` when the file holds no projector (a camera-only file) or
    one of another size.
    """
    calib = load_calibration(path)
    if image_size is not None:
        calib = complete_sizes(calib, proj_size=check_size(path, "the projector size", image_size))
    if calib.projector is None:
        raise CalibrationFileError(f"{path}: holds no projector (a camera-only calibration); give a procam "
                                   "calibration of this projector")
    size = tuple(int(v) for v in calib.projector.image_size)
    if image_size is not None and size != tuple(int(v) for v in image_size):
        raise CalibrationFileError(f"{path}: the projector's intrinsics are for {size[0]}x{size[1]}, this pose's "
                                   f"projector is {int(image_size[0])}x{int(image_size[1])}; give the calibration "
                                   "of this projector at this resolution")
    return calib.projector


def load_rig_calibration(path) -> RigCalibration:
    """The :class:`~procam.calibration.RigCalibration` a rig calibration JSON file holds (every device, relative
    pose and pair as written): every device block and relative pose checked by the one validator set
    (:func:`rig_devices`), the pairs read by :func:`procam.io.load_calibration` with ``pair=``, so validated
    like any calibration.  :class:`CalibrationFileError` naming the file and the field otherwise."""
    path = Path(path)
    doc = load_rig_document(path)
    cams, projs, rel = rig_devices(path, doc)
    pairs = {key: load_calibration(path, pair=key) for key in doc["pairs"]}
    verdict = doc.get("verdict") or {}
    if not isinstance(verdict, dict):
        bad(path, "verdict", "must be an object", fix=RIG_HINT)
    return RigCalibration(str(doc.get("method", "")), cams, projs, rel, pairs, tuple(doc.get("poses") or ()),
                          str(doc.get("uncertainty", "")), dict(doc.get("info") or {}),
                          tuple(doc.get("warnings") or ()), str(verdict.get("level", "failed")),
                          tuple(str(r) for r in verdict.get("reasons", ())))
