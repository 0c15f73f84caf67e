"""kamino410/procam-calibration's files: ``calibration_result.xml`` written and read, ``camera_config.json`` read.

Their ``calibrate.py`` writes a ``cv2.FileStorage`` XML with the keys of :data:`procam.io.formats.KAMINO410`
(``cam_int, cam_dist, proj_int, proj_dist, rotation, translation``) plus ``img_shape`` (the camera's
``[height, width]``) and ``rms``; the extrinsics are OpenCV ``stereoCalibrate``'s with the camera first, exactly
procam's ``R, T``.  Their files do not store the projector's size; procam's export adds ``proj_shape``.  Every
number read is checked by :mod:`procam.io.validate`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..calibration import Calibration, Device, Distortion
from ..errors import CalibrationFileError
from .files import atomic_path
from .formats import KAMINO410
from .opencv import camera_size, cv_message, distortion, has, matrix, open_storage, real, write_devices  # noqa: F401
from .validate import (bad, check_K, check_rotation, check_size, check_translation, opencv_coeffs,
                       validate_calibration)

#: kamino410/procam-calibration's ``calibration_result.xml`` keys -> meaning (procam's name).
KAMINO410_KEYS = {
    "img_shape": "camera image shape (height, width), 2x1 double",
    "rms": "stereoCalibrate RMS, px (procam: stereo_rms)",
    "cam_int": "camera K, 3x3 (procam: camera.K)",
    "cam_dist": "camera OpenCV distortion, 1x5 (procam: camera distortion; division -> OpenCV fit)",
    "proj_int": "projector K, 3x3 (procam: projector.K)",
    "proj_dist": "projector OpenCV distortion, 1x5",
    "rotation": "camera -> projector R, 3x3 (older files: 'roration')",
    "translation": "camera -> projector T, 3x1, chessboard units (procam: T)",
}
#: Their early files' spelling of ``rotation``.
OLD_ROTATION_KEY = "roration"


def save_kamino410(calib: Calibration, path) -> Path:
    """Write kamino410/procam-calibration's ``calibration_result.xml`` (``cv2.FileStorage``), atomically.

    Keys as theirs (:data:`KAMINO410_KEYS`): ``img_shape`` (camera ``[height, width]``, 2x1 double),
    ``rms``, ``cam_int``, ``cam_dist`` (1x5), ``proj_int``, ``proj_dist`` (1x5), ``rotation``,
    ``translation`` (3x1), with their meaning: ``x_proj = rotation x_cam + translation`` (OpenCV
    ``stereoCalibrate`` with the camera first, exactly procam's ``R, T``), ``translation`` in the
    chessboard's unit.  A division-model camera is written as its OpenCV ``(k1, k2, p1, p2, k3)`` fit
    (as procam's YAML).  procam adds ``proj_shape`` (projector ``[height, width]``), which their
    reader ignores and :func:`load_kamino410` uses.  ``.xml`` (theirs), ``.yml`` or ``.yaml``.
    """
    import cv2

    path = Path(path)
    if path.suffix.lower() not in (".xml", ".yml", ".yaml"):
        raise CalibrationFileError(f"{path}: kamino410's format is an OpenCV FileStorage file; name it .xml "
                                   "(as theirs), .yml or .yaml")
    if calib.projector is None or calib.R is None or calib.T is None:
        raise CalibrationFileError(f"{path}: a camera-only calibration has no projector, so no kamino410 file")
    W, H = (int(v) for v in calib.camera.image_size)
    Wp, Hp = (int(v) for v in calib.projector.image_size)
    with atomic_path(path) as tmp:
        fs = cv2.FileStorage(str(tmp), cv2.FILE_STORAGE_WRITE)
        fs.write("img_shape", np.array([[H], [W]], float))
        fs.write("rms", float(calib.stereo_rms))
        write_devices(fs, KAMINO410, calib)
        fs.write("proj_shape", np.array([[Hp], [Wp]], float))
        fs.release()
    return path


def read_calibration(fs, path, proj_size=None) -> Calibration:
    """The calibration in kamino410's keys from the open file ``fs`` of ``path`` (not validated as a whole:
    :func:`procam.io.validate.validate_calibration` does that).

    ``proj_size`` (width, height) is needed for files from their tool, which do not store the projector's
    size; without it procam's ``proj_shape`` is used, else ``(2 u0, 2 v0)`` is assumed and a warning added.
    Accepts their old misspelt ``roration`` key.
    """
    path = Path(path)
    keys = KAMINO410
    rot_key = keys.R if has(fs, keys.R) else OLD_ROTATION_KEY
    missing = [k for k in (keys.cam_K, keys.proj_K, keys.T) if not has(fs, k)]
    if not has(fs, rot_key):
        missing.append(keys.R)
    if missing:
        raise CalibrationFileError(f"{path}: missing {', '.join(missing)}; expected kamino410's keys "
                                   "cam_int, cam_dist, proj_int, proj_dist, rotation, translation, img_shape")
    Kc = check_K(path, keys.cam_K, matrix(fs, path, keys.cam_K))
    Kp = check_K(path, keys.proj_K, matrix(fs, path, keys.proj_K))
    R = check_rotation(path, rot_key, matrix(fs, path, rot_key))
    T = check_translation(path, keys.T, matrix(fs, path, keys.T))
    shape = matrix(fs, path, "img_shape")
    if shape is None:
        bad(path, "img_shape", "is missing (the camera's height, width)")
    cam_size = camera_size(path, shape, Kc)
    warnings = []
    if proj_size is not None:
        proj_size = check_size(path, "the projector size", proj_size)
    elif has(fs, "proj_shape"):
        proj_size = check_size(path, "proj_shape", matrix(fs, path, "proj_shape").ravel()[::-1])
    else:
        proj_size = (int(round(2 * Kp[0, 2])), int(round(2 * Kp[1, 2])))
        warnings.append(f"{path.name} does not store the projector size; assumed {proj_size[0]}x{proj_size[1]} "
                        "from its principal point: give the real size")
    return Calibration(Device(Kc, cam_size, distortion(fs, path, keys.cam_dist)),
                       Device(Kp, proj_size, distortion(fs, path, keys.proj_dist)), R, T, "kamino410",
                       stereo_rms=real(fs, path, "rms"), warnings=tuple(warnings),
                       info={"source": str(path), **({"image_size_assumed": ["proj_size"]} if warnings else {})})


def load_kamino410(path, proj_size=None) -> Calibration:
    """Read kamino410/procam-calibration's ``calibration_result.xml`` (or a file :func:`save_kamino410` wrote),
    with the projector size ``proj_size`` (width, height) when the file does not store it (see
    :func:`read_calibration`).  :func:`procam.io.load_calibration` reads these files too (without
    ``proj_size``).

    Raises :class:`~procam.errors.CalibrationFileError` naming the file and the key.
    """
    import cv2

    path = Path(path)
    if not path.is_file():
        raise CalibrationFileError(f"{path}: no such file")
    fs = open_storage(path, "give kamino410's calibration_result.xml")
    try:
        calib = read_calibration(fs, path, proj_size)
    except (cv2.error, SystemError) as e:
        raise CalibrationFileError(f"{path}: not a readable OpenCV calibration ({cv_message(e)})") from None
    finally:
        fs.release()
    return validate_calibration(calib, path)


def camera_from_config(path, doc: dict) -> tuple[np.ndarray, Distortion, tuple[int, int] | None]:
    """One camera's ``(K, distortion, image size or None)`` from their ``camera_config.json``
    (``{"camera": {"P": [9 numbers], "distortion": [...], "width", "height"}}``)."""
    cam = doc["camera"]
    P = cam.get("P")
    try:
        P = np.asarray(P, float).reshape(3, 3)      # 9 numbers in a row
    except (TypeError, ValueError):
        pass
    K = check_K(path, "camera.P", P)
    coeffs = opencv_coeffs(path, "camera.distortion", cam.get("distortion"))
    size = None
    if cam.get("width") is not None and cam.get("height") is not None:
        size = check_size(path, "camera.width/height", (cam["width"], cam["height"]))
    return K, Distortion("opencv", coeffs=coeffs) if any(coeffs) else Distortion(), size
