"""A calibration in rows of text: the tables ``procam calibrate`` / ``evaluate`` print and the report shows.

Plain data, no printing: each table is one :class:`TextTable` (its header and rows, every cell a string,
built by one function here), which the CLI renders with rich and the HTML report as HTML, so the terminal
and the page show the same cells. The tables: the parameters (:func:`parameter_table`), the poses
(:func:`pose_table`), the metric verification (:func:`verification_table`, :func:`cross_table`), the
leave-one-pose-out spread of the parameters (:func:`spread_table`), and the devices as a projector datasheet
prints them (:func:`datasheet_table`, :mod:`procam.datasheet`) with how they are mounted (:func:`mounting_lines`,
:mod:`procam.mounting`).

Every ``±`` is 1 sigma from the fit's Jacobian, assuming the model is right and the corner noise i.i.d.
(:mod:`procam.uncertainty`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import datasheet as _datasheet
from . import models

#: What every ``±`` in these rows means.
PLUS_MINUS = "± is 1σ from the fit, assuming the model and i.i.d. corner noise"
#: What the ``±`` of a single-pose calibration with a real projector (:mod:`procam.single_pose.dense`) covers.
PLUS_MINUS_DENSE = ("± is 1σ covering the fit's noise, residuals correlated across the image (a block jackknife), "
                    "the lens models the data cannot tell apart, the priors, and a lens decentring of a few pixels")


def plus_minus(calib) -> str:
    """What the ``±`` of ``calib`` means (:data:`PLUS_MINUS` or :data:`PLUS_MINUS_DENSE`)."""
    return PLUS_MINUS_DENSE if calib.info.get("dense") is not None else PLUS_MINUS


@dataclass(frozen=True)
class TextTable:
    """A table as text.

    Attributes
    ----------
    header : the column names.
    rows : one tuple of cells per row, as long as ``header``.
    pooled : the row over all rows (``"all"``), shown apart (bold, highlighted) after them; None without one.
    left : how many leading columns hold words (left-aligned); the others hold numbers (right-aligned).
    """

    header: tuple
    rows: tuple
    pooled: tuple | None = None
    left: int = 1


def short_name(name) -> str:
    """A pose's name without its folder."""
    s = str(name or "")
    return Path(s).name or s


def projector_freed(calib) -> frozenset:
    """Which of the paper projector's assumptions (``"u0p"``, ``"alpha_p"``) a single-pose calibration estimated
    instead: both with the dense samples (:mod:`procam.single_pose.dense`), those the background lifted without them
    (:mod:`procam.single_pose.background`); empty when the paper's model was kept."""
    if calib.info.get("dense") is not None:
        return frozenset({"u0p", "alpha_p"})
    model = calib.info.get("background_model")  # "single-pose" (unchanged), "assumed", "u0p", "u0p+alpha_p"
    return frozenset() if model in (None, "single-pose", "assumed") else frozenset(str(model).split("+"))


def projector_assumptions(calib) -> list[str]:
    """What a single-pose calibration's projector numbers assume, in words (empty for other methods): the
    paper's u0p = W/2 and alpha_p = 1 where they were kept, what the background estimated instead, and no
    projector lens distortion."""
    if not calib.method.startswith("single-pose") or calib.projector is None:
        return []
    dense = calib.info.get("dense")
    if dense is not None:
        return _dense_assumptions(calib, dense)
    freed = projector_freed(calib)
    W = calib.projector.image_size[0]
    u0 = float(calib.projector.K[0, 2])
    if "u0p" in freed:
        out = [f"u0p = {pm(u0, _std(calib, 'u0p'), '.1f')} px is ESTIMATED from the background behind the board"]
    elif abs(u0 - W / 2) < 1e-6:
        out = [f"u0p = W/2 = {W / 2:g} px is ASSUMED, not estimated"]
    else:
        out = [f"u0p = {u0:g} px is GIVEN, not estimated"]
    if "alpha_p" in freed:
        out.append("alpha_p is ESTIMATED from the background")
    else:
        out.append("alpha_p = 1 (fy_p = f_p) is ASSUMED")
    out.append("the projector has NO lens distortion (ASSUMED)")
    return out


