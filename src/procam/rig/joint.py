"""The joint refinement of a rig: every device's intrinsics and distortion, every device's pose relative to the
reference camera and every board pose, in one sparse robust least-squares problem.

Unknowns: per device ``fx, fy, u0, v0`` and its OpenCV distortion model's free terms; per device other than the
reference camera its pose ``x_dev = R x_ref + T`` (rotation vector, translation); per rig pose the board ->
reference-camera pose.  Observations: each device at each pose sees the board's corners once (a camera its
detected corners, a projector its decoded coordinates at them).  A device's residual block depends on its own
intrinsics, its pose and one board pose only, so the Jacobian is sparse (scipy ``least_squares`` with a
``scipy.sparse`` Jacobian and the ``lsmr`` trust-region solver); its blocks are analytic
(:mod:`procam.multi_pose.bundle`, the bundle adjuster of every multi-pose solver; a pair is a rig of two).

Weights: each device's residuals are divided by that device's noise sigma (px), estimated from its own
residuals after a first solve (each device has its own Gaussian noise: projector coordinates decoded at the
corners are noisier than the corners).  The loss is ``soft_l1`` at 3 sigma: plain least squares for inliers.
Covariance: Gauss-Newton ``s^2 (J^T J)^-1`` of the weighted problem (:func:`procam.uncertainty.covariance`,
infinite when ill-conditioned), assuming the model is right and the corner noise independent and Gaussian
with the per-device sigma.

Failure modes: a device that no pose shows, or poses that do not determine a distortion model, give an
infinite covariance (the caller's verdict says so); the solver's iteration limit is reported in ``status``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import models
from .. import uncertainty as unc
from ..multi_pose import bundle
from ..multi_pose.bundle import JointDevice, Observation

__all__ = ["JointDevice", "Observation", "JointResult", "refine_rig"]


@dataclass(frozen=True)
class JointResult:
    """:func:`refine_rig`'s result.

    ``K``, ``dist`` : per device (lists); ``R``, ``T`` : per device, reference -> device; ``board_R``,
    ``board_t`` : per pose, board -> reference camera; ``sigma`` : per device noise (px) used as its weight;
    ``residuals`` : per observation, observed - predicted (N, 2) px, unweighted; ``x``, ``cov`` : the solution
    vector and its covariance; ``intr_index`` : per device the indices of ``fx, fy, u0, v0`` then its free
    distortion terms in ``x``; ``free`` : per device the free distortion indices; ``pose_index`` : per device
    the indices of its (rvec, t) in ``x`` (None for the reference); ``status`` 1 when the Gauss-Newton polish converged, else ``least_squares``'s (0: evaluation limit); ``nfev``, ``cost`` of ``least_squares``.
    """

    K: list
    dist: list
    R: list
    T: list
    board_R: list
    board_t: list
    sigma: np.ndarray
    residuals: list
    x: np.ndarray
    cov: np.ndarray
    intr_index: list
    free: list
    pose_index: list
    status: int
    nfev: int
    cost: float


#: The soft_l1 loss's scale in units of each device's sigma: residuals well below it count as least squares.
_F_SCALE = 3.0


def refine_rig(devices, observations, board_r, board_t, *, sigma=None, max_nfev: int = 100,
               tol: float = 1e-8) -> JointResult:
    """Jointly refine a rig (module docstring).

    Parameters
    ----------
    devices : :class:`JointDevice` sequence, the reference camera first.
    observations : :class:`Observation` sequence.
    board_r, board_t : per pose the initial board -> reference-camera rotation vector (3,) and translation (3,).
    sigma : per device initial noise (px), default 1; re-estimated from the residuals after a first solve.
    max_nfev, tol : solver budget and tolerances (ftol = xtol = gtol) of each of the two solves.

    Returns
    -------
    :class:`JointResult`
    """
    devices = list(devices)
    obs = [Observation(o.device, o.pose, np.asarray(o.obj, float).reshape(-1, 3), np.asarray(o.pts, float).reshape(-1, 2))
           for o in observations]
    lay = bundle.Layout([d.model for d in devices], len(board_r))
    dist0 = []
    for i, d in enumerate(devices):
        v = bundle.start_dist(d.dist, lay.ncoef[i])
        v[[k for k in range(lay.ncoef[i]) if k not in lay.free[i]]] = 0.0  # the held terms are zero
        dist0.append(v)
    x = lay.pack(devices, board_r, board_t)
    weights = np.ones(len(devices)) if sigma is None else np.maximum(np.asarray(sigma, float), 1e-3)
    unit = np.ones(len(devices))
    sol = None
    for _ in range(2):  # solve, re-estimate each device's sigma from its residuals, solve again
        sol = bundle.solve(x, lay, obs, dist0, 1.0 / weights, sparse=True, loss="soft_l1", f_scale=_F_SCALE, tol=tol,
                           max_nfev=max_nfev)
        x, polished = _polish(sol.x, lay, obs, dist0, weights)
        raw = bundle.model(x, lay, obs, dist0, unit, False)
        weights = _sigmas(raw, obs, lay, len(devices))
    r, J = bundle.model(x, lay, obs, dist0, 1.0 / weights, True)
    cov = unc.covariance(J.toarray(), unc.sigma_from_residuals(r, len(x)) if len(r) > len(x) else float("nan"))
    Ks, ds, Rs, Ts = [], [], [], []
    for i in range(len(devices)):
        K, d = lay.intrinsics(x, i, dist0)
        Ks.append(K)
        ds.append(d)
        if lay.pose[i] is None:
            Rs.append(np.eye(3))
            Ts.append(np.zeros(3))
        else:
            Rs.append(models.rvec_to_matrix(x[lay.pose[i][:3]]))
            Ts.append(x[lay.pose[i][3:]].copy())
    residuals, row = [], 0
    raw = bundle.model(x, lay, obs, dist0, unit, False)
    for o in obs:
        n2 = 2 * len(o.obj)
        residuals.append(-raw[row:row + n2].reshape(-1, 2))
        row += n2
    return JointResult(K=Ks, dist=ds, R=Rs, T=Ts, board_R=[models.rvec_to_matrix(x[b[:3]]) for b in lay.board],
                       board_t=[x[b[3:]].copy() for b in lay.board], sigma=weights, residuals=residuals, x=x, cov=cov,
                       intr_index=lay.intr, free=lay.free, pose_index=lay.pose, status=1 if polished else min(int(sol.status), 0),
                       nfev=int(sol.nfev), cost=float(sol.cost))


def _polish(x, lay: bundle.Layout, obs, dist0, weights, iterations: int = 25, tol: float = 1e-4):
    """Gauss-Newton steps of the robust problem (iteratively reweighted: the soft_l1 weight of each residual) with
    the exact sparse normal equations: ``lsmr``'s inexact trust-region steps approach the minimum, these land on
    it (linearly: the weights move with the residuals).  Converged when no parameter moves by more than ``tol``
    of its std (``|dx_k| sqrt((J^T J)_kk)`` bounds ``|dx_k| / std_k`` for unit-sigma residuals).  Returns
    (x, converged)."""
    from scipy.sparse import diags
    from scipy.sparse.linalg import spsolve

    for _ in range(iterations):
        r, J = bundle.model(x, lay, obs, dist0, 1.0 / weights, True)
        w = (1.0 + (r / _F_SCALE) ** 2) ** -0.25
        Jw = diags(w) @ J
        A = (Jw.T @ Jw).tocsc()
        d = np.sqrt(A.diagonal())
        d[d == 0] = 1.0
        D = diags(1.0 / d)
        dx = D @ spsolve((D @ A @ D).tocsc(), -(D @ (Jw.T @ (w * r))))
        if not np.all(np.isfinite(dx)):
            return x, False
        x = x + dx
        if np.max(np.abs(dx) * d) < tol:  # |dx_k| d_k bounds the step in units of the parameter's std
            return x, True
    return x, False


def _sigmas(raw, obs, lay: bundle.Layout, n_dev: int) -> np.ndarray:
    """Per device noise sigma (px) of the unweighted residuals: sqrt(sum r^2 / (m - n)) with the device's
    intrinsics and pose counted against its own residuals (the board poses are shared, not counted)."""
    ss, m = np.zeros(n_dev), np.zeros(n_dev)
    row = 0
    for o in obs:
        n2 = 2 * len(o.obj)
        ss[o.device] += float(np.sum(raw[row:row + n2] ** 2))
        m[o.device] += n2
        row += n2
    own = np.array([len(lay.intr[i]) + (0 if lay.pose[i] is None else 6) for i in range(n_dev)])
    dof = np.maximum(m - own, 1.0)
    return np.maximum(np.sqrt(ss / dof), 1e-3)
