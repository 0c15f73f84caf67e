"""The paper's principal-axis parameterisation, Zhang's closed forms and the two 6-parameter LM problems.

A device's pose is written through its principal axis: ``O`` (3,) the device centre and ``Q`` (3,) the
board point the principal axis hits, both in board coordinates, and ``phi`` the roll about that axis.
The camera problem solves ``theta_c = (f, alpha, phi, O)`` with the principal point fixed, the projector
problem ``theta_p = (f, v0, phi, O)`` with ``u0`` fixed and ``alpha = 1``; each is started from Zhang's
closed form and from the paper's initial values, and the valid lowest-cost solution is kept (mirror
solutions -- f <= 0, alpha <= 0, the board behind the device -- never).

Homographies are named ``H_ab`` for the map from plane ``b`` to plane ``a``: ``H_cb`` maps board
coordinates to undistorted camera pixels, ``H_pb`` board to projector pixels, ``H_bp`` its inverse.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import models
from ..errors import CalibrationError

_LM = dict(method="lm", x_scale="jac", xtol=1e-12, ftol=1e-12, gtol=1e-12)


@dataclass(frozen=True)
class Start:
    """One LM run: the start's name, the final parameter vector and cost, and whether it is valid."""

    name: str
    x: np.ndarray
    cost: float
    valid: bool


@dataclass(frozen=True)
class CameraLM:
    """The camera's 6-parameter LM solution (``principal_point`` fixed; undistorted pixels).

    ``f``, ``alpha``; ``phi`` (rad), ``O`` (3,), ``Q`` (3,) the principal-axis parameters; ``R, t`` the
    board -> camera pose; ``cost``; ``start`` the winning start's name; ``runs`` every :class:`Start`;
    ``H_cb`` the board -> image homography; ``closed_form`` Zhang's ``(f, alpha)`` or None;
    ``residuals`` (N, 2) predicted - observed pixels.
    """

    f: float
    alpha: float
    phi: float
    O: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    t: np.ndarray
    cost: float
    start: str
    runs: tuple
    H_cb: np.ndarray
    closed_form: tuple | None
    residuals: np.ndarray


@dataclass(frozen=True)
class ProjectorLM:
    """The projector's 6-parameter LM solution (``u0`` fixed, ``alpha = 1``).

    ``x`` the principal-axis parameters ``(f, v0, phi, O (3))``; ``f``, ``v0``; ``R, t`` the board ->
    projector pose; ``cost``; ``start``; ``runs``; ``H_bp`` the projector -> board homography; ``u0``;
    ``closed_form`` Zhang's ``(f, v0)`` or None; ``residuals`` (N, 2) predicted - observed pixels.
    """

    x: np.ndarray
    f: float
    v0: float
    R: np.ndarray
    t: np.ndarray
    cost: float
    start: str
    runs: tuple
    H_bp: np.ndarray
    u0: float
    closed_form: tuple | None
    residuals: np.ndarray


def _rz(phi: float) -> np.ndarray:
    c, s = np.cos(phi), np.sin(phi)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def principal_axis_frame(Q, O) -> np.ndarray:
    """Rotation A (3, 3), columns = device axes in board coordinates, with z along ``Q - O``."""
    Q = np.asarray(Q, float).reshape(3)
    O = np.asarray(O, float).reshape(3)
    Z = Q - O
    Y = np.cross(Z, [1.0, 0.0, 0.0])
    if np.linalg.norm(Y) < 1e-6 * np.linalg.norm(Z):
        Y = np.cross(Z, [0.0, 1.0, 0.0])
    X = np.cross(Y, Z)
    return np.column_stack([X / np.linalg.norm(X), Y / np.linalg.norm(Y), Z / np.linalg.norm(Z)])


def pa_extrinsics(phi: float, O, Q):
    """Board -> device pose ``(R, t)`` of the principal-axis model: ``R = A_j^T, t = -R O``.

    ``phi`` (rad) is the roll about the principal axis, ``O`` (3,) the device centre and ``Q`` (3,)
    the board point on the principal axis, both in board coordinates.
    """
    Aj = principal_axis_frame(Q, O) @ _rz(phi)
    R = Aj.T
    return R, -R @ np.asarray(O, float).reshape(3)


def _phi_of(R, O, Q) -> float:
    M = principal_axis_frame(Q, O).T @ np.asarray(R).T
    return float(np.arctan2(M[1, 0], M[0, 0]))


def homography(src, dst) -> np.ndarray:
    """:func:`procam.models.homography`, raising :class:`CalibrationError` for degenerate corners."""
    try:
        return models.homography(src, dst)
    except ValueError:
        raise CalibrationError("homography estimation failed (corners collinear or too few)") from None


def zhang_projector(H_pb, u0: float):
    """Closed-form ``(f, v0)`` from the board -> projector homography, known ``u0`` and alpha = 1."""
    Hs = np.array([[1.0, 0, -u0], [0, 1.0, 0], [0, 0, 1.0]]) @ np.asarray(H_pb, float)
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


def device_side(R, t) -> float:
    """+1 if the device centre ``O = -R^T t`` (board frame) is on the board's +z side, else -1."""
    return 1.0 if models.invert(R, t)[1][2] > 0 else -1.0


def valid_pose(R, t, M, side) -> bool:
    """Every board point in front of the device, and the device on the board's ``side``."""
    depth = (M @ R.T + t)[:, 2]
    return bool(np.all(depth > 0) and device_side(R, t) == side)


