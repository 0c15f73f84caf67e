"""procam's file formats: calibrations (JSON, OpenCV FileStorage YAML) and correspondences (JSON).

The schemas are in ``docs/file-formats.md``. Every file is written under a temporary name and renamed
(:func:`procam.io.files.atomic_path`); readers validate what they load and raise
:class:`~procam.errors.CalibrationFileError` naming the file.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..board import Board
from ..calibration import Calibration, Device, Distortion
from ..distortion import opencv_from_division
from ..errors import CalibrationFileError
from ..summary import projector_assumptions
from ..view import CORNER_REASONS, View
from .files import atomic_path, to_jsonable, write_text


def _nan_to_none(a) -> list:
    a = np.asarray(a, float)
    return [[None if not np.isfinite(v) else float(v) for v in row] for row in a.reshape(len(a), -1)]


def view_to_dict(view, options: dict | None = None) -> dict:
    """JSON-able dict of a :class:`~procam.view.View` (NaN -> null) with per-corner diagnostics."""

    d = view.diagnostics
    corners = []
    for k in range(len(view.obj_pts)):
        c = {"index": k}
        if "reason" in d:
            c["reason"] = CORNER_REASONS.get(int(d["reason"][k]), str(d["reason"][k]))
        for key in ("pixels", "window_pixels", "inliers", "residual_px"):
            if key in d:
                v = float(d[key][k])
                c[key] = v if np.isfinite(v) else None
        corners.append(c)
    out = {"format": "procam-correspondences", "version": 1, "pose": view.name,
           "camera_size": list(view.cam_size) if view.cam_size else None,
           "projector_size": list(view.proj_size) if view.proj_size else None,
           "board_points": _nan_to_none(view.obj_pts), "camera_points": _nan_to_none(view.cam_pts),
           "projector_points": _nan_to_none(view.proj_pts), "corners": corners}
    if view.board is not None:
        out["board"] = view.board.to_dict()
    if options:
        out["options"] = options
    return out


def view_from_dict(d: dict):
    """Inverse of :func:`view_to_dict` (diagnostics other than the per-corner numbers are dropped)."""

    def arr(key):
        return np.array([[np.nan if v is None else v for v in row] for row in d[key]], float)

    rev = {v: k for k, v in CORNER_REASONS.items()}
    diag = {}
    corners = d.get("corners", [])
    if corners and "reason" in corners[0]:
        diag["reason"] = np.array([rev.get(c["reason"], 255) for c in corners], np.uint8)
    for key in ("pixels", "window_pixels", "inliers", "residual_px"):
        if corners and key in corners[0]:
            diag[key] = np.array([np.nan if c[key] is None else c[key] for c in corners], float)
    b = d.get("board")
    board = Board(int(b["cols"]), int(b["rows"]), float(b["square"])) if isinstance(b, dict) else None
    return View(arr("board_points"), arr("camera_points"), arr("projector_points"), d.get("pose", "view"),
                tuple(d["camera_size"]) if d.get("camera_size") else None,
                tuple(d["projector_size"]) if d.get("projector_size") else None, diag, board)


# --------------------------------------------------------------------------------------------
# calibration files
# --------------------------------------------------------------------------------------------

CONVENTIONS = {
    "pixels": "(x, y) = (column, row); origin at the centre of the top-left pixel",
    "K": "[[fx, 0, u0], [0, fy, v0], [0, 0, 1]], pixels",
    "extrinsics": "x_projector = R @ x_camera + T (camera -> projector, as OpenCV stereoCalibrate); T in board units",
    "board_pose": "X_device = R_board @ X_board + t_board; board corner k = j*cols + i at (i*s, j*s, 0) - centroid",
    "angles": "degrees; (psi, nu, phi) intrinsic XYZ: R = Rx(psi) Ry(nu) Rz(phi)",
    "division": "undistorted = c + (distorted - c) / (1 + k1 r^2 + k2 r^4), r = |distorted - c| in pixels",
    "opencv": "OpenCV distortion coefficients (k1, k2, p1, p2[, k3, ...]) in normalised coordinates",
}




def _device_dict(dev, rms) -> dict | None:
    if dev is None:
        return None
    return {"K": np.asarray(dev.K).tolist(), "image_size": [int(v) for v in dev.image_size],
            "distortion": dev.distortion.to_dict(), "rms_px": rms}


#: What each verdict level means, written next to it.
VERDICT_MEANING = {
    "good": "fit to use",
    "weak": "usable: less precise than a better pose (set) would make it; see the reasons",
    "degenerate": "do not use: the poses do not determine some parameters, whose values may be anything",
    "failed": "do not use: an estimate is impossible for a real device",
    "unknown": "the file records no verdict",
}
#: What every standard deviation in the file means.
UNCERTAINTY_NOTE = ("std: 1 sigma from the fit's Jacobian, assuming the model is right and the corner noise "
                    "independent and Gaussian; single-pose results also assume what 'assumptions' lists")


def calibration_to_dict(calib, include_views: bool = True) -> dict:
    """The JSON document of a :class:`~procam.calibration.Calibration` (schema: docs/file-formats.md)."""
    info = {k: v for k, v in calib.info.items() if isinstance(v, (str, int, float, bool, list, dict, type(None)))}
    out = {
        "format": "procam-calibration", "version": 1, "method": calib.method,
        "verdict": {"level": calib.verdict, "reasons": list(calib.verdict_reasons),
                    "meaning": VERDICT_MEANING.get(calib.verdict, "")},
        "uncertainty": UNCERTAINTY_NOTE,
        "assumptions": projector_assumptions(calib),
        "conventions": CONVENTIONS,
        "camera": _device_dict(calib.camera, calib.cam_rms),
        "projector": _device_dict(calib.projector, calib.proj_rms),
        "R": None if calib.R is None else np.asarray(calib.R).tolist(),
        "T": None if calib.T is None else np.asarray(calib.T).reshape(3).tolist(),
        "stereo_rms_px": calib.stereo_rms,
        "std": calib.std, "poses": list(calib.poses), "warnings": list(calib.warnings), "info": info,
    }
    if calib.camera is not None and calib.camera.distortion.model == "division":
        d = calib.camera.distortion
        coeffs, err = opencv_from_division(calib.camera.K, d.center, d.k1, d.k2, calib.camera.image_size)
        out["camera"]["opencv_fit"] = {"coeffs": list(map(float, coeffs)), "max_err_px": float(err),
                                       "note": "OpenCV (k1, k2, p1, p2, k3) fitted to the division model over "
                                               "the image; written as cam_kc in the YAML file"}
    if include_views and calib.views:
        out["views"] = [view_to_dict(v) for v in calib.views]
    return to_jsonable(out)


def _verdict(v) -> str:
    level = v.get("level") if isinstance(v, dict) else v
    return level if level in VERDICT_MEANING else "unknown"


def _verdict_reasons(path, v) -> tuple:
    reasons = v.get("reasons", []) if isinstance(v, dict) else []
    if not isinstance(reasons, list):
        _bad(path, "verdict.reasons", "must be a list of strings")
    return tuple(str(r) for r in reasons)


def _yaml_string(fs, key) -> str:
    node = fs.getNode(key)
    return node.string() if node.isString() else ""


def save_calibration(calib, path) -> Path:
    """Write ``calib`` as JSON (``.json``) or OpenCV FileStorage YAML (``.yml``/``.yaml``), atomically."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in (".yml", ".yaml"):
        return save_opencv_yaml(calib, path)
    return write_text(path, json.dumps(calibration_to_dict(calib), indent=1))


