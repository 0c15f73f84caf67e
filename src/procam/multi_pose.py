"""Multi-pose (Zhang-style) procam calibration: the baseline the paper compares against.

Pipeline (Moreno & Taubin's reference, plus an optional joint refinement):

1. :func:`calibrate_device` for the camera and for the projector separately: OpenCV
   ``calibrateCamera`` with a selectable OpenCV distortion model.  Two starts are tried and the one
   with the lower RMS is kept: OpenCV's own initialisation (principal point at the image centre) and
   a zero-skew Zhang closed form.  A lens-shifted projector has its principal point outside the
   image, which OpenCV refuses as an initial guess; the guess is then applied in a translated pixel
   frame whose (virtual) image contains the principal point, and the result translated back (exact:
   every OpenCV distortion model is a function of ``(x - c) / f`` only).
2. ``stereoCalibrate`` with ``CALIB_FIX_INTRINSIC`` for ``(R, T)`` (the "frozen" step every peer
   tool ships: the intrinsics are not improved by the stereo constraint).
3. ``refine=True`` (default): a joint least-squares refinement of both intrinsics, both distortion
   vectors, ``(R, T)`` and every board pose (scipy ``least_squares``, robust loss, analytic Jacobian
   from ``cv2.projectPoints`` and ``cv2.composeRT``).

Conventions as in :mod:`procam.calibration`: board poses map board -> camera, ``x_p = R x_c + T``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from . import models
from . import uncertainty as unc
from .calibration import Calibration, Device, Distortion
from .errors import CalibrationError
from .residuals import rms
from .view import View

#: OpenCV distortion models: name -> (vector length, free coefficient indices in OpenCV's order
#: (k1, k2, p1, p2, k3[, k4, k5, k6])).
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
        if len(o) < 6:
            raise CalibrationError(f"pose #{k + 1} has only {len(o)} usable corners; at least 6 are needed")
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
    best = min(good, key=lambda k: good[k][0])
    rms, K, d, rv, tv = good[best]
    coeffs = np.zeros(ncoef)
    d = np.asarray(d, float).ravel()
    coeffs[:min(ncoef, len(d))] = d[:ncoef]
    return DeviceCalibration(K=np.asarray(K, float), coeffs=coeffs, rvecs=[np.asarray(r, float).ravel() for r in rv],
                             tvecs=[np.asarray(t, float).ravel() for t in tv], rms=float(rms), init=best,
                             rms_by_init={k: float(v[0]) for k, v in tries.items()}, init_errors=errors)


# --------------------------------------------------------------------------------------------------
# Joint refinement
# --------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class _Layout:
    cam_free: tuple[int, ...]
    proj_free: tuple[int, ...]
    ncoef_c: int
    ncoef_p: int
    n_views: int

    @property
    def nc(self):
        return 4 + len(self.cam_free)

    @property
    def npj(self):
        return 4 + len(self.proj_free)

    @property
    def off_rt(self):
        return self.nc + self.npj

    def off_view(self, j):
        return self.off_rt + 6 + 6 * j

    @property
    def size(self):
        return self.off_rt + 6 + 6 * self.n_views

    def pack(self, Kc, dc, Kp, dp, r, T, rvecs, tvecs):
        x = [Kc[0, 0], Kc[1, 1], Kc[0, 2], Kc[1, 2], *np.asarray(dc)[list(self.cam_free)],
             Kp[0, 0], Kp[1, 1], Kp[0, 2], Kp[1, 2], *np.asarray(dp)[list(self.proj_free)],
             *np.ravel(r), *np.ravel(T)]
        for rv, tv in zip(rvecs, tvecs):
            x += [*np.ravel(rv), *np.ravel(tv)]
        return np.asarray(x, float)

    def unpack(self, x, dc0, dp0):
        def dev(off, free, d0):
            K = np.array([[x[off], 0, x[off + 2]], [0, x[off + 1], x[off + 3]], [0, 0, 1.0]])
            d = np.array(d0, float).copy()
            d[list(free)] = x[off + 4: off + 4 + len(free)]
            return K, d

        Kc, dc = dev(0, self.cam_free, dc0)
        Kp, dp = dev(self.nc, self.proj_free, dp0)
        r = x[self.off_rt: self.off_rt + 3]
        T = x[self.off_rt + 3: self.off_rt + 6]
        rvecs = [x[self.off_view(j): self.off_view(j) + 3] for j in range(self.n_views)]
        tvecs = [x[self.off_view(j) + 3: self.off_view(j) + 6] for j in range(self.n_views)]
        return Kc, dc, Kp, dp, r, T, rvecs, tvecs


def _stereo_model(x, lay: _Layout, objs, cams, projs, dc0, dp0, want_jac: bool, w_proj: float = 1.0):
    """Residuals (projected - observed; per view: camera 2N then projector 2N, the projector's scaled
    by ``w_proj``) and Jacobian."""
    import cv2

    Kc, dc, Kp, dp, r, T, rvecs, tvecs = lay.unpack(x, dc0, dp0)
    res = []
    jac_blocks = []
    row = 0
    for j in range(lay.n_views):
        obj = objs[j].reshape(-1, 1, 3)
        n2 = 2 * len(objs[j])
        pc, Jc = cv2.projectPoints(obj, rvecs[j], tvecs[j], Kc, dc)
        r3, t3, dr3dr1, dr3dt1, dr3dr2, dr3dt2, dt3dr1, dt3dt1, dt3dr2, dt3dt2 = cv2.composeRT(
            rvecs[j], tvecs[j], r, T)
        pp, Jp = cv2.projectPoints(obj, r3, t3, Kp, dp)
        res.append(pc.reshape(-1) - cams[j].reshape(-1))
        res.append(w_proj * (pp.reshape(-1) - projs[j].reshape(-1)))
        if want_jac:
            J = np.zeros((2 * n2, lay.size))
            # camera block
            J[:n2, 0:4] = Jc[:, 6:10]
            J[:n2, 4:lay.nc] = Jc[:, [10 + i for i in lay.cam_free]]
            ov = lay.off_view(j)
            J[:n2, ov:ov + 3] = Jc[:, 0:3]
            J[:n2, ov + 3:ov + 6] = Jc[:, 3:6]
            # projector block
            Jr, Jt = Jp[:, 0:3], Jp[:, 3:6]
            J[n2:, lay.nc:lay.nc + 4] = Jp[:, 6:10]
            J[n2:, lay.nc + 4:lay.off_rt] = Jp[:, [10 + i for i in lay.proj_free]]
            J[n2:, lay.off_rt:lay.off_rt + 3] = Jr @ dr3dr2 + Jt @ dt3dr2
            J[n2:, lay.off_rt + 3:lay.off_rt + 6] = Jr @ dr3dt2 + Jt @ dt3dt2
            J[n2:, ov:ov + 3] = Jr @ dr3dr1 + Jt @ dt3dr1
            J[n2:, ov + 3:ov + 6] = Jr @ dr3dt1 + Jt @ dt3dt1
            J[n2:] *= w_proj
            jac_blocks.append(J)
        row += 2 * n2
    r_all = np.concatenate(res)
    if want_jac:
        return r_all, np.vstack(jac_blocks)
    return r_all


@dataclass(frozen=True)
class StereoRefinement:
    """The joint refinement's result (:func:`refine_stereo`).

    ``Kc, dc, Kp, dp`` intrinsics and OpenCV distortion vectors; ``R, T`` camera -> projector; ``rvecs,
    tvecs`` board -> camera per pose; ``residuals`` per pose ``(cam (N, 2), proj (N, 2))``, observed -
    predicted px, unweighted; ``cov`` the parameter covariance (Gauss-Newton ``s^2 (J^T J)^-1`` of the
    weighted problem, infinite when ill-conditioned), rows named by ``names`` (:mod:`procam.parameters`
    vocabulary, ``cam_dist[i]``/``proj_dist[i]`` for distortion coefficient i); ``x`` the solution
    vector; ``status``, ``nfev``, ``cost`` of ``least_squares``.
    """

    Kc: np.ndarray
    dc: np.ndarray
    Kp: np.ndarray
    dp: np.ndarray
    R: np.ndarray
    T: np.ndarray
    rvecs: list
    tvecs: list
    residuals: list
    cov: np.ndarray
    names: tuple
    x: np.ndarray
    status: int
    nfev: int
    cost: float


def refine_stereo(objs, cams, projs, Kc, dc, Kp, dp, R, T, rvecs, tvecs, *, cam_dist="k1k2p1p2k3",
                  proj_dist="k1k2p1p2k3", loss: str = "soft_l1", loss_scale: float = 1.0,
                  proj_weight: float = 1.0, max_nfev: int = 200, tol: float = 1e-12):
    """Joint least-squares refinement of both devices, ``(R, T)`` and the board poses.

    Parameters
    ----------
    objs, cams, projs : per-pose lists of (N_j, 3) board points, (N_j, 2) camera and (N_j, 2)
        projector pixels (all finite).
    Kc, dc, Kp, dp : initial intrinsics (3, 3) and OpenCV distortion vectors.
    R, T : initial camera -> projector rotation (3, 3) and translation (3,).
    rvecs, tvecs : initial board -> camera poses, one (3,) pair per pose.
    cam_dist, proj_dist : which distortion coefficients are free (:data:`DIST_MODELS`).
    loss, loss_scale : scipy robust loss and its soft threshold in (camera) pixels (residuals well
        below ``loss_scale`` are treated as plain least squares).
    proj_weight : factor on the projector residuals (``sigma_cam / sigma_proj`` gives the
        maximum-likelihood weighting when both noises are Gaussian).
    max_nfev, tol : solver budget and tolerances (ftol = xtol = gtol).

    Returns
    -------
    :class:`StereoRefinement`
    """
    from scipy.optimize import least_squares

    _, ncc, cfree = _check_dist(cam_dist)
    _, ncp, pfree = _check_dist(proj_dist)
    dc0 = np.zeros(ncc)
    dc0[:min(ncc, len(dc))] = np.asarray(dc, float).ravel()[:ncc]
    dp0 = np.zeros(ncp)
    dp0[:min(ncp, len(dp))] = np.asarray(dp, float).ravel()[:ncp]
    lay = _Layout(cfree, pfree, ncc, ncp, len(objs))
    objs = [np.asarray(o, float).reshape(-1, 3) for o in objs]
    cams = [np.asarray(c, float).reshape(-1, 2) for c in cams]
    projs = [np.asarray(p, float).reshape(-1, 2) for p in projs]
    x0 = lay.pack(Kc, dc0, Kp, dp0, models.matrix_to_rvec(R), T, rvecs, tvecs)

    cache = {}

    w = float(proj_weight)

    def fun(x):
        rr, J = _stereo_model(x, lay, objs, cams, projs, dc0, dp0, True, w)
        cache["x"], cache["J"] = x.copy(), J
        return rr

    def jac(x):
        if "x" in cache and np.array_equal(cache["x"], x):
            return cache["J"]
        return _stereo_model(x, lay, objs, cams, projs, dc0, dp0, True, w)[1]

    sol = least_squares(fun, x0, jac=jac, method="trf", loss=loss, f_scale=loss_scale, x_scale="jac",
                        ftol=tol, xtol=tol, gtol=tol, max_nfev=max_nfev)
    x = sol.x
    Kc1, dc1, Kp1, dp1, r1, T1, rv1, tv1 = lay.unpack(x, dc0, dp0)
    rr, J = _stereo_model(x, lay, objs, cams, projs, dc0, dp0, True, w)
    # Gauss-Newton covariance of the weighted problem, infinite when ill-conditioned (procam.uncertainty)
    cov = unc.covariance(J, unc.sigma_from_residuals(rr, len(x)) if len(rr) > len(x) else float("nan"))
    names = (["f_c", "fy_c", "u0c", "v0c"] + [f"cam_dist[{i}]" for i in cfree]
             + ["f_p", "fy_p", "u0p", "v0p"] + [f"proj_dist[{i}]" for i in pfree]
             + ["R_rx", "R_ry", "R_rz", "T_x", "T_y", "T_z"]
             + [f"pose{j}_{c}" for j in range(len(objs)) for c in ("rx", "ry", "rz", "tx", "ty", "tz")])
    residuals = []
    row = 0
    for o in objs:
        n2 = 2 * len(o)
        # reported observed - predicted (the model's residuals are projected - observed)
        residuals.append((-rr[row:row + n2].reshape(-1, 2), -rr[row + n2:row + 2 * n2].reshape(-1, 2) / w))
        row += 2 * n2
    return StereoRefinement(Kc=Kc1, dc=dc1, Kp=Kp1, dp=dp1, R=models.rvec_to_matrix(r1), T=T1, rvecs=rv1, tvecs=tv1,
                            residuals=residuals, cov=cov, names=tuple(names), x=x, status=int(sol.status),
                            nfev=int(sol.nfev), cost=float(sol.cost))


# --------------------------------------------------------------------------------------------------
# Procam calibration
# --------------------------------------------------------------------------------------------------

def _rms(arrs) -> float:
    """Pooled RMS (px) of a list of (N, 2) residual arrays (:func:`procam.residuals.rms`)."""
    return rms(list(arrs))


def _std_dict(ref: StereoRefinement, n_cam_dist: int, n_proj_dist: int) -> dict:
    """Standard deviations from the refinement covariance, named as every procam result
    (:mod:`procam.parameters`): ``f_c, fy_c, u0c, v0c, f_p, fy_p, u0p, v0p`` (px), ``cam_dist``,
    ``proj_dist`` (one per coefficient; 0 for a coefficient the model fixes), ``R_euler_deg`` (3,) (delta
    method through the Euler angles) and ``T`` (3,)."""
    sd = unc.std(ref.cov)
    names = list(ref.names)
    out = {n: float(sd[names.index(n)]) for n in ("f_c", "fy_c", "u0c", "v0c", "f_p", "fy_p", "u0p", "v0p")}
    for key, n in (("cam_dist", n_cam_dist), ("proj_dist", n_proj_dist)):
        out[key] = [float(sd[names.index(f"{key}[{i}]")]) if f"{key}[{i}]" in names else 0.0 for i in range(n)]
    i = names.index("R_rx")
    ce = unc.propagate(ref.cov[i:i + 3, i:i + 3], lambda r: models.euler_deg(models.rvec_to_matrix(r)),
                       ref.x[i:i + 3])
    out["R_euler_deg"] = unc.std(ce).tolist()
    out["T"] = sd[i + 3:i + 6].tolist()
    return out


def calibrate(views: Sequence[View], *, cam_size=None, proj_size=None, cam_dist: str = "k1k2p1p2k3",
              proj_dist: str = "k1k2p1p2k3", refine: bool = True, loss: str = "soft_l1",
              loss_scale: float = 1.0, balance: bool = True, init: str = "auto", fix_aspect_ratio: bool = False,
              iterations: int = 100, stereo_iterations: int = 150, min_corners: int = 6) -> Calibration:
    """Multi-pose procam calibration (Zhang / Moreno–Taubin, optionally jointly refined).

    Parameters
    ----------
    views : two or more :class:`procam.view.View` (three or more recommended); NaN corners are
        dropped per view (``view.valid``).
    cam_size, proj_size : (width, height) in pixels; default: taken from the views.
    cam_dist, proj_dist : OpenCV distortion model of each device (:data:`DIST_MODELS`); the default
        ``"k1k2p1p2k3"`` is OpenCV's (and Moreno & Taubin's).
    refine : run the joint refinement after the frozen-intrinsics stereo step.
    loss, loss_scale : robust loss of the refinement and its soft threshold in camera pixels.
    balance : weight the projector residuals by ``rms_cam / rms_proj`` of the per-device step
        (maximum likelihood when each device has its own Gaussian noise; projector corners are
        usually noisier).  ``False`` weights both equally, as ``stereoCalibrate`` does.
    init, fix_aspect_ratio, iterations : passed to :func:`calibrate_device`.
    stereo_iterations : iteration cap of ``stereoCalibrate`` (Moreno & Taubin: 150).
    min_corners : poses with fewer valid corners are an error.

    Returns
    -------
    :class:`procam.calibration.Calibration` with ``method="multi-pose"``, OpenCV distortion on both
    devices, ``cam_rms``/``proj_rms`` (per-device RMS of the final model), ``stereo_rms`` (RMS over
    all camera and projector points of the final stereo model), ``std`` (from the refinement's
    covariance, keys as :func:`_std_dict`; empty without refinement), ``poses`` (per-pose angles and RMS) and ``info`` with the
    frozen-step result under ``"frozen"`` (K, dist, R, T, RMS) for comparison.

    Raises
    ------
    CalibrationError
        Fewer than two poses, missing image sizes, too few corners, or no solution.
    """
    import cv2

    views = list(views)
    if len(views) < 2:
        raise CalibrationError(f"multi-pose calibration needs at least 2 poses (3 or more recommended), "
                               f"got {len(views)}; use --method single for one pose")
    cam_size = cam_size or views[0].cam_size
    proj_size = proj_size or views[0].proj_size
    if cam_size is None or proj_size is None:
        raise CalibrationError("multi-pose calibration needs the camera and projector image sizes "
                               "(set View.cam_size/proj_size or pass cam_size=, proj_size=)")
    cam_size = (int(cam_size[0]), int(cam_size[1]))
    proj_size = (int(proj_size[0]), int(proj_size[1]))
    objs, cams, projs, names = [], [], [], []
    for k, v in enumerate(views):
        m = v.valid
        if m.sum() < min_corners:
            raise CalibrationError(f"pose {v.name!r}: only {int(m.sum())} corners have both camera and "
                                   f"projector points (need {min_corners}); re-capture or drop this pose")
        objs.append(v.obj_pts[m])
        cams.append(v.cam_pts[m])
        projs.append(v.proj_pts[m])
        names.append(v.name if v.name else f"pose{k + 1}")

    cal_c = calibrate_device(objs, cams, cam_size, cam_dist, init=init, fix_aspect_ratio=fix_aspect_ratio,
                             iterations=iterations)
    cal_p = calibrate_device(objs, projs, proj_size, proj_dist, init=init, fix_aspect_ratio=fix_aspect_ratio,
                             iterations=iterations)
    Kc, dc, rvc, tvc, rms_c = cal_c.K, cal_c.coeffs, cal_c.rvecs, cal_c.tvecs, cal_c.rms
    Kp, dp, rms_p = cal_p.K, cal_p.coeffs, cal_p.rms
    o32, c32 = _as_cv(objs, cams)
    _, p32 = _as_cv(objs, projs)
    try:
        out = cv2.stereoCalibrate(o32, c32, p32, Kc, dc, Kp, dp, cam_size, flags=cv2.CALIB_FIX_INTRINSIC,
                                  criteria=_criteria(stereo_iterations))
    except cv2.error as e:
        raise CalibrationError(f"stereo step failed: {str(e).strip().splitlines()[-1]}") from None
    rms_s, R0, T0 = float(out[0]), np.asarray(out[5], float), np.asarray(out[6], float).ravel()
    frozen = {"cam_K": Kc.tolist(), "cam_dist": dc.tolist(), "proj_K": Kp.tolist(), "proj_dist": dp.tolist(),
              "R": R0.tolist(), "T": T0.tolist(), "cam_rms": rms_c, "proj_rms": rms_p, "stereo_rms": rms_s,
              "cam_init": cal_c.init, "proj_init": cal_p.init}
    info = {"frozen": frozen, "cam_dist_model": cam_dist, "proj_dist_model": proj_dist, "refined": bool(refine),
            "pose_names": names}
    warnings = []
    std = {}
    if refine:
        floor = 1e-3  # px: noise-free data have RMS ~ 0; keep the weight finite
        w_proj = max(rms_c, floor) / max(rms_p, floor) if balance else 1.0
        ref = refine_stereo(objs, cams, projs, Kc, dc, Kp, dp, R0, T0, rvc, tvc, cam_dist=cam_dist,
                            proj_dist=proj_dist, loss=loss, loss_scale=loss_scale, proj_weight=w_proj)
        Kc, dc, Kp, dp, R, T = ref.Kc, ref.dc, ref.Kp, ref.dp, ref.R, ref.T
        rv_board, tv_board = ref.rvecs, ref.tvecs
        res = ref.residuals
        cam_res = [r[0] for r in res]
        proj_res = [r[1] for r in res]
        cam_rms, proj_rms = _rms(cam_res), _rms(proj_res)
        stereo_rms = _rms(cam_res + proj_res)
        std = _std_dict(ref, len(dc), len(dp))
        info["refinement"] = {"loss": loss, "loss_scale": loss_scale, "proj_weight": w_proj, "status": ref.status,
                              "nfev": ref.nfev, "cost": ref.cost}
        if ref.status <= 0:
            warnings.append("joint refinement stopped at its evaluation limit; the result may not be converged")
        if not (Kc[0, 0] > 0 and Kc[1, 1] > 0 and Kp[0, 0] > 0 and Kp[1, 1] > 0):
            raise CalibrationError("joint refinement diverged (non-positive focal length); "
                                   "try --no-refine or more varied poses")
    else:
        R, T = R0, T0
        rv_board, tv_board = rvc, tvc
        cam_res, proj_res = [], []
        for j in range(len(objs)):
            pc = models.project(Kc, models.rvec_to_matrix(rvc[j]), tvc[j], objs[j])
            cam_res.append(cams[j] - Distortion("opencv", coeffs=tuple(dc)).distort(pc, Kc))
            Rp, tp = models.compose(R, T, models.rvec_to_matrix(rvc[j]), tvc[j])
            pp = Distortion("opencv", coeffs=tuple(dp)).distort(models.project(Kp, Rp, tp, objs[j]), Kp)
            proj_res.append(projs[j] - pp)
        cam_rms, proj_rms, stereo_rms = rms_c, rms_p, rms_s

    poses = []
    for j in range(len(objs)):
        Rc = models.rvec_to_matrix(rv_board[j])
        Rp, tp = models.compose(R, T, Rc, tv_board[j])
        poses.append({"name": names[j], "n_corners": int(len(objs[j])),
                      "camera_angles_deg": models.board_angles_deg(Rc, tv_board[j]).tolist(),
                      "projector_angles_deg": models.board_angles_deg(Rp, tp).tolist(),
                      "R_cam": Rc.tolist(), "t_cam": np.asarray(tv_board[j], float).tolist(),
                      "cam_rms": _rms([cam_res[j]]), "proj_rms": _rms([proj_res[j]]),
                      "stereo_rms": _rms([cam_res[j], proj_res[j]])})
    if len(views) < 3:
        warnings.append("only 2 poses: the multi-pose intrinsics are weakly constrained; use 3 or more")
    camera = Device(Kc, cam_size, Distortion("opencv", coeffs=tuple(float(c) for c in dc)))
    projector = Device(Kp, proj_size, Distortion("opencv", coeffs=tuple(float(c) for c in dp)))
    return Calibration(camera=camera, projector=projector, R=np.asarray(R, float), T=np.asarray(T, float).ravel(),
                       method="multi-pose", cam_rms=cam_rms, proj_rms=proj_rms, stereo_rms=stereo_rms, std=std,
                       poses=tuple(poses), views=tuple(views), warnings=tuple(warnings), info=info)
