"""Cramér–Rao lower bounds for single-pose calibration.

For i.i.d. Gaussian pixel noise ``sigma`` on the observations and a model ``m(p)``
the Fisher information is ``I = J^T J / sigma^2`` with ``J = dm/dp`` at the truth, and
any unbiased estimator has ``std(p_k) >= sqrt([I^-1]_kk)``.  These bounds say what *any*
single-pose method could achieve at a pose; biases from model errors (a principal
point that is not the COD, ``u0p = W/2``, projector lens distortion) come on top.

Computation:

1. ``J`` by complex-step differentiation (exact to rounding; central differences with
   step ``rel_step * max(1, |p_k|)`` as an option) in the scaled parameters
   (``kappa1 = k1 s^2``, ``kappa2 = k2 s^4`` with ``s = 1000`` px; rotations are local
   perturbations ``R = exp([w]_x) R_true`` about ``w = 0``).
2. Normalise the columns of ``J`` to unit norm.
3. If ``sigma_min / sigma_max`` of the normalised ``J`` is below ``cond_limit``
   the pose is degenerate for that model: every bound is ``inf``.
4. Otherwise ``Cov = sigma^2 (J_n^T J_n)^-1``, rescaled to raw units.  ``inv``, not
   ``pinv``: a pseudo-inverse silently reports tiny bounds at degenerate poses.

The model is the solver's own (:func:`procam.models.project`, :func:`procam.models.distort_division`),
and the Jacobian and covariance are :mod:`procam.uncertainty`'s, so the bound is computed on the model
the single-pose solver fits. The device bounds are :class:`Bound` s (the std bound per intrinsic
parameter, named as in :mod:`procam.parameters`, the pose's bounds, the covariance and the condition
number); :func:`extrinsics_bound` gives an :class:`ExtrinsicsBound`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import models
from . import uncertainty as unc

__all__ = ["Bound", "ExtrinsicsBound", "ViewsBound", "camera_bound", "projector_bound", "extrinsics_bound",
           "fisher_bound", "view_information", "views_bound", "VIEW_PARAMS"]

_CAMERA_MODELS = ("full", "known_distortion", "known_alpha", "known_intrinsics")


@dataclass(frozen=True)
class Bound:
    """Cramer-Rao lower bound of one device's single-pose calibration at one pose.

    Attributes
    ----------
    std : dict
        Lower bound of the standard deviation of each intrinsic parameter, named as in
        :mod:`procam.parameters` (camera ``f_c, alpha_c, u0c, v0c, k1, k2``; projector ``f_p, v0p``);
        0.0 for a parameter the model treats as known, ``inf`` everywhere when the pose is degenerate.
    omega : (3,) rad, bounds of a small rotation of the board pose about the device axes.
    t : (3,) board units, bounds of the pose's translation.
    cov : (P, P) covariance bound in raw units, rows named by ``params``.
    params : tuple of the parameter names (rows of ``cov``).
    condition : ``s_min / s_max`` of the column-normalised Jacobian (degenerate below ``cond_limit``).
    model : ``"full"``, ``"known_distortion"``, ``"known_alpha"`` (camera) or ``"projector"``.
    prior_used : whether the camera bound includes the principal-point prior (``pp_prior_std``).
    """

    std: dict
    omega: np.ndarray
    t: np.ndarray
    cov: np.ndarray
    params: tuple
    condition: float
    model: str
    prior_used: bool = False

    @property
    def degenerate(self) -> bool:
        """True when the pose determines none of the intrinsics (every bound infinite)."""
        return not np.all(np.isfinite(self.cov))


@dataclass(frozen=True)
class ExtrinsicsBound:
    """Delta-method bound of the camera -> projector extrinsics (:func:`extrinsics_bound`).

    ``euler_deg`` (3,) stds of the Euler angles of ``R`` (degrees); ``T`` (3,) stds of ``T``; ``sigma_T`` =
    ``sqrt(sum var T)``; ``T_norm`` std of ``|T|``; ``cov`` (6, 6) of ``(psi, nu, phi [rad], T)``. ``inf``
    when either device is degenerate.
    """

    euler_deg: np.ndarray
    T: np.ndarray
    sigma_T: float
    T_norm: float
    cov: np.ndarray


def _perturb(R, w):
    """``exp([w]_x) @ R``: a rotation perturbed in the device frame (complex-step safe)."""
    return models.rvec_to_matrix(w) @ R


def fisher_bound(model, p0, sigma, *, rel_step=1e-6, cond_limit=unc.RCOND, jacobian="complex", prior_precision=None):
    """Generic CRLB: covariance lower bound of the parameters of ``model`` at ``p0``.

    Parameters
    ----------
    model : callable
        ``model(p) -> (M,)`` noise-free observations (pixels) for parameters ``p`` (P,).
    p0 : array_like, shape (P,)
        True (scaled) parameters.
    sigma : float
        Standard deviation of the i.i.d. Gaussian noise on each observation (pixels).
    rel_step : float
        Central-difference step relative to ``max(1, |p_k|)``.
    cond_limit : float
        ``sigma_min / sigma_max`` of the column-normalised Jacobian below which the
        problem is declared degenerate.
    jacobian : {"complex", "central"}
        How :func:`procam.uncertainty.jacobian` differentiates ``model``.
    prior_precision : (P,), optional
        Information of a Gaussian prior per (scaled) parameter, ``1 / prior_std^2`` (0 = none): the bound
        becomes the Bayesian one, ``(J^T J / sigma^2 + P)^-1``.

    Returns
    -------
    cov : ndarray, shape (P, P)
        ``sigma^2 (J^T J)^-1`` (:func:`procam.uncertainty.covariance`), all ``inf`` when degenerate or
        non-finite.
    condition : float
        ``sigma_min / sigma_max`` of the normalised Jacobian (0 when non-finite).
    """
    J = unc.jacobian(model, np.asarray(p0, float), method=jacobian, rel_step=rel_step)
    return unc.covariance(J, sigma, prior_precision=prior_precision, rcond=cond_limit), unc.condition(J)


def camera_bound(K, dist_center, k1, k2, R, t, obj_pts, sigma=0.1, model="full", *,
                 radius_scale=1000.0, rel_step=1e-6, cond_limit=unc.RCOND, jacobian="complex", pp_prior_std=None,
                 pp_prior_when="always"):
    """CRLB of a single-pose camera calibration with the division model.

    Observations are the 2N **distorted** corners
    ``m_hat = D^-1(pi(K (R M + t)); c, k1, k2)``.

    Parameters
    ----------
    K : array_like, shape (3, 3)
        True intrinsics ``[[f, 0, u0], [0, alpha f, v0], [0, 0, 1]]`` (pixels).
    dist_center : array_like, shape (2,) or None
        True centre of distortion ``c`` (pixels); ``None`` means the principal point.
        In the ``"full"`` model the unknowns ``(cu, cv)`` move the principal point and the
        COD together (the method sets the principal point to the COD).
    k1, k2 : float
        Division-model coefficients (px^-2, px^-4); ``k1 < 0`` is barrel.
    R, t : array_like, shapes (3, 3) and (3,)
        Board -> camera pose (``X_cam = R X + t``), board units.
    obj_pts : array_like, shape (N, 3)
        Board corners (board units).
    sigma : float
        Corner noise (pixels, per coordinate).
    model : {"full", "known_distortion", "known_alpha"}
        ``"full"``: ``p = (f, alpha, cu, cv, kappa1, kappa2, omega, t)`` (12);
        ``"known_distortion"``: ``c, k1, k2`` known, ``p = (f, alpha, omega, t)`` (8),
        the limit of the paper's stage-2 LM; ``"known_alpha"``: ``alpha`` known too,
        ``p = (f, omega, t)`` (7); ``"known_intrinsics"``: the camera calibrated beforehand, only its board
        pose unknown, ``p = (omega, t)`` (6) -- the camera side of a single-pose calibration with
        ``known_camera`` (the projector's bound is unchanged: its ``(f_p, v0p)`` and pose are the board
        homography's 8 degrees of freedom whatever the camera knows; only ``R, T`` gain).
    radius_scale : float
        ``s`` of the conditioning scale ``kappa1 = k1 s^2``, ``kappa2 = k2 s^4`` (pixels).
    rel_step, cond_limit, jacobian
        See :func:`fisher_bound`.
    pp_prior_std : float, optional
        ``"full"`` model only: a Gaussian prior of this std (px) on the principal point / COD, as the
        single-pose solver assumes it (image centre, ``CameraOptions.pp_prior_std``) when the corners do not
        pin it. The bound is then the Bayesian one (finite even without distortion).
    pp_prior_when : ``"always"``, or ``"needed"``: the solver's rule -- the prior only when the bound without
        it leaves the principal point less certain than ``pp_prior_std`` (or undetermined); one Jacobian
        serves both bounds. ``Bound.prior_used`` says which it is.

    Returns
    -------
    :class:`Bound`
        ``std`` with ``"f_c"``, ``"alpha_c"``, ``"u0c"``, ``"v0c"``, ``"k1"``, ``"k2"`` (stds in their units;
        ``0.0`` for parameters the model treats as known, ``inf`` everywhere when the
        pose is degenerate), ``omega`` (3,) rad, ``t`` (3,), ``cov``, ``params``, ``condition``, ``model``.

    Examples
    --------
    >>> import numpy as np
    >>> from procam.board import object_points
    >>> from procam.models import intrinsic_matrix, euler_to_matrix
    >>> K = intrinsic_matrix(1539.0, 674.0, 512.0, alpha=1.004)
    >>> R = euler_to_matrix(*np.radians([20.0, 20.0, 0.0]))
    >>> b = camera_bound(K, None, -1e-7, 0.0, R, [0, 0, 500], object_points(10, 6, 24.0))
    >>> round(b.std["f_c"], 1)
    4.1
    """
    if model not in _CAMERA_MODELS:
        raise ValueError(f"model must be one of {_CAMERA_MODELS}, got {model!r}")
    K = np.asarray(K, float)
    R = np.asarray(R, float)
    t = np.asarray(t, float).reshape(3)
    M = np.asarray(obj_pts, float).reshape(-1, 3)
    f0, af0 = K[0, 0], K[1, 1]
    alpha0 = af0 / f0
    pp0 = K[:2, 2].copy()
    c0 = pp0.copy() if dist_center is None else np.asarray(dist_center, float).reshape(2)
    s = float(radius_scale)

    def observe(f, alpha, dc, kap1, kap2, w, tt):
        # the solver's model (procam.models): pinhole projection, then the division model's inverse
        K = models.intrinsic_matrix(f, pp0[0] + dc[0], pp0[1] + dc[1], alpha)
        m = models.project(K, _perturb(R, w), tt, M)
        return models.distort_division(m, c0 + dc, kap1 / s ** 2, kap2 / s ** 4).ravel()

    kap1, kap2 = k1 * s ** 2, k2 * s ** 4
    if model == "full":
        names = ["f_c", "alpha_c", "u0c", "v0c", "k1", "k2", "wx", "wy", "wz", "tx", "ty", "tz"]
        p0 = np.r_[f0, alpha0, 0.0, 0.0, kap1, kap2, 0.0, 0.0, 0.0, t]

        def fun(p):
            return observe(p[0], p[1], p[2:4], p[4], p[5], p[6:9], p[9:12])
        raw_scale = np.r_[1.0, 1.0, 1.0, 1.0, 1.0 / s ** 2, 1.0 / s ** 4, np.ones(6)]
    elif model == "known_distortion":
        names = ["f_c", "alpha_c", "wx", "wy", "wz", "tx", "ty", "tz"]
        p0 = np.r_[f0, alpha0, 0.0, 0.0, 0.0, t]

        def fun(p):
            return observe(p[0], p[1], np.zeros(2), kap1, kap2, p[2:5], p[5:8])
        raw_scale = np.ones(8)
    elif model == "known_alpha":
        names = ["f_c", "wx", "wy", "wz", "tx", "ty", "tz"]
        p0 = np.r_[f0, 0.0, 0.0, 0.0, t]

        def fun(p):
            return observe(p[0], alpha0, np.zeros(2), kap1, kap2, p[1:4], p[4:7])
        raw_scale = np.ones(7)
    else:
        names = ["wx", "wy", "wz", "tx", "ty", "tz"]
        p0 = np.r_[0.0, 0.0, 0.0, t]

        def fun(p):
            return observe(f0 + 0 * p[0], alpha0, np.zeros(2) + 0 * p[0], kap1, kap2, p[0:3], p[3:6])
        raw_scale = np.ones(6)

    if pp_prior_when not in ("always", "needed"):
        raise ValueError(f"pp_prior_when must be 'always' or 'needed', got {pp_prior_when!r}")
    prior = None
    if pp_prior_std is not None:
        if model != "full":
            raise ValueError(f"pp_prior_std applies to the 'full' model only, got model {model!r}")
        if not (np.isfinite(pp_prior_std) and pp_prior_std > 0):
            raise ValueError(f"pp_prior_std must be a positive number of pixels, got {pp_prior_std}")
        prior = np.zeros(len(p0))
        prior[2:4] = 1.0 / float(pp_prior_std) ** 2
    keys = ["f_c", "alpha_c", "u0c", "v0c", "k1", "k2"]
    if prior is None or pp_prior_when == "always":
        cov, cond = fisher_bound(fun, p0, sigma, rel_step=rel_step, cond_limit=cond_limit,
                                 jacobian=jacobian, prior_precision=prior)
        return _pack(cov * np.outer(raw_scale, raw_scale), names, cond, model, keys, prior_used=prior is not None)
    J = unc.jacobian(fun, np.asarray(p0, float), method=jacobian, rel_step=rel_step)
    cond = unc.condition(J)
    free = _pack(unc.covariance(J, sigma, rcond=cond_limit) * np.outer(raw_scale, raw_scale), names, cond, model,
                 keys)
    pp = max(free.std["u0c"], free.std["v0c"])
    if np.isfinite(pp) and pp <= pp_prior_std:
        return free
    cov = unc.covariance(J, sigma, prior_precision=prior, rcond=cond_limit)
    return _pack(cov * np.outer(raw_scale, raw_scale), names, cond, model, keys, prior_used=True)


def projector_bound(K, R, t, obj_pts, sigma=0.2, *, rel_step=1e-6, cond_limit=unc.RCOND, jacobian="complex"):
    """CRLB of the single-pose projector calibration (unknowns ``f_p, v0p`` and the pose).

    ``u0p`` and ``alpha_p`` are held at the values in ``K``:
    ``p = (f, v0, omega, t)``, exactly the 8 dof of the board -> projector homography.

    Parameters
    ----------
    K : array_like, shape (3, 3)
        True projector intrinsics (pixels).
    R, t : array_like, shapes (3, 3) and (3,)
        Board -> projector pose, board units.
    obj_pts : array_like, shape (N, 3)
        Board corners.
    sigma : float
        Projector-corner noise (pixels, per coordinate).
    rel_step, cond_limit, jacobian
        See :func:`fisher_bound`.

    Returns
    -------
    :class:`Bound`
        ``std`` with ``"f_p"``, ``"v0p"`` (pixels; ``inf`` when degenerate, i.e. ``nu_p = 0``), ``omega``,
        ``t``, ``cov``, ``params``, ``condition``, ``model``.

    Examples
    --------
    >>> import numpy as np
    >>> from procam.board import object_points
    >>> from procam.models import intrinsic_matrix, euler_to_matrix
    >>> K = intrinsic_matrix(2421.0, 1013.0, 1065.0, alpha=1.002)
    >>> R = euler_to_matrix(*np.radians([10.0, 10.0, 0.0]))
    >>> round(projector_bound(K, R, [0, 0, 500], object_points(10, 6, 24.0)).std["f_p"], 0)
    11.0
    """
    K = np.asarray(K, float)
    R = np.asarray(R, float)
    t = np.asarray(t, float).reshape(3)
    M = np.asarray(obj_pts, float).reshape(-1, 3)
    alpha0, u0 = K[1, 1] / K[0, 0], K[0, 2]
    names = ["f_p", "v0p", "wx", "wy", "wz", "tx", "ty", "tz"]
    p0 = np.r_[K[0, 0], K[1, 2], 0.0, 0.0, 0.0, t]

    def fun(p):
        K = models.intrinsic_matrix(p[0], u0, p[1], alpha0)
        return models.project(K, _perturb(R, p[2:5]), p[5:8], M).ravel()

    cov, cond = fisher_bound(fun, p0, sigma, rel_step=rel_step, cond_limit=cond_limit,
                             jacobian=jacobian)
    return _pack(cov, names, cond, "projector", ["f_p", "v0p"])


def _std(cov, k):
    v = cov[k, k]
    return float(np.sqrt(v)) if np.isfinite(v) and v >= 0 else float("inf")


def _pack(cov, names, cond, model, scalar_keys, prior_used=False) -> Bound:
    if not np.all(np.isfinite(cov)):
        std = {key: (float("inf") if key in names else 0.0) for key in scalar_keys}
    else:
        std = {key: (_std(cov, names.index(key)) if key in names else 0.0) for key in scalar_keys}
    omega = np.array([_std(cov, names.index(k)) for k in ("wx", "wy", "wz")])
    t = np.array([_std(cov, names.index(k)) for k in ("tx", "ty", "tz")])
    return Bound(std=std, omega=omega, t=t, cov=cov, params=tuple(names), condition=cond, model=model,
                 prior_used=prior_used)


def extrinsics_bound(cam, proj, R_cb, t_cb, R_pb, t_pb, *, rel_step=1e-7):
    """Delta-method bound of the procam extrinsics ``R = R_pb R_cb^T``, ``T = t_pb - R t_cb``.

    The camera and projector observations are independent, so the pose covariances of the
    two device bounds (their ``omega``/``t`` blocks, marginalised over the intrinsics) are
    combined block-diagonally and pushed through ``(R, T)``.

    Parameters
    ----------
    cam, proj : :class:`Bound`
        Results of :func:`camera_bound` and :func:`projector_bound` at the true poses.
    R_cb, t_cb, R_pb, t_pb : array_like
        True board -> camera and board -> projector poses.
    rel_step : float
        Finite-difference step (rad or board units, relative to ``max(1, |x|)``).

    Returns
    -------
    :class:`ExtrinsicsBound`
    """
    R_cb, R_pb = np.asarray(R_cb, float), np.asarray(R_pb, float)
    t_cb, t_pb = np.asarray(t_cb, float).reshape(3), np.asarray(t_pb, float).reshape(3)
    blocks = []
    for b in (cam, proj):
        idx = [b.params.index(k) for k in ("wx", "wy", "wz", "tx", "ty", "tz")]
        blocks.append(np.asarray(b.cov, float)[np.ix_(idx, idx)])
    if not all(np.all(np.isfinite(c)) for c in blocks):
        inf3 = np.full(3, np.inf)
        return ExtrinsicsBound(euler_deg=inf3, T=inf3.copy(), sigma_T=float("inf"), T_norm=float("inf"),
                               cov=np.full((6, 6), np.inf))
    C = np.zeros((12, 12))
    C[:6, :6], C[6:, 6:] = blocks

    def fun(q):
        Rcq, tcq = _perturb(R_cb, q[0:3]), t_cb + q[3:6]
        Rpq, tpq = _perturb(R_pb, q[6:9]), t_pb + q[9:12]
        Rx = Rpq @ Rcq.T
        T = tpq - Rx @ tcq
        return np.r_[models.matrix_to_euler(Rx), T, np.linalg.norm(T)]

    q0 = np.zeros(12)
    cov = unc.propagate(C, fun, q0, rel_step=rel_step)
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    return ExtrinsicsBound(euler_deg=np.degrees(sd[:3]), T=sd[3:6], sigma_T=float(np.sqrt(np.sum(sd[3:6] ** 2))),
                           T_norm=float(sd[6]), cov=cov[:6, :6])


# --------------------------------------------------------------------------------------------
# a camera calibrated from several photos (Zhang / OpenCV calibrateCamera)
# --------------------------------------------------------------------------------------------

#: The intrinsics of a camera calibrated from photos, in OpenCV's order (``fx, fy, cx, cy`` and the distortion
#: coefficients ``k1, k2, p1, p2, k3`` and the rational model's ``k4, k5, k6``), named as in :mod:`procam.parameters` where a name exists.
VIEW_PARAMS = ("f_c", "fy_c", "u0c", "v0c", "k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6")


@dataclass(frozen=True)
class ViewsBound:
    """The covariance of a camera's intrinsics calibrated from several photos (:func:`views_bound`).

    ``cov`` (P, P) in raw units (px for ``f_c, fy_c, u0c, v0c``; OpenCV's normalised coefficients for the
    distortion), rows named by ``params`` (a subset of :data:`VIEW_PARAMS`: the free ones); ``std`` the square
    roots of its diagonal by name (``inf`` everywhere when the photos do not determine the parameters);
    ``sigma`` the corner noise (px per coordinate) it was scaled with.
    """

    cov: np.ndarray
    params: tuple
    std: dict
    sigma: float

    @property
    def determined(self) -> bool:
        return bool(np.all(np.isfinite(self.cov)))


def view_information(K, coeffs, rvec, tvec, obj_pts, free_dist=(0, 1, 2, 3, 4)) -> np.ndarray:
    """The information one photo gives about a camera's intrinsics, its board pose marginalised (the Schur
    complement ``A - B D^-1 B^T`` of ``J^T J``), per unit corner noise.

    ``K`` (3, 3) and ``coeffs`` (5,) or (8,) OpenCV intrinsics and distortion; ``rvec, tvec`` the board -> camera pose
    (Rodrigues vector, board units); ``obj_pts`` (N, 3) the board corners the photo shows; ``free_dist`` the
    indices (0..7 = ``k1, k2, p1, p2, k3, k4, k5, k6``) of the coefficients that are fitted.  Returns (4 + F, 4 + F) in the
    order ``fx, fy, cx, cy`` and the free coefficients (pixels^2 per parameter unit^2).  The Jacobian is OpenCV's
    own (``cv2.projectPoints``), the model :func:`procam.multi_pose.calibrate_camera` fits.
    """
    import cv2

    c = np.asarray(coeffs, float).ravel()
    dist = np.zeros(max(5, len(c)))
    dist[:len(c)] = c
    _, J = cv2.projectPoints(np.asarray(obj_pts, np.float64).reshape(-1, 1, 3), np.asarray(rvec, float).reshape(3),
                             np.asarray(tvec, float).reshape(3), np.asarray(K, float), dist)
    cols = [6, 7, 8, 9] + [10 + k for k in free_dist]
    Ji, Jp = J[:, cols], J[:, :6]
    A, B, D = Ji.T @ Ji, Ji.T @ Jp, Jp.T @ Jp
    return A - B @ np.linalg.solve(D, B.T)


def views_bound(K, coeffs, poses, obj_pts, sigma: float, free_dist=(0, 1, 2, 3, 4), *, extra=None,
                cond_limit=unc.RCOND) -> ViewsBound:
    """The covariance of a camera's intrinsics from several photos: ``sigma^2 (sum_i I_i)^-1`` with ``I_i`` each
    photo's :func:`view_information` (the poses marginalised), the Cramér-Rao bound at ``K, coeffs`` for corner
    noise ``sigma`` -- and, with ``sigma`` the fit's residual noise, the Gauss-Newton covariance of the fit
    (what OpenCV's ``stdDeviationsIntrinsics`` are the roots of).

    ``poses``: ``(rvec, tvec)`` per photo; ``obj_pts``: the board corners (N, 3), one array for all photos or a
    sequence of one per photo; ``extra``: information (P, P) to add (e.g. of photos summed before, or of a
    candidate pose).  Degenerate (``inf``) when the column-normalised information is rank-deficient.
    """
    P = 4 + len(free_dist)
    info = np.zeros((P, P)) if extra is None else np.array(extra, float)
    per_photo = isinstance(obj_pts, (list, tuple))
    for k, (rvec, tvec) in enumerate(poses):
        info = info + view_information(K, coeffs, rvec, tvec, obj_pts[k] if per_photo else obj_pts, free_dist)
    params = VIEW_PARAMS[:4] + tuple(VIEW_PARAMS[4 + k] for k in free_dist)
    d = np.sqrt(np.clip(np.diag(info), 0.0, None))
    cov = np.full((P, P), np.inf)
    if np.all(d > 0) and np.all(np.isfinite(info)):
        n = info / np.outer(d, d)
        w = np.linalg.eigvalsh(n)
        if w[0] > 0 and np.sqrt(w[0] / w[-1]) >= cond_limit:
            cov = float(sigma) ** 2 * np.linalg.inv(n) / np.outer(d, d)
            cov = 0.5 * (cov + cov.T)
    std = {name: (float(np.sqrt(cov[k, k])) if np.isfinite(cov[k, k]) else float("inf"))
           for k, name in enumerate(params)}
    return ViewsBound(cov, params, std, float(sigma))
