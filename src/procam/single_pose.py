"""The seed method: procam calibration from ONE pose of a planar chessboard (METHOD §5-§10, §16).

Pipeline per pose (camera, then projector, then the procam extrinsics):

1. camera distortion: centre of distortion (COD) from the radial fundamental matrix, division-model
   ``k1, k2`` by the linear solve, undistortion (:mod:`procam.distortion`); the principal point is the
   COD. When the COD is unreliable (weak distortion) the default falls back to the image centre, says
   so, and widens the reported uncertainty (METHOD §5.2 [decision]);
2. homographies ``H_C^B`` (undistorted camera -> board) and ``H_P^B`` (projector -> board);
3. the principal-axis parameterisation (§7) and the two 6-parameter Levenberg-Marquardt problems (§8),
   each started from Zhang's closed form (§10) and from the paper's initial values; the valid
   lowest-cost solution is kept, mirror solutions (f <= 0, alpha <= 0, board behind the device) never;
4. optionally (``refine="joint"``, default) a joint maximum-likelihood refinement of the camera's
   ``(f, alpha, c, k1, k2, pose)`` on the **distorted** corners -- the staged estimate above is about
   1.5x the Cramer-Rao bound for f_c, the joint one reaches it;
5. ``R = R_p R_c^T, T = T_p - R T_c`` (camera -> projector, as OpenCV ``stereoCalibrate``);
6. pose angles, the paper's advice rule and the true degeneracy conditions (§10.4), and the standard
   deviation of every parameter from the Jacobian at the solution (:mod:`procam.uncertainty`); a
   focal length outside [0.2, 5] x the image diagonal is a failed estimate, not a number.

Real captures: per device, corners whose residual exceeds ``max(0.5 px, 5 robust sigma)`` are rejected
as outliers and the device refitted without them until stable (reported in the solution, in
``Calibration.poses`` and as a warning; ``reject_outliers=False`` turns it off); too few or collinear
corners raise :class:`~procam.errors.CalibrationError` saying how many are usable and needed.

Board frame: corner k at ``(i s, j s, 0) - centroid`` (centred; METHOD §1); pose ``(R, t)`` maps
board -> device. Angles are reported in degrees, in a board frame whose z axis points away from the
device (fronto-parallel <=> psi = nu = 0).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import cv2
import numpy as np
from scipy.optimize import least_squares

from . import distortion as dist
from . import models
from . import uncertainty as unc
from .calibration import Calibration, Device, Distortion
from .errors import CalibrationError
from .residuals import pnp, rms, stereo_pose

#: scale of the conditioned distortion coefficients: k1 = kappa1 / S^2, k2 = kappa2 / S^4 (METHOD §13)
KAPPA_SCALE = 1000.0
CAMERA_PARAMS = ("f_c", "alpha_c", "u0c", "v0c", "kappa1", "kappa2", "rx", "ry", "rz", "tx", "ty", "tz")
PROJECTOR_PARAMS = ("f_p", "v0p", "rx", "ry", "rz", "tx", "ty", "tz")
_LM = dict(method="lm", x_scale="jac", xtol=1e-12, ftol=1e-12, gtol=1e-12)
#: focal lengths outside this range x the image diagonal are impossible (diagonal fields of view ~136 .. ~11 deg)
PLAUSIBLE_F_RANGE = (0.2, 5.0)


# ----------------------------------------------------------------------------------------------
# results
@dataclass(frozen=True)
class _DeviceSolution:
    """Fields shared by :class:`CameraSolution` and :class:`ProjectorSolution` (documented there)."""

    K: np.ndarray
    distortion: Distortion
    R: np.ndarray
    t: np.ndarray
    rms_px: float
    residuals: np.ndarray
    std: dict
    angles_deg: np.ndarray
    cost: float
    warnings: tuple = ()
    params: np.ndarray | None = None
    covariance: np.ndarray | None = None
    mask: np.ndarray | None = None
    image_size: tuple | None = None
    info: dict = field(default_factory=dict)
    rejected: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    rejected_residuals_px: np.ndarray = field(default_factory=lambda: np.zeros(0))
    outlier_threshold_px: float = float("nan")


@dataclass(frozen=True)
class CameraSolution(_DeviceSolution):
    """Single-pose camera calibration.

    Attributes
    ----------
    K : (3, 3) intrinsics ``[[f, 0, u0], [0, alpha f, v0], [0, 0, 1]]``.
    distortion : :class:`procam.calibration.Distortion` (``"division"`` about the principal point,
        or ``"none"``).
    R, t : board -> camera pose, (3, 3) and (3,) board units.
    rms_px : RMS (Euclidean, per corner) of ``residuals`` in distorted pixels.
    residuals : (N, 2) observed minus predicted distorted pixels (NaN for corners not used).
    std : dict name -> standard deviation from the Jacobian at the solution (px, px^-2, px^-4, deg,
        board units). Keys: ``f_c, alpha_c, fy_c, u0c, v0c, k1, k2, angles_deg (3), t (3)``.
    angles_deg : (psi, nu, phi) of the board in the camera frame, degrees.
    cost : ``0.5 * sum(residuals^2)``.
    warnings : tuple of human-readable caveats.
    cod : :class:`procam.distortion.CODEstimate` or None (principal point given).
    principal_point_source : ``"cod"`` (centre of distortion, reliable), ``"joint"`` (COD weak, but the
        joint fit of all parameters pins the principal point), ``"image-center"`` (fallback: image
        centre, the prior mean of a MAP fit when ``refine="joint"``) or ``"given"``.
    staged : dict -- the paper's staged estimate (f, alpha, k1, k2, K, rms_px, start, cost) before
        the joint refinement.
    params, covariance : the full model's parameters ``CAMERA_PARAMS`` (12,) and their (12, 12)
        covariance (rows/columns of fixed parameters are 0, of assumed ones carry their prior).
    mask : (N,) bool, corners used (finite and not rejected as outliers).
    rejected : (n_rej,) int, indices (rows of the input arrays) of corners rejected as outliers;
        ``rejected_residuals_px`` (n_rej,) their residual norms (px) under the final model;
        ``outlier_threshold_px`` the rejection threshold of the last pass (NaN when rejection is off).
        ``residuals`` holds the rejected corners' residuals too.
    """

    cod: dist.CODEstimate | None = None
    principal_point_source: str = "cod"
    staged: dict = field(default_factory=dict)


@dataclass(frozen=True)
class ProjectorSolution(_DeviceSolution):
    """Single-pose projector calibration (``u0p`` fixed, ``alpha_p = 1``, no distortion).

    Attributes as :class:`CameraSolution`; ``params`` are ``PROJECTOR_PARAMS`` = (f_p, v0p, rvec (3),
    t (3)) of the pinhole model with ``u0`` fixed, ``covariance`` (8, 8); ``std`` keys ``f_p, v0p,
    angles_deg, t``; ``H_pb`` the projector -> board homography; ``info["theta"]`` the principal-axis
    parameters (f_p, v0p, phi_p, O (3)) the LM solved for; ``rejected``, ``rejected_residuals_px``,
    ``outlier_threshold_px`` as for the camera.
    """

    H_pb: np.ndarray | None = None
    u0: float = float("nan")


# ----------------------------------------------------------------------------------------------
# geometry helpers
def _rz(phi: float) -> np.ndarray:
    c, s = np.cos(phi), np.sin(phi)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def principal_axis_frame(Q, O) -> np.ndarray:
    """Rotation A (3, 3), columns = device axes in board coordinates, with z along ``Q - O`` (§7.1)."""
    Q = np.asarray(Q, float).reshape(3)
    O = np.asarray(O, float).reshape(3)
    Z = Q - O
    Y = np.cross(Z, [1.0, 0.0, 0.0])
    if np.linalg.norm(Y) < 1e-6 * np.linalg.norm(Z):
        Y = np.cross(Z, [0.0, 1.0, 0.0])
    X = np.cross(Y, Z)
    return np.column_stack([X / np.linalg.norm(X), Y / np.linalg.norm(Y), Z / np.linalg.norm(Z)])


def pa_extrinsics(phi: float, O, Q):
    """Board -> device pose ``(R, t)`` of the principal-axis model (§7.2): ``R = A_j^T, t = -R O``.

    ``phi`` (rad) is the roll about the principal axis, ``O`` (3,) the device centre and ``Q`` (3,)
    the board point on the principal axis, both in board coordinates.
    """
    Aj = principal_axis_frame(Q, O) @ _rz(phi)
    R = Aj.T
    return R, -R @ np.asarray(O, float).reshape(3)


def _phi_of(R, O, Q) -> float:
    M = principal_axis_frame(Q, O).T @ np.asarray(R).T
    return float(np.arctan2(M[1, 0], M[0, 0]))


def _dehom(H, pts) -> np.ndarray:
    p = np.column_stack([pts, np.ones(len(pts))]) @ np.asarray(H).T
    return p[:, :2] / p[:, 2:3]


def homography(src, dst, *, refine: bool = True) -> np.ndarray:
    """Homography ``dst ~ H src`` (3, 3), ``H[2, 2] = 1``: normalised DLT, then LM on the dst-side error.

    Exact (to rounding) on noise-free correspondences, which ``cv2.findHomography`` is not
    (its refinement stops at ~1e-6 px). Raises :class:`CalibrationError` if the points are degenerate.
    """
    src = np.asarray(src, float).reshape(-1, 2)
    dst = np.asarray(dst, float).reshape(-1, 2)
    if len(src) < 4:
        raise CalibrationError(f"homography needs >= 4 points, got {len(src)}")
    Ts, Td = dist._normalizer(src), dist._normalizer(dst)
    a = np.column_stack([src, np.ones(len(src))]) @ Ts.T
    b = np.column_stack([dst, np.ones(len(dst))]) @ Td.T
    z = np.zeros_like(a)
    A = np.vstack([np.hstack([a, z, -b[:, :1] * a]), np.hstack([z, a, -b[:, 1:2] * a])])
    _, s, Vt = np.linalg.svd(A)
    if s[-2] <= 1e-12 * s[0]:
        raise CalibrationError("homography estimation failed (corners collinear or too few)")
    H = np.linalg.solve(Td, Vt[-1].reshape(3, 3) @ Ts)
    if not np.all(np.isfinite(H)) or abs(H[2, 2]) < 1e-300:
        raise CalibrationError("homography estimation failed (corners collinear or too few)")
    H = H / H[2, 2]
    if refine:
        def fun(h):
            return (_dehom(np.append(h, 1.0).reshape(3, 3), src) - dst).ravel()

        with np.errstate(all="ignore"):
            r = least_squares(fun, H.ravel()[:8], method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15)
        if np.all(np.isfinite(r.x)) and r.cost <= 0.5 * np.sum(fun(H.ravel()[:8]) ** 2):
            H = np.append(r.x, 1.0).reshape(3, 3)
    return H


def zhang_camera(H_bc, principal_point):
    """Closed-form ``(f, alpha)`` from the board -> image homography, known principal point (§10.2).

    Returns None when the pose is (near-)degenerate (no positive solution).
    """
    u0, v0 = principal_point
    Hs = np.array([[1.0, 0, -u0], [0, 1.0, -v0], [0, 0, 1.0]]) @ np.asarray(H_bc, float)
    Hs = Hs / np.linalg.norm(Hs)
    p, q = Hs[:, 0], Hs[:, 1]
    A = np.array([[p[0] * q[0], p[1] * q[1]], [p[0] ** 2 - q[0] ** 2, p[1] ** 2 - q[1] ** 2]])
    b = -np.array([p[2] * q[2], p[2] ** 2 - q[2] ** 2])
    try:
        a, bb = np.linalg.solve(A, b)
    except np.linalg.LinAlgError:
        return None
    if not (np.isfinite(a) and np.isfinite(bb)) or a <= 0 or bb <= 0:
        return None
    return float(a ** -0.5), float(np.sqrt(a / bb))


def zhang_projector(H_bp, u0: float):
    """Closed-form ``(f, v0)`` from the board -> projector homography, known ``u0`` and alpha = 1 (§10.2)."""
    Hs = np.array([[1.0, 0, -u0], [0, 1.0, 0], [0, 0, 1.0]]) @ np.asarray(H_bp, float)
    Hs = Hs / np.linalg.norm(Hs)
    p, q = Hs[:, 0], Hs[:, 1]
    A = np.array([[-(p[1] * q[2] + p[2] * q[1]), p[2] * q[2]],
                  [-2 * (p[1] * p[2] - q[1] * q[2]), p[2] ** 2 - q[2] ** 2]])
    b = -np.array([p[0] * q[0] + p[1] * q[1], p[0] ** 2 + p[1] ** 2 - q[0] ** 2 - q[1] ** 2])
    try:
        v0, c = np.linalg.solve(A, b)
    except np.linalg.LinAlgError:
        return None
    if not (np.isfinite(v0) and np.isfinite(c)) or c - v0 ** 2 <= 0:
        return None
    return float(np.sqrt(c - v0 ** 2)), float(v0)


def pose_from_homography(K, H_bd):
    """Board -> device pose from the board -> image homography and K (§10.3); board in front."""
    M = np.linalg.solve(np.asarray(K, float), np.asarray(H_bd, float))
    lam = 1.0 / np.sqrt(np.linalg.norm(M[:, 0]) * np.linalg.norm(M[:, 1]))
    M = M * lam
    if M[2, 2] < 0:
        M = -M
    r1, r2 = M[:, 0], M[:, 1]
    U, _, Vt = np.linalg.svd(np.column_stack([r1, r2, np.cross(r1, r2)]))
    R = U @ Vt
    if np.linalg.det(R) < 0:
        R = U @ np.diag([1, 1, -1]) @ Vt
    return R, M[:, 2].copy()


#: (psi, nu, phi) degrees of a board -> device pose (kept here for callers; see
#: :func:`procam.models.board_angles_deg`).
board_angles_deg = models.board_angles_deg


def _device_side(R, t) -> float:
    """+1 if the device centre ``O = -R^T t`` (board frame) is on the board's +z side, else -1."""
    return 1.0 if models.invert(R, t)[1][2] > 0 else -1.0


