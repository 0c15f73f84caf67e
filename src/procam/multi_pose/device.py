"""One device's multi-pose calibration: OpenCV ``calibrateCamera`` with a choice of distortion model, from
OpenCV's own start and from a zero-skew Zhang closed form, for principal points inside or outside the image."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import CalibrationError

DIST_MODELS: dict[str, tuple[int, tuple[int, ...]]] = {
    "none": (5, ()),
    "k1": (5, (0,)),
    "k1k2": (5, (0, 1)),
    "k1k2p1p2": (5, (0, 1, 2, 3)),
    "k1k2p1p2k3": (5, (0, 1, 2, 3, 4)),
    "rational": (8, tuple(range(8))),
}


def _dist_flags(dist: str) -> int:
    """``calibrateCamera`` flags that leave exactly the model's coefficients free."""
    import cv2

    return {"none": cv2.CALIB_FIX_K1 | cv2.CALIB_FIX_K2 | cv2.CALIB_FIX_K3 | cv2.CALIB_ZERO_TANGENT_DIST,
            "k1": cv2.CALIB_FIX_K2 | cv2.CALIB_FIX_K3 | cv2.CALIB_ZERO_TANGENT_DIST,
            "k1k2": cv2.CALIB_FIX_K3 | cv2.CALIB_ZERO_TANGENT_DIST,
            "k1k2p1p2": cv2.CALIB_FIX_K3, "k1k2p1p2k3": 0, "rational": cv2.CALIB_RATIONAL_MODEL}[dist]

_EPS = np.finfo(float).eps


def _criteria(iterations: int):
    import cv2

    return (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, int(iterations), _EPS)


def _check_dist(dist: str) -> tuple[int, int, tuple[int, ...]]:
    """``(calibrateCamera flags, vector length, free coefficient indices)`` of a model name."""
    if dist not in DIST_MODELS:
        raise CalibrationError(f"unknown distortion model {dist!r}; choose one of {', '.join(DIST_MODELS)}")
    return (_dist_flags(dist), *DIST_MODELS[dist])


# --------------------------------------------------------------------------------------------------
# Closed-form initial intrinsics
# --------------------------------------------------------------------------------------------------

def zhang_intrinsics(obj_list, img_list, image_size) -> np.ndarray | None:
    """Zero-skew Zhang closed form for K from board homographies (no distortion).

    Parameters
    ----------
    obj_list : sequence of (N_j, 3) board points (z = 0).
    img_list : sequence of (N_j, 2) pixels.
    image_size : (width, height), used only to normalise pixel coordinates.

    Returns
    -------
    K : (3, 3), or None when fewer than 2 poses or the constraints are degenerate.
        With zero skew, ``B = K^-T K^-1`` has 4 degrees of freedom and each homography gives two
        constraints, so two non-degenerate poses suffice.  The principal point may
        fall anywhere, inside the image or not.
    """
    import cv2

    W, H = image_size
    s = 1.0 / max(W, H)
    Nrm = np.array([[s, 0, -0.5 * s * W], [0, s, -0.5 * s * H], [0, 0, 1.0]])
    rows = []
    for obj, img in zip(obj_list, img_list):
        obj = np.asarray(obj, float)
        img = np.asarray(img, float)
        if len(obj) < 4:
            continue
        imgn = img @ Nrm[:2, :2].T + Nrm[:2, 2]
        Hm, _ = cv2.findHomography(obj[:, :2], imgn, 0)
        if Hm is None:
            continue
        h1, h2 = Hm[:, 0], Hm[:, 1]

        def v(a, b):
            return np.array([a[0] * b[0], a[0] * b[2] + a[2] * b[0], a[1] * b[1],
                             a[1] * b[2] + a[2] * b[1], a[2] * b[2]])

        rows.append(v(h1, h2))
        rows.append(v(h1, h1) - v(h2, h2))
    if len(rows) < 4:
        return None
    A = np.asarray(rows)
    A /= np.linalg.norm(A, axis=1, keepdims=True) + 1e-300
    try:
        b = np.linalg.svd(A)[2][-1]
    except np.linalg.LinAlgError:
        return None
    B11, B13, B22, B23, B33 = b
    if B11 < 0:
        B11, B13, B22, B23, B33 = -b
    if B11 <= 0 or B22 <= 0:
        return None
    cx, cy = -B13 / B11, -B23 / B22
    lam = B33 - B13 ** 2 / B11 - B23 ** 2 / B22
    if not lam > 0:
        return None
    Kn = np.array([[np.sqrt(lam / B11), 0, cx], [0, np.sqrt(lam / B22), cy], [0, 0, 1.0]])
    K = np.linalg.solve(Nrm, Kn)
    K /= K[2, 2]
    K[0, 1] = K[1, 0] = K[2, 0] = K[2, 1] = 0.0
    return K if np.all(np.isfinite(K)) else None


