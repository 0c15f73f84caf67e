"""A dense single-pose fit (:mod:`.dense`) as the calibration: devices, ``R, T``, every ``±``, the rating.

The calibration of :func:`procam.single_pose.calibrate` is first the seed method's (the camera from its corners,
the paper's projector); when the pose carries dense samples, :func:`apply` replaces the devices, the extrinsics and
their standard deviations by the dense fit's, rates the projector by the ``±`` it reports (not by the bound of the
paper's model, which assumed what the dense fit estimates), and records what was estimated, what entered as a
prior and which lens models the data could not tell apart.
"""

from __future__ import annotations

import numpy as np

from .. import models
from .. import uncertainty as unc
from ..errors import CalibrationError
from ..residuals import pnp, stereo_pose
from ..stats import rms
from . import joint as J
from .dense import MODELS, DenseFit

#: A projector rated good: what this pose determines (the dense fit's ``±`` with each lens's decentring held at its
#: estimate, or at zero where the board alone cannot see it; the reported ``±`` adds its prior) at most these, so that the values are within 1 % and 15 px with about 95 %
#: probability.
GOOD_F_REL = 0.005
GOOD_PP_PX = 7.5
#: Beyond these the pose does not determine the projector (degenerate).
DEGENERATE_F_REL = 0.05
DEGENERATE_PP_PX = 150.0
#: A projector that gives coordinates to fewer than this fraction of the board's corners lights part of the board:
#: its rating says that its numbers rest on that part.
PARTLY_LIT = 0.9


def _derived(p):
    """Derived quantities of the joint vector: fy_c, fy_p, Euler angles of R (3), T (3), board angles in the camera
    (3) and in the projector (3)."""
    Rc, tc = models.rvec_to_matrix(p[6:9]), p[9:12]
    Rp, tp = models.rvec_to_matrix(p[21:24]), p[24:27]
    R = Rp @ Rc.T
    T = tp - R @ tc
    return np.r_[p[0] * p[1], p[J.IDX["f_p"]] * p[J.IDX["alpha_p"]], models.euler_deg(R), T,
                 models.board_angles_deg(Rc, tc), models.board_angles_deg(Rp, tp)]


def _opencv_coefficients(fit: DenseFit, proj_size) -> tuple:
    """The projector's OpenCV ``k1, k2, p1, p2, k3`` about its principal point: the fit's, with a decentred lens's
    offset (``dpx, dpy``) turned into the tangential terms OpenCV has for it (:func:`procam.models.brown_recentred`,
    over the panel; the chosen model's radial terms and ``p1, p2``)."""
    p = fit.p
    coeffs = np.array([p[J.IDX[t]] for t in J.DIST_TERMS], float)
    f, a, u0, v0 = (float(p[J.IDX[n]]) for n in ("f_p", "alpha_p", "u0p", "v0p"))
    e = np.array([p[J.IDX["dpx"]] / f, p[J.IDX["dpy"]] / (a * f)])
    if not np.any(e) or not np.any(coeffs):
        return tuple(float(c) for c in coeffs)
    W, H = proj_size
    extent = (-u0 / f, (W - u0) / f, -v0 / (a * f), (H - v0) / (a * f))
    free = sorted({J.DIST_TERMS.index(t) for t in MODELS.get(fit.model, ())} | {2, 3})
    out, _ = models.brown_recentred(coeffs, e, extent, free)
    return tuple(float(c) for c in out)