# ----------------------------------------------------------------------------------------------
# the two 6-parameter problems
def _valid_pose(R, t, M, side) -> bool:
    depth = (M @ R.T + t)[:, 2]
    return bool(np.all(depth > 0) and _device_side(R, t) == side)


def _run_starts(fun, starts, check):
    """LM from each start; returns (best, all) where each is a dict(x, cost, start, valid)."""
    runs = []
    for name, x0 in starts:
        x0 = np.asarray(x0, float)
        try:
            with np.errstate(all="ignore"):
                r = least_squares(fun, x0, max_nfev=300, **_LM)
            x, cost = r.x, float(r.cost)
            ok = bool(np.isfinite(cost) and np.all(np.isfinite(x)) and check(x))
        except (ValueError, np.linalg.LinAlgError, FloatingPointError):
            x, cost, ok = x0, float("inf"), False
        runs.append(dict(x=x, cost=cost, start=name, valid=ok))
    good = [r for r in runs if r["valid"]]
    best = min(good, key=lambda r: r["cost"]) if good else None
    return best, runs


def _side_and_pose(K0, H_bd):
    R0, t0 = pose_from_homography(K0, H_bd)
    return _device_side(R0, t0), R0, t0, models.invert(R0, t0)[1]


def _board_width(M) -> float:
    span = np.ptp(M[:, :2], axis=0)
    return float(max(span.max(), 1e-9))


def solve_camera_lm(obj, und, principal_point, image_size, *, board_width=None):
    """The camera's 6-parameter LM (§8.1) from the closed-form and the paper's starts.

    Parameters
    ----------
    obj : (N, 3) board points; und : (N, 2) undistorted pixels (all finite).
    principal_point : (u0, v0), fixed. image_size : (W, H) for the paper's f start.
    board_width : board width w_b for the paper's start O = (0, 0, +-2 w_b) (default: the corners' span).

    Returns
    -------
    dict with f, alpha, phi, O, Q, R, t, cost, start, runs, H_bc, closed_form.
    """
    M = np.asarray(obj, float)
    u0, v0 = principal_point
    H_bc = homography(M[:, :2], und)
    Q = np.append(_dehom(np.linalg.inv(H_bc), np.array([[u0, v0]]))[0], 0.0)
    W, Hh = image_size
    f_paper = float(np.hypot(W, Hh))
    cf = zhang_camera(H_bc, (u0, v0))
    f0, a0 = cf if cf else (f_paper, 1.0)
    K0 = models.intrinsic_matrix(f0, u0, v0, a0)
    side, R0, t0, O0 = _side_and_pose(K0, H_bc)
    wb = board_width or _board_width(M)

    def fun(x):
        K = models.intrinsic_matrix(x[0], u0, v0, x[1])
        R, t = pa_extrinsics(x[2], x[3:6], Q)
        return (models.project(K, R, t, M) - und).ravel()

    def check(x):
        if x[0] <= 0 or x[1] <= 0:
            return False
        R, t = pa_extrinsics(x[2], x[3:6], Q)
        return _valid_pose(R, t, M, side)

    starts = []
    if cf:
        starts.append(("closed-form", [cf[0], cf[1], _phi_of(R0, O0, Q), *O0]))
    starts.append(("paper", [f_paper, 1.0, 0.0, 0.0, 0.0, side * 2 * wb]))
    best, runs = _run_starts(fun, starts, check)
    if best is None:
        return dict(ok=False, runs=runs, H_bc=H_bc, Q=Q, closed_form=cf)
    x = best["x"]
    R, t = pa_extrinsics(x[2], x[3:6], Q)
    return dict(ok=True, f=float(x[0]), alpha=float(x[1]), phi=float(x[2]), O=x[3:6].copy(), Q=Q, R=R, t=t,
                cost=best["cost"], start=best["start"], runs=runs, H_bc=H_bc, closed_form=cf,
                residuals=fun(x).reshape(-1, 2))


def _proj_Q(H_pb, u0, v0):
    return np.append(_dehom(H_pb, np.array([[u0, v0]]))[0], 0.0)


def _proj_pose(x, H_pb, u0):
    return pa_extrinsics(x[2], x[3:6], _proj_Q(H_pb, u0, x[1]))


