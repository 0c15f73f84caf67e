"""The single-pose rating of a pose: is it good for single-pose calibration? One level per device -- good,
weak, degenerate or failed (:data:`procam.verdict.LEVELS`) -- with the real reason in words; the pose's
level (the worst device's) is the single-pose calibration's verdict (:func:`judge`).

The rating must not depend on where Levenberg-Marquardt happened to stop: at a pose that determines nothing
the fitted numbers may be anything (another CPU's BLAS kernels send LM elsewhere), but the rating may not
flip. So it rests on **stable** quantities first (:func:`predict`): the board's angles from the
board -> image homography with nominal intrinsics (the image diagonal as focal length unless Zhang's closed
form gives a plausible one; the principal point at the image centre, or ``u0p``), and the Cramer-Rao
standard deviation of the focal length at that pose (:mod:`procam.crlb`, for the noise the fit measured but
at least a typical corner noise). Only a pose those call sound can then be

* ``failed`` -- the fitted focal length is impossible for the image size (outside ``plausible_f_range`` x the
  diagonal), or
* made ``weak``/``degenerate`` by the fit's own standard deviation (it includes what the stable prediction
  leaves out: the principal point and the distortion).

The paper's empirical rules (camera ``|psi_c| + |nu_c| > 10 deg``, projector ``|nu_p| > 13 deg``) are
reported, and make a pose weak, but the true degeneracies are these: the camera's ``(f, alpha)`` are
unobservable iff ``psi_c = 0`` or ``nu_c = 0`` (the board parallel to an image axis, fronto-parallel
included); the projector's ``(f, v0)`` with ``u0`` fixed iff ``nu_p = 0``, whatever ``psi_p``.
"""

from __future__ import annotations

import warnings as _warnings
from dataclasses import dataclass

import numpy as np

from .. import crlb, distortion, models
from ..errors import (CalibrationError, DegeneratePoseError, DegeneratePoseWarning, FailedEstimateWarning,
                      WeakPoseWarning)
from ..verdict.gates import FOCAL_RANGE, focal_failure
from ..verdict import LEVELS
from ._principal_axis import homography, zhang_projector


@dataclass(frozen=True)
class RatingOptions:
    """Thresholds of :func:`rate_pose`.

    Attributes
    ----------
    camera_rule_deg, projector_rule_deg : the paper's empirical rule: camera ``|psi_c| + |nu_c|`` and
        projector ``|nu_p|`` above these (degrees).
    degenerate_angle_deg : an angle below this is treated as zero (degenerate).
    weak_angle_deg : an angle below this makes the pose weak (poorly conditioned).
    degenerate_rel_std, weak_rel_std : relative std of f above which the pose is degenerate / weak.
    plausible_f_range : focal lengths outside this range x the image diagonal (diagonal fields of view of
        ~136 deg down to ~11 deg) are impossible for a real device (:data:`procam.verdict.gates.FOCAL_RANGE`).
    camera_noise_px, projector_noise_px : the least corner noise (px) the stable prediction assumes.
    data_alarm : corners that scatter about the fitted model more than this many times that noise are bad data
        (a wrong decode or detection), not a bad pose: the rating says so instead of asking for another pose.
    u0p_spread_fraction : how far from the panel's centre a real projector's ``u0p`` may lie, as a fraction of
        its width (horizontal lens shift; the rigs issue 23 measured and the simulator's presets sit within 3 %).
        The paper's projector assumes ``u0p = W/2``; what that assumption can cost ``f_p`` over this range
        (:func:`procam.single_pose.projector.u0_cost`) joins the fit's ``±`` in the rating, so a pose is not
        rated good when the assumption alone may put ``f_p`` several % off.
    """

    camera_rule_deg: float = 10.0
    projector_rule_deg: float = 13.0
    degenerate_angle_deg: float = 1.0
    weak_angle_deg: float = 4.0
    degenerate_rel_std: float = 0.10
    weak_rel_std: float = 0.02
    plausible_f_range: tuple = FOCAL_RANGE
    camera_noise_px: float = 0.1
    projector_noise_px: float = 0.2
    data_alarm: float = 10.0
    u0p_spread_fraction: float = 0.03