def to_devices(fit: DenseFit, cam_sol, camera_size, proj_size, known_camera=None, known_projector=None):
    """The camera and projector :class:`procam.calibration.Device` of a dense fit, and ``R, T`` (camera ->
    projector)."""
    from ..calibration import Device, Distortion

    p = fit.p
    if known_camera is not None:
        camera = known_camera
    else:
        Kc = models.intrinsic_matrix(p[0], p[2], p[3], p[1])
        centre = (float(p[2] + p[J.IDX["dcx"]]), float(p[3] + p[J.IDX["dcy"]]))     # the division model has a centre
        camera = Device(Kc, tuple(camera_size), Distortion("division", centre, float(p[4] / J.S ** 2),
                                                            float(p[5] / J.S ** 4)))
    if known_projector is not None:
        projector = known_projector
    else:
        Kp = models.intrinsic_matrix(p[J.IDX["f_p"]], p[J.IDX["u0p"]], p[J.IDX["v0p"]], p[J.IDX["alpha_p"]])
        coeffs = _opencv_coefficients(fit, proj_size)
        dist = Distortion("opencv", coeffs=coeffs) if any(coeffs) else Distortion()
        projector = Device(Kp, tuple(proj_size), dist)
    Rc, tc = models.rvec_to_matrix(p[6:9]), p[9:12]
    Rp, tp = models.rvec_to_matrix(p[21:24]), p[24:27]
    R = Rp @ Rc.T
    return camera, projector, R, tp - R @ tc, (Rc, tc), (Rp, tp)


def std_dict(fit: DenseFit, known_camera=None, known_projector=None) -> dict:
    """Standard deviations under procam's parameter names (:mod:`procam.parameters`) from the fit's covariance."""
    C, p = fit.cov, fit.p
    s = np.sqrt(np.clip(np.diag(C), 0, None))
    free = np.diag(C) > 0
    typ = np.where(free, np.abs(p).clip(1e-3), 1.0)
    with np.errstate(all="ignore"):
        sd = np.sqrt(np.clip(np.diag(unc.propagate(C, _derived, p, typical=typ)), 0, None))
    out = {"R_euler_deg": [float(v) for v in sd[2:5]], "T": [float(v) for v in sd[5:8]],
           "camera_angles_deg": [float(v) for v in sd[8:11]], "projector_angles_deg": [float(v) for v in sd[11:14]]}
    if known_camera is None:
        out.update({"f_c": float(s[0]), "alpha_c": float(s[1]), "fy_c": float(sd[0]), "u0c": float(s[2]),
                    "v0c": float(s[3]), "k1": float(s[4] / J.S ** 2), "k2": float(s[5] / J.S ** 4)})
    if known_projector is None:
        i = J.IDX
        out.update({"f_p": float(s[i["f_p"]]), "fy_p": float(sd[1]), "alpha_p": float(s[i["alpha_p"]]),
                    "u0p": float(s[i["u0p"]]), "v0p": float(s[i["v0p"]]),
                    "proj_dist": _dist_std(fit, s)})
    return out


def _dist_std(fit: DenseFit, s) -> list:
    """The std of the projector's written OpenCV coefficients: the fit's, and for ``p1, p2`` what an estimated
    decentring ``e`` puts there (``p2 = -k1 e_x``, ``p1 = -k1 e_y`` to first order; :func:`to_devices`)."""
    i = J.IDX
    out = [float(s[i[t]]) for t in J.DIST_TERMS]
    k1, f, a = fit.p[i["k1p"]], fit.p[i["f_p"]], fit.p[i["alpha_p"]]
    if f > 0 and a > 0:
        out[2] = float(np.hypot(out[2], abs(k1) * s[i["dpy"]] / (a * f)))
        out[3] = float(np.hypot(out[3], abs(k1) * s[i["dpx"]] / f))
    return out


#: The priors' pull on a fit (the sum of their squared normalised residuals ``((estimate - mean) / std)^2``) beyond
#: which the data contradict them: 5 sigma of one term.
PRIOR_PULL_ALARM = 25.0
#: A datasheet prior *holds* its parameter when the fit's std of it is at least this fraction of the prior's: the
#: estimate is then the prior's, not the data's.
PRIOR_HOLDS = 0.5


