"""procam's JSON files: calibrations (``procam-calibration``) and correspondences (``procam-correspondences``).

The schemas are in ``docs/file-formats.md``.  :func:`calibration_to_dict` / :func:`save_calibration_json` write
a calibration, :func:`calibration_from_json` reads one back (every field checked by :mod:`procam.io.validate`);
:func:`view_to_dict` / :func:`view_from_dict` are one pose's correspondences, also embedded in a calibration's
``views``.  Files are written atomically (:func:`procam.io.files.atomic_path`).  The one reader of every
calibration format, :func:`procam.io.load_calibration`, hands a procam JSON document here.
"""

from __future__ import annotations

from dataclasses import replace

import json
from pathlib import Path

import numpy as np

from ..board import Board
from ..datasheet import calibration_datasheet
from ..mounting import mounting
from ..calibration import Calibration, Device
from ..distortion import opencv_from_division
from ..errors import CalibrationFileError, ProcamError
from ..summary import projector_assumptions
from ..view import CORNER_REASONS, View
from ..verdict import MEANING, VERDICTS
from .files import portable_names, to_jsonable, write_text
from .formats import CALIBRATION_FORMAT, CORRESPONDENCES_FORMAT
from .validate import (bad, check_distortion, check_K, check_rms, check_rotation, check_size, check_translation, numbers,
                       short, FIX)


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
    out = {"format": CORRESPONDENCES_FORMAT, "version": 1, "pose": view.name,
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


#: What each verdict level means, written next to it (the one glossary, :data:`procam.verdict.MEANING`).
VERDICT_MEANING = MEANING
#: What every standard deviation in the file means.
UNCERTAINTY_NOTE = ("std: 1 sigma from the fit's Jacobian, assuming the model is right and the corner noise "
                    "independent and Gaussian; single-pose results also assume what 'assumptions' lists")
#: ... of a single-pose calibration with a real projector (procam.single_pose.dense).
DENSE_UNCERTAINTY_NOTE = ("std: 1 sigma covering the fit's noise, residuals correlated across the image (a block "
                          "jackknife), the lens models the data cannot tell apart, the priors 'assumptions' lists, "
                          "and a lens decentring of a few pixels")


#: What the ``covariance`` block of a camera-only calibration is.
COVARIANCE_NOTE = ("the covariance of the camera's intrinsics (rows and columns named by params: fx, fy, u0, v0 in px, "
                   "OpenCV's distortion coefficients), the fit's Gauss-Newton covariance scaled by its residual noise "
                   "sigma_px per coordinate (procam.crlb.views_bound); null: the photos do not determine them")


#: What the ``datasheet`` block of a calibration file is (derived from K; a reader ignores it).
DATASHEET_NOTE = ("derived from K and its std (procam.datasheet): throw_ratio = fx / W; shift_h_pct = 100 ((W - 1)/2 "
                  "- u0) / W (+ image right of the lens axis); shift_v_pct = 100 (v0 - (H - 1)/2) / H (+ image above "
                  "the axis); offset_pct = 2 shift_v_pct; fov in degrees; std 1 sigma, first order")


def calibration_to_dict(calib, include_views: bool = True) -> dict:
    """The JSON document of a :class:`~procam.calibration.Calibration` (schema: docs/file-formats.md)."""
    info = {k: v for k, v in calib.info.items() if isinstance(v, (str, int, float, bool, list, dict, type(None)))}
    cov, source = calib.info.get("covariance"), calib.info.get("calibrated_from")
    info = {k: v for k, v in info.items() if k not in ("covariance", "calibrated_from")}
    out = {
        "format": CALIBRATION_FORMAT, "version": 1, "method": calib.method,
        "verdict": {"level": calib.verdict, "reasons": list(calib.verdict_reasons),
                    "meaning": VERDICT_MEANING.get(calib.verdict, "")},
        "uncertainty": DENSE_UNCERTAINTY_NOTE if calib.info.get("dense") is not None else UNCERTAINTY_NOTE,
        "assumptions": projector_assumptions(calib),
        "conventions": CONVENTIONS,
        "camera": _device_dict(calib.camera, calib.cam_rms),
        "projector": _device_dict(calib.projector, calib.proj_rms),
        "R": None if calib.R is None else np.asarray(calib.R).tolist(),
        "T": None if calib.T is None else np.asarray(calib.T).reshape(3).tolist(),
        "stereo_rms_px": calib.stereo_rms,
        "std": calib.std, "poses": list(calib.poses), "warnings": list(calib.warnings), "info": info,
    }
    if source is not None:
        out["calibrated_from"] = source
    if cov is not None:
        m = np.asarray(cov["matrix"], float)
        out["covariance"] = {"params": list(cov["params"]), "matrix": m if np.all(np.isfinite(m)) else None,
                             "sigma_px": cov.get("sigma_px"), "note": COVARIANCE_NOTE}
    if calib.camera is not None and calib.camera.distortion.model == "division":
        d = calib.camera.distortion
        coeffs, err = opencv_from_division(calib.camera.K, d.center, d.k1, d.k2, calib.camera.image_size)
        out["camera"]["opencv_fit"] = {"coeffs": list(map(float, coeffs)), "max_err_px": float(err),
                                       "note": "OpenCV (k1, k2, p1, p2, k3) fitted to the division model over "
                                               "the image; written as cam_kc in the YAML file"}
    sheets = {d: calibration_datasheet(calib, d) for d in ("camera", "projector")}
    out["datasheet"] = {**{d: v.to_dict() for d, v in sheets.items() if v is not None},
                        "note": DATASHEET_NOTE}
    out["mounting"] = mounting(calib).to_dict()
    if include_views and calib.views:
        out["views"] = [view_to_dict(v) for v in calib.views]
    return to_jsonable(out)


def verdict_level(v) -> str:
    """The verdict level a file records (an object with ``level``, or the level itself); ``"unknown"`` when it
    records none procam knows."""
    level = v.get("level") if isinstance(v, dict) else v
    return level if level in VERDICTS else "unknown"


def _verdict_reasons(path, v) -> tuple:
    reasons = v.get("reasons", []) if isinstance(v, dict) else []
    if not isinstance(reasons, list):
        bad(path, "verdict.reasons", "must be a list of strings")
    return tuple(str(r) for r in reasons)


def save_calibration_json(calib, path) -> Path:
    """Write ``calib`` as procam's calibration JSON (:func:`calibration_to_dict`), atomically; the poses' names
    that are paths are stored relative to the file's folder (:func:`procam.io.files.portable_names`), never as the
    user's absolute paths."""
    doc = portable_names(calibration_to_dict(calib), Path(path).parent)
    return write_text(path, json.dumps(doc, indent=1))


def device_from_json(path, doc: dict, name: str) -> Device | None:
    """The device ``name`` (``"camera"``, ``"projector"``) of a procam calibration document, checked; None for a
    projector that is null (a camera-only calibration)."""
    x = doc.get(name)
    if x is None:
        if name == "camera":
            bad(path, "camera", "is missing (null)")
        return None
    if not isinstance(x, dict):
        bad(path, name, f"must be an object with K, image_size and distortion, got {short(x)}")
    K = check_K(path, f"{name}.K", x.get("K"))
    size = check_size(path, f"{name}.image_size", x.get("image_size"))
    return Device(K, size, check_distortion(path, f"{name}.distortion", x.get("distortion")))


def calibration_from_json(path, doc: dict) -> Calibration:
    """The :class:`~procam.calibration.Calibration` of a procam calibration document (``format``
    ``procam-calibration``) read from ``path``; every field checked (:mod:`procam.io.validate`)."""
    camera, projector = device_from_json(path, doc, "camera"), device_from_json(path, doc, "projector")
    R = T = None
    if projector is not None or doc.get("R") is not None or doc.get("T") is not None:
        if projector is None:
            bad(path, "projector", "is missing (null) while R and T are given")
        R, T = check_rotation(path, "R", doc.get("R")), check_translation(path, "T", doc.get("T"))
    for key in ("std", "info"):
        if not isinstance(doc.get(key, {}), dict):
            bad(path, key, "must be an object")
    for key in ("poses", "views", "warnings"):
        if not isinstance(doc.get(key, []), list):
            bad(path, key, "must be a list")
    views = []
    for i, v in enumerate(doc.get("views", [])):
        try:
            views.append(view_from_dict(v))
        except (KeyError, ValueError, TypeError, AttributeError, IndexError, ProcamError) as e:  # a Board's own
            what = str(e) if isinstance(e, ProcamError) else f"{type(e).__name__}: {e}"
            raise CalibrationFileError(f"{path}: views are not procam correspondences (views[{i}]: {what}); {FIX}") \
                from None
    views = tuple(views)
    info = doc.get("info", {})
    if "covariance" in doc:
        info = {**info, "covariance": _covariance_from_json(path, doc["covariance"])}
        if camera is not None and camera.distortion.model in ("opencv", "none"):   # OpenCV's parameters: its model's
            c = info["covariance"]
            camera = replace(camera, covariance=(c["params"], c["matrix"]))
    if "calibrated_from" in doc:
        info = {**info, "calibrated_from": _source_from_json(path, doc["calibrated_from"])}
    return Calibration(
        camera=camera, projector=projector, R=R, T=T, method=str(doc.get("method", "unknown")),
        cam_rms=check_rms(path, "camera.rms_px", (doc.get("camera") or {}).get("rms_px")),
        proj_rms=check_rms(path, "projector.rms_px", (doc.get("projector") or {}).get("rms_px")),
        stereo_rms=check_rms(path, "stereo_rms_px", doc.get("stereo_rms_px")), std=doc.get("std", {}),
        poses=tuple(doc.get("poses", [])), views=views, warnings=tuple(str(w) for w in doc.get("warnings", [])),
        info=info, verdict=verdict_level(doc.get("verdict")),
        verdict_reasons=_verdict_reasons(path, doc.get("verdict")))


_COV_HINT = "write the camera file again with 'procam calibrate PHOTOS... --camera-only' (or delete the covariance block)"


def _covariance_from_json(path, c) -> dict:
    """The ``covariance`` block: ``{"params": [names], "matrix": (P, P) array (all inf for null), "sigma_px"}``,
    checked (names known, a symmetric matrix with a non-negative diagonal)."""
    from ..crlb import VIEW_PARAMS

    if not isinstance(c, dict):
        bad(path, "covariance", f"must be an object with params and matrix, got {short(c)}", fix=_COV_HINT)
    params = c.get("params")
    if not isinstance(params, list) or not params or any(p not in VIEW_PARAMS for p in params) \
            or len(set(params)) != len(params):
        bad(path, "covariance.params", f"must be distinct names of {', '.join(VIEW_PARAMS)}, got {short(params)}",
            fix=_COV_HINT)
    n = len(params)
    if c.get("matrix") is None:
        m = np.full((n, n), np.inf)
    else:
        m = numbers(path, "covariance.matrix", c.get("matrix"), (n, n), fix=_COV_HINT)
        if np.abs(m - m.T).max() > 1e-9 * max(1e-300, np.abs(m).max()) or np.any(np.diag(m) < 0):
            bad(path, "covariance.matrix", "must be symmetric with a non-negative diagonal", fix=_COV_HINT)
    sigma = c.get("sigma_px")
    if sigma is not None and not (isinstance(sigma, (int, float)) and not isinstance(sigma, bool)
                                  and np.isfinite(sigma) and sigma >= 0):
        bad(path, "covariance.sigma_px", f"must be a non-negative number or null, got {short(sigma)}", fix=_COV_HINT)
    return {"params": tuple(params), "matrix": m, "sigma_px": None if sigma is None else float(sigma)}


def _source_from_json(path, c) -> dict:
    """The ``calibrated_from`` block: ``{"inputs": [{"name": ...}], "count": n, "date": ISO 8601}``, checked."""
    if not isinstance(c, dict) or not isinstance(c.get("inputs"), list) \
            or not all(isinstance(i, dict) and isinstance(i.get("name"), str) for i in c["inputs"]):
        bad(path, "calibrated_from", f"must be an object with inputs [{{\"name\": ...}}], count and date, got "
                                     f"{short(c)}")
    count = c.get("count")
    if not isinstance(count, int) or isinstance(count, bool) or count != len(c["inputs"]):
        bad(path, "calibrated_from.count", f"must be the number of inputs ({len(c['inputs'])}), got {short(count)}")
    if not isinstance(c.get("date", ""), str):
        bad(path, "calibrated_from.date", f"must be an ISO 8601 date, got {short(c.get('date'))}")
    return {"inputs": [dict(i) for i in c["inputs"]], "count": count, "date": c.get("date", "")}
