"""The background check's fits of the one single-pose model.

:mod:`procam.single_pose.background` compares nested models of the same data: the paper's projector
(``u0p`` held at its assumed value, ``alpha_p`` at 1 or under its prior, no lens terms) against ``u0p`` (and
``alpha_p``) freed, and one ``u0p`` against one per part of the background. Each is the one single-pose model,
:class:`procam.single_pose.joint.JointModel`, with a choice of free parameters: the camera's board corners (the
parameters its own single-pose fit estimated, its principal-point prior if it used one), the projector's board
corners (pixels) and the background points' distances to their epipolar lines (projector pixels), all in noise
sigmas. :class:`PaperFits` starts it from a single-pose calibration's camera and projector solutions
(:func:`_single_pose_parts`), solves it (robustly: a graduated Cauchy loss on the background) and returns a
:class:`BackgroundFit` whose calibration carries a covariance that includes the camera's own uncertainty.
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
from . import joint as J

_N_CAM = len(J.CAMERA_VECTOR)
#: The projector parameters of the paper's model: the rest of :data:`procam.single_pose.joint.PROJECTOR` is held.
_PAPER_PROJECTOR = ("f_p", "u0p", "v0p", "alpha_p") + J.POSE_P


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
    params : (31,) the joint model's vector (:data:`procam.single_pose.joint.NAMES`).
    covariance : (31, 31); rows/columns of fixed parameters are 0.
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


def epipolar(Kc, und, Kp, R, T, proj) -> np.ndarray:
    """Signed distances (M,) of projector pixels ``proj`` (M, 2) to the epipolar lines of undistorted camera
    pixels ``und`` (M, 2) (``F = K_p^-T [T]x R K_c^-1``), projector pixels."""
    Kc = np.asarray(Kc)
    y = (und[:, 1] - Kc[1, 2]) / Kc[1, 1]
    x = (und[:, 0] - Kc[0, 2] - Kc[0, 1] * y) / Kc[0, 0]
    ray = np.column_stack([x, y, np.ones(len(und))])
    ln = ray @ (_skew(T) @ R).T                    # lines in normalised projector coordinates
    line = ln @ np.linalg.inv(Kp)                  # K_p^-T ln, as rows
    return (line[:, 0] * proj[:, 0] + line[:, 1] * proj[:, 1] + line[:, 2]) / np.hypot(line[:, 0], line[:, 1])


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


class PaperFits:
    """The joint model of a single-pose calibration, its background points and a choice of free parameters.

    Parameters
    ----------
    calibration : a :func:`procam.single_pose.calibrate` result without dense samples; ``cs, ps`` its camera and
        projector solutions (:func:`_single_pose_parts`).
    cam, proj : (M, 2) the background's distorted camera pixels and projector pixels.
    free : the projector parameters freed besides ``f_p, v0p`` and the pose: ``()``, ``("u0p",)`` or
        ``("u0p", "alpha_p")``.
    sigma_n : the background's noise (projector px); ``alpha_std``: while ``alpha_p`` is not freed, its prior
        ``1 +- alpha_std`` (0 holds it at 1).
    groups : (M,) int 0..G-1 or None: the background points of group g >= 1 get their own ``u0p``.
    board : None, or ``(cam (K, 2), proj (K, 2), sigma px)`` dense board samples that replace the projector's
        board corners (an experiment of ``benchmarks/background.py``).

    ``keep`` ((M,) bool) selects the background points in use. Parameter vectors are the model's
    (:attr:`procam.single_pose.joint.JointModel.names`).
    """

    def __init__(self, calibration, cs, ps, cam, proj, free, sigma_n, alpha_std=0.0, groups=None, board=None):
        self.cal, self.cs, self.ps = calibration, cs, ps
        self.free = tuple(free)
        view = calibration.views[0]
        C = np.asarray(cs.covariance, float)
        free_c = np.diag(C) > 0                   # the camera parameters its own fit estimated
        # the camera's corners (its likelihood, as its single-pose fit) and its principal-point prior
        cmask = np.asarray(cs.mask, bool) if cs.mask is not None else view.valid
        sigma_c = float(cs.info.get("sigma_px", np.nan))
        sigma_c = max(sigma_c, 0.01) if np.isfinite(sigma_c) else 0.1
        pp_prior = None
        if cs.principal_point_source == "image-center" and cs.info.get("pp_prior_std"):
            W, H = cs.image_size
            pp_prior = (np.array([(W - 1) / 2.0, (H - 1) / 2.0]), float(cs.info["pp_prior_std"]))
        pmask = np.array(ps.mask if ps.mask is not None else view.valid, bool)
        sigma_p = float(ps.info.get("sigma_px", np.nan))
        if not (np.isfinite(sigma_p) and sigma_p > 0):
            sigma_p = max(rms(ps.residuals[pmask]) if ps.residuals is not None else 0.0, 0.05)
        sigma_p = max(sigma_p, 0.02)
        # a camera whose intrinsics were given (single_pose.calibrate(known_camera=...)): held, any lens model
        self.fixed_camera = calibration.camera if not free_c[:6].any() else None
        fixed = None if self.fixed_camera is None else J.FixedDevice(np.asarray(self.fixed_camera.K, float),
                                                                      self.fixed_camera)
        priors = [("alpha_p", 1.0, float(alpha_std))] if "alpha_p" not in free and alpha_std > 0 else []
        obj = np.asarray(view.obj_pts, float)
        empty = np.empty((0, 2))
        bc, bp, sb = (empty, empty, 1.0) if board is None else board
        data = J.JointData(obj[cmask], np.asarray(view.cam_pts, float)[cmask], bc, bp, cam, proj,
                           camera_fixed=fixed, pp_prior=pp_prior, priors=priors,
                           corner_obj=None if board is not None else obj[pmask],
                           corner_proj=None if board is not None else np.asarray(view.proj_pts, float)[pmask],
                           back_groups=groups)
        self.model = J.JointModel(data, J.Scales(sigma_c, float(sb), float(sigma_n), sigma_p))
        self.model.pixel_distance = True      # the check's statistic: distances in projector pixels
        self.sigma_n = float(sigma_n)
        self.nfev = 0
        names = self.model.names
        q = np.asarray(ps.params, float)
        p0 = np.zeros(len(names))
        p0[:_N_CAM] = np.asarray(cs.params, float)
        p0[[J.IDX[n] for n in ("f_p", "alpha_p", "u0p", "v0p")]] = (q[0], 1.0, ps.u0, q[1])
        p0[[J.IDX[n] for n in J.POSE_P]] = q[2:8]
        p0[len(J.NAMES):] = ps.u0
        self.p0 = p0
        held = set(_PAPER_PROJECTOR) - {"f_p", "v0p", *free, *J.POSE_P} - ({"alpha_p"} if alpha_std > 0 else set())
        self.free_names = tuple(n for i, n in enumerate(J.CAMERA_VECTOR) if free_c[i]) + \
            tuple(n for n in _PAPER_PROJECTOR if n not in held) + names[len(J.NAMES):]

    @property
    def keep(self) -> np.ndarray:
        return self.model.keep_back

    @keep.setter
    def keep(self, value):
        self.model.keep_back = np.asarray(value, bool)

    def start(self, p=None) -> np.ndarray:
        """A start: the single-pose solution, or another fit's vector ``p`` with this fit's held parameters at
        their single-pose values (a vector without group ``u0p`` gets its ``u0p`` for each group)."""
        if p is None:
            return self.p0.copy()
        p = np.asarray(p, float)
        out = self.p0.copy()
        mask = np.isin(self.model.names, self.free_names)
        n = min(len(p), len(out))
        out[:n][mask[:n]] = p[:n][mask[:n]]
        out[len(p):] = p[J.IDX["u0p"]]
        return out

    def _least_squares(self, p):
        f = J.solve(self.model, p, self.free_names, max_nfev=200, tol=1e-12)
        self.nfev += f.nfev
        return f.p

    def solve(self, p0, robust: bool = False) -> np.ndarray:
        """Least squares from ``p0``; ``robust``: graduated Cauchy loss on the background (scale from the
        initial residuals' 75th percentile down to 3 noise sigmas), then the result."""
        self.model.cauchy = None
        if not robust:
            return self._least_squares(p0)
        r0 = np.abs(self.distances(p0)[self.keep]) / self.sigma_n
        c0 = max(3.0, float(np.percentile(r0[np.isfinite(r0)], 75))) if np.isfinite(r0).any() else 3.0
        p = p0
        try:
            for c in np.geomspace(c0, 3.0, max(1, int(np.ceil(np.log(c0 / 3.0) / np.log(4.0)))) + 1):
                self.model.cauchy = float(c)
                p = self._least_squares(p)
        finally:
            self.model.cauchy = None
        return p

    def solve_best(self, starts) -> np.ndarray:
        """:meth:`solve` from each start; the solution with the lowest cost."""
        best = None
        for p0 in starts:
            p = self.solve(p0)
            c = self.cost(p)
            if best is None or c < best[1]:
                best = (p, c)
        return best[0]

    def cost(self, p) -> float:
        r = np.where(np.isfinite(r := self.model.residuals(np.asarray(p, float))), r, 1e6)
        return float(r @ r)

    def devices(self, p):
        """``Kc, (centre, k1, k2), Rc, tc, Kp, Rp, tp, R, T`` of the vector ``p`` (board -> camera and -> projector
        poses, camera -> projector ``R, T``)."""
        Kc = models.intrinsic_matrix(p[0], p[2], p[3], p[1])
        if self.fixed_camera is not None:
            Kc = np.asarray(self.fixed_camera.K, float)
        k1, k2 = p[4] / models.KAPPA_SCALE ** 2, p[5] / models.KAPPA_SCALE ** 4
        Rc, tc = models.rvec_to_matrix(p[6:9]), np.asarray(p[9:12])
        Kp = models.intrinsic_matrix(p[J.IDX["f_p"]], p[J.IDX["u0p"]], p[J.IDX["v0p"]], p[J.IDX["alpha_p"]])
        Rp, tp = models.rvec_to_matrix(p[21:24]), np.asarray(p[24:27])
        R = Rp @ Rc.T
        return Kc, (np.asarray(p[2:4]), k1, k2), Rc, tc, Kp, Rp, tp, R, tp - R @ tc

    def distances(self, p) -> np.ndarray:
        """(M,) signed epipolar distances (projector px) of every background point (``keep`` or not), one ``u0p``."""
        Kc, (c, k1, k2), _, _, Kp, _, _, R, T = self.devices(p)
        d = self.model.data
        if self.fixed_camera is not None:
            und = self.fixed_camera.undistort(d.back_cam)
        elif self.cal.camera.distortion.model == "none":
            und = d.back_cam
        else:
            und = models.undistort_division(d.back_cam, c, k1, k2)
        return epipolar(Kc, und, Kp, R, T, d.back_proj)

    def fit_result(self, p, model) -> BackgroundFit:
        p = np.asarray(p, float)
        cost = self.cost(p)
        C = J.linearise(self.model, p, self.free_names)[2][:len(J.NAMES), :len(J.NAMES)]
        p = p[:len(J.NAMES)]
        cal = _calibration_from(self, p, C)
        s = unc.std(C)
        std = {k: float(s[J.IDX[n]]) for k, n in (("f_c", "f_c"), ("alpha_c", "alpha_c"), ("u0c", "u0c"),
                                                   ("v0c", "v0c"), ("f_p", "f_p"), ("u0p", "u0p"), ("v0p", "v0p"),
                                                   ("alpha_p", "alpha_p"))}
        return BackgroundFit(model=model, free=self.free, calibration=cal, params=p, covariance=C, std=std,
                             cost=cost, n_background=int(self.keep.sum()), sigma_n=self.sigma_n)


def _calibration_from(fits: PaperFits, p, C) -> Calibration:
    """The calibration of a joint fit: devices, extrinsics, std (delta method), RMS on the pose."""
    cal = fits.cal
    Kc, (c, k1, k2), Rc, tc, Kp, Rp, tp, R, T = fits.devices(p)
    dist = (Distortion("division", (float(c[0]), float(c[1])), float(k1), float(k2))
            if cal.camera.distortion.model == "division" and fits.fixed_camera is None else cal.camera.distortion)
    camera = cal.camera if fits.fixed_camera is not None else Device(Kc, tuple(cal.camera.image_size), dist)
    projector = Device(Kp, tuple(cal.projector.image_size), Distortion())

    def derived(v):
        Kc_, _, Rc_, tc_, Kp_, Rp_, tp_, R_, T_ = fits.devices(v)
        return np.r_[Kc_[1, 1], Kp_[1, 1], models.euler_deg(R_), T_, models.board_angles_deg(Rc_, tc_),
                     models.board_angles_deg(Rp_, tp_)]

    s = unc.std(C)
    sd = np.sqrt(np.abs(np.diag(unc.propagate(C, derived, p, typical=np.r_[np.abs(p)].clip(1e-2)))))
    std = dict(cal.std)
    std.update({"f_c": float(s[0]), "alpha_c": float(s[1]), "fy_c": float(sd[0]), "u0c": float(s[2]),
                "v0c": float(s[3]), "k1": float(s[4] / models.KAPPA_SCALE ** 2),
                "k2": float(s[5] / models.KAPPA_SCALE ** 4), "f_p": float(s[J.IDX["f_p"]]),
                "v0p": float(s[J.IDX["v0p"]]),
                "R_euler_deg": [float(v) for v in sd[2:5]], "T": [float(v) for v in sd[5:8]],
                "camera_angles_deg": [float(v) for v in sd[8:11]],
                "projector_angles_deg": [float(v) for v in sd[11:14]]})
    if "u0p" in fits.free:
        std["u0p"] = float(s[J.IDX["u0p"]])
    if "alpha_p" in fits.free_names:
        std["alpha_p"] = float(s[J.IDX["alpha_p"]])
        std["fy_p"] = float(sd[1])
    view = cal.views[0]
    cs, ps = fits.cs, fits.ps
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