def solve_projector_lm(obj, proj, proj_size, *, u0=None, board_width=None):
    """The projector's 6-parameter LM (§8.2): theta = (f_p, v0p, phi_p, O), u0 fixed, alpha = 1.

    ``Q(v0) = H_P^B (u0, v0, 1)`` is recomputed inside every residual evaluation.
    """
    M = np.asarray(obj, float)
    W, Hh = proj_size
    u0 = W / 2.0 if u0 is None else float(u0)
    H_bp = homography(M[:, :2], proj)
    H_pb = np.linalg.inv(H_bp)
    H_pb = H_pb / H_pb[2, 2]
    f_paper = float(np.hypot(W, Hh))
    cf = zhang_projector(H_bp, u0)
    f0, v00 = cf if cf else (f_paper, Hh / 2.0)
    side, R0, t0, O0 = _side_and_pose(models.intrinsic_matrix(f0, u0, v00), H_bp)
    wb = board_width or _board_width(M)

    def fun(x):
        K = models.intrinsic_matrix(x[0], u0, x[1])
        R, t = _proj_pose(x, H_pb, u0)
        return (models.project(K, R, t, M) - proj).ravel()

    def check(x):
        if x[0] <= 0:
            return False
        R, t = _proj_pose(x, H_pb, u0)
        return _valid_pose(R, t, M, side)

    starts = []
    if cf:
        starts.append(("closed-form", [f0, v00, _phi_of(R0, O0, _proj_Q(H_pb, u0, v00)), *O0]))
    starts.append(("paper", [f_paper, Hh / 2.0, 0.0, 0.0, 0.0, side * 2 * wb]))
    best, runs = _run_starts(fun, starts, check)
    if best is None:
        return dict(ok=False, runs=runs, H_pb=H_pb, u0=u0, closed_form=cf)
    x = best["x"]
    R, t = _proj_pose(x, H_pb, u0)
    return dict(ok=True, x=x.copy(), f=float(x[0]), v0=float(x[1]), R=R, t=t, cost=best["cost"],
                start=best["start"], runs=runs, H_pb=H_pb, u0=u0, closed_form=cf,
                residuals=fun(x).reshape(-1, 2), fun=fun)


# ----------------------------------------------------------------------------------------------
# camera: full (distorted) model
def camera_predict(p, obj) -> np.ndarray:
    """Distorted pixels (N, 2) of board points ``obj`` (N, 3) for the full camera parameters ``p``.

    ``p = (f, alpha, u0, v0, kappa1, kappa2, rvec (3), t (3))`` with ``k1 = kappa1 / S^2``,
    ``k2 = kappa2 / S^4``, ``S = KAPPA_SCALE``; the division model's centre is the principal point.
    Points where the division model has no inverse are NaN.
    """
    p = np.asarray(p, float)
    K = models.intrinsic_matrix(p[0], p[2], p[3], p[1])
    mu = models.project(K, models.rvec_to_matrix(p[6:9]), p[9:12], obj)
    k1, k2 = p[4] / KAPPA_SCALE ** 2, p[5] / KAPPA_SCALE ** 4
    if k1 == 0 and k2 == 0:
        return mu
    return models.distort_division(mu, p[2:4], k1, k2)


def _camera_residual_fn(obj, cam, p_fixed, free, pp_prior=None):
    """Residuals (2N,) [+ 2 prior residuals ``w (pp - pp_mean)`` when ``pp_prior = (pp_mean, w)``]."""
    p_fixed = np.asarray(p_fixed, float)

    def fun(x):
        p = p_fixed.copy()
        p[free] = x
        r = (camera_predict(p, obj) - cam).ravel()
        r = np.where(np.isfinite(r), r, 1e3)
        if pp_prior is not None:
            r = np.concatenate([r, pp_prior[1] * (p[2:4] - pp_prior[0])])
        return r

    return fun


def _full_params(K, c, k1, k2, R, t):
    return np.array([K[0, 0], K[1, 1] / K[0, 0], c[0], c[1], k1 * KAPPA_SCALE ** 2, k2 * KAPPA_SCALE ** 4,
                     *models.matrix_to_rvec(R), *np.asarray(t, float).reshape(3)])


_rms = rms  # NaN-skipping RMS (procam.residuals.rms)


def _clean(obj_pts, img_pts, what):
    obj = np.asarray(obj_pts, float)
    if obj.ndim != 2 or obj.shape[1] not in (2, 3):
        raise CalibrationError(f"{what}: board points must be (N, 2) or (N, 3), got {obj.shape}")
    if obj.shape[1] == 2:
        obj = np.column_stack([obj, np.zeros(len(obj))])
    img = np.asarray(img_pts, float).reshape(-1, 2)
    if len(img) != len(obj):
        raise CalibrationError(f"{what}: {len(obj)} board points but {len(img)} image points")
    mask = np.isfinite(obj).all(1) & np.isfinite(img).all(1)
    return obj, img, mask


def _inside(pt, size) -> bool:
    return bool(-0.5 <= pt[0] <= size[0] - 0.5 and -0.5 <= pt[1] <= size[1] - 0.5)


# ----------------------------------------------------------------------------------------------
# input checks and outlier rejection
#: defaults of the outlier rejection (documented in :func:`calibrate_camera`)
OUTLIER_K = 5.0
OUTLIER_FLOOR_PX = 0.5
OUTLIER_MAX_FRACTION = 0.2
OUTLIER_MAX_ITER = 5


def _spread_ok(xy, rel_tol: float = 1e-12) -> bool:
    """True unless the planar points (n, 2) are collinear or all but one are (no homography then).

    The test is on the eigenvalues of the 2x2 scatter matrix of the points, and of the points with
    each one left out (rank-one downdates, O(n)): ``lambda_min <= rel_tol * lambda_max`` is a line.
    """
    xy = np.asarray(xy, float).reshape(-1, 2)
    n = len(xy)
    if n < 4:
        return False

    def flat(S, Q, k):
        m = S / k
        C = Q / k - m[..., :, None] * m[..., None, :]
        tr = C[..., 0, 0] + C[..., 1, 1]
        det = C[..., 0, 0] * C[..., 1, 1] - C[..., 0, 1] * C[..., 1, 0]
        disc = np.sqrt(np.maximum(tr * tr / 4 - det, 0.0))
        lmax, lmin = tr / 2 + disc, tr / 2 - disc
        return lmin <= rel_tol * np.maximum(lmax, 1e-300)

    xy = xy - xy.mean(axis=0)
    S, Q = xy.sum(axis=0), xy.T @ xy
    if flat(S, Q, n):
        return False
    leave_one = flat(S - xy, Q - xy[:, :, None] * xy[:, None, :], n - 1)
    return not bool(np.any(leave_one))


def _check_corners(obj, mask, min_points: int, name: str, what: str, hint: str) -> None:
    """Raise :class:`CalibrationError` (saying how many corners are usable and needed) unless the
    usable corners ``obj[mask]`` can determine a single-pose fit."""
    n, n_all = int(mask.sum()), len(mask)
    need = (f"single-pose calibration needs at least {max(min_points, 4)}, spread over at least 2 rows and "
            f"2 columns of the board")
    if n < min_points:
        raise CalibrationError(f"pose {name!r}: only {n} of {n_all} {what} are usable; {need}; {hint}")
    if not _spread_ok(obj[mask, :2]):
        raise CalibrationError(f"pose {name!r}: the {n} usable {what} all (or all but one) lie on one line of the "
                               f"board (e.g. one row or column); {need}; {hint}")


def robust_sigma(residuals) -> float:
    """Robust standard deviation (px) of one residual component: ``1.4826 * MAD`` of the x and y
    components of the (n, 2) residuals pooled (non-finite rows ignored)."""
    r = np.asarray(residuals, float).reshape(-1, 2)
    r = r[np.isfinite(r).all(1)].ravel()
    if r.size == 0:
        return float("nan")
    return float(1.4826 * np.median(np.abs(r - np.median(r))))


def _prescreen(obj, obs, valid, k: float, floor_px: float):
    """Corners consistent with a least-median-of-squares homography board -> image: ((N,) bool, robust
    sigma of the homography's residuals in px), or (None, nan).

    Only a rescue start for poses whose plain fit is wrecked by gross outliers (hundreds of px): the
    threshold ``max(floor, k * robust sigma)`` of the homography residuals is wide enough for lens
    distortion, and every corner is re-tested against the real model afterwards.
    """
    src, dst = obj[valid, :2].astype(np.float64), obs[valid].astype(np.float64)
    try:
        H, _ = cv2.findHomography(src, dst, cv2.LMEDS)
    except cv2.error:
        return None, float("nan")
    if H is None or not np.all(np.isfinite(H)):
        return None, float("nan")
    with np.errstate(all="ignore"):
        r = _dehom(H, src) - dst
        norm = np.hypot(r[:, 0], r[:, 1])
    sig = robust_sigma(r)
    keep = norm <= max(floor_px, k * sig)
    out = np.zeros_like(valid)
    out[np.flatnonzero(valid)[keep]] = True
    return out, sig