def _prior_words(name: str, mu: float, sd: float, proj_size) -> str:
    """A prior in the datasheet's words where it has them (module :mod:`procam.datasheet`)."""
    W, H = (float(v) for v in proj_size)
    if name == "f_p":
        return f"the datasheet's throw ratio {mu / W:.4g} ± {sd / W:.2g} (f_p = {mu:.5g} ± {sd:.3g} px)"
    if name == "v0p":
        return f"the datasheet's vertical lens shift {100 * (mu - (H - 1) / 2) / H:.3g} % ± {100 * sd / H:.2g} % " \
               f"(v0p = {mu:.5g} ± {sd:.3g} px)"
    if name == "u0p":
        return f"the prior u0p = {mu:.5g} ± {sd:.3g} px (horizontal lens shift {100 * ((W - 1) / 2 - mu) / W:.3g} %)"
    return f"the assumed {name} = {mu:.4g} ± {sd:.3g}"


def prior_conflict(fit: DenseFit, proj_size) -> str:
    """Why the data contradict the datasheet priors that hold the fit, or '' when they do not.

    The priors' pull is the sum of their squared normalised residuals (decentrings aside); beyond
    :data:`PRIOR_PULL_ALARM` the data contradict them.  It is the datasheet's number that is wrong (not the pose) when
    a datasheet prior (``f_p`` of a throw ratio, ``v0p`` of a lens shift) holds its parameter (the fit's std of it at
    least :data:`PRIOR_HOLDS` of the prior's): the estimate is then the prior's, and the other priors give way.  A
    prior the data outweigh (a loose tolerance) moves nothing: the estimate is the data's, said by the fit's
    conflicts only."""
    terms = [(n, mu, sd, (float(fit.p[J.IDX[n]]) - mu) / sd) for n, mu, sd in fit.priors if n not in J.DECENTRING]
    pull = sum(z * z for *_, z in terms)
    held = [t for t in terms if t[0] in ("f_p", "v0p") and fit.std(t[0]) >= PRIOR_HOLDS * t[2]]
    if pull <= PRIOR_PULL_ALARM or not held:
        return ""
    shown = sorted((t for t in terms if abs(t[3]) > 2 or t in held), key=lambda t: -abs(t[3]))
    pulls = ", ".join(f"{n} {float(fit.p[J.IDX[n]]):.5g} ({z:+.1f} sigma from {mu:.5g})" for n, mu, _, z in shown)
    want = " and ".join(f"a {'smaller' if z < 0 else 'larger'} {'throw ratio' if n == 'f_p' else 'vertical lens shift'}"
                        for n, _, _, z in held)
    return (f"the data contradict {' and '.join(_prior_words(n, mu, sd, proj_size) for n, mu, sd, _ in held)}, "
            f"which holds the fit (the fit's ± is the prior's) while the data want {want}: the priors pull the "
            f"estimate by chi-square {pull:.0f} "
            f"(at most {PRIOR_PULL_ALARM:.0f}): {pulls}; the pose is not the cause -- check the datasheet's number "
            "(docs/datasheet.md), widen its tolerance or leave it out")