@dataclass(frozen=True)
class Prediction:
    """Stable quantities of one device at a pose (:func:`predict`).

    ``angles_deg`` (3,) the board's ``(psi, nu, phi)`` from the homography with nominal intrinsics;
    ``rel_std_f`` the Cramer-Rao std of f over f (``inf`` when the pose determines nothing); ``f_nominal``
    (px) and ``sigma_px`` the focal length and corner noise it assumes.
    """

    angles_deg: np.ndarray
    rel_std_f: float
    f_nominal: float
    sigma_px: float


def _nominal_f(closed_form_f, size) -> float:
    diag = float(np.hypot(*size))
    if closed_form_f is not None and np.isfinite(closed_form_f) and 0.3 * diag <= closed_form_f <= 3.0 * diag:
        return float(closed_form_f)
    return diag


def predict(device: str, obj, pts, image_size, sigma: float, *, u0: float | None = None) -> Prediction | None:
    """The stable prediction for ``device`` (``"camera"`` or ``"projector"``) from its corners.

    Parameters
    ----------
    obj : (N, 3) board points; pts : (N, 2) the device's pixels (NaN rows ignored; the camera's are distorted
        and undistorted here with a one-term division model about the image centre, solved linearly).
    image_size : (W, H); sigma : corner noise (px) for the bound.
    u0 : the projector's fixed principal point column (default ``W / 2``).

    Returns None when the corners cannot give a homography.
    """
    if image_size is None:
        return None
    obj = np.asarray(obj, float)
    pts = np.asarray(pts, float).reshape(-1, 2)
    if obj.ndim != 2 or obj.shape[1] != 3 or len(obj) != len(pts):
        return None
    ok = np.isfinite(obj).all(1) & np.isfinite(pts).all(1)
    if ok.sum() < 4:
        return None
    M, m = obj[ok], pts[ok]
    W, Hh = image_size
    if device == "camera" and len(M) >= 8:
        # lens distortion would tilt the homography's pose: remove it first with the linear division-model
        # solve about the image centre (closed form: no iteration that could stop elsewhere)
        c = ((W - 1) / 2.0, (Hh - 1) / 2.0)
        try:
            with np.errstate(all="ignore"):
                k1 = distortion.estimate_division(M, m, c, n_coeffs=1)[0]
                und = models.undistort_division(m, c, k1)
            if np.all(np.isfinite(und)):
                m = und
        except (TypeError, ValueError, np.linalg.LinAlgError):
            pass
    try:
        with np.errstate(all="ignore"):
            H = homography(M[:, :2], m)
    except CalibrationError:
        return None
    if not np.all(np.isfinite(H)):
        return None
    if device == "camera":
        pp = ((W - 1) / 2.0, (Hh - 1) / 2.0)
        cf = models.zhang_camera(H, pp)
        f0 = _nominal_f(cf[0] if cf else None, image_size)
        K = models.intrinsic_matrix(f0, pp[0], pp[1])
    else:
        u0 = W / 2.0 if u0 is None else float(u0)
        cf = zhang_projector(H, u0)
        f0 = _nominal_f(cf[0] if cf else None, image_size)
        v0 = cf[1] if cf and f0 == cf[0] else Hh / 2.0
        K = models.intrinsic_matrix(f0, u0, v0)
    R, t = models.pose_from_homography(K, H)
    angles = models.board_angles_deg(R, t)
    if device == "camera":
        b = crlb.camera_bound(K, None, 0.0, 0.0, R, t, M, sigma, model="known_distortion")
        s = b.std["f_c"]
    else:
        s = crlb.projector_bound(K, R, t, M, sigma).std["f_p"]
    return Prediction(angles_deg=angles, rel_std_f=float(s / f0) if np.isfinite(s) else float("inf"),
                      f_nominal=f0, sigma_px=float(sigma))


def _pct(r) -> str:
    return "±inf" if r is None or not np.isfinite(r) else f"±{100 * r:.1f} %"


def _uncertainty_words(key, pred_rel, fit_rel, prediction) -> tuple[float, str]:
    """The relative ``±`` a rating rests on and its label: the bound predicted at this pose, or the fit's own ``±``
    (they are different numbers under different assumptions; never printed unlabelled)."""
    if pred_rel is not None and (fit_rel is None or pred_rel >= fit_rel):
        fit = f"; the fit's own ± is {_pct(fit_rel)[1:]}" if fit_rel is not None else ""
        return pred_rel, (f"{key} {_pct(pred_rel)} predicted at this pose (Cramer-Rao bound for "
                          f"{prediction.sigma_px:.2g} px corner noise{fit})")
    if fit_rel is not None:
        return fit_rel, f"{key} {_pct(fit_rel)} from the fit"
    return 0.0, f"{key} ± not known"