def _dense_assumptions(calib, dense) -> list[str]:
    """What a dense single-pose projector rests on (:mod:`procam.single_pose.dense`): each intrinsic estimated from
    the pose's samples or resting on its prior, and the lens model."""
    if "projector given" in calib.method:
        return ["the projector's intrinsics and distortion are GIVEN (an earlier calibration), not estimated"]
    K = calib.projector.K
    value = {"f_p": K[0, 0], "u0p": K[0, 2], "v0p": K[1, 2], "alpha_p": K[1, 1] / K[0, 0]}
    where = "the pose's decoded board" + (" and background" if dense.background_used else " (no background)")
    out = []
    named = {n: (mu, sd) for n, mu, sd in dense.priors}
    for name in ("u0p", "v0p", "alpha_p", "f_p"):
        s = _std(calib, name)
        fmt = ".4f" if name == "alpha_p" else ".1f"
        if name in named:
            mu, sd = named[name]
            if s is not None and s > 0.7 * sd:
                out.append(f"{name} rests on its PRIOR {mu:{fmt}} ± {sd:.3g}: this pose barely determines it (the ± "
                           "includes the prior)")
                continue
            out.append(f"{name} = {pm(value[name], s, fmt)} is ESTIMATED from {where} (prior {mu:{fmt}} ± {sd:.3g})")
        elif name in ("u0p", "v0p"):
            out.append(f"{name} = {pm(value[name], s, fmt)} is ESTIMATED from {where}")
    d = calib.projector.distortion
    if d.model == "opencv" and any(d.coeffs):
        terms = "k1, k2, p1, p2, k3"
        out.append(f"the projector's lens distortion (OpenCV {terms}: {', '.join(f'{c:.4g}' for c in d.coeffs)}) is "
                   f"ESTIMATED (model {dense.model}, chosen by held-out error)")
    else:
        out.append("the projector's lens distortion: none estimated (the held-out data ask for none)")
    return out


def _std(calib, key, idx=None):
    v = calib.std.get(key)
    if v is None:
        return None
    try:
        return float(v[idx]) if idx is not None else float(v)
    except (TypeError, IndexError, ValueError):
        return None


def pm(value, std, fmt=".2f") -> str:
    """``"value ± std"`` (just the value when the std is unknown or not finite)."""
    if std is None or not np.isfinite(std):
        return f"{value:{fmt}}"
    return f"{value:{fmt}} ± {std:{fmt}}"


def parameter_rows(calib) -> list[tuple[str, str, str]]:
    """``(parameter, camera, projector)`` rows: intrinsics ± std, distortion, RMS, extrinsics."""
    rows = []
    cK = calib.camera.K
    pK = calib.projector.K if calib.projector is not None else None

    def row(name, ckey, cval, pkey=None, pval=None, fmt=".2f"):
        rows.append((name, pm(cval, _std(calib, ckey), fmt) if cval is not None else "",
                     pm(pval, _std(calib, pkey), fmt) if pval is not None else ""))

    row("f (px)", "f_c", cK[0, 0], "f_p", None if pK is None else pK[0, 0])
    row("fy (px)", "fy_c", cK[1, 1], "fy_p", None if pK is None else pK[1, 1])
    row("u0 (px)", "u0c", cK[0, 2], "u0p", None if pK is None else pK[0, 2])
    row("v0 (px)", "v0c", cK[1, 2], "v0p", None if pK is None else pK[1, 2])
    d = calib.camera.distortion
    p_dist = ""  # the projector's distortion shares the camera's row
    if calib.projector is not None and calib.projector.distortion.model == "opencv":
        p_dist = "opencv " + " ".join(f"{c:.4g}" for c in calib.projector.distortion.coeffs)
    if d.model == "division":
        rows.append(("distortion", f"division c=({d.center[0]:.1f}, {d.center[1]:.1f})", p_dist))
        row("k1 (px^-2)", "k1", d.k1, fmt=".4g")
        row("k2 (px^-4)", "k2", d.k2, fmt=".4g")
    elif d.model == "opencv":
        rows.append(("distortion", "opencv " + " ".join(f"{c:.4g}" for c in d.coeffs), p_dist))
    elif p_dist:
        rows.append(("distortion", "none", p_dist))
    if p_dist and calib.method.startswith("single-pose") and _std(calib, "proj_dist", 0) is not None:
        for i, term in enumerate(("k1", "k2", "p1", "p2", "k3")):
            c, sd = calib.projector.distortion.coeffs[i], _std(calib, "proj_dist", i)
            if c or sd:
                rows.append((f"{term} (OpenCV)", "", pm(c, sd, ".4g")))
    rows.append(("RMS reprojection (px)", f"{calib.cam_rms:.3f}", "" if pK is None else f"{calib.proj_rms:.3f}"))
    if calib.R is not None:
        eul = models.euler_deg(calib.R)
        for i, n in enumerate(("psi", "nu", "phi")):
            rows.append((f"R {n} (deg)", pm(eul[i], _std(calib, "R_euler_deg", i)), ""))
        for i, n in enumerate("XYZ"):
            rows.append((f"T {n}", pm(float(calib.T[i]), _std(calib, "T", i)), ""))
        rows.append(("|T| (baseline)", f"{np.linalg.norm(calib.T):.2f}", ""))
        rows.append(("stereo RMS (px)", f"{calib.stereo_rms:.3f}", ""))
    return rows