def _opencv_kc(dev) -> np.ndarray:
    d = dev.distortion
    if d.model == "opencv":
        return np.asarray(d.coeffs, float).reshape(1, -1)
    if d.model == "division":
        coeffs, _ = opencv_from_division(dev.K, d.center, d.k1, d.k2, dev.image_size)
        return np.asarray(coeffs, float).reshape(1, -1)
    return np.zeros((1, 5))


def save_opencv_yaml(calib, path) -> Path:
    """OpenCV FileStorage YAML with the keys ``cam_K, cam_kc, proj_K, proj_kc, R, T, cam_error,
    proj_error, stereo_error`` (as Moreno–Taubin's tool writes them), plus ``cam_size``/``proj_size``.

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
        fs.write("cam_K", np.asarray(calib.camera.K, float))
        fs.write("cam_kc", _opencv_kc(calib.camera))
        fs.write("proj_K", np.asarray(calib.projector.K, float))
        fs.write("proj_kc", _opencv_kc(calib.projector))
        fs.write("R", np.asarray(calib.R, float))
        fs.write("T", np.asarray(calib.T, float).reshape(3, 1))
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


#: Plausible bounds of a calibration file's numbers (beyond them a file is corrupt, not a camera).
MAX_FOCAL_PX = 1e7
MAX_IMAGE_SIDE = 100000
MAX_BASELINE = 1e9
OPENCV_DIST_LENGTHS = (4, 5, 8, 12, 14)


def _bad(path, field: str, what: str):
    raise CalibrationFileError(f"{path}: {field} {what}; fix the file or re-run 'procam calibrate'")


def _short(v) -> str:
    t = repr(v)
    return t if len(t) <= 60 else t[:57] + "..."


def _numbers(path, field: str, v, shape: tuple) -> np.ndarray:
    """``v`` as a finite float array of ``shape`` (3-vectors may be 3x1 or 1x3), or a one-line error naming ``field``."""
    want = "x".join(map(str, shape)) if len(shape) > 1 else f"{shape[0]} numbers"
    if v is None:
        _bad(path, field, "is missing (null)")
    try:
        a = np.array(v, dtype=float)
    except (TypeError, ValueError):
        _bad(path, field, f"must be {'a ' + want + ' matrix' if len(shape) > 1 else want}, got {_short(v)}")
    if len(shape) == 1 and a.size == shape[0] and a.ndim <= 2:
        a = a.reshape(shape)
    if a.shape != shape:
        got = "x".join(map(str, a.shape)) or "a single number"
        _bad(path, field, f"must be {'a ' + want + ' matrix' if len(shape) > 1 else want}, got {got}")
    if not np.all(np.isfinite(a)):
        _bad(path, field, "holds NaN or infinite values")
    return a


def _check_K(path, field: str, K) -> np.ndarray:
    K = _numbers(path, field, K, (3, 3))
    fx, fy, u0, v0 = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
    if not (0 < fx <= MAX_FOCAL_PX and 0 < fy <= MAX_FOCAL_PX):
        _bad(path, field, f"focal lengths must be positive and at most {MAX_FOCAL_PX:.0e} px, got fx = {fx:g}, "
                          f"fy = {fy:g}")
    if np.abs(K[2] - [0, 0, 1]).max() > 1e-9 or abs(K[1, 0]) > 1e-9:
        _bad(path, field, "must be [[fx, s, u0], [0, fy, v0], [0, 0, 1]]")
    if max(abs(u0), abs(v0), abs(K[0, 1])) > 10 * MAX_IMAGE_SIDE:
        _bad(path, field, f"principal point ({u0:g}, {v0:g}) or skew is implausibly large")
    return K


def _check_size(path, field: str, v) -> tuple[int, int]:
    try:
        w, h = (float(x) for x in np.asarray(v, dtype=float).ravel())
    except (TypeError, ValueError):
        _bad(path, field, f"must be [width, height] in pixels, got {_short(v)}")
    if not (w == int(w) and h == int(h) and 1 <= w <= MAX_IMAGE_SIDE and 1 <= h <= MAX_IMAGE_SIDE):
        _bad(path, field, f"must be [width, height], whole pixels from 1 to {MAX_IMAGE_SIDE}, got {_short(v)}")
    return int(w), int(h)


def _check_distortion(path, field: str, d) -> Distortion:
    if d is None:
        return Distortion()
    if not isinstance(d, dict):
        _bad(path, field, f"must be an object with a model, got {_short(d)}")
    model = d.get("model", "none")
    if model == "none":
        return Distortion()
    if model == "division":
        c = _numbers(path, f"{field}.center", d.get("center"), (2,))
        k1 = _numbers(path, f"{field}.k1", [d.get("k1")], (1,))[0]
        k2 = _numbers(path, f"{field}.k2", [d.get("k2", 0.0)], (1,))[0]
        return Distortion("division", (float(c[0]), float(c[1])), float(k1), float(k2))
    if model == "opencv":
        coeffs = d.get("coeffs")
        n = len(coeffs) if isinstance(coeffs, (list, tuple)) else -1
        if n not in OPENCV_DIST_LENGTHS:
            _bad(path, f"{field}.coeffs", f"must be {', '.join(map(str, OPENCV_DIST_LENGTHS))} OpenCV coefficients, "
                                          f"got {_short(coeffs)}")
        return Distortion("opencv", coeffs=tuple(float(c) for c in _numbers(path, f"{field}.coeffs", coeffs, (n,))))
    _bad(path, f"{field}.model", f"must be none, division or opencv, got {_short(model)}")


def _check_rotation(path, field: str, R) -> np.ndarray:
    R = _numbers(path, field, R, (3, 3))
    err = float(np.abs(R.T @ R - np.eye(3)).max())
    if err > 1e-3 or np.linalg.det(R) <= 0:
        _bad(path, field, f"is not a rotation matrix (R^T R differs from I by {err:.3g}, det {np.linalg.det(R):.3g})")
    return R


def _check_translation(path, field: str, T) -> np.ndarray:
    T = _numbers(path, field, T, (3,))
    n = float(np.linalg.norm(T))
    if not 0 < n <= MAX_BASELINE:
        _bad(path, field, f"has length {n:g}: camera and projector must be apart (baseline > 0, at most "
                          f"{MAX_BASELINE:.0e} board units)")
    return T


def _check_rms(path, field: str, v) -> float:
    if v is None:
        return float("nan")
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        _bad(path, field, f"must be a number of pixels, got {_short(v)}")
    return float(v)


def validate_calibration(calib, path) -> Calibration:
    """Check every field of a loaded :class:`~procam.calibration.Calibration`: shapes, finiteness, positive
    focal lengths, plausible magnitudes, a rotation ``R``, a non-zero ``T``, known distortion models.

    Returns ``calib``; raises :class:`~procam.errors.CalibrationFileError` naming ``path`` and the field.
    """
    if calib.camera is None:
        _bad(path, "camera", "is missing (null)")
    for name, dev in (("camera", calib.camera), ("projector", calib.projector)):
        if dev is None:
            continue
        _check_K(path, f"{name}.K", dev.K)
        _check_size(path, f"{name}.image_size", dev.image_size)
        d = dev.distortion
        if d.model == "division":
            _numbers(path, f"{name}.distortion.center", d.center, (2,))
            _numbers(path, f"{name}.distortion.k1, k2", [d.k1, d.k2], (2,))
        elif d.model == "opencv":
            if len(d.coeffs) not in OPENCV_DIST_LENGTHS:
                _bad(path, f"{name}.distortion.coeffs", f"must be {', '.join(map(str, OPENCV_DIST_LENGTHS))} OpenCV "
                                                        f"coefficients, got {len(d.coeffs)}")
            _numbers(path, f"{name}.distortion.coeffs", d.coeffs, (len(d.coeffs),))
    if calib.projector is not None or calib.R is not None or calib.T is not None:
        if calib.projector is None:
            _bad(path, "projector", "is missing (null) while R and T are given")
        _check_rotation(path, "R", calib.R)
        _check_translation(path, "T", calib.T)
    return calib


def _cv_message(e: BaseException) -> str:
    """The useful part of an OpenCV error (also when wrapped in a SystemError): ``'Parsing error: ...'``."""
    import re

    seen = 0
    while isinstance(e, SystemError) and (e.__cause__ or e.__context__) and seen < 5:
        e, seen = e.__cause__ or e.__context__, seen + 1
    text = (str(e).strip().splitlines() or [""])[-1]
    m = re.search(r"error: \(-?\d+:([^)]*)\) (.*)$", text)
    return f"{m.group(1)}: {m.group(2)}" if m else text


def _load_yaml(path):
    import cv2

    try:
        fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
        opened = fs.isOpened()
    except (cv2.error, SystemError) as e:
        msg = _cv_message(e)
        raise CalibrationFileError(f"{path}: not a readable OpenCV FileStorage file ({msg}); give a calibration "
                                   "written by 'procam calibrate'") from None
    if not opened:
        raise CalibrationFileError(f"{path}: not a readable OpenCV FileStorage file; give a calibration written by "
                                   "'procam calibrate'")
    try:
        missing = [k for k in ("cam_K", "proj_K", "R", "T") if fs.getNode(k).empty()]
        if missing:
            raise CalibrationFileError(f"{path}: missing {', '.join(missing)}; expected the keys cam_K, cam_kc, "
                                       "proj_K, proj_kc, R, T")

        def mat(k):
            n = fs.getNode(k)
            if n.empty():
                return None
            m = n.mat()
            if m is None:
                if n.isReal() or n.isInt():
                    return np.array([[n.real()]])
                _bad(path, k, "must be a matrix (!!opencv-matrix) of numbers")
            return np.asarray(m, float)

        def real(k):
            n = fs.getNode(k)
            if n.empty():
                return float("nan")
            if not (n.isReal() or n.isInt()):
                _bad(path, k, "must be a number of pixels")
            return float(n.real())

        cK, pK = _check_K(path, "cam_K", mat("cam_K")), _check_K(path, "proj_K", mat("proj_K"))
        assumed = []

        def size(k, K):
            m = mat(k)
            if m is not None:
                return _check_size(path, k, m)
            assumed.append(k)
            return (max(1, round(2 * K[0, 2])), max(1, round(2 * K[1, 2])))

        def dist(k):
            m = mat(k)
            if m is None or not np.any(m):
                return Distortion()
            c = m.ravel()
            if c.size not in OPENCV_DIST_LENGTHS:
                _bad(path, k, f"must have {', '.join(map(str, OPENCV_DIST_LENGTHS))} OpenCV coefficients, got {c.size}")
            return Distortion("opencv", coeffs=tuple(float(v) for v in _numbers(path, k, c, (c.size,))))

        method_node = fs.getNode("method")
        method = method_node.string() if method_node.isString() else ""
        calib = Calibration(
            camera=Device(cK, size("cam_size", cK), dist("cam_kc")),
            projector=Device(pK, size("proj_size", pK), dist("proj_kc")),
            R=_check_rotation(path, "R", mat("R")), T=_check_translation(path, "T", mat("T")),
            method=method or "opencv-yaml", cam_rms=real("cam_error"), proj_rms=real("proj_error"),
            stereo_rms=real("stereo_error"), info={"image_size_assumed": assumed} if assumed else {},
            verdict=_verdict(_yaml_string(fs, "verdict")))
    except (cv2.error, SystemError) as e:
        raise CalibrationFileError(f"{path}: not a readable OpenCV calibration ({_cv_message(e)})") from None
    finally:
        fs.release()
    return calib


def _load_json(path):
    try:
        doc = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, ValueError) as e:
        raise CalibrationFileError(f"{path}: not a procam calibration JSON file ({e})") from None
    if not isinstance(doc, dict):
        raise CalibrationFileError(f"{path}: not a procam calibration JSON file (the top level is not an object)")
    if doc.get("format") != "procam-calibration":
        raise CalibrationFileError(f"{path}: not a procam calibration JSON file (missing format: procam-calibration)")

    def device(name):
        x = doc.get(name)
        if x is None:
            if name == "camera":
                _bad(path, "camera", "is missing (null)")
            return None
        if not isinstance(x, dict):
            _bad(path, name, f"must be an object with K, image_size and distortion, got {_short(x)}")
        K = _check_K(path, f"{name}.K", x.get("K"))
        size = _check_size(path, f"{name}.image_size", x.get("image_size"))
        return Device(K, size, _check_distortion(path, f"{name}.distortion", x.get("distortion")))

    camera, projector = device("camera"), device("projector")
    R = T = None
    if projector is not None or doc.get("R") is not None or doc.get("T") is not None:
        if projector is None:
            _bad(path, "projector", "is missing (null) while R and T are given")
        R, T = _check_rotation(path, "R", doc.get("R")), _check_translation(path, "T", doc.get("T"))
    for key in ("std", "info"):
        if not isinstance(doc.get(key, {}), dict):
            _bad(path, key, "must be an object")
    for key in ("poses", "views", "warnings"):
        if not isinstance(doc.get(key, []), list):
            _bad(path, key, "must be a list")
    try:
        views = tuple(view_from_dict(v) for v in doc.get("views", []))
    except (KeyError, ValueError, TypeError, AttributeError, IndexError) as e:
        raise CalibrationFileError(f"{path}: views are not procam correspondences ({type(e).__name__}: {e})") from None
    return Calibration(
        camera=camera, projector=projector, R=R, T=T, method=str(doc.get("method", "unknown")),
        cam_rms=_check_rms(path, "camera.rms_px", (doc.get("camera") or {}).get("rms_px")),
        proj_rms=_check_rms(path, "projector.rms_px", (doc.get("projector") or {}).get("rms_px")),
        stereo_rms=_check_rms(path, "stereo_rms_px", doc.get("stereo_rms_px")), std=doc.get("std", {}),
        poses=tuple(doc.get("poses", [])), views=views, warnings=tuple(str(w) for w in doc.get("warnings", [])),
        info=doc.get("info", {}), verdict=_verdict(doc.get("verdict")),
        verdict_reasons=_verdict_reasons(path, doc.get("verdict")))


def load_calibration(path):
    """Read a calibration file written by procam (JSON) or an OpenCV YAML with the de-facto keys.

    Every field is checked (:func:`validate_calibration`): shapes, finiteness, positive focal lengths,
    plausible magnitudes, a rotation ``R`` and non-zero ``T``, a known distortion model (an unknown one is
    refused, not read as none).  A YAML file without ``cam_size``/``proj_size`` gets ``2 (u0, v0)`` as the
    image size, and ``info["image_size_assumed"]`` lists the keys that were missing.

    Raises :class:`~procam.errors.CalibrationFileError` naming the file and the field.
    """
    path = Path(path)
    if not path.is_file():
        raise CalibrationFileError(f"{path}: no such file; give a calibration written by 'procam calibrate'")
    if path.suffix.lower() in (".yml", ".yaml", ".xml"):
        calib = _load_yaml(path)
    else:
        calib = _load_json(path)
    return validate_calibration(calib, path)
