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
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .. import models
from ..errors import CalibrationFileError
from ..io.formats import RIG_CALIBRATION_FORMAT
from .result import RigCalibration, RigDevice

__all__ = ["rig_to_dict", "save_rig_calibration", "load_rig_document", "load_rig_calibration", "is_rig_calibration",
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
    """The JSON document of a :class:`~procam.rig.result.RigCalibration` (module docstring); pose names relative
    to ``base`` (the file's folder) when given."""
    from ..io.files import portable_names, to_jsonable
    from ..io.procam import calibration_to_dict
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
    from ..io.files import atomic_path, write_text

    path = Path(path)
    if path.suffix.lower() not in (".yml", ".yaml", ".xml"):
        return write_text(path, json.dumps(rig_to_dict(rc, path.parent), indent=1))
    import cv2

    from ..io.formats import OPENCV
    from ..io.opencv import device_coeffs, write_devices

    first = next(iter(rc.pairs.values()))
    with atomic_path(path) as tmp:
        fs = cv2.FileStorage(str(tmp), cv2.FILE_STORAGE_WRITE)
        write_devices(fs, OPENCV, first)
        fs.write("cam_size", np.array(first.camera.image_size, np.int32).reshape(1, 2))
        fs.write("proj_size", np.array(first.projector.image_size, np.int32).reshape(1, 2))
        fs.write("method", f"rig {rc.method}")
        fs.write("verdict", rc.verdict)
        fs.write("rig_reference", rc.reference)
        fs.write("rig_cameras", ",".join(d.name for d in rc.cameras))
        fs.write("rig_projectors", ",".join(d.name for d in rc.projectors))
        fs.write("rig_conventions", RIG_CONVENTIONS)
        for d in rc.devices:
            fs.write(f"{d.name}_K", np.asarray(d.device.K, float))
            fs.write(f"{d.name}_kc", device_coeffs(d.device))
            fs.write(f"{d.name}_size", np.array(d.device.image_size, np.int32).reshape(1, 2))
            fs.write(f"{d.name}_R", np.asarray(d.R, float))
            fs.write(f"{d.name}_T", np.asarray(d.T, float).reshape(3, 1))
        fs.release()
    return path


def is_rig_calibration(path) -> bool:
    """Whether ``path`` is a JSON file whose ``format`` is a rig calibration's (False for anything unreadable:
    the calibration reader then says what is wrong with it)."""
    path = Path(path)
    if not path.is_file() or path.suffix.lower() in (".yml", ".yaml", ".xml"):
        return False
    try:
        doc = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, ValueError):
        return False
    return isinstance(doc, dict) and doc.get("format") == RIG_CALIBRATION_FORMAT


def load_rig_document(path) -> dict:
    """The JSON document of a rig calibration file, checked to be one (:class:`CalibrationFileError` otherwise);
    its pairs are read by :func:`procam.io.load_calibration` with ``pair=``."""
    path = Path(path)
    try:
        doc = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, ValueError) as e:
        raise CalibrationFileError(f"{path}: not a readable rig calibration ({e}); give a file written by "
                                   "'procam calibrate' from rig pose folders") from None
    if not isinstance(doc, dict) or doc.get("format") != RIG_CALIBRATION_FORMAT:
        raise CalibrationFileError(f"{path}: not a procam rig calibration (missing format: {RIG_CALIBRATION_FORMAT})")
    for key in ("cameras", "projectors", "pairs", "relative"):
        if not isinstance(doc.get(key), dict):
            raise CalibrationFileError(f"{path}: {key} must be an object")
    return doc


def _device_from(path, name: str, kind: str, d) -> RigDevice:
    from ..calibration import Device, Distortion

    try:
        dev = Device(np.asarray(d["K"], float).reshape(3, 3), tuple(int(v) for v in d["image_size"]),
                     Distortion.from_dict(d.get("distortion") or {}))
        R, T = np.asarray(d["R"], float).reshape(3, 3), np.asarray(d["T"], float).reshape(3)
    except (KeyError, TypeError, ValueError) as e:
        raise CalibrationFileError(f"{path}: {kind} {name!r}: {e}; give a file written by 'procam calibrate' "
                                   "from rig pose folders") from None
    if not (np.isfinite(dev.K).all() and np.isfinite(R).all() and np.isfinite(T).all()):
        raise CalibrationFileError(f"{path}: {kind} {name!r}: K, R and T must be finite")
    verdict = d.get("verdict") or {}
    std = {k: v for k, v in (d.get("std") or {}).items()}
    return RigDevice(name, kind, dev, R, T, std, str(verdict.get("level", "failed")),
                     tuple(str(r) for r in verdict.get("reasons", ())))


def load_rig_calibration(path) -> RigCalibration:
    """The :class:`~procam.rig.result.RigCalibration` a rig calibration JSON file holds (every device, relative
    pose and pair as written; the pairs read by :func:`procam.io.load_calibration` with ``pair=``, so validated
    like any calibration).  :class:`CalibrationFileError` naming the file and the field otherwise."""
    from ..io import load_calibration
    from .result import RelativePose

    path = Path(path)
    doc = load_rig_document(path)
    cams = tuple(_device_from(path, n, "camera", d) for n, d in doc["cameras"].items())
    projs = tuple(_device_from(path, n, "projector", d) for n, d in doc["projectors"].items())
    if not cams:
        raise CalibrationFileError(f"{path}: a rig calibration without cameras")
    rel = {}
    for key, r in doc["relative"].items():
        a, _, b = key.partition("->")
        try:
            s = r.get("std") or {}
            rel[key] = RelativePose(a, b, np.asarray(r["R"], float).reshape(3, 3), np.asarray(r["T"], float).reshape(3),
                                    np.asarray(s.get("angles_deg", [np.nan] * 3), float),
                                    np.asarray(s.get("T", [np.nan] * 3), float), float(s.get("baseline", np.nan)))
        except (KeyError, TypeError, ValueError, AttributeError) as e:
            raise CalibrationFileError(f"{path}: relative pose {key!r}: {e}") from None
    pairs = {key: load_calibration(path, pair=key) for key in doc["pairs"]}
    verdict = doc.get("verdict") or {}
    return RigCalibration(str(doc.get("method", "")), cams, projs, rel, pairs, tuple(doc.get("poses") or ()),
                          str(doc.get("uncertainty", "")), dict(doc.get("info") or {}),
                          tuple(doc.get("warnings") or ()), str(verdict.get("level", "failed")),
                          tuple(str(r) for r in verdict.get("reasons", ())))