def _run_starts(fun, starts, check):
    """LM from each start; returns (best :class:`Start` or None, all runs)."""
    from scipy.optimize import least_squares

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
        runs.append(Start(name, x, cost, ok))
    good = [r for r in runs if r.valid]
    best = min(good, key=lambda r: r.cost) if good else None
    return best, tuple(runs)


def _side_and_pose(K0, H_db):
    R0, t0 = models.pose_from_homography(K0, H_db)
    return device_side(R0, t0), R0, t0, models.invert(R0, t0)[1]


def board_width(M) -> float:
    """The corners' span (board units): the paper's w_b for its initial distance 2 w_b."""
    span = np.ptp(M[:, :2], axis=0)
    return float(max(span.max(), 1e-9))


def solve_camera_lm(obj, und, principal_point, image_size, *, width=None) -> CameraLM | None:
    """The camera's 6-parameter LM from the closed-form and the paper's starts.

    Parameters
    ----------
    obj : (N, 3) board points; und : (N, 2) undistorted pixels (all finite).
    principal_point : (u0, v0), fixed. image_size : (W, H) for the paper's f start (the image diagonal).
    width : board width w_b for the paper's start O = (0, 0, +-2 w_b) (default: the corners' span).

    Returns
    -------
    :class:`CameraLM`, or None when no start reaches a valid (non-mirror) solution.
    """
    M = np.asarray(obj, float)
    u0, v0 = principal_point
    H_cb = homography(M[:, :2], und)
    Q = np.append(models.apply_homography(np.linalg.inv(H_cb), np.array([[u0, v0]]))[0], 0.0)
    W, Hh = image_size
    f_paper = float(np.hypot(W, Hh))
    cf = models.zhang_camera(H_cb, (u0, v0))
    f0, a0 = cf if cf else (f_paper, 1.0)
    K0 = models.intrinsic_matrix(f0, u0, v0, a0)
    side, R0, t0, O0 = _side_and_pose(K0, H_cb)
    wb = width or board_width(M)

    def fun(x):
        K = models.intrinsic_matrix(x[0], u0, v0, x[1])
        R, t = pa_extrinsics(x[2], x[3:6], Q)
        return (models.project(K, R, t, M) - und).ravel()

    def check(x):
        if x[0] <= 0 or x[1] <= 0:
            return False
        R, t = pa_extrinsics(x[2], x[3:6], Q)
        return valid_pose(R, t, M, side)

    starts = []
    if cf:
        starts.append(("closed-form", [cf[0], cf[1], _phi_of(R0, O0, Q), *O0]))
    starts.append(("paper", [f_paper, 1.0, 0.0, 0.0, 0.0, side * 2 * wb]))
    best, runs = _run_starts(fun, starts, check)
    if best is None:
        return None
    x = best.x
    R, t = pa_extrinsics(x[2], x[3:6], Q)
    return CameraLM(f=float(x[0]), alpha=float(x[1]), phi=float(x[2]), O=x[3:6].copy(), Q=Q, R=R, t=t,
                    cost=best.cost, start=best.name, runs=runs, H_cb=H_cb, closed_form=cf,
                    residuals=fun(x).reshape(-1, 2))


def _proj_Q(H_bp, u0, v0):
    return np.append(models.apply_homography(H_bp, np.array([[u0, v0]]))[0], 0.0)


def _proj_pose(x, H_bp, u0):
    return pa_extrinsics(x[2], x[3:6], _proj_Q(H_bp, u0, x[1]))


def solve_projector_lm(obj, proj, proj_size, *, u0=None, width=None) -> ProjectorLM | None:
    """The projector's 6-parameter LM: theta = (f_p, v0p, phi_p, O), u0 fixed, alpha = 1.

    ``Q(v0) = H_bp (u0, v0, 1)`` is recomputed inside every residual evaluation. Returns
    :class:`ProjectorLM`, or None when no start reaches a valid (non-mirror) solution.
    """
    M = np.asarray(obj, float)
    W, Hh = proj_size
    u0 = W / 2.0 if u0 is None else float(u0)
    H_pb = homography(M[:, :2], proj)
    H_bp = np.linalg.inv(H_pb)
    H_bp = H_bp / H_bp[2, 2]
    f_paper = float(np.hypot(W, Hh))
    cf = zhang_projector(H_pb, u0)
    f0, v00 = cf if cf else (f_paper, Hh / 2.0)
    side, R0, t0, O0 = _side_and_pose(models.intrinsic_matrix(f0, u0, v00), H_pb)
    wb = width or board_width(M)

    def fun(x):
        K = models.intrinsic_matrix(x[0], u0, x[1])
        R, t = _proj_pose(x, H_bp, u0)
        return (models.project(K, R, t, M) - proj).ravel()

    def check(x):
        if x[0] <= 0:
            return False
        R, t = _proj_pose(x, H_bp, u0)
        return valid_pose(R, t, M, side)

    starts = []
    if cf:
        starts.append(("closed-form", [f0, v00, _phi_of(R0, O0, _proj_Q(H_bp, u0, v00)), *O0]))
    starts.append(("paper", [f_paper, Hh / 2.0, 0.0, 0.0, 0.0, side * 2 * wb]))
    best, runs = _run_starts(fun, starts, check)
    if best is None:
        return None
    x = best.x
    R, t = _proj_pose(x, H_bp, u0)
    return ProjectorLM(x=x.copy(), f=float(x[0]), v0=float(x[1]), R=R, t=t, cost=best.cost, start=best.name,
                       runs=runs, H_bp=H_bp, u0=u0, closed_form=cf, residuals=fun(x).reshape(-1, 2))