# --------------------------------------------------------------------------------------------------
# One device
# --------------------------------------------------------------------------------------------------

def _as_cv(obj_list, img_list):
    objs = [np.ascontiguousarray(np.asarray(o, np.float64).reshape(-1, 3), dtype=np.float32) for o in obj_list]
    imgs = [np.ascontiguousarray(np.asarray(i, np.float64).reshape(-1, 1, 2), dtype=np.float32) for i in img_list]
    return objs, imgs


def _calib_with_guess(obj_list, img_list, image_size, K0, flags, ncoef, criteria):
    """calibrateCamera from the guess ``K0`` in a pixel frame translated so that the principal point
    lies inside a virtual image (OpenCV rejects a guess outside the image)."""
    import cv2

    W, H = image_size
    margin = 0.05 * max(W, H)
    lo = np.minimum([0.0, 0.0], K0[:2, 2] - margin)
    hi = np.maximum([W, H], K0[:2, 2] + margin)
    shift = -lo
    size = (int(np.ceil(hi[0] - lo[0])) + 1, int(np.ceil(hi[1] - lo[1])) + 1)
    Ks = K0.copy()
    Ks[:2, 2] += shift
    imgs = [np.asarray(i, float).reshape(-1, 2) + shift for i in img_list]
    objs, imgs = _as_cv(obj_list, imgs)
    rms, K, d, rv, tv = cv2.calibrateCamera(objs, imgs, size, Ks, np.zeros(ncoef), flags=flags
                                            | cv2.CALIB_USE_INTRINSIC_GUESS, criteria=criteria)
    K = K.copy()
    K[:2, 2] -= shift
    return rms, K, d, rv, tv


@dataclass(frozen=True)
class DeviceCalibration:
    """One device's multi-pose calibration (:func:`calibrate_device`).

    ``K`` (3, 3); ``coeffs`` (5,) or (8,) OpenCV distortion vector; ``rvecs``, ``tvecs`` lists of (3,) per
    pose (board -> device); ``rms`` the RMS reprojection error in pixels over all points
    (``calibrateCamera``'s); ``init`` the start that won, ``rms_by_init`` the RMS of each start,
    ``init_errors`` why a start failed.
    """

    K: np.ndarray
    coeffs: np.ndarray
    rvecs: list
    tvecs: list
    rms: float
    init: str
    rms_by_init: dict
    init_errors: dict