def projector_rating(fit: DenseFit, proj_size, known_projector=None, options=None) -> dict:
    """The projector's rating from the dense fit's ``±`` (module constants), in the rating's words (the keys of
    :func:`procam.single_pose.rating.rate_pose`'s device entries, ``source = "fit"``)."""
    from .rating import RatingOptions

    o = options or RatingOptions()
    a = models.board_angles_deg(models.rvec_to_matrix(fit.p[21:24]), fit.p[24:27])
    base = {"psi_abs_deg": float(abs(a[0])), "nu_abs_deg": float(abs(a[1])),
            "paper_rule_ok": bool(abs(a[1]) > o.projector_rule_deg), "predicted_rel_std_f": None, "source": "fit"}
    if known_projector is not None:
        moved = fit.given_projector
        if moved and moved["moved"]:     # R, T would absorb a zoom or focus change: not a result
            said = ", ".join(f"{n} {v[1]:.1f} ± {v[2]:.2g} (given {v[0]:.1f}, {v[1] - v[0]:+.1f} px)"
                             for n, v in ((n, moved[n]) for n in ("f_p", "v0p")))
            pct = 100 * (moved["f_p"][1] / moved["f_p"][0] - 1)
            return {**base, "level": "failed", "degenerate": True, "weak": False, "failed": True, "given": True,
                    "rel_std_f": 0.0, "given_projector": moved,
                    "message": (f"projector: FAILED: the given intrinsics no longer hold: this pose puts {said} "
                                f"(f_p {pct:+.2f} %; chi-square {moved['chi2']:.0f} > {moved['limit']:.0f}) -- a zoom "
                                "or focus change, or another projector? R, T would absorb it: calibrate the projector "
                                "again from this pose (without the projector's intrinsics)")}
        return {**base, "level": "good", "degenerate": False, "weak": False, "failed": False, "given": True,
                "rel_std_f": 0.0, "given_projector": moved,
                "message": "projector: intrinsics given, not estimated from this pose" + (
                    f" (this pose agrees with them: chi-square {moved['chi2']:.1f})" if moved else "")}
    f = fit.p[J.IDX["f_p"]]
    sf, su, sv = (fit.std(n, pose_only=True) for n in ("f_p", "u0p", "v0p"))
    rel = sf / f if f > 0 else float("inf")
    pp = max(su, sv)
    lo, hi = (r * float(np.hypot(*proj_size)) for r in o.plausible_f_range)
    level = "good"
    # what the pose cannot determine first (its estimate may then be anything), then an impossible estimate
    if not (np.isfinite(rel) and np.isfinite(pp)) or rel > DEGENERATE_F_REL or pp > DEGENERATE_PP_PX:
        level = "degenerate"
    elif not (np.isfinite(f) and lo <= f <= hi):
        level = "failed"
    elif rel > GOOD_F_REL or pp > GOOD_PP_PX:
        level = "weak"
    what = (f"this pose determines f_p {f:.1f} to ± {sf:.1f} px ({100 * rel:.2f} %), u0p to ± {su:.1f}, v0p to ± "
            f"{sv:.1f} px (noise, correlated residuals, the lens models the data cannot tell apart, the priors"
            f"{'; the rim of the board that disagreed with the rest left out' if fit.rim_left_out else ''}; the "
            f"reported ± adds where the lens's distortion is centred, within a few pixels of its principal point)")
    if fit.lit_corners and fit.lit_corners[0] < PARTLY_LIT * fit.lit_corners[1]:
        what += (f"; the projector lights {fit.lit_corners[0]} of the board's {fit.lit_corners[1]} corners: these "
                 "numbers rest on that part of the board")
    conflict = prior_conflict(fit, proj_size)
    if conflict:      # the estimate is the datasheet's, bent to fit it: not a result, whatever its ±
        level, msg = "failed", f"projector: FAILED estimate: {conflict}"
    elif level == "failed":
        msg = (f"projector: FAILED estimate: f_p = {f:.4g} px is impossible for a {proj_size[0]}x{proj_size[1]} panel "
               f"(plausible {lo:.0f}-{hi:.0f} px) -- turn the board about the projector's vertical axis")
    elif level == "good":
        msg = f"projector: pose OK: {what}"
    elif level == "weak":
        msg = (f"projector: weak pose: {what}; aim for under {100 * GOOD_F_REL:.1f} % and {GOOD_PP_PX:g} px -- turn "
               "the board about the projector's vertical axis (|nu_p| 15-30 deg), let it fill more of the projector "
               "image, keep the wall behind it lit")
    else:
        msg = (f"projector: degenerate pose: {what}: this pose does not determine the projector -- turn the board "
               "about the projector's vertical axis (|nu_p| 15-30 deg) with the wall behind it lit")
    return {**base, "level": level, "degenerate": level in ("degenerate", "failed"), "weak": level == "weak",
            "failed": level == "failed", "message": msg, "rel_std_f": float(rel), "pp_std_px": float(pp)}


