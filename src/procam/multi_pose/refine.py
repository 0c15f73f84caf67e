"""The joint refinement of a multi-pose procam calibration: both devices' intrinsics and distortion, ``(R, T)``
and every board pose in one robust least-squares problem (analytic Jacobian from ``cv2.projectPoints`` and
``cv2.composeRT``)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import models
from .. import uncertainty as unc
from .device import _check_dist

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