def calibrate_device(obj_list, img_list, image_size, dist: str = "k1k2p1p2k3", *,
                     init: str = "auto", fix_aspect_ratio: bool = False, iterations: int = 100) -> DeviceCalibration:
    """Zhang calibration of one device (camera or projector) from several board poses.

    Parameters
    ----------
    obj_list : sequence of (N_j, 3) board points per pose (z = 0, board units).
    img_list : sequence of (N_j, 2) pixels per pose (distorted, as observed).
    image_size : (width, height) in pixels.
    dist : OpenCV distortion model, one of :data:`DIST_MODELS`
        (``"none"``, ``"k1"``, ``"k1k2"``, ``"k1k2p1p2"``, ``"k1k2p1p2k3"`` = OpenCV default, ``"rational"``).
    init : ``"auto"`` (try both starts below, keep the lower RMS), ``"opencv"`` (OpenCV's own
        initialisation, principal point at the image centre: exactly Moreno & Taubin's call) or
        ``"zhang"`` (zero-skew closed form; works for a principal point outside the image).
    fix_aspect_ratio : keep ``fy / fx`` at the initial value (``CALIB_FIX_ASPECT_RATIO``).
    iterations : maximum Levenberg–Marquardt iterations (criteria COUNT + EPS, eps = DBL_EPSILON).

    Returns
    -------
    :class:`DeviceCalibration`

    Raises
    ------
    CalibrationError
        If no start converges to a finite, positive-focal solution, or fewer than 2 poses are given.
    """
    import cv2

    flags, ncoef, _ = _check_dist(dist)
    if fix_aspect_ratio:
        flags |= cv2.CALIB_FIX_ASPECT_RATIO
    if init not in ("auto", "opencv", "zhang"):
        raise ValueError(f"init must be auto, opencv or zhang, got {init!r}")
    if len(obj_list) < 2:
        raise CalibrationError(f"multi-pose calibration needs at least 2 poses, got {len(obj_list)}")
    for k, o in enumerate(obj_list):
        if len(o) < 4:
            raise CalibrationError(f"pose #{k + 1} has only {len(o)} usable corners; at least 4 (its board "
                                   "homography) are needed")
    image_size = (int(image_size[0]), int(image_size[1]))
    crit = _criteria(iterations)
    tries: dict[str, tuple] = {}
    errors: dict[str, str] = {}
    if init in ("auto", "opencv"):
        try:
            objs, imgs = _as_cv(obj_list, img_list)
            tries["opencv"] = cv2.calibrateCamera(objs, imgs, image_size, np.eye(3), np.zeros(ncoef),
                                                  flags=flags, criteria=crit)
        except cv2.error as e:  # pragma: no cover - depends on data
            errors["opencv"] = str(e).strip().splitlines()[-1]
    if init in ("auto", "zhang"):
        K0 = zhang_intrinsics(obj_list, img_list, image_size)
        if K0 is not None and K0[0, 0] > 0 and K0[1, 1] > 0:
            if fix_aspect_ratio:
                K0[1, 1] = K0[0, 0]
            try:
                tries["zhang"] = _calib_with_guess(obj_list, img_list, image_size, K0, flags, ncoef, crit)
            except cv2.error as e:  # pragma: no cover
                errors["zhang"] = str(e).strip().splitlines()[-1]
        else:
            errors["zhang"] = "degenerate closed form"
    good = {k: v for k, v in tries.items()
            if np.isfinite(v[0]) and np.all(np.isfinite(v[1])) and v[1][0, 0] > 0 and v[1][1, 1] > 0}
    if not good:
        raise CalibrationError("multi-pose device calibration failed for every start ("
                               + "; ".join(f"{k}: {v}" for k, v in errors.items())
                               + "); check that the poses are varied (tilted, not all parallel)")
    # the lower RMS wins; a tie (within 1e-9 relative: both starts reach one minimum) goes to OpenCV's start
    best = "opencv" if "opencv" in good else next(iter(good))
    for k, v in good.items():
        if v[0] < good[best][0] * (1.0 - 1e-9):
            best = k
    rms, K, d, rv, tv = good[best]
    coeffs = np.zeros(ncoef)
    d = np.asarray(d, float).ravel()
    coeffs[:min(ncoef, len(d))] = d[:ncoef]
    return DeviceCalibration(K=np.asarray(K, float), coeffs=coeffs, rvecs=[np.asarray(r, float).ravel() for r in rv],
                             tvecs=[np.asarray(t, float).ravel() for t in tv], rms=float(rms), init=best,
                             rms_by_init={k: float(v[0]) for k, v in tries.items()}, init_errors=errors)
