"""The joint single-pose model: one least-squares problem over the camera and a real projector.

A real projector throws its image above or below its lens axis (vertical lens shift: ``v0p`` near or beyond the
panel's last row), often a little sideways, through a lens that distorts. One pose of a plane cannot tell a
pinhole projector's ``u0p``/``alpha_p`` from its focal length (the board's homography has 8 degrees of freedom),
but the decoded patterns carry much more than 60 corners:

* the **board samples** (:mod:`procam.correspond.samples`): camera pixels on the board whose projector coordinates are
  known to a fraction of a pixel, thousands per pose. Through the camera (its distortion, intrinsics and board
  pose) each is a point of the board's plane, which the projector images through its distortion: for a
  lens-shifted projector the distortion centre is the lens axis, far from the panel centre, and the radial field
  it leaves across the board pins ``(u0p, v0p)`` where the lens distorts enough;
* the **background samples**: the wall (or anything) behind the board, off the board's plane, constrains the
  camera-projector epipolar geometry whatever its shape: each sample's projector point must lie on the epipolar
  line of its camera pixel (one residual each, in projector pixels, after removing the projector's distortion);
  with the board this is the second plane that fixes ``u0p`` and ``alpha_p``;
* the **camera corners**, the camera's own single-pose likelihood, so the camera is estimated jointly and its own
  uncertainty (``f_c`` is known to a percent or two from one pose) is carried into the projector's numbers instead
  of a camera taken as exact;
* the **projector corners** (a correspondences file's projector data: the board corners decoded at the projector,
  the paper's data), each a board point imaged by the projector's model, in projector pixels; and
* **priors** where the user or the model says something: ``alpha_p = 1`` to a few tenths of a percent, a
  datasheet's throw ratio and lens shift, the camera's principal point near the image centre when its centre of
  distortion is unobservable.

The parameter vector is the camera's (:data:`procam.parameters.CAMERA_VECTOR`: division model about its
principal point) followed by the projector's :data:`PROJECTOR`: ``f_p, alpha_p, u0p, v0p``, OpenCV's distortion
``k1, k2, p1, p2, k3`` on normalised coordinates about ``(u0p, v0p)`` (the forward map takes a 3-D point to the
panel pixel that lights it, as ``cv2.projectPoints``), and the board -> projector pose ``(rvec, t)``. A camera or
projector whose intrinsics are given is held fixed (its pixels undistorted once by its own model, any OpenCV model).

The paper's projector is this model with ``u0p``, ``alpha_p`` (or its prior) and the lens terms held, on the
projector corners; the background check (:mod:`.background`) frees ``u0p`` per part of the background
(:attr:`JointData.back_groups`) and may put a Cauchy loss on the background (:attr:`JointModel.cauchy`).

Every residual is divided by its noise (camera corners, board and background samples, projector corners each have
a scale the fit measures), so the cost is a chi-square and the Jacobian's covariance is in the data's units. Derivatives are exact
(forward mode, :mod:`procam._dual`): one pass gives the Jacobian of all ~27 parameters. The lens models are
:mod:`procam.models`' (the division model, OpenCV's), the covariance and its degeneracy rule
:func:`procam.uncertainty.covariance`'s.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import _dual as D
from .. import models
from .. import uncertainty as unc
from ..models import brown, brown_inverse, brown_jacobian, distort_division_xy, undistort_division_xy
from ..parameters import CAMERA_VECTOR

#: The projector's part of the joint parameter vector.
PROJECTOR = ("f_p", "alpha_p", "u0p", "v0p", "k1p", "k2p", "p1p", "p2p", "k3p", "prx", "pry", "prz", "ptx", "pty",
             "ptz")
#: Where each device's distortion centre sits from its principal point (px): zero in the camera's single-pose model
#: and in OpenCV's, and held there by a prior (:mod:`.dense`) whose width is what that assumption can cost for a
#: lens whose distortion is decentred.
DECENTRING = ("dcx", "dcy", "dpx", "dpy")
#: The joint parameter vector: the camera's, the projector's, the decentrings.
NAMES = CAMERA_VECTOR + PROJECTOR + DECENTRING
NC = len(CAMERA_VECTOR)
#: Index of each name in :data:`NAMES`.
IDX = {n: i for i, n in enumerate(NAMES)}
#: The projector's OpenCV distortion terms, in OpenCV's order.
DIST_TERMS = ("k1p", "k2p", "p1p", "p2p", "k3p")
#: The projector's board pose.
POSE_P = ("prx", "pry", "prz", "ptx", "pty", "ptz")
POSE_C = ("rx", "ry", "rz", "tx", "ty", "tz")
S = models.KAPPA_SCALE


# ------------------------------------------------------------------------------------------------
# the model's pieces (plain arrays or Duals; the lens models are procam.models')

def _transpose(R):
    return [[R[j][i] for j in range(3)] for i in range(3)]


def _matmul(A, B):
    return [[A[i][0] * B[0][j] + A[i][1] * B[1][j] + A[i][2] * B[2][j] for j in range(3)] for i in range(3)]


# ------------------------------------------------------------------------------------------------
# the data and the model

@dataclass(frozen=True)
class FixedDevice:
    """A device whose intrinsics are given: its undistorted pixels are computed once (any of its models)."""

    K: np.ndarray
    device: object   # procam.calibration.Device


@dataclass
class JointData:
    """What one joint fit sees (all pixels distorted, as decoded).

    obj : (N, 3) board corners; cam : (N, 2) camera corners (NaN = not used).
    board_cam, board_proj : (M, 2) board samples; board_w : (M,) their relative noise (1 = typical).
    back_cam, back_proj : (B, 2) background samples; back_w : (B,) their relative noise.
    camera_fixed, projector_fixed : a :class:`FixedDevice`, or None (estimated).
    pp_prior : (centre (2,), std) of the camera's principal point, or None.
    priors : list of ``(name, mean, std)`` Gaussian priors on projector parameters.
    corner_obj, corner_proj : (K, 3) board corners and (K, 2) the projector pixels decoded at them (the projector
        corners; empty by default).
    back_groups : (B,) int 0..G-1 or None: background samples of group g >= 1 see their own ``u0p``
        (:meth:`JointModel.names` gets ``u0p_1 .. u0p_{G-1}``): the background's consistency test.
    """

    obj: np.ndarray
    cam: np.ndarray
    board_cam: np.ndarray
    board_proj: np.ndarray
    back_cam: np.ndarray
    back_proj: np.ndarray
    board_w: np.ndarray | None = None
    back_w: np.ndarray | None = None
    camera_fixed: FixedDevice | None = None
    projector_fixed: FixedDevice | None = None
    pp_prior: tuple | None = None
    priors: list = field(default_factory=list)
    corner_obj: np.ndarray | None = None
    corner_proj: np.ndarray | None = None
    back_groups: np.ndarray | None = None

    def __post_init__(self):
        ok = np.isfinite(self.cam).all(1) & np.isfinite(self.obj).all(1)
        self.obj, self.cam = np.asarray(self.obj, float)[ok], np.asarray(self.cam, float)[ok]
        for a, w in (("board", "board_w"), ("back", "back_w")):
            c, p = np.asarray(getattr(self, a + "_cam"), float), np.asarray(getattr(self, a + "_proj"), float)
            ok = np.isfinite(c).all(1) & np.isfinite(p).all(1)
            setattr(self, a + "_cam", c[ok])
            setattr(self, a + "_proj", p[ok])
            wv = getattr(self, w)
            setattr(self, w, np.ones(int(ok.sum())) if wv is None else np.asarray(wv, float)[ok])
            if a == "back" and self.back_groups is not None:
                self.back_groups = np.asarray(self.back_groups, int)[ok]
        o = np.empty((0, 3)) if self.corner_obj is None else np.asarray(self.corner_obj, float).reshape(-1, 3)
        q = np.empty((0, 2)) if self.corner_proj is None else np.asarray(self.corner_proj, float).reshape(-1, 2)
        ok = np.isfinite(o).all(1) & np.isfinite(q).all(1)
        self.corner_obj, self.corner_proj = o[ok], q[ok]
        if self.camera_fixed is not None:
            dev = self.camera_fixed.device
            self._cam_und = dev.undistort(self.cam)
            self._board_cam_und = dev.undistort(self.board_cam)
            self._back_cam_und = dev.undistort(self.back_cam)
        if self.projector_fixed is not None:
            dev = self.projector_fixed.device
            self._back_proj_und = dev.undistort(self.back_proj)


@dataclass
class Scales:
    """The noise of each block (px): camera corners, board samples, background samples, projector corners."""

    camera: float
    board: float
    background: float
    corners: float = 1.0


class JointModel:
    """Residuals of :class:`JointData` for a full parameter vector ``p`` (:data:`NAMES`), plain or Dual.

    ``keep_board`` / ``keep_back``: (M,) / (B,) bool, the samples in use (outliers out).
    ``cauchy``: None (least squares), or the scale (in noise sigmas) of a Cauchy loss on the background residuals
    (residual ``sign(r) c sqrt(log(1 + (r/c)^2))``: the corners and priors stay quadratic).
    ``pixel_distance``: the background's epipolar distance measured in the projector's pixels, to first order (the
    normalised distance over its gradient by the sample's pixel, through ``alpha_p`` and the lens: one pixel of
    noise moves it by one pixel whatever the parameters, so no parameter can shrink the noise: the background
    check's statistic, :mod:`.background_fit`, and the dense fit's after its start), instead of the normalised
    distance times ``f_p`` (the default: the same for a pinhole with square pixels; from far off, the pixel form
    let one dense fit of the ``hard`` rig shrink the residuals through ``alpha_p`` to ``f_p`` = 9 px).
    """

    def __init__(self, data: JointData, scales: Scales):
        self.data = data
        self.scales = scales
        self.keep_board = np.ones(len(data.board_cam), bool)
        self.keep_back = np.ones(len(data.back_cam), bool)
        self.cauchy: float | None = None
        self.pixel_distance = False

    def on(self, **changes) -> "JointModel":
        """The same model (samples in use, loss, distance measure, noise scales) on data with ``changes`` (fields of
        :class:`JointData`, e.g. a held device moved or freed, pixels shifted): what a held device's uncertainty, a
        residual pattern or a given device's check does to this fit."""
        from dataclasses import replace

        m = JointModel(replace(self.data, **changes), self.scales)
        m.keep_board, m.keep_back, m.cauchy, m.pixel_distance = (self.keep_board, self.keep_back, self.cauchy,
                                                                 self.pixel_distance)
        return m

    @property
    def names(self) -> tuple:
        """The parameter vector's names: :data:`NAMES`, then ``u0p_g`` of each background group g >= 1."""
        g = self.data.back_groups
        return NAMES + tuple(f"u0p_{k}" for k in range(1, int(g.max()) + 1 if g is not None and len(g) else 1))

    # camera side -----------------------------------------------------------------------------------
    def _camera(self, p):
        """``(f, alpha, u0, v0, k1, k2, cx, cy)``: intrinsics, division coefficients and distortion centre."""
        d = self.data
        if d.camera_fixed is not None:
            K = d.camera_fixed.K
            return float(K[0, 0]), float(K[1, 1] / K[0, 0]), float(K[0, 2]), float(K[1, 2]), 0.0, 0.0, 0.0, 0.0
        return p[0], p[1], p[2], p[3], p[4] / S ** 2, p[5] / S ** 4, p[2] + p[27], p[3] + p[28]

    def _rays(self, p, pix, und_fixed):
        """Normalised camera rays (x, y) of distorted camera pixels ``pix`` (M, 2)."""
        f, a, u0, v0, k1, k2, cx, cy = self._camera(p)
        if self.data.camera_fixed is not None:
            ux, uy = und_fixed[:, 0], und_fixed[:, 1]
        else:
            ux, uy = undistort_division_xy(pix[:, 0], pix[:, 1], cx, cy, k1, k2)
        return (ux - u0) / f, (uy - v0) / (a * f)

    def _projector(self, p):
        """``(f, alpha, u0, v0, coeffs (5), dx, dy)``: intrinsics, OpenCV coefficients and the distortion centre's
        offset from the principal point (normalised by f)."""
        d = self.data
        if d.projector_fixed is not None:
            K = d.projector_fixed.K
            coeffs = list(getattr(d.projector_fixed.device.distortion, "coeffs", ()) or ()) + [0.0] * 5
            return float(K[0, 0]), float(K[1, 1] / K[0, 0]), float(K[0, 2]), float(K[1, 2]), coeffs[:5], 0.0, 0.0
        return p[12], p[13], p[14], p[15], [p[16], p[17], p[18], p[19], p[20]], p[29] / p[12], p[30] / (p[12] * p[13])

    def _epipolar(self, p, m, Rc, tc, Rp, tp):
        """The background samples ``m`` (bool mask): their epipolar lines ``ln`` (3 arrays: ``ln . (x, y, 1) = 0`` in
        the projector's normalised coordinates) and their projector points there, undistorted ``(xn, yn)``; and
        the distortion's Jacobian at them, ``(a, b, d)`` of ``[[a, b], [b, d]]`` (None for a held projector)."""
        d = self.data
        rx, ry = self._rays(p, d.back_cam[m], d._back_cam_und[m] if d.camera_fixed is not None else None)
        R = _matmul(Rp, _transpose(Rc))
        T = [tp[i] - (R[i][0] * tc[0] + R[i][1] * tc[1] + R[i][2] * tc[2]) for i in range(3)]
        Rr = [R[i][0] * rx + R[i][1] * ry + R[i][2] for i in range(3)]
        ln = [T[1] * Rr[2] - T[2] * Rr[1], T[2] * Rr[0] - T[0] * Rr[2], T[0] * Rr[1] - T[1] * Rr[0]]
        fp, ap, u0p, v0p, kp, ex, ey = self._projector(p)
        if d.back_groups is not None:          # u0p per group of the background (group 0: the projector's own)
            g = d.back_groups[m]
            u0p = u0p + sum((g == k) * (p[len(NAMES) + k - 1] - u0p) for k in range(1, int(g.max(initial=0)) + 1))
        if d.projector_fixed is not None:
            und = d._back_proj_und[m]
            return ln, (und[:, 0] - u0p) / fp, (und[:, 1] - v0p) / (ap * fp), None
        xn, yn = brown_inverse((d.back_proj[m, 0] - u0p) / fp - ex, (d.back_proj[m, 1] - v0p) / (ap * fp) - ey, *kp)
        return ln, xn + ex, yn + ey, brown_jacobian(xn, yn, *kp)

    # residual blocks, in pixels ---------------------------------------------------------------------
    def blocks(self, p):
        """``(camera (2N,), board (2M,), background (B,), priors (P,))`` residuals: the first three in pixels
        (observed - predicted), the priors in their own sigmas."""
        d = self.data
        Rc = D.rotation([p[6], p[7], p[8]])
        tc = [p[9], p[10], p[11]]
        # 1. camera corners
        X = D.transform(Rc, tc, [d.obj[:, 0], d.obj[:, 1], d.obj[:, 2]])
        f, a, u0, v0, k1, k2, cx, cy = self._camera(p)
        xu, yu = f * X[0] / X[2] + u0, a * f * X[1] / X[2] + v0
        if d.camera_fixed is not None:
            cam_res = [d._cam_und[:, 0] - xu, d._cam_und[:, 1] - yu]
        else:
            xd, yd = distort_division_xy(xu, yu, cx, cy, k1, k2)
            cam_res = [d.cam[:, 0] - xd, d.cam[:, 1] - yd]
        fp, ap, u0p, v0p, kp, ex, ey = self._projector(p)
        Rp = D.rotation([p[21], p[22], p[23]])
        tp = [p[24], p[25], p[26]]
        # 2. board samples: camera ray -> the board's plane -> the projector's panel
        m = self.keep_board
        rx, ry = self._rays(p, d.board_cam[m], d._board_cam_und[m] if d.camera_fixed is not None else None)
        n = [Rc[0][2], Rc[1][2], Rc[2][2]]
        lam = (n[0] * tc[0] + n[1] * tc[1] + n[2] * tc[2]) / (n[0] * rx + n[1] * ry + n[2])
        Xc = [rx * lam - tc[0], ry * lam - tc[1], lam - tc[2]]
        Xb = [Rc[0][i] * Xc[0] + Rc[1][i] * Xc[1] + Rc[2][i] * Xc[2] for i in range(3)]     # R_cb^T (X - t_cb)
        Xp = D.transform(Rp, tp, Xb)
        bx, by = brown(Xp[0] / Xp[2] - ex, Xp[1] / Xp[2] - ey, *kp)
        board_res = [d.board_proj[m, 0] - (fp * (bx + ex) + u0p), d.board_proj[m, 1] - (ap * fp * (by + ey) + v0p)]
        # 3. background samples: distance to the epipolar line, projector pixels
        m = self.keep_back
        ln, xn, yn, jac = self._epipolar(p, m, Rc, tc, Rp, tp)
        if self.pixel_distance:
            # the distance in the projector's pixels, to first order: the normalised one over its gradient by the
            # sample's pixel, (l0, l1) A^-1 diag(1/fp, 1/(ap fp)), A the distortion's Jacobian there
            if jac is None:
                gx, gy = ln[0], ln[1] / ap
            else:
                a, b, dd = jac
                det = a * dd - b * b
                gx, gy = (ln[0] * dd - ln[1] * b) / det, (ln[1] * a - ln[0] * b) / (det * ap)
            back_res = (ln[0] * xn + ln[1] * yn + ln[2]) / D.sqrt(gx * gx + gy * gy) * fp
        else:
            back_res = (ln[0] * xn + ln[1] * yn + ln[2]) / D.sqrt(ln[0] * ln[0] + ln[1] * ln[1]) * fp
        # 4. priors
        pri = []
        if d.pp_prior is not None and d.camera_fixed is None:
            c, sd = d.pp_prior
            pri += [(p[2] - c[0]) / sd, (p[3] - c[1]) / sd]
        for name, mu, sd in d.priors:
            pri.append((p[IDX[name]] - mu) / sd)
        return cam_res, board_res, back_res, pri

    def corners(self, p):
        """``(2, K)`` residuals of the projector corners (observed - predicted, projector pixels)."""
        d = self.data
        if not len(d.corner_obj):
            return [np.empty(0), np.empty(0)]
        fp, ap, u0p, v0p, kp, ex, ey = self._projector(p)
        Rp = D.rotation([p[21], p[22], p[23]])
        Xp = D.transform(Rp, [p[24], p[25], p[26]], [d.corner_obj[:, 0], d.corner_obj[:, 1], d.corner_obj[:, 2]])
        bx, by = brown(Xp[0] / Xp[2] - ex, Xp[1] / Xp[2] - ey, *kp)
        return [d.corner_proj[:, 0] - (fp * (bx + ex) + u0p), d.corner_proj[:, 1] - (ap * fp * (by + ey) + v0p)]

    def residuals(self, p):
        """All residuals in noise sigmas (Dual when ``p`` is), one 1-D vector: camera corners (x then y), board
        samples (x then y), background, priors, projector corners (x then y)."""
        cam_res, board_res, back_res, pri = self.blocks(p)
        s = self.scales
        d = self.data
        wb = d.board_w[self.keep_board] * s.board
        wg = d.back_w[self.keep_back] * s.background
        back = back_res / wg
        if self.cauchy is not None:
            back = _cauchy(back, self.cauchy)
        corner = self.corners(p)
        parts = [cam_res[0] / s.camera, cam_res[1] / s.camera, board_res[0] / wb, board_res[1] / wb,
                 back, *pri, corner[0] / s.corners, corner[1] / s.corners]
        if isinstance(p, D.Dual):
            return D.concatenate([q for q in parts if np.size(D.value(q))])
        return np.concatenate([np.ravel(q) for q in parts if np.size(q)])