def _angle_words(device, angles, prediction) -> str:
    """The board's angles as the pose table prints them (signed, the fit's), and the homography's where the rating
    rests on those and they read otherwise."""
    d = "c" if device == "camera" else "p"
    shown = np.asarray(angles, float) if angles is not None else prediction.angles_deg
    keys = (0, 1) if device == "camera" else (1,)
    txt = ", ".join(f"{('psi', 'nu')[i]}_{d} = {shown[i]:.1f}" for i in keys) + " deg"
    if angles is not None and prediction is not None:
        pa = prediction.angles_deg
        if any(abs(abs(pa[i]) - abs(shown[i])) >= 0.05 for i in keys):
            txt += (" (" + ", ".join(f"|{('psi', 'nu')[i]}_{d}| = {abs(pa[i]):.1f}" for i in keys)
                    + " from the board's homography with nominal intrinsics, which the rating uses)")
    return txt


def _with_assumption(key, rel, rel_txt, fit_rel, assumed) -> tuple[float, str, bool]:
    """The rating's relative ``±`` with what an assumption can cost (``assumed = (cost_rel, words)``) added in
    quadrature to the fit's, when that is the larger; labelled as such."""
    if not assumed or assumed[0] is None:
        return rel, rel_txt, False
    cost, words = assumed
    total = float(np.hypot(fit_rel or 0.0, cost)) if np.isfinite(cost) else float("inf")
    if total <= rel:
        return rel, rel_txt, False
    own = f"; the fit's own ± is {_pct(fit_rel)[1:]}" if fit_rel is not None else ""
    return total, f"{key} {_pct(total)} with what {words} can cost ({_pct(cost)[1:]}{own})", True