def _fit_robust(fit, predict, obs, obj, valid, *, enabled: bool, k: float, floor_px: float, max_fraction: float,
                max_iter: int, min_points: int):
    """Fit, flag corners whose residual norm exceeds ``max(floor_px, k * robust_sigma)``, refit without
    them, repeat until the set of used corners is stable (at most ``max_iter`` refits).

    ``fit(used_mask) -> solution``; ``predict(solution) -> (N, 2)`` for every row. Rejected corners are
    re-tested against every new fit (a corner pulled off by a gross outlier comes back). Nothing is
    rejected when more than ``max_fraction`` of the corners would be (the model, not a few corners,
    is wrong), or when the rest would be too few or degenerate. When the plain fit fails, flags
    outliers, or fits worse than a plain homography (gross outliers wrecked it), a second start
    without the corners a robust (LMedS) homography calls outliers competes with it.

    Returns (solution, used (N,) bool, threshold_px, notes list of str).
    """
    if not enabled:
        return fit(valid), valid, float("nan"), []
    n_valid = int(valid.sum())

    def flag(sol):
        with np.errstate(all="ignore"):
            res = predict(sol) - obs
            norm = np.hypot(res[:, 0], res[:, 1])
        thr = max(float(floor_px), float(k) * robust_sigma(res[valid]))
        return valid & (norm <= thr), thr          # NaN (unpredictable) counts as an outlier

    def too_many(mask):
        return n_valid - int(mask.sum()) > max_fraction * n_valid

    def median_residual(sol):
        with np.errstate(all="ignore"):
            res = predict(sol) - obs
            norm = np.hypot(res[valid, 0], res[valid, 1])
        return float(np.median(np.where(np.isfinite(norm), norm, np.inf)))

    error = None
    try:
        sol, used = fit(valid), valid.copy()
    except CalibrationError as e:
        sol, used, error = None, valid.copy(), e
    # a second start without the corners a robust homography calls outliers (outliers can wreck the
    # COD, the closed forms and the LM starts) when the plain fit failed, flags outliers or fits worse
    # than a homography; the start with the lower median residual over all corners (least median of
    # squares) wins, and every corner is re-tested below
    pre, sig_h = _prescreen(obj, obs, valid, k, floor_px)
    suspicious = sol is None
    if not suspicious:
        with np.errstate(all="ignore"):
            sig_m = robust_sigma(predict(sol)[valid] - obs[valid])
        suspicious = bool(flag(sol)[0].sum() < n_valid or not sig_m <= 2.0 * sig_h + 1e-9)
    if suspicious and pre is not None and min_points <= pre.sum() < n_valid and _spread_ok(obj[pre, :2]):
        try:
            sol2 = fit(pre)
            if sol is None or median_residual(sol2) < median_residual(sol):
                sol, used = sol2, pre
        except CalibrationError:
            pass
    if sol is None:
        raise error
    seen = {used.tobytes()}
    notes: list[str] = []
    thr = float("nan")
    for it in range(max_iter + 1):
        new, thr_i = flag(sol)
        if too_many(new):
            notes.append(f"{n_valid - int(new.sum())} of {n_valid} corners have residuals above {thr_i:.2f} px: "
                         f"the model does not fit this pose well (not a few outliers), so no corner was rejected")
            if used.sum() < n_valid:      # an earlier pass rejected some: go back to all corners
                try:
                    sol, used = fit(valid), valid.copy()
                except CalibrationError:
                    pass
            thr = thr_i
            break
        if int(new.sum()) < min_points or not _spread_ok(obj[new, :2]):
            break
        thr = thr_i
        if np.array_equal(new, used) or new.tobytes() in seen or it == max_iter:
            break
        try:
            sol_new = fit(new)
        except CalibrationError:
            break
        sol, used = sol_new, new
        seen.add(new.tobytes())
    return sol, used, thr, notes


def _rejection_report(sol, predict, obs, valid, used, thr, notes, name: str, what: str, k: float,
                      floor_px: float, max_list: int = 8):
    """The solution with all valid corners' residuals, the rejected corners and their warning."""
    with np.errstate(all="ignore"):
        res = obs - predict(sol)  # observed - predicted, as documented on the solutions
    res[~valid] = np.nan
    rej = np.flatnonzero(valid & ~used)
    norms = np.hypot(res[rej, 0], res[rej, 1])
    warnings = list(sol.warnings)
    if len(rej):
        order = np.argsort(-np.nan_to_num(norms, nan=np.inf))
        listed = ", ".join(f"#{rej[i]} ({norms[i]:.1f} px)" for i in order[:max_list])
        more = f" and {len(rej) - max_list} more" if len(rej) > max_list else ""
        warnings.append(f"pose {name!r}: {len(rej)} of {int(valid.sum())} {what} corners rejected as outliers "
                        f"(residual > {thr:.2f} px = max({floor_px:g} px, {k:g} x robust sigma)): {listed}{more}; "
                        f"the fit uses the other {int(used.sum())} (reject_outliers=False keeps them)")
    warnings += [f"pose {name!r}: {what}: {n}" for n in notes]
    return replace(sol, residuals=res, rejected=rej, rejected_residuals_px=norms, outlier_threshold_px=float(thr),
                   warnings=tuple(warnings))


def _staged_camera(M, m, c, size, use_dist, n_coeffs, board_width, name, warnings):
    """METHOD §5.3-§8.1 with the principal point / COD ``c``: returns (p_full (12,), staged dict, fit_k2)."""
    k1 = k2 = 0.0
    fit_k2 = use_dist and n_coeffs >= 2
    if use_dist:
        k1, k2, _ = dist.estimate_division(M, m, c, n_coeffs=n_coeffs)
        r2 = np.sum((m - c) ** 2, axis=1)
        if np.any(1 + k1 * r2 + k2 * r2 * r2 < 0.1) and n_coeffs >= 2:
            k1, k2, _ = dist.estimate_division(M, m, c, n_coeffs=1)
            fit_k2 = False
            warnings.append(f"pose {name!r}: two-term division model folded over the board; k2 set to 0")
        if np.any(1 + k1 * r2 + k2 * r2 * r2 < 0.1):
            k1 = k2 = 0.0
            warnings.append(f"pose {name!r}: division model unusable on this pose; distortion set to 0")
    und = models.undistort_division(m, c, k1, k2) if use_dist else m.copy()
    lm = solve_camera_lm(M, und, c, size, board_width=board_width)
    if not lm["ok"]:
        raise CalibrationError(f"pose {name!r}: camera LM found no valid (non-mirror) solution from any "
                               f"start; the pose is probably degenerate (board fronto-parallel?)")
    K_st = models.intrinsic_matrix(lm["f"], c[0], c[1], lm["alpha"])
    p_staged = _full_params(K_st, c, k1, k2, lm["R"], lm["t"])
    staged = dict(f=lm["f"], alpha=lm["alpha"], principal_point=np.array(c, float), k1=k1, k2=k2, K=K_st,
                  R=lm["R"], t=lm["t"], start=lm["start"], cost_undistorted=lm["cost"],
                  rms_undistorted_px=_rms(lm["residuals"]), closed_form=lm["closed_form"],
                  starts=[(r["start"], r["cost"], r["valid"]) for r in lm["runs"]],
                  rms_px=_rms(camera_predict(p_staged, M) - m))
    return p_staged, staged, fit_k2


def _joint_camera(M, m, p0, free, pp_prior, size, max_nfev=150):
    """Joint ML/MAP refinement of the full camera model from ``p0``; returns (p, cost) or (None, inf).

    The result is rejected if it is invalid, fits worse than ``p0``, or puts the camera on the other
    side of the board than the (staged) start ``p0`` does (a mirror solution).
    """
    fun = _camera_residual_fn(M, m, p0, free, pp_prior)
    try:
        with np.errstate(all="ignore"):
            r = least_squares(fun, p0[free], max_nfev=max_nfev, **_LM)
    except (ValueError, np.linalg.LinAlgError):  # pragma: no cover - guard
        return None, float("inf")
    pj = np.array(p0, float)
    pj[free] = r.x
    if not np.all(np.isfinite(pj)) or pj[0] <= 0 or pj[1] <= 0 or not _inside(pj[2:4], size):
        return None, float("inf")
    Rj = models.rvec_to_matrix(pj[6:9])
    side = _device_side(models.rvec_to_matrix(p0[6:9]), p0[9:12])  # the start's side, not the result's
    if not _valid_pose(Rj, pj[9:12], M, side) or not np.all(np.isfinite(camera_predict(pj, M))):
        return None, float("inf")
    if r.cost > 0.5 * np.sum(fun(p0[free]) ** 2) + 1e-12:
        return None, float("inf")
    return pj, float(r.cost)