def _cauchy(r, c: float):
    """The Cauchy loss as a residual: ``sign(r) c sqrt(log(1 + (r/c)^2))`` (its square is twice the loss), plain or
    Dual (derivative ``|t| / ((1 + t^2) sqrt(log(1 + t^2)))``, ``t = r/c``, 1 at 0)."""
    v = D.value(r)
    t = v / c
    L = np.log1p(t * t)
    out = np.sign(t) * c * np.sqrt(L)
    if not isinstance(r, D.Dual):
        return out
    with np.errstate(all="ignore"):
        g = np.where(np.abs(t) > 1e-6, np.abs(t) / ((1.0 + t * t) * np.sqrt(L)), 1.0)
    return D.Dual(out, r.d * g[..., None])


# ------------------------------------------------------------------------------------------------
# the fit

@dataclass(frozen=True)
class JointFit:
    """One least-squares solution of a :class:`JointModel` with the parameters ``free`` (names) estimated.

    p : (27,) full parameter vector; free : the names estimated; cov : (27, 27) covariance (zero rows and columns
    for fixed parameters) from the Jacobian, in the scales' units; cost : the chi-square (sum of squared residuals
    in sigmas); n_residuals : their count; jac : (n, len(free)) Jacobian at the solution; residuals : (n,).
    """

    p: np.ndarray
    free: tuple
    cov: np.ndarray
    cost: float
    n_residuals: int
    jac: np.ndarray
    residuals: np.ndarray
    nfev: int