def _rate_device(device: str, angles, prediction: Prediction | None, std_f, f, size, o: RatingOptions,
                 assumed=None) -> dict:
    """One device's rating (see the module docstring); ``assumed``: ``(cost_rel, words)``, what an assumption of
    the model can cost the focal length (:func:`_with_assumption`)."""
    key = "f_c" if device == "camera" else "f_p"
    a = prediction.angles_deg if prediction is not None else np.asarray(angles, float)
    psi, nu = abs(float(a[0])), abs(float(a[1]))
    fit_rel = None
    if std_f is not None and f is not None and f:
        fit_rel = float(std_f) / abs(float(f)) if np.isfinite(std_f) else float("inf")
    pred_rel = prediction.rel_std_f if prediction is not None else None
    angle_txt = _angle_words(device, angles, prediction)
    floor = o.camera_noise_px if device == "camera" else o.projector_noise_px
    if device == "camera":
        angle = min(psi, nu)
        paper_ok = psi + nu > o.camera_rule_deg
        rule = f"the paper's rule wants |psi_c| + |nu_c| > {o.camera_rule_deg:g} deg"
        turn = "tilt the board about both image axes (e.g. 15-25 deg each)"
        unseen = "f_c and alpha_c are not determined when the board is not tilted about BOTH image axes"
        check_data = ("check the corner detection (a blurred or moved capture, a wrong --board, a board that is not "
                      "flat)")
    else:
        angle = nu
        paper_ok = nu > o.projector_rule_deg
        rule = f"the paper's rule wants |nu_p| > {o.projector_rule_deg:g} deg"
        turn = "turn the board left/right about the projector's vertical axis (|nu_p| 15-30 deg)"
        unseen = "with u0p fixed, f_p and v0p are not determined without a rotation about the projector's vertical axis"
        check_data = ("check the decoded maps (procam decode --png): a pattern and its inverse swapped, patterns from "
                      "another capture, or the wrong --projector size")
    sigma = prediction.sigma_px if prediction is not None else None
    bad_data = sigma is not None and np.isfinite(sigma) and sigma > o.data_alarm * floor and angle >= o.weak_angle_deg
    if bad_data:  # the data, not the pose: never ask for another pose the user already has
        turn = (f"the corners scatter {sigma:.2g} px about the model, {sigma / floor:.0f} times a sound capture's "
                f"{floor:g} px, at a pose that is fine ({angle_txt}): the data, not the pose, limit this result; "
                + check_data)
    impossible = None
    if f is not None and size is not None:
        impossible = focal_failure(key, float(f), tuple(size), o.plausible_f_range)
    # what the rating found, as data (``findings``: code and numbers; ``next``: the move it asks for), then in words
    findings = []
    move = "check the data" if bad_data else ("tilt the board" if device == "camera" else "turn the board")
    # 1. stable quantities decide degeneracy
    if angle < o.degenerate_angle_deg:
        level, msg = "degenerate", f"{device}: degenerate pose ({angle_txt}): {unseen}; {turn}"
        findings.append({"code": "angle-zero", "angle_deg": float(angle), "limit_deg": o.degenerate_angle_deg})
    elif pred_rel is not None and pred_rel > o.degenerate_rel_std:
        level = "degenerate"
        msg = (f"{device}: degenerate pose: here {key} can only be known to {_pct(pred_rel)} (predicted for "
               f"{prediction.sigma_px:.2g} px corner noise; {angle_txt}); {turn}")
        findings.append({"code": "undetermined", "param": key, "rel_std": float(pred_rel), "basis": "predicted",
                         "limit": o.degenerate_rel_std})
    # 2. then the estimate
    elif impossible:
        level, msg = "failed", f"{device}: FAILED estimate: {impossible}; {turn}"
        findings.append({"code": "impossible", "param": key, "value": float(f)})
    elif fit_rel is not None and fit_rel > o.degenerate_rel_std:
        level = "degenerate"
        msg = (f"{device}: degenerate pose: {key} = {f:.1f} ± {fit_rel * abs(f):.3g} px ({_pct(fit_rel)} from the "
               f"fit); {turn}")
        findings.append({"code": "undetermined", "param": key, "rel_std": float(fit_rel), "basis": "fit",
                         "limit": o.degenerate_rel_std})
    else:
        reasons = []
        rel, rel_txt = _uncertainty_words(key, pred_rel, fit_rel, prediction)
        rel, rel_txt, by_assumption = _with_assumption(key, rel, rel_txt, fit_rel, assumed)
        basis = "assumption" if by_assumption else ("predicted" if rel == pred_rel else "fit")
        if rel > o.weak_rel_std:
            reasons.append(f"{rel_txt} (aim for under {_pct(o.weak_rel_std)[1:]})")
            findings.append({"code": "uncertain", "param": key, "rel_std": float(rel), "basis": basis,
                             "limit": o.weak_rel_std})
            if by_assumption and not bad_data:
                move = "measure u0p"
                turn = ("the board's corners alone cannot measure u0p: calibrate from the decoded pose folder (its "
                        "dense samples and the wall behind the board measure u0p, lens shift and distortion), give "
                        "u0p if it is known (Python: ProjectorOptions(u0=...)), or calibrate from several poses")
        if angle < o.weak_angle_deg:
            reasons.append(f"an angle is close to zero ({angle_txt})")
            findings.append({"code": "angle-small", "angle_deg": float(angle), "limit_deg": o.weak_angle_deg})
        if not paper_ok and not bad_data:
            reasons.append(rule)
            findings.append({"code": "paper-rule", "limit_deg": o.camera_rule_deg if device == "camera"
                             else o.projector_rule_deg})
        if bad_data and not reasons:
            reasons.append("its corners do not fit the model")
        if bad_data:
            findings.append({"code": "misfit", "sigma_px": float(sigma), "typical_px": floor})
        if reasons:
            level = "weak"
            msg = f"{device}: weak pose ({angle_txt}): " + "; ".join(reasons) + f" -- {turn}"
        else:
            level, msg = "good", f"{device}: pose OK ({rel_txt}; {angle_txt})"
    out = dict(psi_abs_deg=psi, nu_abs_deg=nu, paper_rule_ok=bool(paper_ok), level=level,
               degenerate=level in ("degenerate", "failed"), weak=level == "weak", failed=level == "failed",
               rel_std_f=fit_rel, predicted_rel_std_f=pred_rel, bad_data=bool(bad_data), findings=findings,
               next=None if level == "good" else move, message=msg)
    if assumed and assumed[0] is not None:
        out["assumption_rel_f"] = float(assumed[0])
    if device == "camera":
        out.update(sum_abs_deg=psi + nu, min_abs_deg=min(psi, nu))
    return out