def calibrate_camera(obj_pts, cam_pts, image_size, *, principal_point=None, distortion: str | None = "division",
                     cod: str = "auto", refine: str = "joint", n_coeffs: int = 2,
                     min_cod_score: float = dist.MIN_COD_SCORE, pp_prior_std: float | None = None,
                     pp_prior_fraction: float = 0.025, pp_max_std: float | None = None,
                     board_width: float | None = None, reject_outliers: bool = True,
                     outlier_k: float = OUTLIER_K, outlier_floor_px: float = OUTLIER_FLOOR_PX,
                     outlier_max_fraction: float = OUTLIER_MAX_FRACTION, outlier_max_iter: int = OUTLIER_MAX_ITER,
                     min_points: int = 8, name: str = "view") -> CameraSolution:
    """Single-pose camera calibration: intrinsics, division distortion and board pose.

    Parameters
    ----------
    obj_pts : (N, 3) or (N, 2) board points (board units; z = 0).
    cam_pts : (N, 2) **distorted** camera pixels; rows with NaN are ignored.
    image_size : (width, height) in pixels.
    principal_point : (u0, v0), optional
        Known principal point (then no COD step; also the centre of distortion). The paper's
        simulation uses this with ``distortion=None``.
    distortion : ``"division"`` (default) or None/``"none"`` (pinhole only).
    cod : ``"auto"`` (use the COD when reliable, else fall back to the image centre with a warning),
        ``"paper"`` (always use the COD, as the paper), ``"image-center"`` (always fall back).
    refine : ``"joint"`` (default; ML refinement of f, alpha, principal point, k1, k2 and pose on the
        distorted corners -- the principal point stays fixed when it is assumed or given) or
        ``"none"`` (the paper's staged estimate).
    n_coeffs : 1 or 2 division coefficients.
    min_cod_score : threshold on the COD observability ``s8/s9``.
    pp_prior_std : float, optional
        Standard deviation (px) of an **assumed** principal point (image-centre fallback) used to
        widen the reported uncertainty; default ``pp_prior_fraction * max(W, H)``.
    pp_prior_fraction : default prior std as a fraction of the larger image side (0.025: real
        lenses put the principal point within a few percent of the image centre).
    pp_max_std : float, optional
        With ``cod="auto"`` and a weak COD, the joint fit's own principal point (pp free, no prior) is
        accepted when its data-only std is at most this (px; default ``pp_prior_std``): the corners then
        pin it better than the image-centre assumption would. Otherwise the image centre is used as
        the mean of a Gaussian prior (MAP) and a warning says so.
    board_width : w_b for the paper's initial distance 2 w_b (default: the span of the corners).
    reject_outliers : bool
        After the fit, corners whose residual norm exceeds ``max(outlier_floor_px, outlier_k *
        sigma_r)`` are rejected and the whole pose is refitted without them, until the set is stable
        (at most ``outlier_max_iter`` refits; a rejected corner comes back if a later fit explains it).
        ``sigma_r`` = 1.4826 MAD of the residual components (a robust noise estimate). With Gaussian
        noise a clean corner exceeds ``k sigma`` with probability ``exp(-k^2 / 2)`` (4e-6 for the
        default k = 5; the floor of 0.5 px keeps every corner of clean, low-noise data). Nothing is
        rejected when more than ``outlier_max_fraction`` (0.2) of the corners would be: then the model,
        not a few corners, is wrong, and a warning says so. Rejections are reported in
        ``rejected``/``rejected_residuals_px`` and as a warning.
    min_points : minimum number of usable corners.
    name : pose name used in messages.

    Returns
    -------
    CameraSolution

    Raises
    ------
    CalibrationError
        Too few corners, no valid (non-mirror) solution, or ``cod="paper"`` with no finite COD.
    """
    obj, cam, mask = _clean(obj_pts, cam_pts, f"pose {name!r}")
    if image_size is None:
        raise CalibrationError(f"pose {name!r}: the camera image size is unknown; pass image_size=(W, H)")
    W, Hh = int(image_size[0]), int(image_size[1])
    if cod not in ("auto", "paper", "image-center"):
        raise ValueError(f"cod must be 'auto', 'paper' or 'image-center', got {cod!r}")
    if refine not in ("joint", "none", None):
        raise ValueError(f"refine must be 'joint' or 'none', got {refine!r}")
    _check_corners(obj, mask, min_points, name, "camera corners", "check the board detection")
    kw = dict(principal_point=principal_point, distortion=distortion, cod=cod, refine=refine, n_coeffs=n_coeffs,
              min_cod_score=min_cod_score, pp_prior_std=pp_prior_std, pp_prior_fraction=pp_prior_fraction,
              pp_max_std=pp_max_std, board_width=board_width, name=name)

    def predict(sol):
        return camera_predict(sol.params, obj)

    sol, used, thr, notes = _fit_robust(lambda u: _camera_fit(obj, cam, u, (W, Hh), **kw), predict, cam, obj, mask,
                                        enabled=reject_outliers, k=outlier_k, floor_px=outlier_floor_px,
                                        max_fraction=outlier_max_fraction, max_iter=outlier_max_iter,
                                        min_points=min_points)
    return _rejection_report(sol, predict, cam, mask, used, thr, notes, name, "camera", outlier_k, outlier_floor_px)


def _camera_fit(obj, cam, mask, image_size, *, principal_point, distortion, cod, refine, n_coeffs, min_cod_score,
                pp_prior_std, pp_prior_fraction, pp_max_std, board_width, name) -> CameraSolution:
    """One single-pose camera fit on the corners ``mask`` (see :func:`calibrate_camera`)."""
    W, Hh = image_size
    M, m = obj[mask], cam[mask]
    use_dist = distortion not in (None, "none", False)
    warnings: list[str] = []
    center_img = np.array([(W - 1) / 2.0, (Hh - 1) / 2.0])
    sigma_pp = pp_prior_std if pp_prior_std is not None else pp_prior_fraction * max(W, Hh)

    # 1. principal point / centre of distortion
    cod_est = None
    fallback_reason = None      # COD unreliable with cod="auto": the principal point comes from a prior
    map_ok = False              # the MAP fit (prior on the principal point) was accepted
    if principal_point is not None:
        c = np.asarray(principal_point, float).reshape(2)
        pp_source = "given"
    else:
        cod_est = dist.estimate_cod(M, m, image_size=(W, Hh), min_score=min_cod_score) if use_dist else None
        if use_dist and cod == "paper":
            if not np.all(np.isfinite(cod_est.center)):
                raise CalibrationError(f"pose {name!r}: the centre of distortion could not be computed "
                                       f"({cod_est.reason}); use cod='auto'")
            c, pp_source = cod_est.center.copy(), "cod"
            if not cod_est.reliable:
                warnings.append(f"pose {name!r}: centre of distortion unreliable ({cod_est.reason}) but used "
                                f"as the principal point (cod='paper'): f_c may be wrong by 10 % or more")
        elif use_dist and cod == "auto" and cod_est.reliable:
            c, pp_source = cod_est.center.copy(), "cod"
        else:
            c, pp_source = center_img.copy(), "image-center"
            if use_dist and cod == "auto":
                fallback_reason = cod_est.reason

    # 2.-3. the paper's staged estimate: division model (linear, given c), undistortion, 6-parameter LM
    p_staged, staged, fit_k2 = _staged_camera(M, m, c, (W, Hh), use_dist, n_coeffs, board_width, name, warnings)

    # 4. joint refinement
    free = np.ones(12, bool)
    if not use_dist:
        free[4:6] = False
    elif not fit_k2:
        free[5] = False
    if pp_source == "given" or (pp_source == "image-center" and not use_dist):
        free[2:4] = False
    p = p_staged.copy()
    typical = np.array([1, 1, 1, 1, 0.01, 0.01, 0.01, 0.01, 0.01, 1, 1, 1.0])
    if refine == "joint" and pp_source == "image-center" and use_dist and cod == "auto":
        # COD weak: let the joint ML fit estimate the principal point, from the image centre and from the
        # COD; accept it only if the data pin it better than the prior would (data-only std <= pp_max_std)
        starts = [p_staged]
        if cod_est is not None and np.all(np.isfinite(cod_est.center)) and _inside(cod_est.center, (W, Hh)):
            try:
                starts.append(_staged_camera(M, m, cod_est.center, (W, Hh), use_dist, n_coeffs, board_width,
                                             name, [])[0])
            except CalibrationError:
                pass
        best, best_cost = None, float("inf")
        for p0 in starts:
            pj, cj = _joint_camera(M, m, p0, free, None, (W, Hh))
            if pj is not None and cj < best_cost:
                best, best_cost = pj, cj
        if best is not None:
            Jb = unc.numeric_jacobian(_camera_residual_fn(M, m, best, free), best[free], typical=typical[free])
            sb = unc.sigma_from_residuals((camera_predict(best, M) - m).ravel(), int(free.sum()))
            cb = unc.covariance(Jb, sb)
            ipp = [int(np.sum(free[:2])), int(np.sum(free[:3]))]
            std_pp = float(np.max(unc.std(cb)[ipp]))
            max_std = pp_max_std if pp_max_std is not None else sigma_pp
            if std_pp <= max_std:
                p, pp_source, fallback_reason = best, "joint", None
                warnings.append(f"pose {name!r}: centre of distortion weakly observed ({cod_est.reason}); "
                                f"principal point from the joint fit of all parameters instead: "
                                f"({p[2]:.1f}, {p[3]:.1f}) +- {std_pp:.1f} px")
    if pp_source == "image-center" and use_dist and refine == "joint":
        # an assumed principal point becomes the mean of a Gaussian prior (MAP): the distorted corners
        # move it only as far as they really constrain it
        sig0 = unc.sigma_from_residuals((camera_predict(p_staged, M) - m).ravel(), 10)
        pj, _ = _joint_camera(M, m, p_staged, free, (c.copy(), sig0 / sigma_pp), (W, Hh))
        if pj is not None:
            p, map_ok = pj, True
        else:
            warnings.append(f"pose {name!r}: joint refinement rejected (invalid or worse); staged estimate kept")
    elif refine == "joint" and pp_source != "joint":
        pj, _ = _joint_camera(M, m, p_staged, free, None, (W, Hh))
        if pj is not None:
            p = pj
        else:
            warnings.append(f"pose {name!r}: joint refinement rejected (invalid or worse); staged estimate kept")
    # 5. residuals, covariance, std
    res = camera_predict(p, M) - m
    full_fun = _camera_residual_fn(M, m, p, np.ones(12, bool))
    J = unc.numeric_jacobian(full_fun, p, typical=typical)
    n_free = int(free.sum())
    sigma = unc.sigma_from_residuals(res.ravel(), n_free)
    cols = free.copy()
    prior = np.zeros(12)
    if pp_source == "image-center":
        cols[2:4] = True
        prior[2:4] = 1.0 / sigma_pp ** 2
    elif pp_source == "joint":
        cols[2:4] = True
    idx = np.flatnonzero(cols)
    cov = np.zeros((12, 12))
    cov[np.ix_(idx, idx)] = unc.covariance(J[:, idx], sigma, prior_precision=prior[idx])
    K = models.intrinsic_matrix(p[0], p[2], p[3], p[1])
    R = models.rvec_to_matrix(p[6:9])
    t = p[9:12].copy()
    std = _camera_std(p, cov)
    if fallback_reason is not None:
        if map_ok:
            how = (f"principal point estimated with a Gaussian prior centred on the image centre ({c[0]:.1f}, "
                   f"{c[1]:.1f}) with std {sigma_pp:.0f} px per axis (MAP fit of all parameters): final "
                   f"({p[2]:.1f}, {p[3]:.1f}) +- ({std['u0c']:.1f}, {std['v0c']:.1f}) px")
        else:
            how = (f"principal point fixed at the image centre ({p[2]:.1f}, {p[3]:.1f}); the reported std "
                   f"includes a +-{sigma_pp:.0f} px prior on it")
        warnings.append(f"pose {name!r}: centre of distortion unreliable ({fallback_reason}); {how}. f_c, alpha_c "
                        f"and the distortion are only as good as that prior. For an accurate principal point use a "
                        f"pose with more visible lens distortion (board filling the image) or several poses.")
    dist_obj = Distortion("division", (float(p[2]), float(p[3])), float(p[4] / KAPPA_SCALE ** 2),
                          float(p[5] / KAPPA_SCALE ** 4)) if use_dist else Distortion()
    residuals = np.full((len(obj), 2), np.nan)
    residuals[mask] = -res  # observed - predicted
    info = dict(sigma_px=sigma, n_points=int(mask.sum()), refine=refine or "none", free=free,
                max_distortion_px=dist.max_displacement(m, p[2:4], dist_obj.k1, dist_obj.k2) if use_dist else 0.0,
                pp_prior_std=sigma_pp if pp_source == "image-center" else None)
    return CameraSolution(K=K, distortion=dist_obj, R=R, t=t, rms_px=_rms(res), residuals=residuals, std=std,
                          angles_deg=board_angles_deg(R, t), cost=float(0.5 * np.sum(res ** 2)),
                          warnings=tuple(warnings), cod=cod_est, principal_point_source=pp_source,
                          staged=staged, params=p, covariance=cov, mask=mask, image_size=(W, Hh), info=info)


