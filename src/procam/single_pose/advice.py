"""Is a pose good for single-pose calibration? The paper's rule, the true degeneracies, the predicted
uncertainty and the plausibility of the estimate, in one verdict per device."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import CalibrationError


@dataclass(frozen=True)
class AdviceOptions:
    """Thresholds of :func:`advice`.

    Attributes
    ----------
    camera_rule_deg, projector_rule_deg : the paper's empirical rule: camera ``|psi_c| + |nu_c|`` and
        projector ``|nu_p|`` above these (degrees).
    degenerate_angle_deg : an angle below this is treated as zero (degenerate).
    weak_angle_deg : an angle below this makes the pose weak (poorly conditioned).
    degenerate_rel_std, weak_rel_std : relative std of f above which the pose is degenerate / weak.
    plausible_f_range : focal lengths outside this range x the image diagonal (diagonal fields of view of
        ~136 deg down to ~11 deg) are impossible for a real device.
    """

    camera_rule_deg: float = 10.0
    projector_rule_deg: float = 13.0
    degenerate_angle_deg: float = 1.0
    weak_angle_deg: float = 4.0
    degenerate_rel_std: float = 0.10
    weak_rel_std: float = 0.02
    plausible_f_range: tuple = (0.2, 5.0)


def advice(camera_angles_deg=None, projector_angles_deg=None, std=None, *, values=None, camera_size=None,
           projector_size=None, options: AdviceOptions = AdviceOptions()) -> dict:
    """Is this pose good for single-pose calibration? The paper's rule and the true conditions.

    The paper's empirical rule: camera ``|psi_c| + |nu_c| > 10 deg``, projector ``|nu_p| > 13 deg``.
    The true degeneracies (Zhang's constraints with a known principal point): the camera's (f, alpha) are unobservable iff
    ``psi_c = 0`` or ``nu_c = 0`` (board plane parallel to an image axis, including fronto-parallel);
    the projector's (f, v0) with u0 fixed iff ``nu_p = 0``, whatever psi_p.

    Parameters
    ----------
    camera_angles_deg, projector_angles_deg : (psi, nu, phi) degrees of the board in each device
        frame, or None when the device is absent.
    std : dict with ``f_c`` and/or ``f_p`` (px), optional; with ``values`` (dict with ``f_c``, ``f_p``)
        the relative uncertainty is also judged.
    camera_size, projector_size : (W, H) pixels; with ``values`` a focal length outside
        ``options.plausible_f_range`` x the image diagonal is impossible for a real device: the estimate
        has **failed** (``failed``, and ``degenerate``), whatever its std says.
    options : :class:`AdviceOptions`, the thresholds.

    Returns
    -------
    dict with ``camera`` and ``projector`` sub-dicts (``paper_rule_ok``, ``degenerate``, ``weak``,
    ``failed``, ``rel_std_f``, ``message``) and ``ok`` (neither degenerate nor weak), ``degenerate``
    and ``failed``.
    """
    o = options
    camera_rule_deg, projector_rule_deg, degenerate_angle_deg = o.camera_rule_deg, o.projector_rule_deg, \
        o.degenerate_angle_deg
    weak_angle_deg, degenerate_rel_std, weak_rel_std = o.weak_angle_deg, o.degenerate_rel_std, o.weak_rel_std
    plausible_f_range = o.plausible_f_range
    std = std or {}
    values = values or {}
    out: dict = {}

    def rel(key):
        s, v = std.get(key), values.get(key)
        if s is None or v is None or not v:
            return None
        return float(s) / abs(float(v)) if np.isfinite(s) else float("inf")

    def implausible(key, size, device):
        """Message if the focal length is impossible for this image size, else None."""
        f = values.get(key)
        if f is None or size is None:
            return None
        lo, hi = (plausible_f_range[0] * np.hypot(*size), plausible_f_range[1] * np.hypot(*size))
        if np.isfinite(f) and lo <= f <= hi:
            return None
        return (f"{device}: FAILED estimate: {key} = {f:.4g} px is impossible for a {size[0]}x{size[1]} image "
                f"(plausible {lo:.0f}-{hi:.0f} px = {plausible_f_range[0]:g}-{plausible_f_range[1]:g} x the "
                f"diagonal); this pose does not determine the {device}'s intrinsics")

    def rel_txt(key, r):
        v = values.get(key)
        return f"{key} = {v:.1f} +- {r * abs(v):.3g} px" if v is not None and np.isfinite(r) else f"{key} +- inf"

    if camera_angles_deg is not None:
        psi, nu = abs(float(camera_angles_deg[0])), abs(float(camera_angles_deg[1]))
        r = rel("f_c")
        failed = implausible("f_c", camera_size, "camera")
        paper_ok = psi + nu > camera_rule_deg
        degen = (failed is not None or min(psi, nu) < degenerate_angle_deg
                 or (r is not None and r > degenerate_rel_std))
        weak = not degen and (not paper_ok or min(psi, nu) < weak_angle_deg or (r is not None and r > weak_rel_std))
        if failed:
            msg = failed + " (tilt the board about both image axes, e.g. 15-25 deg each)"
        elif degen and min(psi, nu) >= degenerate_angle_deg:
            msg = (f"camera: degenerate pose: {rel_txt('f_c', r)} ({100 * r:.0f} %) is not determined by this pose "
                   f"(|psi_c| = {psi:.1f}, |nu_c| = {nu:.1f} deg as estimated); tilt the board about both image "
                   f"axes (e.g. 15-25 deg each)")
        elif degen:
            msg = (f"camera: degenerate pose (|psi_c| = {psi:.1f} deg, |nu_c| = {nu:.1f} deg): f_c and alpha_c "
                   f"are not determined when the board is not tilted about BOTH image axes; tilt the board "
                   f"about both (e.g. 15-25 deg each)")
        elif weak:
            msg = (f"camera: weak pose (|psi_c| = {psi:.1f}, |nu_c| = {nu:.1f} deg"
                   + (f", f_c +-{100 * r:.1f} %" if r is not None else "")
                   + f"); the paper's rule wants |psi_c| + |nu_c| > {camera_rule_deg:g} deg and each angle "
                     f"should be clearly non-zero")
        else:
            msg = "camera: pose OK"
        out["camera"] = dict(psi_abs_deg=psi, nu_abs_deg=nu, sum_abs_deg=psi + nu, min_abs_deg=min(psi, nu),
                             paper_rule_ok=bool(paper_ok), degenerate=bool(degen), weak=bool(weak),
                             failed=failed is not None, rel_std_f=r, message=msg)
    if projector_angles_deg is not None:
        psi, nu = abs(float(projector_angles_deg[0])), abs(float(projector_angles_deg[1]))
        r = rel("f_p")
        failed = implausible("f_p", projector_size, "projector")
        paper_ok = nu > projector_rule_deg
        degen = failed is not None or nu < degenerate_angle_deg or (r is not None and r > degenerate_rel_std)
        weak = not degen and (not paper_ok or (r is not None and r > weak_rel_std))
        if failed:
            msg = failed + " (with u0p fixed it needs the board turned left/right about the projector's vertical axis)"
        elif degen and nu >= degenerate_angle_deg:
            msg = (f"projector: degenerate pose: {rel_txt('f_p', r)} ({100 * r:.0f} %) is not determined by this "
                   f"pose (|nu_p| = {nu:.1f} deg as estimated); with u0p fixed, f_p and v0p need a clear rotation "
                   f"of the board about the projector's vertical axis; turn the board left/right")
        elif degen:
            msg = (f"projector: degenerate pose (|nu_p| = {nu:.1f} deg): with u0p fixed, f_p and v0p need a "
                   f"rotation of the board about the projector's vertical axis; turn the board left/right")
        elif weak:
            msg = (f"projector: weak pose (|nu_p| = {nu:.1f} deg"
                   + (f", f_p +-{100 * r:.1f} %" if r is not None else "")
                   + f"); the paper's rule wants |nu_p| > {projector_rule_deg:g} deg")
        else:
            msg = "projector: pose OK"
        out["projector"] = dict(psi_abs_deg=psi, nu_abs_deg=nu, paper_rule_ok=bool(paper_ok), degenerate=bool(degen),
                                weak=bool(weak), failed=failed is not None, rel_std_f=r, message=msg)
    subs = [v for v in out.values() if isinstance(v, dict)]
    out["degenerate"] = any(s["degenerate"] for s in subs)
    out["failed"] = any(s["failed"] for s in subs)
    out["ok"] = not any(s["degenerate"] or s["weak"] for s in subs)
    return out


def judge(adv, name, strict, on_failure, warnings):
    """Warnings from the advice; raise on a failed estimate (``on_failure="raise"``) or, if ``strict``,
    on a degenerate pose."""
    if on_failure not in ("raise", "warn"):
        raise ValueError(f"on_failure must be 'raise' or 'warn', got {on_failure!r}")
    keys = [k for k in ("camera", "projector") if isinstance(adv.get(k), dict)]
    for key in keys:
        if adv[key]["degenerate"] or adv[key]["weak"]:
            warnings.append(f"pose {name!r}: {adv[key]['message']}")
    if adv["failed"] and on_failure == "raise":
        raise CalibrationError(f"pose {name!r}: single-pose calibration failed: "
                               + "; ".join(adv[k]["message"] for k in keys if adv[k]["failed"])
                               + "; use another pose (on_failure='warn' returns the failed estimate anyway)")
    if strict and adv["degenerate"]:
        raise CalibrationError(f"pose {name!r}: degenerate pose for single-pose calibration: "
                               + "; ".join(adv[k]["message"] for k in keys if adv[k]["degenerate"]))
