"""The bundle adjuster of every multi-pose solver: N devices (cameras and projectors alike, each an OpenCV lens
model), each device's pose relative to the reference device and every board pose, in one least-squares problem.
A procam pair is a rig of two (:func:`procam.multi_pose.refine.refine_stereo`); a rig is N
(:func:`procam.rig.joint.refine_rig`); each chooses its loss, weights and solver around this one model.

Unknowns ``x`` (:class:`Layout`): per device ``fx, fy, u0, v0`` (px) and its distortion model's free terms; per
device other than the reference (index 0) its pose ``x_dev = R x_ref + T`` (rotation vector rad, translation in
board units); per board pose the board -> reference-device pose (rotation vector, translation).
Observations: device ``i`` at pose ``j`` sees board points at pixels (:class:`Observation`).  A residual block
depends on its device's intrinsics, its device's pose and one board pose only: the Jacobian is block-sparse and
analytic (``cv2.projectPoints`` and ``cv2.composeRT``), dense or ``scipy.sparse`` as the solver wants.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import models
from .device import _check_dist

__all__ = ["JointDevice", "Observation", "Layout", "start_dist", "model", "solve"]


@dataclass(frozen=True)
class JointDevice:
    """A device of the joint problem: ``name``, ``K`` (3, 3) and ``dist`` (OpenCV vector) to start from,
    ``model`` (an OpenCV distortion model name of :data:`procam.multi_pose.DIST_MODELS`), ``R, T`` reference ->
    device to start from (ignored for the reference, index 0)."""

    name: str
    K: np.ndarray
    dist: np.ndarray
    model: str
    R: np.ndarray
    T: np.ndarray


@dataclass(frozen=True)
class Observation:
    """Device ``device`` (index) at pose ``pose`` (index) sees board points ``obj`` (N, 3) at pixels ``pts``
    (N, 2), all finite."""

    device: int
    pose: int
    obj: np.ndarray
    pts: np.ndarray


def start_dist(dist, ncoef: int) -> np.ndarray:
    """The OpenCV distortion vector ``dist`` cut or zero-padded to ``ncoef`` terms."""
    v = np.zeros(ncoef)
    dd = np.asarray(dist, float).ravel()[:ncoef]
    v[:len(dd)] = dd
    return v


class Layout:
    """Where each unknown sits in ``x``: ``intr[i]`` device i's ``fx, fy, u0, v0`` then its free distortion terms
    (``free[i]`` their indices in its ``ncoef[i]``-term vector); ``pose[i]`` device i's (rvec, T) (None for the
    reference); ``board[j]`` board pose j's (rvec, t); ``size`` the length of ``x``."""

    def __init__(self, dist_models, n_poses: int):
        self.free, self.ncoef, self.intr = [], [], []
        off = 0
        for m in dist_models:
            _, nc, free = _check_dist(m)
            self.free.append(tuple(free))
            self.ncoef.append(nc)
            self.intr.append(list(range(off, off + 4 + len(free))))
            off += 4 + len(free)
        self.pose = [None]
        for _ in dist_models[1:]:
            self.pose.append(list(range(off, off + 6)))
            off += 6
        self.board = []
        for _ in range(n_poses):
            self.board.append(list(range(off, off + 6)))
            off += 6
        self.size = off

    def pack(self, devices, board_r, board_t) -> np.ndarray:
        """``x`` from :class:`JointDevice` starts and per pose board -> reference rotation vectors and translations."""
        x = np.zeros(self.size)
        for i, d in enumerate(devices):
            K = np.asarray(d.K, float)
            dist = start_dist(d.dist, self.ncoef[i])
            x[self.intr[i]] = [K[0, 0], K[1, 1], K[0, 2], K[1, 2], *dist[list(self.free[i])]]
            if i:
                x[self.pose[i]] = [*models.matrix_to_rvec(d.R), *np.asarray(d.T, float).ravel()]
        for j, (r, t) in enumerate(zip(board_r, board_t)):
            x[self.board[j]] = [*np.ravel(r), *np.ravel(t)]
        return x

    def intrinsics(self, x, i, dist0):
        """Device i's ``K`` (3, 3) and distortion vector (its held terms from ``dist0[i]``)."""
        v = x[self.intr[i]]
        K = np.array([[v[0], 0.0, v[2]], [0.0, v[1], v[3]], [0.0, 0.0, 1.0]])
        d = np.array(dist0[i], float).copy()
        d[list(self.free[i])] = v[4:]
        return K, d