def _camera_std(p, cov) -> dict:
    s = unc.std(cov)

    def ang(q):
        R = models.rvec_to_matrix(q[6:9])
        return board_angles_deg(R, q[9:12])

    def fy(q):
        return np.array([q[0] * q[1]])

    ca = unc.propagate(cov, ang, p, typical=1.0)
    cfy = unc.propagate(cov, fy, p)
    return {"f_c": float(s[0]), "alpha_c": float(s[1]), "fy_c": float(np.sqrt(abs(cfy[0, 0]))),
            "u0c": float(s[2]), "v0c": float(s[3]), "k1": float(s[4] / KAPPA_SCALE ** 2),
            "k2": float(s[5] / KAPPA_SCALE ** 4), "angles_deg": np.sqrt(np.abs(np.diag(ca))),
            "t": s[9:12].copy()}


# ----------------------------------------------------------------------------------------------
# projector
def calibrate_projector(obj_pts, proj_pts, proj_size, *, u0=None, board_width=None, reject_outliers: bool = True,
                        outlier_k: float = OUTLIER_K, outlier_floor_px: float = OUTLIER_FLOOR_PX,
                        outlier_max_fraction: float = OUTLIER_MAX_FRACTION, outlier_max_iter: int = OUTLIER_MAX_ITER,
                        min_points: int = 8, name: str = "view") -> ProjectorSolution:
    """Single-pose projector calibration (§8.2): ``f_p, v0p`` and the pose with ``u0p`` fixed, alpha = 1.

    Parameters
    ----------
    obj_pts : (N, 3) or (N, 2) board points; proj_pts : (N, 2) projector pixels (NaN rows ignored).
    proj_size : (width, height) of the projector in pixels.
    u0 : fixed principal point column (default ``W / 2``, the paper's assumption).
    board_width : w_b for the paper's initial distance (default: the span of the corners).
    reject_outliers, outlier_k, outlier_floor_px, outlier_max_fraction, outlier_max_iter :
        outlier rejection as in :func:`calibrate_camera` (a mis-decoded corner's projector
        coordinates are rejected and the projector refitted without them).
    min_points : minimum number of usable corners. name : pose name used in messages.
    """
    obj, pp, mask = _clean(obj_pts, proj_pts, f"pose {name!r}")
    if proj_size is None:
        raise CalibrationError(f"pose {name!r}: the projector size is unknown; pass proj_size=(W, H)")
    W, Hh = int(proj_size[0]), int(proj_size[1])
    _check_corners(obj, mask, min_points, name, "projector corners", "check the decoding")

    def predict(sol):
        return projector_predict(sol.params, obj, sol.u0)

    sol, used, thr, notes = _fit_robust(
        lambda m: _projector_fit(obj, pp, m, (W, Hh), u0=u0, board_width=board_width, name=name), predict, pp, obj,
        mask, enabled=reject_outliers, k=outlier_k, floor_px=outlier_floor_px, max_fraction=outlier_max_fraction,
        max_iter=outlier_max_iter, min_points=min_points)
    return _rejection_report(sol, predict, pp, mask, used, thr, notes, name, "projector", outlier_k, outlier_floor_px)


def _projector_fit(obj, pp, mask, proj_size, *, u0, board_width, name) -> ProjectorSolution:
    """One single-pose projector fit on the corners ``mask`` (see :func:`calibrate_projector`)."""
    W, Hh = proj_size
    M, m = obj[mask], pp[mask]
    lm = solve_projector_lm(M, m, (W, Hh), u0=u0, board_width=board_width)
    if not lm["ok"]:
        raise CalibrationError(f"pose {name!r}: projector LM found no valid (non-mirror) solution from any "
                               f"start; the pose is probably degenerate (no rotation about the projector's y axis?)")
    x = lm["x"]
    res = lm["residuals"]
    u0v = lm["u0"]
    # covariance in the plain pinhole parameters (f, v0, rvec, t): the principal-axis parameters are
    # tied to the data through H_P^B, so their Jacobian would understate the uncertainty
    q = np.concatenate([[lm["f"], lm["v0"]], models.matrix_to_rvec(lm["R"]), lm["t"]])
    J = unc.numeric_jacobian(lambda v: (projector_predict(v, M, u0v) - m).ravel(), q,
                             typical=np.array([1, 1, 0.01, 0.01, 0.01, 1, 1, 1.0]))
    sigma = unc.sigma_from_residuals(res.ravel(), 8)
    cov = unc.covariance(J, sigma)
    s = unc.std(cov)

    def ang(v):
        return board_angles_deg(models.rvec_to_matrix(v[2:5]), v[5:8])

    std = {"f_p": float(s[0]), "v0p": float(s[1]),
           "angles_deg": np.sqrt(np.abs(np.diag(unc.propagate(cov, ang, q, typical=1.0)))),
           "t": s[5:8].copy()}
    K = models.intrinsic_matrix(lm["f"], u0v, lm["v0"])
    residuals = np.full((len(obj), 2), np.nan)
    residuals[mask] = -res  # observed - predicted
    return ProjectorSolution(K=K, distortion=Distortion(), R=lm["R"], t=lm["t"], rms_px=_rms(res),
                             residuals=residuals, std=std, angles_deg=board_angles_deg(lm["R"], lm["t"]),
                             cost=float(lm["cost"]), params=q, covariance=cov, H_pb=lm["H_pb"], u0=u0v, mask=mask,
                             image_size=(W, Hh),
                             info=dict(sigma_px=sigma, start=lm["start"], closed_form=lm["closed_form"],
                                       theta=x.copy(),
                                       starts=[(r["start"], r["cost"], r["valid"]) for r in lm["runs"]]))


def projector_predict(q, obj, u0) -> np.ndarray:
    """Projector pixels (N, 2) for ``q = (f, v0, rvec (3), t (3))`` with ``u0`` fixed and alpha = 1."""
    q = np.asarray(q, float)
    return models.project(models.intrinsic_matrix(q[0], u0, q[1]), models.rvec_to_matrix(q[2:5]), q[5:8], obj)


