"""The rig calibration file: JSON (``"format": "procam-rig-calibration"``) or OpenCV FileStorage YAML/XML.

JSON (schema in docs/rigs.md): ``reference`` (the reference camera), ``cameras`` and ``projectors`` ({name: K,
image_size, distortion, R, T (reference -> device, ``X_dev = R X_ref + T``), center, angles_deg, std, verdict}),
``relative`` ({"a->b": R, T, angles_deg, baseline, std}), ``uncertainty`` (what every ± assumes), ``verdict``,
and ``pairs`` ({"camera/projector": an ordinary procam calibration document}): each pair is what
:func:`procam.io.load_calibration` ``(path, pair="camera/projector")`` (or just the projector's or camera's name
when it is in one pair) reads back, in that pair's camera frame, so every procam command and reader that takes
a calibration takes one pair of the rig.

YAML/XML: the reference pair under procam's single-pair keys (``cam_K, cam_kc, proj_K, proj_kc, R, T``, sizes:
an OpenCV reader of procam's files reads the reference camera and the first projector), plus for every device
``<name>_K``, ``<name>_kc``, ``<name>_size``, ``<name>_R``, ``<name>_T`` (reference -> device) and the lists
``rig_cameras`` / ``rig_projectors``.  Written atomically.

Read back by :func:`procam.io.calibration_file.load_rig_calibration` (the one calibration reader): every device block and relative pose is checked by the one validator
set (:mod:`procam.io.validate`, as a pair file's devices are: ``K`` sane, a rotation ``R``, a finite ``T``, a known
distortion), and every pair by :func:`procam.io.load_calibration`.  A JSON key given twice is refused.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .. import models
from ..errors import CalibrationFileError
from ..calibration import RelativePose, RigCalibration, RigDevice
from .formats import RIG_CALIBRATION_FORMAT
from .validate import (bad, check_distortion, check_K, check_rotation, check_size, check_translation,
                       load_json, numbers, short)

__all__ = ["rig_to_dict", "save_rig_calibration", "load_rig_document", "is_rig_calibration",
           "RIG_CONVENTIONS"]

RIG_CONVENTIONS = ("reference frame: the first camera's; a device's pose X_dev = R X_ref + T (board units, mm for "
                   "a board in mm); relative 'a->b': X_b = R X_a + T; angles: intrinsic XYZ Euler (psi, nu, phi) in "
                   "degrees; pixels (x, y) with the origin at the centre of the top-left pixel")


def _device_dict(d) -> dict:
    dev = d.device
    return {"kind": d.kind, "K": np.asarray(dev.K).tolist(), "image_size": [int(v) for v in dev.image_size],
            "distortion": dev.distortion.to_dict(), "R": np.asarray(d.R).tolist(), "T": np.asarray(d.T).tolist(),
            "center": d.center.tolist(), "angles_deg": models.euler_deg(d.R).tolist(),
            "std": {k: v for k, v in d.std.items() if v is not None},
            "verdict": {"level": d.verdict, "reasons": list(d.verdict_reasons)}}


def rig_to_dict(rc: RigCalibration, base=None) -> dict:
    """The JSON document of a :class:`~procam.calibration.RigCalibration` (module docstring); pose names relative
    to ``base`` (the file's folder) when given."""
    from .files import portable_names, to_jsonable
    from .procam import calibration_to_dict
    from ..verdict import MEANING

    pairs = {}
    for key, cal in rc.pairs.items():
        doc = calibration_to_dict(cal)
        pairs[key] = portable_names(doc, base) if base is not None else doc
    out = {"format": RIG_CALIBRATION_FORMAT, "version": 1, "method": rc.method, "reference": rc.reference,
           "verdict": {"level": rc.verdict, "reasons": list(rc.verdict_reasons),
                       "meaning": MEANING.get(rc.verdict, "")},
           "uncertainty": rc.uncertainty, "conventions": RIG_CONVENTIONS,
           "cameras": {d.name: _device_dict(d) for d in rc.cameras},
           "projectors": {d.name: _device_dict(d) for d in rc.projectors},
           "relative": {k: r.to_dict() for k, r in rc.relative.items()},
           "poses": list(rc.pose_names), "warnings": list(rc.warnings),
           "info": {k: v for k, v in rc.info.items() if isinstance(v, (str, int, float, bool, list, dict))},
           "pairs": pairs}
    doc = to_jsonable(out)
    if base is not None:
        doc["poses"] = [portable_names({"name": p}, base)["name"] for p in doc["poses"]]
    return doc


def save_rig_calibration(rc: RigCalibration, path) -> Path:
    """Write ``rc`` as JSON (any suffix but ``.yml``/``.yaml``/``.xml``) or OpenCV FileStorage, atomically."""
    from .files import atomic_path, write_text

    path = Path(path)
    if path.suffix.lower() not in (".yml", ".yaml", ".xml"):
        return write_text(path, json.dumps(rig_to_dict(rc, path.parent), indent=1))
    import cv2

    from .formats import OPENCV
    from .opencv import write_devices

    ref = _reference_keys(rc, path)
    first = next(iter(rc.pairs.values()))
    with atomic_path(path) as tmp:
        fs = cv2.FileStorage(str(tmp), cv2.FILE_STORAGE_WRITE)
        write_devices(fs, OPENCV, first)
        fs.write("cam_size", ref["cam_size"])
        fs.write("proj_size", ref["proj_size"])
        fs.write("method", f"rig {rc.method}")
        fs.write("verdict", rc.verdict)
        fs.write("rig_reference", rc.reference)
        fs.write("rig_cameras", ",".join(d.name for d in rc.cameras))
        fs.write("rig_projectors", ",".join(d.name for d in rc.projectors))
        fs.write("rig_conventions", RIG_CONVENTIONS)
        for d in rc.devices:
            for key, value in _device_keys(d).items():
                if key not in ref:
                    fs.write(key, value)
        fs.release()
    return path


def _reference_keys(rc: RigCalibration, path) -> dict:
    """The reference pair's FileStorage keys and values of a rig's YAML/XML ``path``; a device named cam or proj
    has keys of the same names (cam_K, ...): written once when they hold the same numbers (the same device's),
    refused otherwise (a key given twice).  :func:`save_rig_calibration` checks with it before writing, and so can
    a command before it writes anything."""
    from .opencv import device_coeffs

    first = next(iter(rc.pairs.values()))
    ref = {"cam_K": np.asarray(first.camera.K, float), "cam_kc": device_coeffs(first.camera),
           "cam_size": np.array(first.camera.image_size, np.int32).reshape(1, 2),
           "proj_K": np.asarray(first.projector.K, float), "proj_kc": device_coeffs(first.projector),
           "proj_size": np.array(first.projector.image_size, np.int32).reshape(1, 2)}
    for d in rc.devices:
        for key, value in _device_keys(d).items():
            if key in ref and not np.array_equal(ref[key], value):
                whose = "camera" if key.startswith("cam_") else "projector"
                raise CalibrationFileError(f"{path}: device {d.name!r} would write {key}, procam's key of the "
                                           f"reference pair's {whose}, with other numbers; rename the device or "
                                           "write the rig as JSON")
    return ref


def check_rig_yaml(rc: RigCalibration, path) -> None:
    """Raise :class:`CalibrationFileError` when ``rc`` cannot be written as the YAML/XML ``path`` (a device name
    whose keys are the reference pair's with other numbers); nothing is written."""
    _reference_keys(rc, path)


def _device_keys(d) -> dict:
    """A rig device's FileStorage keys and values: ``<name>_K``, ``_kc``, ``_size``, ``_R``, ``_T``."""
    from .opencv import device_coeffs

    return {f"{d.name}_K": np.asarray(d.device.K, float), f"{d.name}_kc": device_coeffs(d.device),
            f"{d.name}_size": np.array(d.device.image_size, np.int32).reshape(1, 2),
            f"{d.name}_R": np.asarray(d.R, float), f"{d.name}_T": np.asarray(d.T, float).reshape(3, 1)}


def is_rig_calibration(path) -> bool:
    """Whether ``path`` is a JSON file whose ``format`` is a rig calibration's (False for anything unreadable:
    the calibration reader then says what is wrong with it)."""
    path = Path(path)
    if not path.is_file() or path.suffix.lower() in (".yml", ".yaml", ".xml"):
        return False
    from .jsonfile import load_json as _bounded

    try:
        doc = _bounded(path, finite=False)
    except (OSError, UnicodeDecodeError, ValueError):
        return False
    return isinstance(doc, dict) and doc.get("format") == RIG_CALIBRATION_FORMAT


HINT = "give a file written by 'procam calibrate' from rig pose folders"


def load_rig_document(path) -> dict:
    """The JSON document of a rig calibration file, checked to be one (:class:`CalibrationFileError` otherwise;
    a key given twice is refused); its pairs are read by :func:`procam.io.load_calibration` with ``pair=``."""
    path = Path(path)
    doc = load_json(path, "not a readable rig calibration", HINT)
    if not isinstance(doc, dict) or doc.get("format") != RIG_CALIBRATION_FORMAT:
        raise CalibrationFileError(f"{path}: not a procam rig calibration (missing format: {RIG_CALIBRATION_FORMAT})")
    for key in ("cameras", "projectors", "pairs", "relative"):
        if not isinstance(doc.get(key), dict):
            bad(path, key, "must be an object", fix=HINT)
    return doc


def _offset(path, field: str, T, reference: bool) -> np.ndarray:
    """A device's ``T`` (reference -> device): 3 finite numbers; zero for the reference camera, else apart from it
    (:func:`procam.io.validate.check_translation`)."""
    if not reference:
        return check_translation(path, field, T)
    T = numbers(path, field, T, (3,))
    if float(np.linalg.norm(T)) > 1e-9:
        bad(path, field, f"of the reference camera must be zero (it is the reference frame), got {short(T.tolist())}")
    return T


def _device_from(path, name: str, kind: str, d, reference: bool) -> RigDevice:
    """One device block, every field checked by the one validator set (the same rules as a pair file's)."""
    from ..calibration import Device

    where = f"{kind}s.{name}"
    if not isinstance(d, dict):
        bad(path, where, f"must be an object with K, image_size, distortion, R and T, got {short(d)}", fix=HINT)
    dev = Device(check_K(path, f"{where}.K", d.get("K")), check_size(path, f"{where}.image_size", d.get("image_size")),
                 check_distortion(path, f"{where}.distortion", d.get("distortion")))
    R = check_rotation(path, f"{where}.R", d.get("R"))
    if reference and np.abs(R - np.eye(3)).max() > 1e-9:
        bad(path, f"{where}.R", "of the reference camera must be the identity (it is the reference frame)")
    T = _offset(path, f"{where}.T", d.get("T"), reference)
    verdict, std = d.get("verdict") or {}, d.get("std") or {}
    if not isinstance(verdict, dict) or not isinstance(std, dict):
        bad(path, f"{where}.verdict" if not isinstance(verdict, dict) else f"{where}.std", "must be an object",
            fix=HINT)
    return RigDevice(name, kind, dev, R, T, dict(std), str(verdict.get("level", "failed")),
                     tuple(str(r) for r in verdict.get("reasons", ())))


def _relative_from(path, key: str, r) -> RelativePose:
    """One relative pose ``"a->b"``: a rotation ``R``, a finite ``T``, its std."""
    where = f"relative.{key}"
    a, sep, b = key.partition("->")
    if not (sep and a and b):
        bad(path, where, "must be named 'a->b' after two devices", fix=HINT)
    if not isinstance(r, dict):
        bad(path, where, f"must be an object with R, T and std, got {short(r)}", fix=HINT)
    R = check_rotation(path, f"{where}.R", r.get("R"))
    T = numbers(path, f"{where}.T", r.get("T"), (3,))
    s = r.get("std") or {}
    if not isinstance(s, dict):
        bad(path, f"{where}.std", "must be an object", fix=HINT)
    try:
        return RelativePose(a, b, R, T, np.asarray(s.get("angles_deg", [np.nan] * 3), float).reshape(3),
                            np.asarray(s.get("T", [np.nan] * 3), float).reshape(3), float(s.get("baseline", np.nan)))
    except (TypeError, ValueError) as e:
        bad(path, f"{where}.std", f"must hold numbers ({e})", fix=HINT)


def rig_devices(path, doc: dict) -> tuple[tuple, tuple, dict]:
    """The cameras (the reference first), projectors and relative poses of a rig calibration document read from
    ``path``: ``(cameras, projectors, {"a->b": RelativePose})``, every block checked by the one validator set
    (:mod:`procam.io.validate`).  :func:`procam.io.load_calibration` checks them too when it reads one pair, so a
    rig file is read whole or refused."""
    if not isinstance(doc.get("cameras"), dict) or not doc["cameras"]:
        raise CalibrationFileError(f"{path}: a rig calibration without cameras; {HINT}")
    for key in ("projectors", "relative"):
        if not isinstance(doc.get(key), dict):
            bad(path, key, "must be an object", fix=HINT)
    reference = doc.get("reference", next(iter(doc["cameras"])))
    if not isinstance(reference, str) or reference not in doc["cameras"]:
        bad(path, "reference", f"names no camera of the rig (cameras: {', '.join(doc['cameras'])})", fix=HINT)
    both = set(doc["cameras"]) & set(doc["projectors"])
    if both:
        bad(path, "projectors", f"name {sorted(both)[0]!r} is also a camera's; each device has one name", fix=HINT)
    cams = tuple(_device_from(path, n, "camera", d, n == reference) for n, d in doc["cameras"].items())
    cams = tuple(sorted(cams, key=lambda c: c.name != reference))       # the reference first
    projs = tuple(_device_from(path, n, "projector", d, False) for n, d in doc["projectors"].items())
    rel = {key: _relative_from(path, key, r) for key, r in doc["relative"].items()}
    names = {d.name for d in cams + projs}
    for key, r in rel.items():
        if r.a not in names or r.b not in names:
            bad(path, f"relative.{key}", f"names a device the rig does not have (devices: {', '.join(sorted(names))})",
                fix=HINT)
    return cams, projs, rel
