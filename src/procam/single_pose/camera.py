"""Single-pose camera calibration: centre of distortion, division model, principal-axis LM, joint refinement.

1. the principal point: the centre of distortion (COD) from the radial fundamental matrix when it is
   reliable; otherwise (weak distortion) the image centre, as the mean of a Gaussian prior, with a warning
   and a wider uncertainty -- or the joint fit's own principal point when the corners pin it better;
2. the paper's staged estimate: division-model ``k1, k2`` by the linear solve, undistortion, the
   6-parameter principal-axis LM (:mod:`._principal_axis`);
3. ``refine="joint"`` (default): a joint maximum-likelihood refinement of ``(f, alpha, c, k1, k2, pose)``
   on the **distorted** corners (the staged estimate is about 1.5x the Cramer-Rao bound for f_c, the
   joint one reaches it);
4. the covariance of every parameter from the Jacobian at the solution (:mod:`procam.uncertainty`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import distortion as dist
from .. import models
from .. import uncertainty as unc
from ..calibration import Distortion
from ..errors import CalibrationError
from ..stats import rms
from ._principal_axis import _LM, device_side, solve_camera_lm, valid_pose
from ._robust import RobustOptions, check_corners, clean, fit_robust, rejection_report
from ._solution import DeviceSolution
from .. import choices

#: How the principal point is found: ``auto`` (the COD when reliable, else the image centre as a prior),
#: ``paper`` (always the COD), ``image-center`` (always the image centre).
COD_MODES = choices.COD_MODES
#: ``joint`` (ML refinement of every camera parameter on the distorted corners) or ``none`` (the paper's
#: staged estimate).
REFINE_MODES = choices.CAMERA_REFINE_MODES


@dataclass(frozen=True)
class CameraOptions:
    """Options of the single-pose camera fit (:func:`calibrate_camera`).

    Attributes
    ----------
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
    """

    principal_point: tuple | None = None
    distortion: str | None = "division"
    cod: str = "auto"
    refine: str = "joint"
    n_coeffs: int = 2
    min_cod_score: float = dist.MIN_COD_SCORE
    pp_prior_std: float | None = None
    pp_prior_fraction: float = 0.025
    pp_max_std: float | None = None
    board_width: float | None = None

    def __post_init__(self):
        if self.cod not in COD_MODES:
            raise ValueError(f"cod must be one of {', '.join(COD_MODES)}, got {self.cod!r}")
        if self.refine not in REFINE_MODES and self.refine is not None:
            raise ValueError(f"refine must be one of {', '.join(REFINE_MODES)}, got {self.refine!r}")
        if self.n_coeffs not in (1, 2):
            raise ValueError(f"n_coeffs must be 1 or 2, got {self.n_coeffs!r}")


@dataclass(frozen=True)
class CameraSolution(DeviceSolution):
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
    params, covariance : the full model's parameters (:data:`procam.parameters.CAMERA_VECTOR`, (12,)) and their (12, 12)
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


def _camera_residual_fn(obj, cam, p_fixed, free, pp_prior=None):
    """Residuals (2N,) [+ 2 prior residuals ``w (pp - pp_mean)`` when ``pp_prior = (pp_mean, w)``]."""
    p_fixed = np.asarray(p_fixed, float)

    def fun(x):
        p = p_fixed.copy()
        p[free] = x
        r = (models.camera_predict(p, obj) - cam).ravel()
        r = np.where(np.isfinite(r), r, 1e3)
        if pp_prior is not None:
            r = np.concatenate([r, pp_prior[1] * (p[2:4] - pp_prior[0])])
        return r

    return fun


def _full_params(K, c, k1, k2, R, t):
    return np.array([K[0, 0], K[1, 1] / K[0, 0], c[0], c[1], k1 * models.KAPPA_SCALE ** 2, k2 * models.KAPPA_SCALE ** 4,
                     *models.matrix_to_rvec(R), *np.asarray(t, float).reshape(3)])


def _inside(pt, size) -> bool:
    return bool(-0.5 <= pt[0] <= size[0] - 0.5 and -0.5 <= pt[1] <= size[1] - 0.5)


def _staged_camera(M, m, c, size, use_dist, n_coeffs, board_width, name, warnings):
    """The paper's staged estimate with the principal point / COD ``c``: returns (p_full (12,), staged dict, fit_k2)."""
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
    lm = solve_camera_lm(M, und, c, size, width=board_width)
    if lm is None:
        raise CalibrationError(f"pose {name!r}: camera LM found no valid (non-mirror) solution from any "
                               f"start; the pose is probably degenerate (board fronto-parallel?)")
    K_st = models.intrinsic_matrix(lm.f, c[0], c[1], lm.alpha)
    p_staged = _full_params(K_st, c, k1, k2, lm.R, lm.t)
    staged = dict(f=lm.f, alpha=lm.alpha, principal_point=np.array(c, float), k1=k1, k2=k2, K=K_st,
                  R=lm.R, t=lm.t, start=lm.start, cost_undistorted=lm.cost,
                  rms_undistorted_px=rms(lm.residuals), closed_form=lm.closed_form,
                  starts=[(r.name, r.cost, r.valid) for r in lm.runs],
                  rms_px=rms(models.camera_predict(p_staged, M) - m))
    return p_staged, staged, fit_k2