# ----------------------------------------------------------------------------------------------
# advice
def advice(camera_angles_deg=None, projector_angles_deg=None, std=None, *, values=None,
           camera_rule_deg: float = 10.0, projector_rule_deg: float = 13.0, degenerate_angle_deg: float = 1.0,
           weak_angle_deg: float = 4.0, degenerate_rel_std: float = 0.10, weak_rel_std: float = 0.02,
           camera_size=None, projector_size=None, plausible_f_range=PLAUSIBLE_F_RANGE) -> dict:
    """Is this pose good for single-pose calibration? The paper's rule and the true conditions.

    The paper's empirical rule: camera ``|psi_c| + |nu_c| > 10 deg``, projector ``|nu_p| > 13 deg``.
    The true degeneracies (METHOD §10.4): the camera's (f, alpha) are unobservable iff
    ``psi_c = 0`` or ``nu_c = 0`` (board plane parallel to an image axis, including fronto-parallel);
    the projector's (f, v0) with u0 fixed iff ``nu_p = 0``, whatever psi_p.

    Parameters
    ----------
    camera_angles_deg, projector_angles_deg : (psi, nu, phi) degrees of the board in each device
        frame, or None when the device is absent.
    std : dict with ``f_c`` and/or ``f_p`` (px), optional; with ``values`` (dict with ``f_c``, ``f_p``)
        the relative uncertainty is also judged.
    camera_rule_deg, projector_rule_deg : the paper's thresholds.
    degenerate_angle_deg : an angle below this is treated as zero (degenerate).
    weak_angle_deg : an angle below this makes the pose weak (poorly conditioned).
    degenerate_rel_std, weak_rel_std : relative std of f above which the pose is degenerate / weak.
    camera_size, projector_size : (W, H) pixels; with ``values`` a focal length outside
        ``plausible_f_range`` x the image diagonal (default [0.2, 5]: diagonal fields of view of ~136 deg down to
        ~11 deg) is impossible for a real device: the estimate has **failed** (``failed``, and
        ``degenerate``), whatever its std says.

    Returns
    -------
    dict with ``camera`` and ``projector`` sub-dicts (``paper_rule_ok``, ``degenerate``, ``weak``,
    ``failed``, ``rel_std_f``, ``message``) and ``ok`` (neither degenerate nor weak), ``degenerate``
    and ``failed``.
    """
    std = std or {}
    values = values or {}
    out: dict = {}

    def rel(key):
        s, v = std.get(key), values.get(key)
        if s is None or v is None or not v:
            return None
        return float(s) / abs(float(v)) if np.isfinite(s) else float("inf")

    def implausible(key, size, device):
        """Message if the focal length is impossible for this image size, else None."""
        f = values.get(key)
        if f is None or size is None:
            return None
        lo, hi = (plausible_f_range[0] * np.hypot(*size), plausible_f_range[1] * np.hypot(*size))
        if np.isfinite(f) and lo <= f <= hi:
            return None
        return (f"{device}: FAILED estimate: {key} = {f:.4g} px is impossible for a {size[0]}x{size[1]} image "
                f"(plausible {lo:.0f}-{hi:.0f} px = {plausible_f_range[0]:g}-{plausible_f_range[1]:g} x the "
                f"diagonal); this pose does not determine the {device}'s intrinsics")

    def rel_txt(key, r):
        v = values.get(key)
        return f"{key} = {v:.1f} +- {r * abs(v):.3g} px" if v is not None and np.isfinite(r) else f"{key} +- inf"

    if camera_angles_deg is not None:
        psi, nu = abs(float(camera_angles_deg[0])), abs(float(camera_angles_deg[1]))
        r = rel("f_c")
        failed = implausible("f_c", camera_size, "camera")
        paper_ok = psi + nu > camera_rule_deg
        degen = (failed is not None or min(psi, nu) < degenerate_angle_deg
                 or (r is not None and r > degenerate_rel_std))
        weak = not degen and (not paper_ok or min(psi, nu) < weak_angle_deg or (r is not None and r > weak_rel_std))
        if failed:
            msg = failed + " (tilt the board about both image axes, e.g. 15-25 deg each)"
        elif degen and min(psi, nu) >= degenerate_angle_deg:
            msg = (f"camera: degenerate pose: {rel_txt('f_c', r)} ({100 * r:.0f} %) is not determined by this pose "
                   f"(|psi_c| = {psi:.1f}, |nu_c| = {nu:.1f} deg as estimated); tilt the board about both image "
                   f"axes (e.g. 15-25 deg each)")
        elif degen:
            msg = (f"camera: degenerate pose (|psi_c| = {psi:.1f} deg, |nu_c| = {nu:.1f} deg): f_c and alpha_c "
                   f"are not determined when the board is not tilted about BOTH image axes; tilt the board "
                   f"about both (e.g. 15-25 deg each)")
        elif weak:
            msg = (f"camera: weak pose (|psi_c| = {psi:.1f}, |nu_c| = {nu:.1f} deg"
                   + (f", f_c +-{100 * r:.1f} %" if r is not None else "")
                   + f"); the paper's rule wants |psi_c| + |nu_c| > {camera_rule_deg:g} deg and each angle "
                     f"should be clearly non-zero")
        else:
            msg = "camera: pose OK"
        out["camera"] = dict(psi_abs_deg=psi, nu_abs_deg=nu, sum_abs_deg=psi + nu, min_abs_deg=min(psi, nu),
                             paper_rule_ok=bool(paper_ok), degenerate=bool(degen), weak=bool(weak),
                             failed=failed is not None, rel_std_f=r, message=msg)
    if projector_angles_deg is not None:
        psi, nu = abs(float(projector_angles_deg[0])), abs(float(projector_angles_deg[1]))
        r = rel("f_p")
        failed = implausible("f_p", projector_size, "projector")
        paper_ok = nu > projector_rule_deg
        degen = failed is not None or nu < degenerate_angle_deg or (r is not None and r > degenerate_rel_std)
        weak = not degen and (not paper_ok or (r is not None and r > weak_rel_std))
        if failed:
            msg = failed + " (with u0p fixed it needs the board turned left/right about the projector's vertical axis)"
        elif degen and nu >= degenerate_angle_deg:
            msg = (f"projector: degenerate pose: {rel_txt('f_p', r)} ({100 * r:.0f} %) is not determined by this "
                   f"pose (|nu_p| = {nu:.1f} deg as estimated); with u0p fixed, f_p and v0p need a clear rotation "
                   f"of the board about the projector's vertical axis; turn the board left/right")
        elif degen:
            msg = (f"projector: degenerate pose (|nu_p| = {nu:.1f} deg): with u0p fixed, f_p and v0p need a "
                   f"rotation of the board about the projector's vertical axis; turn the board left/right")
        elif weak:
            msg = (f"projector: weak pose (|nu_p| = {nu:.1f} deg"
                   + (f", f_p +-{100 * r:.1f} %" if r is not None else "")
                   + f"); the paper's rule wants |nu_p| > {projector_rule_deg:g} deg")
        else:
            msg = "projector: pose OK"
        out["projector"] = dict(psi_abs_deg=psi, nu_abs_deg=nu, paper_rule_ok=bool(paper_ok), degenerate=bool(degen),
                                weak=bool(weak), failed=failed is not None, rel_std_f=r, message=msg)
    subs = [v for v in out.values() if isinstance(v, dict)]
    out["degenerate"] = any(s["degenerate"] for s in subs)
    out["failed"] = any(s["failed"] for s in subs)
    out["ok"] = not any(s["degenerate"] or s["weak"] for s in subs)
    return out


# ----------------------------------------------------------------------------------------------
# procam
def _pnp_rms(obj, pts, K) -> float:
    """METHOD §11.1 RMS (px) of undistorted ``pts`` with ``K`` fixed (:func:`procam.residuals.pnp`);
    NaN if PnP finds no pose in front of the device."""
    try:
        return rms(pnp(obj, pts, K)[2])
    except CalibrationError:
        return float("nan")


def _stereo_rms(obj, cam_und, proj, Kc, Kp, R, T, R0, t0) -> float:
    """METHOD §11.2 RMS (px) over camera and projector points (:func:`procam.residuals.stereo_pose`)."""
    _, _, rc, rp = stereo_pose(obj, cam_und, proj, Kc, Kp, R, T, R0, t0)
    return rms([rc, rp])


def extrinsics(cam: CameraSolution, proj: ProjectorSolution):
    """Camera -> projector ``(R, T)`` from the two board poses: ``R = R_p R_c^T, T = t_p - R t_c``."""
    R = proj.R @ cam.R.T
    return R, proj.t - R @ cam.t


def _extrinsics_std(cam: CameraSolution, proj: ProjectorSolution):
    """Delta-method std of (Euler XYZ deg of R, T) from the two independent parameter covariances."""
    pc, pp = cam.params, proj.params
    n = len(pc)
    cov = np.zeros((n + len(pp), n + len(pp)))
    cov[:n, :n] = cam.covariance
    cov[n:, n:] = proj.covariance

    def g(q):
        Rc, tc = models.rvec_to_matrix(q[6:9]), q[9:12]
        Rp, tp = models.rvec_to_matrix(q[n + 2:n + 5]), q[n + 5:n + 8]
        R = Rp @ Rc.T
        return np.concatenate([models.euler_deg(R), tp - R @ tc])

    C = unc.propagate(cov, g, np.concatenate([pc, pp]), typical=np.r_[np.ones(n), np.ones(len(pp))])
    s = np.sqrt(np.abs(np.diag(C)))
    return s[:3], s[3:]


def _std_dict(cam: CameraSolution, proj: ProjectorSolution | None) -> dict:
    s = {"f_c": cam.std["f_c"], "alpha_c": cam.std["alpha_c"], "fy_c": cam.std["fy_c"], "u0c": cam.std["u0c"],
         "v0c": cam.std["v0c"], "k1": cam.std["k1"], "k2": cam.std["k2"],
         "camera_angles_deg": [float(v) for v in cam.std["angles_deg"]]}
    if proj is not None:
        s.update({"f_p": proj.std["f_p"], "v0p": proj.std["v0p"],
                  "projector_angles_deg": [float(v) for v in proj.std["angles_deg"]]})
        r, t = _extrinsics_std(cam, proj)
        s["R_euler_deg"] = [float(v) for v in r]
        s["T"] = [float(v) for v in t]
    return s


_OUTLIER_KW = ("reject_outliers", "outlier_k", "outlier_floor_px", "outlier_max_fraction", "outlier_max_iter")
_CAM_KW = ("principal_point", "distortion", "cod", "refine", "n_coeffs", "min_cod_score", "pp_prior_std",
           "pp_prior_fraction", "pp_max_std", "board_width", "min_points") + _OUTLIER_KW
