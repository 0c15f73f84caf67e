"""The joint fit behind :mod:`procam.single_pose.background`: one least-squares problem over the camera's
board corners (and its principal-point prior, if it used one), the projector's board corners and the
background points' distances to their epipolar lines, all in noise sigmas.

It starts from a single-pose calibration's camera and projector solutions (:func:`_single_pose_parts`),
frees the projector parameters the caller names (``u0p``, ``alpha_p``; otherwise the paper's assumptions,
``alpha_p`` with its prior), and returns a :class:`BackgroundFit` whose calibration carries a covariance that
includes the camera's own uncertainty. The check and the model choice that use it are in
:mod:`procam.single_pose.background`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import models
from .. import uncertainty as unc
from ..calibration import Calibration, Device, Distortion
from ..errors import CalibrationError
from ..residuals import pnp, stereo_pose
from ..stats import rms

# the joint parameter vector: camera (procam.parameters.CAMERA_VECTOR) + projector
_N_CAM = 12
_PROJ = ("f_p", "u0p", "v0p", "alpha_p", "rx", "ry", "rz", "tx", "ty", "tz")


@dataclass(frozen=True)
class BackgroundFit:
    """One joint fit of the camera's and the projector's board corners and the background.

    Attributes
    ----------
    model : ``"assumed"`` (the single-pose projector assumptions kept), ``"u0p"`` or ``"u0p+alpha_p"`` (the
        parameters freed, ``+``-joined).
    free : the projector parameters estimated besides ``f_p, v0p`` (empty for ``assumed``).
    calibration : the fitted :class:`~procam.calibration.Calibration` (camera and projector updated,
        ``std`` from ``covariance``).
    params : (22,) camera (:data:`procam.parameters.CAMERA_VECTOR`) + projector
        ``(f_p, u0p, v0p, alpha_p, rvec (3), t (3))`` (board -> projector pose).
    covariance : (22, 22); rows/columns of fixed parameters are 0.
    std : dict name -> 1 sigma (``f_c ... v0c`` of the camera, ``f_p, u0p, v0p, alpha_p``; 0 when fixed).
    cost : sum of the squared whitened residuals (camera corners / sigma_c, its principal-point prior if any,
        the alpha_p prior, projector corners / sigma_p, background / sigma_n).
    n_background : background points in the fit; ``sigma_n`` their noise (px) used for the weights.
    """

    model: str
    free: tuple
    calibration: Calibration
    params: np.ndarray
    covariance: np.ndarray
    std: dict
    cost: float
    n_background: int
    sigma_n: float



def _skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]], dtype=np.result_type(v, float))


def _epipolar(Kc, und, Kp, R, T, proj) -> np.ndarray:
    """Signed distances (M,) of projector pixels to the epipolar lines of undistorted camera pixels."""
    Kc = np.asarray(Kc)
    y = (und[:, 1] - Kc[1, 2]) / Kc[1, 1]
    x = (und[:, 0] - Kc[0, 2] - Kc[0, 1] * y) / Kc[0, 0]
    ray = np.column_stack([x, y, np.ones(len(und))])
    ln = ray @ (_skew(T) @ R).T                    # lines in normalised projector coordinates
    line = ln @ np.linalg.inv(Kp)                  # K_p^-T ln, as rows
    return (line[:, 0] * proj[:, 0] + line[:, 1] * proj[:, 1] + line[:, 2]) / np.hypot(line[:, 0], line[:, 1])


# --------------------------------------------------------------------------------------------------
# the joint fit
# --------------------------------------------------------------------------------------------------

def _single_pose_parts(calibration):
    """The single-pose solutions a joint fit starts from, or a reason why there are none."""
    cs, ps = calibration.info.get("camera"), calibration.info.get("projector")
    if cs is None or ps is None or getattr(cs, "covariance", None) is None or getattr(ps, "params", None) is None \
            or not calibration.views:
        return None, "the calibration is not a single-pose one (its camera and projector solutions are needed)"
    if len(cs.params) != _N_CAM or len(ps.params) != 8:
        return None, "unexpected single-pose parameter vectors"
    if calibration.projector.distortion.model != "none":
        return None, "the projector has a distortion model (the single-pose projector has none)"
    C = np.asarray(cs.covariance, float)
    if not np.all(np.isfinite(C)):
        return None, "the camera's single-pose estimate is degenerate (infinite uncertainty)"
    W, H = calibration.projector.image_size
    f = float(ps.params[0])
    if not (0.2 * np.hypot(W, H) <= f <= 5.0 * np.hypot(W, H)) or not np.all(np.isfinite(ps.covariance)):
        return None, (f"the projector's single-pose estimate failed (f_p = {f:.0f} px), so there is no start for the "
                      "joint fit; use a pose turned about the projector's vertical axis")
    return (cs, ps), ""


class _Joint:
    """Joint least squares: the camera's board corners (and its principal-point prior, if it had one), the
    projector's board corners and the background's epipolar distances, all in noise sigmas."""

    def __init__(self, calibration, cs, ps, cam, proj, free, sigma_n, alpha_std=0.0):
        self.cal = calibration
        self.cs, self.ps = cs, ps
        C = np.asarray(cs.covariance, float)
        self.pc0 = np.asarray(cs.params, float).copy()
        self.free_c = np.diag(C) > 0            # the camera parameters its own fit estimated
        view = calibration.views[0]
        # the camera's corners (its likelihood, exactly as its single-pose fit) and its principal-point prior
        cmask = np.asarray(cs.mask, bool) if cs.mask is not None else view.valid
        cmask = cmask & np.isfinite(view.cam_pts).all(1) & np.isfinite(view.obj_pts).all(1)
        self.obj_c = np.asarray(view.obj_pts, float)[cmask]
        self.cam_c = np.asarray(view.cam_pts, float)[cmask]
        self.sigma_c = max(float(cs.info.get("sigma_px", np.nan)), 0.01) \
            if np.isfinite(cs.info.get("sigma_px", np.nan)) else 0.1
        self.pp_prior = None
        if cs.principal_point_source == "image-center" and cs.info.get("pp_prior_std"):
            W, H = cs.image_size
            self.pp_prior = (np.array([(W - 1) / 2.0, (H - 1) / 2.0]), float(cs.info["pp_prior_std"]))
        mask = np.array(ps.mask if ps.mask is not None else view.valid, bool)
        mask = mask & np.isfinite(view.proj_pts).all(1) & np.isfinite(view.obj_pts).all(1)
        self.obj = np.asarray(view.obj_pts, float)[mask]
        self.corners = np.asarray(view.proj_pts, float)[mask]
        self.sigma_p = float(ps.info.get("sigma_px", np.nan))
        if not (np.isfinite(self.sigma_p) and self.sigma_p > 0):
            self.sigma_p = max(rms(ps.residuals[mask]) if ps.residuals is not None else 0.0, 0.05)
        self.sigma_p = max(self.sigma_p, 0.02)
        q = np.asarray(ps.params, float)
        self.q0 = np.r_[q[0], ps.u0, q[1], 1.0, q[2:8]]
        self.free_q = np.ones(len(_PROJ), bool)
        self.free_q[1] = "u0p" in free
        self.free_q[3] = "alpha_p" in free or alpha_std > 0
        self.alpha_w = 1.0 / alpha_std if ("alpha_p" not in free and alpha_std > 0) else 0.0
        self.free = tuple(free)
        self.cam, self.proj = cam, proj
        self.keep = np.ones(len(cam), bool)
        self.sigma_n = float(sigma_n)
        self.cauchy = None
        self.nfev = 0
        self.groups = None      # (M,) int 0..G-1: groups 1.. get their own u0p (the last G-1 parameters)
        self.dist_model = calibration.camera.distortion.model
        # a camera whose intrinsics were given (single_pose.calibrate(known_camera=...)): any distortion
        # model, its undistorted background points fixed
        self.fixed_camera = calibration.camera if not self.free_c[:6].any() else None
        self.cam_und = self.fixed_camera.undistort(cam) if self.fixed_camera is not None else None

    # packing
    def x0(self, pc=None, q=None):
        """The free vector at the single-pose solution, or at the full parameters ``pc, q`` of another fit
        (parameters fixed here keep their fixed values)."""
        pc = self.pc0 if pc is None else pc
        q = self.q0 if q is None else np.where(self.free_q, q, self.q0)
        x = np.r_[pc[self.free_c], q[self.free_q]]
        return x if self.groups is None else np.r_[x, np.full(self.groups.max(), q[1])]

    def solve_best(self, starts):
        """:meth:`solve` from each start; the solution with the lowest cost."""
        best = None
        for x0 in starts:
            x = self.solve(x0)
            c = self.cost(x)
            if best is None or c < best[1]:
                best = (x, c)
        return best[0]

    def full(self, x):
        pc = self.pc0.astype(np.result_type(x, float)).copy()
        nc = int(self.free_c.sum())
        pc[self.free_c] = x[:nc]
        q = self.q0.astype(np.result_type(x, float)).copy()
        q[self.free_q] = x[nc:nc + int(self.free_q.sum())]
        return pc, q

    @staticmethod
    def devices(pc, q):
        Kc = models.intrinsic_matrix(pc[0], pc[2], pc[3], pc[1])
        k1, k2 = pc[4] / models.KAPPA_SCALE ** 2, pc[5] / models.KAPPA_SCALE ** 4
        Rc, tc = models.rvec_to_matrix(pc[6:9]), pc[9:12]
        Kp = models.intrinsic_matrix(q[0], q[1], q[2], q[3])
        Rp, tp = models.rvec_to_matrix(q[4:7]), q[7:10]
        R = Rp @ Rc.T
        return Kc, (pc[2:4], k1, k2), Rc, tc, Kp, Rp, tp, R, tp - R @ tc

    def undistort(self, cam, c, k1, k2):
        if self.fixed_camera is not None:
            return self.fixed_camera.undistort(cam)
        return cam if self.dist_model == "none" else models.undistort_division(cam, c, k1, k2)

    def distances(self, pc, q, cam, proj):
        Kc, (c, k1, k2), _, _, Kp, _, _, R, T = self.devices(pc, q)
        return _epipolar(Kc, self.undistort(cam, c, k1, k2), Kp, R, T, proj)

    def residuals(self, x):
        pc, q = self.full(x)
        Kc, (c, k1, k2), Rc, tc, Kp, Rp, tp, R, T = self.devices(pc, q)
        if self.fixed_camera is not None:
            pred_c = self.fixed_camera.project(Rc, tc, self.obj_c)
        else:
            pred_c = models.camera_predict(pc, self.obj_c)
        r_cam = ((pred_c - self.cam_c) / self.sigma_c).ravel()
        if self.pp_prior is not None:
            r_cam = np.concatenate([r_cam, (pc[2:4] - self.pp_prior[0]) / self.pp_prior[1]])
        r_corner = ((models.project(Kp, Rp, tp, self.obj) - self.corners) / self.sigma_p).ravel()
        cam, proj = self.cam[self.keep], self.proj[self.keep]
        und = self.cam_und[self.keep] if self.cam_und is not None else self.undistort(cam, c, k1, k2)
        r_bg = _epipolar(Kc, und, Kp, R, T, proj) / self.sigma_n
        if self.groups is not None:
            g = self.groups[self.keep]
            extra = x[int(self.free_c.sum()) + int(self.free_q.sum()):]
            for k, u0 in enumerate(extra, start=1):
                Kg = models.intrinsic_matrix(q[0], u0, q[2], q[3])
                r_bg = np.where(g == k, _epipolar(Kc, und, Kg, R, T, proj) / self.sigma_n, r_bg)
        if self.cauchy is not None:
            # Cauchy loss on the background only (the prior and the corners stay quadratic):
            # residual sign(r) sqrt(2 rho(r)), rho(r) = c^2/2 log(1 + (r/c)^2)
            c = self.cauchy
            r_bg = np.sign(r_bg) * c * np.sqrt(np.log1p((r_bg / c) ** 2))
        r = np.concatenate([r_cam, [self.alpha_w * (q[3] - 1.0)], r_corner, r_bg])
        return np.where(np.isfinite(r), r, 1e6)

    def solve(self, x0, robust: bool = False):
        """Least squares from ``x0``; ``robust``: graduated Cauchy loss on the background (scale from the
        initial residuals' 75th percentile down to 3 noise sigmas), then the result."""
        from scipy.optimize import least_squares

        def run(x):
            with np.errstate(all="ignore"):
                res = least_squares(self.residuals, x, x_scale="jac", method="trf", xtol=1e-12, ftol=1e-12,
                                    gtol=1e-12, max_nfev=200)
            self.nfev += res.nfev
            return res.x

        if not robust:
            self.cauchy = None
            return run(x0)
        r0 = np.abs(self.distances(*self.full(x0), self.cam[self.keep], self.proj[self.keep])) / self.sigma_n
        c0 = max(3.0, float(np.percentile(r0[np.isfinite(r0)], 75))) if np.isfinite(r0).any() else 3.0
        x = x0
        for c in np.geomspace(c0, 3.0, max(1, int(np.ceil(np.log(c0 / 3.0) / np.log(4.0)))) + 1):
            self.cauchy = float(c)
            x = run(x)
        self.cauchy = None
        return x

    def cost(self, x) -> float:
        r = self.residuals(x)
        return float(r @ r)

    def covariance(self, x) -> np.ndarray:
        """(22, 22) covariance of the full vector (0 rows/columns for fixed parameters)."""
        typ = np.r_[np.abs(self.pc0[self.free_c]).clip(1e-2), np.abs(self.q0[self.free_q]).clip(1e-2)]
        J = unc.jacobian(self.residuals, x, typical=typ)
        Cf = unc.covariance(J, 1.0)
        n = _N_CAM + len(_PROJ)
        idx = np.r_[np.nonzero(self.free_c)[0], _N_CAM + np.nonzero(self.free_q)[0]]
        C = np.zeros((n, n))
        C[np.ix_(idx, idx)] = Cf
        return C

    def fit_result(self, x, model) -> BackgroundFit:
        pc, q = self.full(x)
        p = np.r_[pc, q]
        C = self.covariance(x)
        cal = _calibration_from(self.cal, self, pc, q, C, model)
        s = unc.std(C)
        std = {"f_c": s[0], "alpha_c": s[1], "u0c": s[2], "v0c": s[3], "f_p": s[12], "u0p": s[13], "v0p": s[14],
               "alpha_p": s[15]}
        return BackgroundFit(model=model, free=self.free, calibration=cal, params=p,
                             covariance=C, std={k: float(v) for k, v in std.items()}, cost=self.cost(x),
                             n_background=int(self.keep.sum()), sigma_n=self.sigma_n)


def _calibration_from(cal: Calibration, joint: _Joint, pc, q, C, model) -> Calibration:
    """The calibration of a joint fit: devices, extrinsics, std (delta method), RMS on the pose."""
    Kc, (c, k1, k2), Rc, tc, Kp, Rp, tp, R, T = joint.devices(pc, q)
    Kc, Kp, R, T = (np.asarray(a, float) for a in (Kc, Kp, R, T))
    dist = (Distortion("division", (float(c[0]), float(c[1])), float(k1), float(k2))
            if joint.dist_model == "division" and joint.fixed_camera is None else cal.camera.distortion)
    camera = cal.camera if joint.fixed_camera is not None else Device(Kc, tuple(cal.camera.image_size), dist)
    projector = Device(Kp, tuple(cal.projector.image_size), Distortion())
    p = np.r_[pc, q]

    def derived(v):
        Kc_, _, Rc_, tc_, Kp_, Rp_, tp_, R_, T_ = joint.devices(v[:_N_CAM], v[_N_CAM:])
        return np.r_[Kc_[1, 1], Kp_[1, 1], models.euler_deg(R_), T_, models.board_angles_deg(Rc_, tc_),
                     models.board_angles_deg(Rp_, tp_)]

    s = unc.std(C)
    sd = np.sqrt(np.abs(np.diag(unc.propagate(C, derived, p, typical=np.r_[np.abs(p)].clip(1e-2)))))
    std = dict(cal.std)
    std.update({"f_c": float(s[0]), "alpha_c": float(s[1]), "fy_c": float(sd[0]), "u0c": float(s[2]),
                "v0c": float(s[3]), "k1": float(s[4] / models.KAPPA_SCALE ** 2),
                "k2": float(s[5] / models.KAPPA_SCALE ** 4), "f_p": float(s[12]), "v0p": float(s[14]),
                "R_euler_deg": [float(v) for v in sd[2:5]], "T": [float(v) for v in sd[5:8]],
                "camera_angles_deg": [float(v) for v in sd[8:11]],
                "projector_angles_deg": [float(v) for v in sd[11:14]]})
    if "u0p" in joint.free:
        std["u0p"] = float(s[13])
    if joint.free_q[3]:
        std["alpha_p"] = float(s[15])
        std["fy_p"] = float(sd[1])
    view = cal.views[0]
    cs, ps = joint.cs, joint.ps
    cin = np.asarray(cs.mask, bool) if cs.mask is not None else view.valid
    pin = np.asarray(ps.mask, bool) if ps.mask is not None else view.valid
    both = cin & pin
    obj = np.asarray(view.obj_pts, float)
    with np.errstate(all="ignore"):
        cam_und = camera.undistort(np.where(view.valid[:, None], view.cam_pts, np.nan))
    proj_pts = np.asarray(view.proj_pts, float)

    def pnp_rms(o, m, K):
        try:
            return rms(pnp(o, m, K)[2])
        except CalibrationError:
            return float("nan")

    cam_rms = pnp_rms(obj[cin], cam_und[cin], Kc)
    proj_rms = pnp_rms(obj[pin], proj_pts[pin], Kp)
    try:
        _, _, rc, rp = stereo_pose(obj[both], cam_und[both], proj_pts[both], Kc, Kp, R, T, Rc, tc)
        stereo = rms([rc, rp])
    except CalibrationError:
        stereo = float("nan")
    poses = []
    for k, pose in enumerate(cal.poses):
        pose = dict(pose)
        if k == 0:
            pose.update({"camera_angles_deg": [float(a) for a in models.board_angles_deg(Rc, tc)],
                         "projector_angles_deg": [float(a) for a in models.board_angles_deg(Rp, tp)],
                         "cam_rms": cam_rms, "proj_rms": proj_rms, "stereo_rms": stereo})
        poses.append(pose)
    return cal.replace(camera=camera, projector=projector, R=R, T=T, cam_rms=cam_rms, proj_rms=proj_rms,
                       stereo_rms=stereo, std=std, poses=tuple(poses))