def apply(cal, fit: DenseFit, view, *, known_camera=None, known_projector=None):
    """``cal`` (the seed method's calibration of ``view``) with the dense fit's devices, ``R, T``, ``±``, RMS and
    projector rating (module docstring). Returns a new :class:`procam.calibration.Calibration`."""
    cam_sol = cal.info["camera"]
    camera, projector, R, T, (Rc, tc), (Rp, tp) = to_devices(fit, cam_sol, cal.camera.image_size,
                                                             cal.projector.image_size, known_camera, known_projector)
    std = std_dict(fit, known_camera, known_projector)
    obj = np.asarray(view.obj_pts, float)
    pose0 = dict(cal.poses[0])
    cin = np.asarray(cam_sol.mask, bool) if cam_sol.mask is not None else view.valid
    pin = view.valid
    with np.errstate(all="ignore"):
        cam_und = camera.undistort(np.where(view.valid[:, None], view.cam_pts, np.nan))
        proj_und = projector.undistort(np.where(view.valid[:, None], view.proj_pts, np.nan))

    def pnp_rms(o, m, K):
        ok = np.isfinite(m).all(1)
        try:
            return rms(pnp(o[ok], m[ok], K)[2])
        except CalibrationError:
            return float("nan")

    cam_rms = pnp_rms(obj[cin], cam_und[cin], camera.K)
    proj_rms = pnp_rms(obj[pin], proj_und[pin], projector.K)
    both = cin & pin & np.isfinite(cam_und).all(1) & np.isfinite(proj_und).all(1)
    try:
        _, _, rc, rp = stereo_pose(obj[both], cam_und[both], proj_und[both], camera.K, projector.K, R, T, Rc, tc)
        stereo = rms([rc, rp])
    except CalibrationError:
        stereo = float("nan")
    rating = pose0.get("advice")
    models_doc = {n: {"cost": m.cost, "held_out": m.held_out, "terms": list(MODELS.get(n, ())),
                      "f_p": float(m.p[J.IDX["f_p"]]), "u0p": float(m.p[J.IDX["u0p"]]),
                      "v0p": float(m.p[J.IDX["v0p"]])} for n, m in fit.fits.items()}
    pose0.update({"camera_angles_deg": [float(a) for a in models.board_angles_deg(Rc, tc)],
                  "projector_angles_deg": [float(a) for a in models.board_angles_deg(Rp, tp)],
                  "cam_rms": cam_rms, "proj_rms": proj_rms, "stereo_rms": stereo, "advice": rating,
                  "projector_model": {"model": fit.model, "indistinguishable": list(fit.indistinguishable),
                                      "models": models_doc, "n_board_samples": fit.n_board,
                                      "n_background_samples": fit.n_background,
                                      "background_used": fit.background_used,
                                      "background_reason": fit.background_reason,
                                      "noise_px": {"camera": fit.scales.camera, "board": fit.scales.board,
                                                   "background": fit.scales.background},
                                      "priors": [{"name": n, "mean": float(m), "std": float(s)}
                                                 for n, m, s in fit.priors]}})
    warnings = list(cal.warnings)
    if fit.background_reason:
        warnings.append(f"pose {view.name!r}: {fit.background_reason}")
    warnings += [f"pose {view.name!r}: {c}" for c in fit.conflicts]
    info = dict(cal.info)
    info.update(dense=fit, projector_model=fit.model, notes=tuple(fit.notes),
                board_poses={"camera": (Rc, tc), "projector": (Rp, tp)})  # for procam.board.labelling.given_labelling
    method = cal.method if known_projector is None else cal.method + ", projector given"
    return cal.replace(camera=camera, projector=projector, R=R, T=T, std=std, cam_rms=cam_rms, proj_rms=proj_rms,
                       stereo_rms=stereo, poses=(pose0, *cal.poses[1:]), warnings=tuple(warnings), info=info,
                       method=method)
