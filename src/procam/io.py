"""procam's file formats: calibrations (JSON, OpenCV FileStorage YAML) and correspondences (JSON).

The schemas are in ``docs/file-formats.md``. Every file is written under a temporary name and renamed
(:func:`procam._files.atomic_path`); readers validate what they load and raise
:class:`~procam.errors.CalibrationFileError` naming the file.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ._files import atomic_path, to_jsonable, write_text
from .board import Board
from .calibration import Calibration, Device, Distortion
from .correspond import CORNER_REASONS
from .distortion import opencv_from_division
from .errors import CalibrationFileError
from .view import View


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
                    "independent and Gaussian; single-pose results also assume u0p = W/2, alpha_p = 1 and no "
                    "projector distortion")


def calibration_to_dict(calib, include_views: bool = True) -> dict:
    """The JSON document of a :class:`~procam.calibration.Calibration` (schema: docs/file-formats.md)."""
    info = {k: v for k, v in calib.info.items() if isinstance(v, (str, int, float, bool, list, dict, type(None)))}
    out = {
        "format": "procam-calibration", "version": 1, "method": calib.method,
        "verdict": {"level": calib.verdict, "reasons": list(calib.verdict_reasons),
                    "meaning": VERDICT_MEANING.get(calib.verdict, "")},
        "uncertainty": UNCERTAINTY_NOTE,
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


def calibration_from_dict(d: dict):
    """Inverse of :func:`calibration_to_dict`."""
    if d.get("format") != "procam-calibration":
        raise ValueError("not a procam calibration document (missing format: procam-calibration)")

    def dev(x):
        if not x:
            return None
        return Device(np.array(x["K"], float), tuple(x["image_size"]), Distortion.from_dict(x["distortion"]))

    def num(v):
        return float("nan") if v is None else float(v)

    return Calibration(
        camera=dev(d["camera"]), projector=dev(d.get("projector")),
        R=None if d.get("R") is None else np.array(d["R"], float),
        T=None if d.get("T") is None else np.array(d["T"], float),
        method=d.get("method", "unknown"),
        cam_rms=num((d.get("camera") or {}).get("rms_px")), proj_rms=num((d.get("projector") or {}).get("rms_px")),
        stereo_rms=num(d.get("stereo_rms_px")), std=d.get("std", {}), poses=tuple(d.get("poses", [])),
        views=tuple(view_from_dict(v) for v in d.get("views", [])), warnings=tuple(d.get("warnings", [])),
        info=d.get("info", {}), verdict=_verdict(d.get("verdict")),
        verdict_reasons=tuple((d.get("verdict") or {}).get("reasons", [])) if isinstance(d.get("verdict"), dict) else ())


def _verdict(v) -> str:
    level = v.get("level") if isinstance(v, dict) else v
    return level if level in VERDICT_MEANING else "unknown"


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


def load_calibration(path):
    """Read a calibration file written by procam (JSON) or an OpenCV YAML with the de-facto keys.

    Raises :class:`~procam.errors.CalibrationFileError` naming the file and what is wrong.
    """
    path = Path(path)
    if not path.is_file():
        raise CalibrationFileError(f"{path}: no such file; give a calibration written by 'procam calibrate'")
    if path.suffix.lower() in (".yml", ".yaml", ".xml"):
        import cv2

        try:
            fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
        except cv2.error as e:
            raise CalibrationFileError(f"{path}: not an OpenCV FileStorage file ({e})") from None
        missing = [k for k in ("cam_K", "proj_K", "R", "T") if fs.getNode(k).empty()]
        if missing:
            raise CalibrationFileError(f"{path}: missing {', '.join(missing)}; expected the keys cam_K, cam_kc, "
                                       "proj_K, proj_kc, R, T")

        def mat(k):
            n = fs.getNode(k)
            return None if n.empty() else n.mat()

        def real(k):
            n = fs.getNode(k)
            return float("nan") if n.empty() else float(n.real())

        def size(k, K):
            m = mat(k)
            return tuple(int(v) for v in m.ravel()) if m is not None else (int(2 * K[0, 2]), int(2 * K[1, 2]))

        cK, pK = mat("cam_K"), mat("proj_K")
        ckc, pkc = mat("cam_kc"), mat("proj_kc")
        calib = Calibration(
            camera=Device(cK, size("cam_size", cK), Distortion("opencv", coeffs=tuple(ckc.ravel()))
                          if ckc is not None else Distortion()),
            projector=Device(pK, size("proj_size", pK), Distortion("opencv", coeffs=tuple(pkc.ravel()))
                             if pkc is not None and np.any(pkc) else Distortion()),
            R=mat("R"), T=mat("T").ravel(), method=fs.getNode("method").string() or "opencv-yaml",
            cam_rms=real("cam_error"), proj_rms=real("proj_error"), stereo_rms=real("stereo_error"),
            verdict=_verdict(fs.getNode("verdict").string()))
        fs.release()
        return calib
    try:
        doc = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, ValueError) as e:
        raise CalibrationFileError(f"{path}: not a procam calibration JSON file ({e})") from None
    if not isinstance(doc, dict):
        raise CalibrationFileError(f"{path}: not a procam calibration JSON file (the top level is not an object)")
    try:
        return calibration_from_dict(doc)
    except KeyError as e:
        raise CalibrationFileError(f"{path}: not a procam calibration JSON file (missing key {e})") from None
    except (ValueError, TypeError, AttributeError, IndexError) as e:
        raise CalibrationFileError(f"{path}: not a usable procam calibration ({e}); fix the file or calibrate "
                                   "again") from None