_PROJ_KW = ("u0", "board_width", "min_points") + _OUTLIER_KW
_ADV_KW = ("camera_rule_deg", "projector_rule_deg", "degenerate_angle_deg", "weak_angle_deg",
           "degenerate_rel_std", "weak_rel_std", "plausible_f_range")


def _split(options):
    known = set(_CAM_KW) | set(_PROJ_KW) | set(_ADV_KW) | {"strict", "cam_size"}
    bad = set(options) - known
    if bad:
        raise TypeError(f"unknown option(s): {', '.join(sorted(bad))}")
    return ({k: v for k, v in options.items() if k in _CAM_KW}, {k: v for k, v in options.items() if k in _PROJ_KW},
            {k: v for k, v in options.items() if k in _ADV_KW})


def _rejected_list(sol) -> list:
    return [{"index": int(i), "residual_px": float(r)} for i, r in zip(sol.rejected, sol.rejected_residuals_px)]


def _judge(adv, name, strict, on_failure, warnings):
    """Warnings from the advice; raise on a failed estimate (``on_failure="raise"``) or, if ``strict``,
    on a degenerate pose."""
    if on_failure not in ("raise", "warn"):
        raise ValueError(f"on_failure must be 'raise' or 'warn', got {on_failure!r}")
    keys = [k for k in ("camera", "projector") if isinstance(adv.get(k), dict)]
    for key in keys:
        if adv[key]["degenerate"] or adv[key]["weak"]:
            warnings.append(f"pose {name!r}: {adv[key]['message']}")
    if adv["failed"] and on_failure == "raise":
        raise CalibrationError(f"pose {name!r}: single-pose calibration failed: "
                               + "; ".join(adv[k]["message"] for k in keys if adv[k]["failed"])
                               + "; use another pose (on_failure='warn' returns the failed estimate anyway)")
    if strict and adv["degenerate"]:
        raise CalibrationError(f"pose {name!r}: degenerate pose for single-pose calibration: "
                               + "; ".join(adv[k]["message"] for k in keys if adv[k]["degenerate"]))


def calibrate(view, proj_size=None, **options) -> Calibration:
    """Single-pose procam calibration of one :class:`procam.view.View` (METHOD §16).

    Parameters
    ----------
    view : View -- only corners with finite camera AND projector points (``view.valid``) are used.
    proj_size : (W, H) of the projector (default ``view.proj_size``).
    **options : keyword options of :func:`calibrate_camera` (``principal_point, distortion, cod,
        refine, n_coeffs, min_cod_score, pp_prior_std, pp_prior_fraction, board_width, min_points``,
        and the outlier rejection ``reject_outliers, outlier_k, outlier_floor_px,
        outlier_max_fraction, outlier_max_iter``, applied to the camera and the projector), of
        :func:`calibrate_projector` (``u0``), of :func:`advice` (thresholds, ``plausible_f_range``),
        plus ``cam_size`` (default ``view.cam_size``), ``strict`` (raise :class:`CalibrationError` on
        a degenerate pose instead of warning) and ``on_failure`` (``"raise"``, default: raise
        :class:`CalibrationError` when an estimated focal length is impossible, see :func:`advice`;
        ``"warn"``: return it, flagged ``failed`` in the advice, with a warning).

    Returns
    -------
    Calibration
        ``method="single-pose"``; camera with division distortion, projector without; ``R, T``
        camera -> projector; ``cam_rms, proj_rms`` (METHOD §11.1 on this pose, outliers excluded),
        ``stereo_rms`` (§11.2, corners used by both devices); ``std`` with ``f_c, alpha_c, fy_c, u0c,
        v0c, k1, k2, f_p, v0p, R_euler_deg (3), T (3)`` and the board angles' std; one entry in
        ``poses`` with the angles, :func:`advice`, ``rejected_corners`` (``{"camera": [{"index",
        "residual_px"}, ...], "projector": [...]}``, indices into the view's corners) and
        ``outlier_threshold_px``; ``info["camera"]``/``info["projector"]`` hold the full solutions.

    Raises
    ------
    CalibrationError
        Too few usable corners (the message says how many are usable and needed), corners on one
        line, no valid solution, an impossible focal length (``on_failure="raise"``), or a degenerate
        pose with ``strict``.
    """
    strict = bool(options.pop("strict", False))
    on_failure = options.pop("on_failure", "raise")
    cam_size = options.pop("cam_size", None) or view.cam_size
    proj_size = proj_size or view.proj_size
    cam_kw, proj_kw, adv_kw = _split(options)
    name = view.name
    obj_all = view.obj_pts
    valid = view.valid & np.isfinite(obj_all).all(1)
    _check_corners(obj_all, valid, int(options.get("min_points", 8)), name,
                   "corners (with finite camera and projector coordinates)", "check the board detection and decoding")

    def only_valid(a):
        return np.where(valid[:, None], a, np.nan)

    # NaN for corners invalid in either device, so that both fits use the same corners and the
    # rejected corners' indices are the view's
    cam = calibrate_camera(obj_all, only_valid(view.cam_pts), cam_size, name=name, **cam_kw)
    proj = calibrate_projector(obj_all, only_valid(view.proj_pts), proj_size, name=name, **proj_kw)
    R, T = extrinsics(cam, proj)
    std = _std_dict(cam, proj)
    adv = advice(cam.angles_deg, proj.angles_deg, std, values={"f_c": cam.K[0, 0], "f_p": proj.K[0, 0]},
                 camera_size=cam.image_size, projector_size=proj.image_size, **adv_kw)
    warnings = list(cam.warnings) + list(proj.warnings)
    _judge(adv, name, strict, on_failure, warnings)
    cin, pin = cam.mask, proj.mask
    both = cin & pin
    with np.errstate(all="ignore"):
        cam_und = cam.distortion.undistort(only_valid(view.cam_pts), cam.K)
    proj_pts = view.proj_pts
    cam_rms = _pnp_rms(obj_all[cin], cam_und[cin], cam.K)
    proj_rms = _pnp_rms(obj_all[pin], proj_pts[pin], proj.K)
    stereo = _stereo_rms(obj_all[both], cam_und[both], proj_pts[both], cam.K, proj.K, R, T, cam.R, cam.t)
    pose = {"name": name, "camera_angles_deg": [float(a) for a in cam.angles_deg],
            "projector_angles_deg": [float(a) for a in proj.angles_deg], "advice": adv,
            "cam_rms": cam_rms, "proj_rms": proj_rms, "stereo_rms": stereo, "n_corners": int(valid.sum()),
            "n_used": {"camera": int(cin.sum()), "projector": int(pin.sum())},
            "rejected_corners": {"camera": _rejected_list(cam), "projector": _rejected_list(proj)},
            "outlier_threshold_px": {"camera": cam.outlier_threshold_px, "projector": proj.outlier_threshold_px}}
    return Calibration(camera=Device(cam.K, tuple(cam.image_size), cam.distortion),
                       projector=Device(proj.K, tuple(proj.image_size), Distortion()), R=R, T=T,
                       method="single-pose", cam_rms=cam_rms, proj_rms=proj_rms, stereo_rms=stereo, std=std,
                       poses=(pose,), views=(view,), warnings=tuple(warnings),
                       info={"camera": cam, "projector": proj, "principal_point_source": cam.principal_point_source,
                             "cod_score": None if cam.cod is None else cam.cod.score,
                             "refine": cam.info["refine"]})


def calibrate_camera_only(obj_pts, cam_pts, image_size, *, name: str = "view", strict: bool = False,
                          on_failure: str = "raise", **options) -> Calibration:
    """Camera-only single-pose calibration (one photo of a chessboard, no projector): K and division distortion.

    Options as :func:`calibrate_camera` and :func:`advice`; ``strict``, ``on_failure`` as in
    :func:`calibrate`. Returns a :class:`Calibration` with ``projector=None, R=T=None``, ``cam_rms``
    (METHOD §11.1 on this pose, outliers excluded), ``std`` and one pose entry (with
    ``rejected_corners``).
    """
    cam_kw, _, adv_kw = _split(options)
    cam = calibrate_camera(obj_pts, cam_pts, image_size, name=name, **cam_kw)
    std = _std_dict(cam, None)
    adv = advice(cam.angles_deg, None, std, values={"f_c": cam.K[0, 0]}, camera_size=cam.image_size, **adv_kw)
    warnings = list(cam.warnings)
    _judge(adv, name, strict, on_failure, warnings)
    obj, pts, finite = _clean(obj_pts, cam_pts, name)
    mask = cam.mask
    cam_rms = _pnp_rms(obj[mask], cam.distortion.undistort(pts[mask], cam.K), cam.K)
    pose = {"name": name, "camera_angles_deg": [float(a) for a in cam.angles_deg], "projector_angles_deg": None,
            "advice": adv, "cam_rms": cam_rms, "n_corners": int(finite.sum()),
            "n_used": {"camera": int(mask.sum())}, "rejected_corners": {"camera": _rejected_list(cam)},
            "outlier_threshold_px": {"camera": cam.outlier_threshold_px}}
    return Calibration(camera=Device(cam.K, tuple(cam.image_size), cam.distortion), projector=None, R=None, T=None,
                       method="camera-only", cam_rms=cam_rms, std=std, poses=(pose,), warnings=tuple(warnings),
                       info={"camera": cam, "principal_point_source": cam.principal_point_source,
                             "cod_score": None if cam.cod is None else cam.cod.score, "refine": cam.info["refine"]})