def _joint_camera(M, m, p0, free, pp_prior, size, max_nfev=150):
    """Joint ML/MAP refinement of the full camera model from ``p0``; returns (p, cost) or (None, inf).

    The result is rejected if it is invalid, fits worse than ``p0``, or puts the camera on the other
    side of the board than the (staged) start ``p0`` does (a mirror solution).
    """
    from scipy.optimize import least_squares

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
    side = device_side(models.rvec_to_matrix(p0[6:9]), p0[9:12])  # the start's side, not the result's
    if not valid_pose(Rj, pj[9:12], M, side) or not np.all(np.isfinite(models.camera_predict(pj, M))):
        return None, float("inf")
    if r.cost > 0.5 * np.sum(fun(p0[free]) ** 2) + 1e-12:
        return None, float("inf")
    return pj, float(r.cost)


def calibrate_camera(obj_pts, cam_pts, image_size, options: CameraOptions = CameraOptions(), *,
                     robust: RobustOptions = RobustOptions(), name: str = "view") -> CameraSolution:
    """Single-pose camera calibration: intrinsics, division distortion and board pose.

    Parameters
    ----------
    obj_pts : (N, 3) or (N, 2) board points (board units; z = 0).
    cam_pts : (N, 2) **distorted** camera pixels; rows with NaN are ignored.
    image_size : (width, height) in pixels.
    options : :class:`CameraOptions`.
    robust : :class:`~procam.single_pose.RobustOptions` -- the corners' minimum and the outlier
        rejection; rejections are reported in ``rejected``/``rejected_residuals_px`` and as a warning.
    name : pose name used in messages.

    Returns
    -------
    CameraSolution

    Raises
    ------
    CalibrationError
        Too few corners, no valid (non-mirror) solution, or ``cod="paper"`` with no finite COD.
    """
    obj, cam, mask = clean(obj_pts, cam_pts, f"pose {name!r}")
    if image_size is None:
        raise CalibrationError(f"pose {name!r}: the camera image size is unknown; pass image_size=(W, H)")
    W, Hh = int(image_size[0]), int(image_size[1])
    check_corners(obj, mask, robust.min_points, name, "camera corners", "check the board detection")

    def predict(sol):
        return models.camera_predict(sol.params, obj)

    sol, used, thr, notes = fit_robust(lambda u: _camera_fit(obj, cam, u, (W, Hh), options, name), predict, cam, obj,
                                       mask, robust)
    return rejection_report(sol, predict, cam, mask, used, thr, notes, name, "camera", robust)


def _camera_fit(obj, cam, mask, image_size, o: CameraOptions, name: str) -> CameraSolution:
    """One single-pose camera fit on the corners ``mask`` (see :func:`calibrate_camera`)."""
    principal_point, distortion, cod, refine, n_coeffs = o.principal_point, o.distortion, o.cod, o.refine, o.n_coeffs
    min_cod_score, pp_prior_std, pp_prior_fraction, pp_max_std = o.min_cod_score, o.pp_prior_std, \
        o.pp_prior_fraction, o.pp_max_std
    board_width = o.board_width
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
            Jb = unc.jacobian(_camera_residual_fn(M, m, best, free), best[free], typical=typical[free])
            sb = unc.sigma_from_residuals((models.camera_predict(best, M) - m).ravel(), int(free.sum()))
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
        sig0 = unc.sigma_from_residuals((models.camera_predict(p_staged, M) - m).ravel(), 10)
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
    res = models.camera_predict(p, M) - m
    full_fun = _camera_residual_fn(M, m, p, np.ones(12, bool))
    J = unc.jacobian(full_fun, p, typical=typical)
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
    dist_obj = Distortion("division", (float(p[2]), float(p[3])), float(p[4] / models.KAPPA_SCALE ** 2),
                          float(p[5] / models.KAPPA_SCALE ** 4)) if use_dist else Distortion()
    residuals = np.full((len(obj), 2), np.nan)
    residuals[mask] = -res  # observed - predicted
    info = dict(sigma_px=sigma, n_points=int(mask.sum()), refine=refine or "none", free=free,
                max_distortion_px=dist.max_displacement(m, p[2:4], dist_obj.k1, dist_obj.k2) if use_dist else 0.0,
                pp_prior_std=sigma_pp if pp_source == "image-center" else None)
    return CameraSolution(K=K, distortion=dist_obj, R=R, t=t, rms_px=rms(res), residuals=residuals, std=std,
                          angles_deg=models.board_angles_deg(R, t), cost=float(0.5 * np.sum(res ** 2)),
                          warnings=tuple(warnings), cod=cod_est, principal_point_source=pp_source,
                          staged=staged, params=p, covariance=cov, mask=mask, image_size=(W, Hh), info=info)


def _camera_std(p, cov) -> dict:
    s = unc.std(cov)

    def ang(q):
        R = models.rvec_to_matrix(q[6:9])
        return models.board_angles_deg(R, q[9:12])

    def fy(q):
        return np.array([q[0] * q[1]])

    ca = unc.propagate(cov, ang, p, typical=1.0)
    cfy = unc.propagate(cov, fy, p)
    return {"f_c": float(s[0]), "alpha_c": float(s[1]), "fy_c": float(np.sqrt(abs(cfy[0, 0]))),
            "u0c": float(s[2]), "v0c": float(s[3]), "k1": float(s[4] / models.KAPPA_SCALE ** 2),
            "k2": float(s[5] / models.KAPPA_SCALE ** 4), "angles_deg": np.sqrt(np.abs(np.diag(ca))),
            "t": s[9:12].copy()}