def pose_verdict(rating: dict) -> str:
    """One line from a pose's single-pose rating (:func:`procam.single_pose.rating.rate_pose`, the pose's
    ``"advice"`` entry): the devices' messages."""
    if not rating:
        return ""
    parts = [rating[k]["message"] for k in ("camera", "projector")
             if isinstance(rating.get(k), dict) and rating[k].get("message")]
    return "; ".join(parts) or str(rating.get("message", ""))


def parameter_table(calib) -> TextTable:
    """The parameters with their ± (:func:`parameter_rows`); for a single-pose calibration each projector number
    the paper's model assumes says so, or that the background estimated it, and a row says the projector has
    no lens distortion. No projector column for a camera-only calibration."""
    rows = [list(r) for r in parameter_rows(calib)]
    if calib.method == "single-pose" and calib.projector is not None and calib.info.get("dense") is None:
        freed = projector_freed(calib)
        for r in rows:
            if r[0].startswith("u0"):
                r[2] += " (from the background)" if "u0p" in freed else " (assumed W/2)"
            elif r[0].startswith("fy"):
                r[2] += " (from the background)" if "alpha_p" in freed else " (assumed = f)"
        rows.append(["projector distortion", "", "none (assumed)"])
    header = ("parameter", "camera") + (("projector",) if calib.projector is not None else ())
    return TextTable(header, tuple(tuple(r[:len(header)]) for r in rows))


def pose_table(calib) -> TextTable:
    """Per pose the board's angles in both devices and, where it has one, its single-pose verdict
    (:func:`pose_rows`; the verdict column only when a pose has one). No rows without poses."""
    rows = pose_rows(calib)
    n = 4 if any(r[3] for r in rows) else 3
    header = ("pose", "camera ψ, ν, φ (deg)", "projector ψ, ν, φ (deg)", "verdict")[:n]
    return TextTable(header, tuple(r[:n] for r in rows), left=n)


def _verification_row(p, name=None) -> tuple:
    return (short_name(p.name) if name is None else name, str(p.n_corners), str(p.n_pairs), f"{p.scale_error_pct:+.3f}",
            f"{p.spacing_rms:.3f}", f"{p.planarity_rms:.3f}", f"{p.planarity_max:.3f}", f"{p.rigid_rms:.3f}",
            f"{p.reproj_rms:.3f}", f"{p.distance:.0f}")


def verification_table(ver) -> TextTable:
    """One row per pose of a :class:`procam.verify.Verification`, and the pooled ``all`` row (several poses).

    Columns: corners and adjacent pairs triangulated; scale error of the mean adjacent-corner distance
    against the printed square (%); RMS of (distance - square); RMS / max distance of the corners to
    their best plane; RMS after the best rigid fit of the printed board; reprojection RMS of the
    triangulated corners; mean distance from the camera (board units).
    """
    header = ("pose", "corners", "pairs", "scale error (%)", "spacing RMS", "planarity RMS", "planarity max",
              "rigid RMS", "reproj RMS (px)", "distance")
    pooled = _verification_row(ver.overall, "all") if len(ver.poses) > 1 else None
    return TextTable(header, tuple(_verification_row(p) for p in ver.poses), pooled)