def rate_pose(camera_angles_deg=None, projector_angles_deg=None, std=None, *, values=None, cam_size=None,
              proj_size=None, predicted: dict | None = None, options: RatingOptions = RatingOptions(),
              assumed: dict | None = None) -> dict:
    """Is this pose good for single-pose calibration? A rating per device and for the pose.

    Parameters
    ----------
    camera_angles_deg, projector_angles_deg : (psi, nu, phi) degrees of the board in each device
        frame (the fitted pose), or None when the device is absent.
    std : dict with ``f_c`` and/or ``f_p`` (px), optional; with ``values`` (dict with ``f_c``, ``f_p``)
        the fit's relative uncertainty is judged too.
    cam_size, proj_size : (W, H) pixels; with ``values`` a focal length outside
        ``options.plausible_f_range`` x the image diagonal is impossible for a real device.
    predicted : ``{"camera": Prediction, "projector": Prediction}`` (:func:`predict`), the stable
        quantities; their angles replace the fitted ones in the rules. Without them the rating rests on
        the given angles and the fit's std alone (as for angles typed in by hand).
    options : :class:`RatingOptions`, the thresholds.
    assumed : ``{"projector": (cost_rel, words)}``: what an assumption of the model (the paper's ``u0p = W/2``)
        can cost the focal length, relative; it joins the fit's ``±`` (in quadrature) where that is larger, labelled
        (``assumption_rel_f`` in the device's rating).

    Returns
    -------
    dict with ``camera`` and ``projector`` sub-dicts (``level`` one of :data:`LEVELS`, ``degenerate`` (not
    determined, or failed), ``weak``, ``failed``, ``paper_rule_ok``, ``rel_std_f`` (fit), ``predicted_rel_std_f``;
    ``findings``: what the rating found, as data -- a list of ``{"code": ..., numbers}`` with the codes
    ``angle-zero``, ``angle-small`` (``angle_deg``, ``limit_deg``), ``undetermined``, ``uncertain`` (``param``,
    ``rel_std``, ``basis``: predicted / fit / assumption, ``limit``), ``impossible`` (``param``, ``value``),
    ``paper-rule`` (``limit_deg``), ``misfit`` (``sigma_px``, ``typical_px``); ``next``: the move it asks for
    (``tilt the board``, ``turn the board``, ``check the data``, ``measure u0p``; None when good); and ``message``,
    the same in words) and
    for the pose: ``level`` (the worst device's), ``ok`` (good), ``degenerate`` and ``failed``. A single-pose
    calibration keeps it as its pose's ``"advice"`` entry (the key the file format has always used).
    """
    std = std or {}
    values = values or {}
    predicted = predicted or {}
    out: dict = {}
    for device, angles, key, size in (("camera", camera_angles_deg, "f_c", cam_size),
                                      ("projector", projector_angles_deg, "f_p", proj_size)):
        if angles is None and predicted.get(device) is None:
            continue
        out[device] = _rate_device(device, angles, predicted.get(device), std.get(key), values.get(key), size,
                                   options, (assumed or {}).get(device))
    subs = [v for v in out.values() if isinstance(v, dict)]
    level = max((s["level"] for s in subs), key=LEVELS.index, default="good")
    out["level"] = level
    out["degenerate"] = any(s["degenerate"] for s in subs)
    out["failed"] = any(s["failed"] for s in subs)
    out["ok"] = level == "good"
    return out


_WARNING = {"weak": WeakPoseWarning, "degenerate": DegeneratePoseWarning, "failed": FailedEstimateWarning}


def judge(rating: dict, name: str, strict: bool, warnings: list) -> tuple[str, tuple]:
    """The pose's verdict from its rating (:func:`rate_pose`): ``(level, reasons)``. Appends the reasons to
    ``warnings``, emits them as procam warnings (:class:`~procam.errors.WeakPoseWarning`, ...), and with ``strict``
    raises :class:`~procam.errors.DegeneratePoseError` for a degenerate or failed pose."""
    keys = [k for k in ("camera", "projector") if isinstance(rating.get(k), dict)]
    bad = [k for k in keys if rating[k]["level"] != "good"]
    reasons = tuple(f"pose {name!r}: {rating[k]['message']}" for k in bad)
    level = rating["level"]
    warnings.extend(reasons)
    if strict and level in ("degenerate", "failed"):
        raise DegeneratePoseError(f"pose {name!r}: {level} pose for single-pose calibration: "
                                  + "; ".join(rating[k]["message"] for k in keys if rating[k]["level"] == level))
    for k, r in zip(bad, reasons):
        _warnings.warn(r, _WARNING[rating[k]["level"]], stacklevel=3)
    return level, reasons
