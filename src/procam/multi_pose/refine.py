"""The joint refinement of a multi-pose procam calibration: both devices' intrinsics and distortion, ``(R, T)``
and every board pose in one robust least-squares problem; the pair is a rig of two devices in the one bundle
adjuster (:mod:`procam.multi_pose.bundle`), solved with a dense Jacobian."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import models
from .. import uncertainty as unc
from . import bundle
from .bundle import JointDevice, Observation


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
    lay = bundle.Layout([cam_dist, proj_dist], len(objs))
    # a pair is a rig of two: the camera the reference, its terms outside the model held at their given values
    dist0 = [bundle.start_dist(dc, lay.ncoef[0]), bundle.start_dist(dp, lay.ncoef[1])]
    cfree, pfree = lay.free
    objs = [np.asarray(o, float).reshape(-1, 3) for o in objs]
    obs = []
    for j, o in enumerate(objs):
        obs += [Observation(0, j, o, np.asarray(cams[j], float).reshape(-1, 2)),
                Observation(1, j, o, np.asarray(projs[j], float).reshape(-1, 2))]
    devices = [JointDevice("camera", Kc, dist0[0], cam_dist, np.eye(3), np.zeros(3)),
               JointDevice("projector", Kp, dist0[1], proj_dist, R, T)]
    x0 = lay.pack(devices, rvecs, tvecs)
    w = float(proj_weight)
    scale = (1.0, w)
    sol = bundle.solve(x0, lay, obs, dist0, scale, sparse=False, loss=loss, f_scale=loss_scale, tol=tol,
                       max_nfev=max_nfev)
    x = sol.x
    rr, J = bundle.model(x, lay, obs, dist0, scale, True, sparse=False)
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
    Kc1, dc1 = lay.intrinsics(x, 0, dist0)
    Kp1, dp1 = lay.intrinsics(x, 1, dist0)
    r1, T1 = x[lay.pose[1][:3]], x[lay.pose[1][3:]]
    return StereoRefinement(Kc=Kc1, dc=dc1, Kp=Kp1, dp=dp1, R=models.rvec_to_matrix(r1), T=T1,
                            rvecs=[x[b[:3]] for b in lay.board], tvecs=[x[b[3:]] for b in lay.board],
                            residuals=residuals, cov=cov, names=tuple(names), x=x, status=int(sol.status),
                            nfev=int(sol.nfev), cost=float(sol.cost))