def model(x, lay: Layout, obs, dist0, scale, want_jac: bool, sparse: bool = True):
    """Scaled residuals ``scale[device] * (predicted - observed)`` (px times the device's weight, observation by
    observation, each (N, 2) flattened) and, with ``want_jac``, their Jacobian (rows x ``lay.size``;
    ``scipy.sparse`` CSR when ``sparse``, else a dense array)."""
    import cv2

    res, rows, cols, vals = [], [], [], []
    J = None
    if want_jac and not sparse:  # blocks written where they go (the same values as the sparse triplets)
        J = np.zeros((sum(2 * len(o.obj) for o in obs), lay.size))
    row = 0
    for o in obs:
        K, d = lay.intrinsics(x, o.device, dist0)
        rb, tb = x[lay.board[o.pose][:3]], x[lay.board[o.pose][3:]]
        obj = o.obj.reshape(-1, 1, 3)
        if lay.pose[o.device] is None:
            pp, Jp = cv2.projectPoints(obj, rb, tb, K, d)
            blocks = [(lay.board[o.pose], Jp[:, 0:6])]
        else:
            rd, td = x[lay.pose[o.device][:3]], x[lay.pose[o.device][3:]]
            r3, t3, dr3dr1, dr3dt1, dr3dr2, dr3dt2, dt3dr1, dt3dt1, dt3dr2, dt3dt2 = cv2.composeRT(rb, tb, rd, td)
            pp, Jp = cv2.projectPoints(obj, r3, t3, K, d)
            Jr, Jt = Jp[:, 0:3], Jp[:, 3:6]
            blocks = [(lay.board[o.pose], np.hstack([Jr @ dr3dr1 + Jt @ dt3dr1, Jr @ dr3dt1 + Jt @ dt3dt1])),
                      (lay.pose[o.device], np.hstack([Jr @ dr3dr2 + Jt @ dt3dr2, Jr @ dr3dt2 + Jt @ dt3dt2]))]
        w = scale[o.device]
        res.append(w * (pp.reshape(-1) - o.pts.reshape(-1)))
        n2 = 2 * len(o.obj)
        if want_jac:
            blocks.append((lay.intr[o.device], np.hstack([Jp[:, 6:10], Jp[:, [10 + k for k in lay.free[o.device]]]])))
            for idx, B in blocks:
                if J is not None:
                    J[row:row + n2, idx] = w * B
                else:
                    rows.append(np.repeat(np.arange(row, row + n2), len(idx)))
                    cols.append(np.tile(idx, n2))
                    vals.append(w * B.ravel())
        row += n2
    r = np.concatenate(res)
    if not want_jac:
        return r
    if J is not None:
        return r, J
    from scipy import sparse as sp

    rows, cols, vals = np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)
    return r, sp.csr_matrix((vals, (rows, cols)), shape=(row, lay.size))


def solve(x0, lay: Layout, obs, dist0, scale, *, sparse: bool, loss: str, f_scale: float, tol: float,
          max_nfev: int):
    """scipy ``least_squares`` (``trf``, ``x_scale="jac"``, ftol = xtol = gtol = ``tol``) of :func:`model` from
    ``x0``: the exact trust-region solver on a dense Jacobian, ``lsmr`` on a sparse one.  Returns its result."""
    from scipy.optimize import least_squares

    cache: dict = {}

    def fun(x):
        r, J = model(x, lay, obs, dist0, scale, True, sparse)
        cache["x"], cache["J"] = x.copy(), J
        return r

    def jac(x):
        if "x" in cache and np.array_equal(cache["x"], x):
            return cache["J"]
        return model(x, lay, obs, dist0, scale, True, sparse)[1]

    kw = {"tr_solver": "lsmr"} if sparse else {}
    return least_squares(fun, x0, jac=jac, method="trf", loss=loss, f_scale=f_scale, x_scale="jac",
                         ftol=tol, xtol=tol, gtol=tol, max_nfev=max_nfev, **kw)