def solve(model: JointModel, p0, free, *, max_nfev: int = 60, tol: float = 1e-10) -> JointFit:
    """Least squares of ``model`` from ``p0`` over the parameters ``free`` (names of :attr:`JointModel.names`), with
    the exact Jacobian; trust-region reflective, steps scaled by the Jacobian's columns, stopping at ``tol``
    (scipy's xtol, ftol and gtol)."""
    from scipy.optimize import least_squares

    names = model.names
    p0 = np.asarray(p0, float)
    mask = np.array([n in free for n in names])
    basis = np.eye(len(names))[:, mask]
    cache = {}

    def evaluate(x):
        key = x.tobytes()
        if key not in cache:
            cache.clear()
            p = p0.copy()
            p[mask] = x
            r = model.residuals(D.Dual(p, basis))
            v = np.where(np.isfinite(r.v), r.v, 1e6)
            j = np.where(np.isfinite(r.d), r.d, 0.0)
            cache[key] = (v, j)
        return cache[key]

    with np.errstate(all="ignore"):
        res = least_squares(lambda x: evaluate(x)[0], p0[mask], jac=lambda x: evaluate(x)[1], method="trf",
                            x_scale="jac", xtol=tol, ftol=tol, gtol=tol, max_nfev=max_nfev)
    p = p0.copy()
    p[mask] = res.x
    r, J = evaluate(res.x)
    cov = np.zeros((len(names), len(names)))
    idx = np.flatnonzero(mask)
    cov[np.ix_(idx, idx)] = unc.covariance(J, 1.0)  # residuals in sigmas
    return JointFit(p=p, free=tuple(n for n in names if n in free), cov=cov, cost=float(r @ r),
                    n_residuals=len(r), jac=J, residuals=r, nfev=int(res.nfev))