#: What the held-out poses of a :class:`procam.verify.CrossVerification` are, by its ``kind``.
CROSS_LABELS = {"leave-one-out": "leave-one-pose-out", "single-pose-cross": "calibrated on another pose"}


def cross_table(cross) -> TextTable:
    """The overall figures in-sample next to the held-out ones (:data:`CROSS_LABELS`) of a
    :class:`procam.verify.CrossVerification`."""
    def row(name, ver):
        o = ver.overall
        return (name, f"{o.scale_error_pct:+.3f}", f"{o.spacing_rms:.3f}", f"{o.planarity_rms:.3f}",
                f"{o.rigid_rms:.3f}", f"{o.reproj_rms:.3f}", str(len(ver.poses)))

    rows = [row("in-sample", cross.in_sample)]
    if cross.held_out is not None:
        rows.append(row(CROSS_LABELS[cross.kind], cross.held_out))
    header = ("", "scale error (%)", "spacing RMS", "planarity RMS", "rigid RMS", "reproj RMS (px)", "poses")
    return TextTable(header, tuple(rows))


def spread_table(spread: dict) -> TextTable:
    """Each parameter's ± from the fit next to the spread of the leave-one-pose-out refits, from
    :func:`procam.verify.parameter_spread` (``{name: (value, fit std, refit std)}``)."""
    return TextTable(("parameter", "value", "± fit", "± leave-one-out"), tuple(
        (k, f"{v:.2f}", "" if js is None else f"{js:.3g}", f"{jack:.3g}") for k, (v, js, jack) in spread.items()))


def pose_rows(calib) -> list[tuple[str, str, str, str]]:
    """``(pose, camera angles, projector angles, verdict)`` per pose (angles in degrees)."""
    out = []
    for p in calib.poses:
        ca = p.get("camera_angles_deg")
        pa = p.get("projector_angles_deg")
        out.append((Path(str(p.get("name", ""))).name, ", ".join(f"{a:.1f}" for a in ca) if ca else "",
                    ", ".join(f"{a:.1f}" for a in pa) if pa else "", pose_verdict(p.get("advice") or {})))
    return out


#: The datasheet view's rows: (key of :class:`procam.datasheet.DatasheetView`, label, format).
DATASHEET_ROWS = (("throw_ratio", "throw ratio (distance / image width)", ".3f"),
                  ("shift_h_pct", "lens shift, horizontal (% of width; + image right of the axis)", ".2f"),
                  ("shift_v_pct", "lens shift, vertical (% of height; + image above the axis)", ".2f"),
                  ("offset_pct", "offset (% of half height; 2 x vertical shift)", ".2f"),
                  ("fov_h_deg", "field of view, horizontal (deg)", ".2f"),
                  ("fov_v_deg", "field of view, vertical (deg)", ".2f"))


def datasheet_table(calib) -> TextTable:
    """The devices' intrinsics as a projector datasheet prints them (:func:`procam.datasheet.calibration_datasheet`:
    throw ratio, lens shift in % of the image, offset, field of view), each with its ± where the calibration
    has one; the conventions are :mod:`procam.datasheet`'s. No projector column for a camera-only calibration."""
    views = [_datasheet.calibration_datasheet(calib, d) for d in ("camera", "projector")]
    views = [v for v in views if v is not None]
    rows = []
    for key, label, fmt in DATASHEET_ROWS:
        rows.append((label, *(pm(getattr(v, key), v.std.get(key), fmt) for v in views)))
    header = ("datasheet", "camera") + (("projector",) if len(views) > 1 else ())
    return TextTable(header, tuple(rows))


def mounting_lines(calib) -> list[str]:
    """How the devices are mounted, in sentences (:func:`procam.mounting.mounting`: upside-down or portrait
    relative to the camera, where the projector sits)."""
    from .mounting import mounting

    return mounting(calib).lines()
