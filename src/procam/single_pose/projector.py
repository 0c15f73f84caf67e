"""Single-pose projector calibration: ``f_p``, ``v0p`` and the board pose, with ``u0p`` fixed (default
``W / 2``, the paper's assumption), ``alpha_p = 1`` and no projector distortion.

One plane gives two constraints on the intrinsics, so two of them must be assumed; with ``u0p`` fixed,
``(f_p, v0p)`` and the pose have exactly the homography's 8 degrees of freedom, and they are
determined only when the board is turned about the projector's vertical axis (``nu_p != 0``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import models
from .. import uncertainty as unc
from ..calibration import Distortion
from ..errors import CalibrationError
from ..stats import rms
from ._principal_axis import solve_projector_lm
from ._robust import RobustOptions, check_corners, clean, fit_robust, rejection_report
from ._solution import DeviceSolution


@dataclass(frozen=True)
class ProjectorOptions:
    """Options of the single-pose projector fit (:func:`calibrate_projector`).

    Attributes
    ----------
    u0 : fixed principal point column in pixels (default None: ``W / 2``, the paper's assumption).
    board_width : w_b for the paper's initial distance 2 w_b (default: the span of the corners).
    """

    u0: float | None = None
    board_width: float | None = None


@dataclass(frozen=True)
class ProjectorSolution(DeviceSolution):
    """Single-pose projector calibration (``u0p`` fixed, ``alpha_p = 1``, no distortion).

    Attributes as :class:`~procam.single_pose.CameraSolution`; ``params`` are
    :data:`procam.parameters.PROJECTOR_VECTOR` = (f_p, v0p, rvec (3),
    t (3)) of the pinhole model with ``u0`` fixed, ``covariance`` (8, 8); ``std`` keys ``f_p, v0p,
    angles_deg, t``; ``H_bp`` the projector -> board homography; ``info["theta"]`` the principal-axis
    parameters (f_p, v0p, phi_p, O (3)) the LM solved for; ``rejected``, ``rejected_residuals_px``,
    ``outlier_threshold_px`` as for the camera.
    """

    H_bp: np.ndarray | None = None
    u0: float = float("nan")


def calibrate_projector(obj_pts, proj_pts, proj_size, options: ProjectorOptions = ProjectorOptions(), *,
                        robust: RobustOptions = RobustOptions(), name: str = "view") -> ProjectorSolution:
    """Single-pose projector calibration: ``f_p, v0p`` and the pose with ``u0p`` fixed, alpha = 1.

    Parameters
    ----------
    obj_pts : (N, 3) or (N, 2) board points; proj_pts : (N, 2) projector pixels (NaN rows ignored).
    proj_size : (width, height) of the projector in pixels.
    options : :class:`ProjectorOptions`.
    robust : :class:`~procam.single_pose.RobustOptions` (a mis-decoded corner's projector coordinates are
        rejected and the projector refitted without them).
    name : pose name used in messages.
    """
    obj, pp, mask = clean(obj_pts, proj_pts, f"pose {name!r}")
    if proj_size is None:
        raise CalibrationError(f"pose {name!r}: the projector size is unknown; pass proj_size=(W, H)")
    W, Hh = int(proj_size[0]), int(proj_size[1])
    check_corners(obj, mask, robust.min_points, name, "projector corners", "check the decoding")

    def predict(sol):
        return models.projector_predict(sol.params, obj, sol.u0)

    sol, used, thr, notes = fit_robust(lambda m: _projector_fit(obj, pp, m, (W, Hh), options, name), predict, pp, obj,
                                       mask, robust)
    return rejection_report(sol, predict, pp, mask, used, thr, notes, name, "projector", robust)


def u0_cost(obj_pts, proj_pts, sol: ProjectorSolution, spread_px: float, name: str = "view") -> float:
    """What the assumed ``u0p`` can cost ``f_p``: the largest relative change of ``f_p`` when the same corners
    (``sol.mask``) are refitted with ``u0p`` moved by ``-spread_px`` and ``+spread_px``.

    Any ``u0p`` fits one board exactly (see the module docstring), so the fit's ``±`` cannot see this: at a pose
    turned little about the projector's vertical axis ``f_p`` follows ``u0p`` closely. ``inf`` when a refit
    finds no solution.
    """
    obj, pp, _ = clean(obj_pts, proj_pts, f"pose {name!r}")
    f0 = float(sol.K[0, 0])
    worst = 0.0
    for du in (-spread_px, spread_px):
        try:
            f = _projector_fit(obj, pp, sol.mask, sol.image_size, ProjectorOptions(u0=sol.u0 + du), name).K[0, 0]
        except CalibrationError:
            return float("inf")
        worst = max(worst, abs(float(f) - f0) / abs(f0))
    return worst


def _projector_fit(obj, pp, mask, proj_size, o: ProjectorOptions, name: str) -> ProjectorSolution:
    """One single-pose projector fit on the corners ``mask`` (see :func:`calibrate_projector`)."""
    W, Hh = proj_size
    M, m = obj[mask], pp[mask]
    lm = solve_projector_lm(M, m, (W, Hh), u0=o.u0, width=o.board_width)
    if lm is None:
        raise CalibrationError(f"pose {name!r}: projector LM found no valid (non-mirror) solution from any "
                               f"start; the pose is probably degenerate (no rotation about the projector's y axis?)")
    x = lm.x
    res = lm.residuals
    u0v = lm.u0
    # covariance in the plain pinhole parameters (f, v0, rvec, t): the principal-axis parameters are
    # tied to the data through H_bp, so their Jacobian would understate the uncertainty
    q = np.concatenate([[lm.f, lm.v0], models.matrix_to_rvec(lm.R), lm.t])
    J = unc.jacobian(lambda v: (models.projector_predict(v, M, u0v) - m).ravel(), q,
                     typical=np.array([1, 1, 0.01, 0.01, 0.01, 1, 1, 1.0]))
    sigma = unc.sigma_from_residuals(res.ravel(), 8)
    cov = unc.covariance(J, sigma)
    s = unc.std(cov)

    def ang(v):
        return models.board_angles_deg(models.rvec_to_matrix(v[2:5]), v[5:8])

    std = {"f_p": float(s[0]), "v0p": float(s[1]),
           "angles_deg": np.sqrt(np.abs(np.diag(unc.propagate(cov, ang, q, typical=1.0)))),
           "t": s[5:8].copy()}
    K = models.intrinsic_matrix(lm.f, u0v, lm.v0)
    residuals = np.full((len(obj), 2), np.nan)
    residuals[mask] = -res  # observed - predicted
    return ProjectorSolution(K=K, distortion=Distortion(), R=lm.R, t=lm.t, rms_px=rms(res),
                             residuals=residuals, std=std, angles_deg=models.board_angles_deg(lm.R, lm.t),
                             cost=float(lm.cost), params=q, covariance=cov, H_bp=lm.H_bp, u0=u0v, mask=mask,
                             image_size=(W, Hh),
                             info=dict(sigma_px=sigma, start=lm.start, closed_form=lm.closed_form,
                                       theta=x.copy(),
                                       starts=[(r.name, r.cost, r.valid) for r in lm.runs]))