def linearise(model: JointModel, p, free) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The residuals, the Jacobian over ``free`` (names) and its covariance ``(J^T J)^-1`` (27 + 4 square, zero
    rows and columns outside ``free``) at ``p``, without solving: the cost of an assumption held at ``p`` is the
    covariance with its parameter freed under its prior."""
    names = model.names
    p = np.asarray(p, float)
    mask = np.array([n in free for n in names])
    r = model.residuals(D.Dual(p, np.eye(len(names))[:, mask]))
    v, Jm = np.where(np.isfinite(r.v), r.v, 1e6), np.where(np.isfinite(r.d), r.d, 0.0)
    cov = np.zeros((len(names), len(names)))
    idx = np.flatnonzero(mask)
    cov[np.ix_(idx, idx)] = unc.covariance(Jm, 1.0)
    return v, Jm, cov


# ------------------------------------------------------------------------------------------------
# a held device's own uncertainty

#: Where each name of a held device's covariance (:data:`procam.crlb.VIEW_PARAMS`, and the projector's ``f_p, fy_p,
#: u0p, v0p``) sits: an entry of K, or an OpenCV distortion coefficient (index in OpenCV's order).
_K_ENTRY = {"f_c": (0, 0), "fy_c": (1, 1), "u0c": (0, 2), "v0c": (1, 2),
            "f_p": (0, 0), "fy_p": (1, 1), "u0p": (0, 2), "v0p": (1, 2)}
_COEFF = {"k1": 0, "k2": 1, "p1": 2, "p2": 3, "k3": 4, "k4": 5, "k5": 6, "k6": 7}


def _moved(device, names, values):
    """``device`` (:class:`procam.calibration.Device`) with its parameters ``names`` set to ``values``."""
    from dataclasses import replace

    K = np.array(device.K, float)
    dist = device.distortion
    coeffs = list(dist.coeffs) + [0.0] * 8
    for n, v in zip(names, values):
        if n in _K_ENTRY:
            K[_K_ENTRY[n]] = v
        elif n in _COEFF and dist.model == "opencv":
            coeffs[_COEFF[n]] = v
        else:
            raise ValueError(f"a held {dist.model!r} device has no parameter {n!r}")
    if dist.model == "opencv":
        dist = replace(dist, coeffs=tuple(coeffs[:max(len(dist.coeffs), 1 + max(
            (_COEFF[n] for n in names if n in _COEFF), default=-1))]))
    return replace(device, K=K, distortion=dist)


def _value(device, name) -> float:
    if name in _K_ENTRY:
        return float(np.asarray(device.K, float)[_K_ENTRY[name]])
    c = list(device.distortion.coeffs) + [0.0] * 8
    return float(c[_COEFF[name]])


def held_jacobian(model: JointModel, p, which: str, names) -> np.ndarray:
    """``(n, k)``: the derivative of :meth:`JointModel.residuals` at ``p`` by the held device's parameters ``names``
    (K entries ``f_c, fy_c, u0c, v0c`` or ``f_p, ...``, OpenCV's coefficients ``k1 ... k6, p1, p2``), by central
    differences (the held device undistorts through any of its models); ``which``: ``"camera"`` or ``"projector"``."""

    attr = "camera_fixed" if which == "camera" else "projector_fixed"
    held = getattr(model.data, attr)
    if held is None:
        raise ValueError(f"the model's {which} is not held")
    c0 = np.array([_value(held.device, n) for n in names])
    cols = []
    for k, n in enumerate(names):
        h = 1e-6 * max(abs(c0[k]), 1.0) if n in _K_ENTRY else 1e-6
        rs = []
        for s in (1.0, -1.0):
            c = c0.copy()
            c[k] += s * h
            dev = _moved(held.device, names, c)
            m = model.on(**{attr: FixedDevice(np.asarray(dev.K, float), dev)})
            rs.append(m.residuals(np.asarray(p, float)))
        cols.append((rs[0] - rs[1]) / (2 * h))
    return np.column_stack(cols) if cols else np.zeros((0, 0))


def held_covariance(model: JointModel, p, free, which: str, names, cov) -> np.ndarray:
    """What a held device's own uncertainty adds to the covariance of the free parameters (the delta method
    through the fit: the estimate moves by ``-(J^T J)^-1 J^T dr/dc`` per unit change of the held parameters ``c``).

    ``model`` has ``which`` (``"camera"`` or ``"projector"``) held (:class:`FixedDevice`); ``p`` the solution;
    ``free`` the names estimated; ``names`` (k,) and ``cov`` (k, k) the held device's parameters
    (:func:`held_jacobian`) and their covariance (a camera file's). Returns (P, P) over :attr:`JointModel.names`,
    zero outside ``free``; infinite where ``cov`` is.
    """
    if getattr(model.data, "camera_fixed" if which == "camera" else "projector_fixed") is None:
        raise ValueError(f"the model's {which} is not held")
    cov = np.asarray(cov, float)
    out = np.zeros((len(model.names), len(model.names)))
    idx = np.flatnonzero([n in free for n in model.names])
    if not np.all(np.isfinite(cov)):
        out[np.ix_(idx, idx)] = np.inf
        return out
    r0, J, Cp = linearise(model, p, free)
    Jc = held_jacobian(model, p, which, names)
    G = -Cp[np.ix_(idx, idx)] @ J.T @ Jc           # d(free) / d(held)
    out[np.ix_(idx, idx)] = G @ cov @ G.T
    return out
