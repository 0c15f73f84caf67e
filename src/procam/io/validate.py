"""The one validator set: every reader of a calibration (procam JSON, OpenCV FileStorage YAML/XML in procam's
and other tools' layouts, kamino410's files) and of the decoded maps checks what it loads with these functions.

A file is judged by the same rules whatever its format, and a bad field is refused with one line naming the
file and the field (:class:`~procam.errors.CalibrationFileError` unless the reader asks for another class).
The bounds are those of a real device; beyond them a file is corrupt, not a camera.

The rules, and why each is what it is:

* ``K``: a finite 3x3 ``[[fx, s, u0], [0, fy, v0], [0, 0, 1]]``, ``0 < fx, fy <= MAX_FOCAL_PX``, the bottom row
  and ``K[1, 0]`` within 1e-9 of their values, principal point and skew below ``10 MAX_IMAGE_SIDE``.
* image size: ``[width, height]``, whole pixels, each side from :data:`MIN_IMAGE_SIDE` = 2 to
  :data:`MAX_IMAGE_SIDE`.  A one-pixel image is not a calibration image (no chessboard corner fits in it, and
  ``2 u0`` of any real ``K`` exceeds it), so a 1 in a file is a mistake; a 2 is the smallest size whose pixel
  grid has a centre between pixels.
* rotation ``R``: finite 3x3, ``max |R^T R - I| <=`` :data:`ROTATION_TOL` = 1e-3 and ``det R > 0``.  The check
  refuses what is not a rotation (a reflection, a camera matrix, an essential matrix, a corrupt file); it does
  not certify precision.  Real files are not orthonormal to 1e-6: OpenCV's own files carry about 1e-7 after a
  float round trip, and a YAML written by hand or by a tool with 5-6 significant digits 1e-6 to 1e-5, so a
  tolerance of 1e-6 refuses good files.  1e-3 is a scale error of 5e-4 in ``R``: still far from anything else
  that is 3x3.
* distortion: a known model only (an unknown one is refused, never read as none).  OpenCV coefficients are 4,
  5, 8, 12 or 14 finite numbers; no vector or an empty one means no distortion, as for OpenCV's ``distCoeffs``
  (an empty ``Mat`` is zero distortion), so files that write ``[]`` for a distortion-free device are read.  In a
  FileStorage file, all-zero coefficients are no distortion too (procam writes a distortion-free projector so).
  Division model: a finite centre ``(x, y)`` and finite ``k1``, ``k2``.  Either model is a lens's: the image's
  corners and the middles of its sides, undistorted, are finite and from 0.1 to 10 times as far from the principal
  point as in the image (:func:`check_lens`; a 170-degree lens is about 8): a division ``k1`` of 1e10 put the whole
  image on its centre, and every pixel of an exported undistortion map was invalid, without a word.
* translation ``T``: 3 finite numbers, ``0 < |T| <= MAX_BASELINE`` (camera and projector are apart).
* an RMS error: a number of pixels, or absent (NaN).
* a JSON file: each key once in every object (:func:`load_json`); a second value of a key is refused, never
  read as the first or the last.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..errors import CalibrationFileError

if TYPE_CHECKING:
    from ..calibration import Calibration, Distortion

#: Plausible bounds of a calibration file's numbers (beyond them a file is corrupt, not a camera).
MAX_FOCAL_PX = 1e7
MIN_IMAGE_SIDE = 2
MAX_IMAGE_SIDE = 100000
MAX_BASELINE = 1e9
#: Largest ``max |R^T R - I|`` of a rotation read from a file.
ROTATION_TOL = 1e-3
#: The range of a lens's distortion: the image's edge undistorted is this many times as far from the principal point
#: as in the image (a 170-degree lens about 8 times, pincushion a little under 1).
MIN_STRETCH, MAX_STRETCH = 0.1, 10.0
#: The lengths of an OpenCV distortion vector (besides an empty one: no distortion).
OPENCV_DIST_LENGTHS = (4, 5, 8, 12, 14)

FIX = "fix the file or re-run 'procam calibrate'"


def bad(path, field: str, what: str, *, fix: str = FIX, error: type = CalibrationFileError):
    """Raise ``error`` (one line): ``PATH: FIELD WHAT; FIX``."""
    raise error(f"{path}: {field} {what}; {fix}")


def short(v) -> str:
    """``repr(v)``, cut to 60 characters."""
    t = repr(v)
    return t if len(t) <= 60 else t[:57] + "..."


def numbers(path, field: str, v, shape: tuple, **how) -> np.ndarray:
    """``v`` as a finite float array of ``shape`` (3-vectors may be 3x1 or 1x3), or a one-line error naming ``field``
    (``how``: ``fix``, ``error`` of :func:`bad`)."""
    want = "x".join(map(str, shape)) if len(shape) > 1 else f"{shape[0]} numbers"
    if v is None:
        bad(path, field, "is missing (null)", **how)
    try:
        a = np.array(v, dtype=float)
    except (TypeError, ValueError):
        bad(path, field, f"must be {'a ' + want + ' matrix' if len(shape) > 1 else want}, got {short(v)}", **how)
    if len(shape) == 1 and a.size == shape[0] and a.ndim <= 2:
        a = a.reshape(shape)
    if a.shape != shape:
        got = "x".join(map(str, a.shape)) or "a single number"
        bad(path, field, f"must be {'a ' + want + ' matrix' if len(shape) > 1 else want}, got {got}", **how)
    if not np.all(np.isfinite(a)):
        bad(path, field, "holds NaN or infinite values", **how)
    return a


def check_K(path, field: str, K) -> np.ndarray:
    """A camera matrix (module rules), as a (3, 3) float array."""
    K = numbers(path, field, K, (3, 3))
    fx, fy, u0, v0 = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
    if not (0 < fx <= MAX_FOCAL_PX and 0 < fy <= MAX_FOCAL_PX):
        bad(path, field, f"focal lengths must be positive and at most {MAX_FOCAL_PX:.0e} px, got fx = {fx:g}, "
                         f"fy = {fy:g}")
    if np.abs(K[2] - [0, 0, 1]).max() > 1e-9 or abs(K[1, 0]) > 1e-9:
        bad(path, field, "must be [[fx, s, u0], [0, fy, v0], [0, 0, 1]]")
    if max(abs(u0), abs(v0), abs(K[0, 1])) > 10 * MAX_IMAGE_SIDE:
        bad(path, field, f"principal point ({u0:g}, {v0:g}) or skew is implausibly large")
    return K


def check_size(path, field: str, v, **how) -> tuple[int, int]:
    """An image size ``[width, height]`` (module rules) as ``(int, int)``."""
    try:
        w, h = (float(x) for x in np.asarray(v, dtype=float).ravel())
    except (TypeError, ValueError):
        bad(path, field, f"must be [width, height] in pixels, got {short(v)}", **how)
    if not (np.isfinite(w) and np.isfinite(h) and w == int(w) and h == int(h)
            and MIN_IMAGE_SIDE <= w <= MAX_IMAGE_SIDE and MIN_IMAGE_SIDE <= h <= MAX_IMAGE_SIDE):
        bad(path, field, f"must be [width, height], whole pixels from {MIN_IMAGE_SIDE} to {MAX_IMAGE_SIDE}, "
                         f"got {short(v)}", **how)
    return int(w), int(h)


def opencv_coeffs(path, field: str, c) -> tuple[float, ...]:
    """OpenCV distortion coefficients (module rules): ``()`` for none or an empty vector, else their values."""
    if c is None:
        return ()
    try:
        a = np.array(c, dtype=float).ravel()
    except (TypeError, ValueError):
        bad(path, field, f"must be a list of {', '.join(map(str, OPENCV_DIST_LENGTHS))} OpenCV coefficients, "
                         f"got {short(c)}")
    if a.size == 0:
        return ()
    if a.size not in OPENCV_DIST_LENGTHS:
        bad(path, field, f"must have {', '.join(map(str, OPENCV_DIST_LENGTHS))} OpenCV coefficients, got {a.size}")
    return tuple(float(v) for v in numbers(path, field, a, (a.size,)))


def check_distortion(path, field: str, d) -> Distortion:
    """A JSON distortion object (``{"model": "none" | "division" | "opencv", ...}``) as a :class:`Distortion`;
    None is no distortion, and so is an OpenCV model with no coefficients."""
    from ..calibration import Distortion  # here: the decoded maps' reader checks their sizes with this module

    if d is None:
        return Distortion()
    if not isinstance(d, dict):
        bad(path, field, f"must be an object with a model, got {short(d)}")
    model = d.get("model", "none")
    if model == "none":
        return Distortion()
    if model == "division":
        c = numbers(path, f"{field}.center", d.get("center"), (2,))
        k1 = numbers(path, f"{field}.k1", [d.get("k1")], (1,))[0]
        k2 = numbers(path, f"{field}.k2", [d.get("k2", 0.0)], (1,))[0]
        return Distortion("division", (float(c[0]), float(c[1])), float(k1), float(k2))
    if model == "opencv":
        coeffs = d.get("coeffs")
        if not isinstance(coeffs, (list, tuple)):
            bad(path, f"{field}.coeffs", f"must be a list of {', '.join(map(str, OPENCV_DIST_LENGTHS))} OpenCV "
                                         f"coefficients, got {short(coeffs)}")
        coeffs = opencv_coeffs(path, f"{field}.coeffs", coeffs)
        return Distortion("opencv", coeffs=coeffs) if coeffs else Distortion()
    bad(path, f"{field}.model", f"must be none, division or opencv, got {short(model)}")


def check_lens(path, field: str, dev) -> None:
    """The distortion of the device ``dev`` (its ``K``, ``image_size``, ``distortion``) is a lens's (module rules):
    the image's corners and the middles of its sides, undistorted, are finite and from :data:`MIN_STRETCH` to
    :data:`MAX_STRETCH` times as far from the principal point as they are in the image."""
    if dev.distortion.model == "none" or dev.image_size is None:
        return
    w, h = dev.image_size
    K = np.asarray(dev.K, float)
    edge = np.array([[0, 0], [w - 1, 0], [0, h - 1], [w - 1, h - 1], [(w - 1) / 2, 0], [(w - 1) / 2, h - 1],
                     [0, (h - 1) / 2], [w - 1, (h - 1) / 2]], float)
    c = K[:2, 2]
    r = np.hypot(*(edge - c).T)
    with np.errstate(all="ignore"):
        und = dev.distortion.undistort(edge, K)
        stretch = np.hypot(*(und - c).T) / r
    far = r > 0.05 * max(w, h)  # a side's middle may sit on the principal point
    worst = stretch[far][np.argmax(np.abs(np.log(np.where(np.isfinite(stretch[far]) & (stretch[far] > 0),
                                                              stretch[far], np.inf))))] if far.any() else 1.0
    if not np.all(np.isfinite(und)) or not MIN_STRETCH <= worst <= MAX_STRETCH:
        bad(path, field, f"puts the image's edge {worst:.3g} times as far from the principal point as the image does "
                         f"(a lens's distortion: {MIN_STRETCH:g} to {MAX_STRETCH:g} times): not a lens")


def off_centre(K, size) -> float:
    """How far the principal point of ``K`` sits from the centre of a ``size`` = (w, h) image, as the larger of its
    two offsets in fractions of the side (the reader's test of which order a pair of sides is in)."""
    w, h = size
    return max(abs(K[0, 2] - (w - 1) / 2) / w, abs(K[1, 2] - (h - 1) / 2) / h)


def check_rotation(path, field: str, R) -> np.ndarray:
    """A rotation matrix (module rules), as a (3, 3) float array."""
    R = numbers(path, field, R, (3, 3))
    err = float(np.abs(R.T @ R - np.eye(3)).max())
    if err > ROTATION_TOL or np.linalg.det(R) <= 0:
        bad(path, field, f"is not a rotation matrix (R^T R differs from I by {err:.3g}, det {np.linalg.det(R):.3g})")
    return R


def check_translation(path, field: str, T) -> np.ndarray:
    """A camera -> projector translation (module rules), as a (3,) float array."""
    T = numbers(path, field, T, (3,))
    n = float(np.linalg.norm(T))
    if not 0 < n <= MAX_BASELINE:
        bad(path, field, f"has length {n:g}: camera and projector must be apart (baseline > 0, at most "
                         f"{MAX_BASELINE:.0e} board units)")
    return T


def check_rms(path, field: str, v) -> float:
    """An RMS error in pixels (None: NaN)."""
    if v is None:
        return float("nan")
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        bad(path, field, f"must be a number of pixels, got {short(v)}")
    return float(v)


def load_json(path, what: str, hint: str, *, error: type = CalibrationFileError):
    """The JSON document of the file ``path`` through the one bounded reader (:func:`procam.io.jsonfile.load_json`:
    nesting, digits, finite numbers, each key once in every object).  A file that cannot be read or parsed is
    refused with ``PATH: WHAT (why); HINT``, a key given twice with ``PATH: key 'K' is given twice`` (raised as
    ``error``)."""
    from .jsonfile import JSONError
    from .jsonfile import load_json as _bounded

    path = Path(path)
    try:
        return _bounded(path, finite=False)
    except JSONError as e:
        if "is given twice" in str(e):
            raise error(f"{path}: {e}") from None
        raise error(f"{path}: {what} ({e}); {hint}") from None
    except (OSError, UnicodeDecodeError, ValueError) as e:
        raise error(f"{path}: {what} ({e}); {hint}") from None


def validate_calibration(calib, path) -> Calibration:
    """Check every field of a loaded :class:`~procam.calibration.Calibration` by the module's rules: shapes,
    finiteness, positive focal lengths, plausible magnitudes, a rotation ``R``, a non-zero ``T``, known
    distortion models.

    Returns ``calib``; raises :class:`~procam.errors.CalibrationFileError` naming ``path`` and the field.
    """
    if calib.camera is None:
        bad(path, "camera", "is missing (null)")
    for name, dev in (("camera", calib.camera), ("projector", calib.projector)):
        if dev is None:
            continue
        check_K(path, f"{name}.K", dev.K)
        check_size(path, f"{name}.image_size", dev.image_size)
        d = dev.distortion
        if d.model == "division":
            numbers(path, f"{name}.distortion.center", d.center, (2,))
            numbers(path, f"{name}.distortion.k1, k2", [d.k1, d.k2], (2,))
        elif d.model == "opencv":
            if len(d.coeffs) not in OPENCV_DIST_LENGTHS:
                bad(path, f"{name}.distortion.coeffs", f"must have {', '.join(map(str, OPENCV_DIST_LENGTHS))} OpenCV "
                                                       f"coefficients, got {len(d.coeffs)}")
            numbers(path, f"{name}.distortion.coeffs", d.coeffs, (len(d.coeffs),))
        check_lens(path, f"{name}.distortion", dev)
    if calib.projector is not None or calib.R is not None or calib.T is not None:
        if calib.projector is None:
            bad(path, "projector", "is missing (null) while R and T are given")
        check_rotation(path, "R", calib.R)
        check_translation(path, "T", calib.T)
    return calib
