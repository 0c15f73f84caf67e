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
from .parameters import ALPHA_PRIOR_STD

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




def _alpha_prior_std(calib) -> float:
    """The std of the prior ``alpha_p = 1 +- std`` a single-pose projector fit with the background used (the
    calibration's ``info["alpha_prior_std"]`` when it records it)."""
    return float(calib.info.get("alpha_prior_std", ALPHA_PRIOR_STD))


def parameter_status(calib) -> dict:
    """What each parameter of a calibration IS, by name (:mod:`procam.parameters`): ``(kind, words)`` with kind
    ``"estimated"`` (from the data, with the fit's ``±``), ``"prior"`` (estimated but held near a value given
    with a tolerance), ``"assumed"`` (a fixed value of the model, not estimated) or ``"given"`` (the user's,
    e.g. ``--camera``). A solver may record its own in ``info["parameter_status"]`` (same form); they win.

    Only the parameters that are not plainly estimated are listed (and ``u0p`` / ``alpha_p`` of a single-pose
    projector, always).
    """
    out = {}
    W = calib.projector.image_size[0] if calib.projector is not None else None
    if "camera given" in calib.method:
        for k in ("f_c", "fy_c", "alpha_c", "u0c", "v0c", "k1", "k2", "cam_dist"):
            out[k] = ("given", "given (--camera), not estimated from this pose")
    elif calib.method in ("single-pose", "camera-only") and calib.info.get("principal_point_source") == "image-center":
        for k in ("u0c", "v0c"):
            out[k] = ("prior", "a PRIOR: the image centre ± 32 px per axis (the centre of distortion was not "
                               "reliable), refined by the fit")
    if "projector given" in calib.method:
        for k in ("f_p", "fy_p", "alpha_p", "u0p", "v0p", "proj_dist"):
            out[k] = ("given", "given (--projector-intrinsics), not estimated from this pose")
    elif calib.method.startswith("single-pose") and calib.projector is not None and calib.info.get("dense") is None:
        freed = projector_freed(calib)
        K = calib.projector.K
        u0, f, fy = float(K[0, 2]), float(K[0, 0]), float(K[1, 1])
        if "u0p" in freed:
            out["u0p"] = ("estimated", f"u0p = {pm(u0, _std(calib, 'u0p'), '.1f')} px is ESTIMATED from the "
                                       "background behind the board")
        elif abs(u0 - W / 2) < 1e-6:
            out["u0p"] = ("assumed", f"u0p = W/2 = {W / 2:g} px is ASSUMED, not estimated")
        else:
            out["u0p"] = ("given", f"u0p = {u0:g} px is GIVEN, not estimated")
        if "alpha_p" in freed:
            out["alpha_p"] = ("estimated", f"alpha_p = fy_p / f_p = {pm(fy / f, _std(calib, 'alpha_p'), '.4f')} is "
                                           "ESTIMATED from the background")
        elif fy != f or _std(calib, "alpha_p"):
            prior = _alpha_prior_std(calib)
            out["alpha_p"] = ("prior", f"alpha_p = fy_p / f_p = {pm(fy / f, _std(calib, 'alpha_p'), '.4f')} rests on "
                                       f"a PRIOR of 1 ± {prior:g} (the background refines it within that; not "
                                       "estimated freely)")
        else:
            out["alpha_p"] = ("assumed", "alpha_p = 1 (fy_p = f_p) is ASSUMED")
        out["proj_dist"] = ("assumed", "the projector has NO lens distortion (ASSUMED)")
    out.update(calib.info.get("parameter_status") or {})
    return out


def projector_assumptions(calib) -> list[str]:
    """What a single-pose calibration's projector numbers rest on, in words (empty for other methods): with the
    pose's dense samples what each intrinsic rests on (:func:`_dense_assumptions`); otherwise the paper's u0p = W/2
    and alpha_p = 1 where they were kept, a prior where it held them, what the background estimated instead, and no
    projector lens distortion (:func:`parameter_status`)."""
    if not calib.method.startswith("single-pose") or calib.projector is None:
        return []
    dense = calib.info.get("dense")
    if dense is not None:
        return _dense_assumptions(calib, dense)
    st = parameter_status(calib)
    return [st[k][1] for k in ("u0p", "alpha_p", "proj_dist") if k in st]


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
    """``(parameter, camera, projector)`` rows: intrinsics ± std (a given value as given, never ``± 0``), distortion,
    RMS, extrinsics."""
    rows = []
    cK = calib.camera.K
    pK = calib.projector.K if calib.projector is not None else None
    status = parameter_status(calib)

    def cell(key, val, fmt):
        if status.get(key, ("estimated",))[0] == "given":
            return f"{val:{fmt}} (given)"
        return pm(val, _std(calib, key) or None, fmt)  # a fixed value has no ±, not "± 0"

    def row(name, ckey, cval, pkey=None, pval=None, fmt=".2f"):
        rows.append((name, cell(ckey, cval, fmt) if cval is not None else "",
                     cell(pkey, pval, fmt) if pval is not None else ""))

    row("f (px)", "f_c", cK[0, 0], "f_p", None if pK is None else pK[0, 0])
    row("fy (px)", "fy_c", cK[1, 1], "fy_p", None if pK is None else pK[1, 1])
    row("u0 (px)", "u0c", cK[0, 2], "u0p", None if pK is None else pK[0, 2])
    row("v0 (px)", "v0c", cK[1, 2], "v0p", None if pK is None else pK[1, 2])
    d = calib.camera.distortion
    p_dist = ""  # the projector's distortion shares the camera's row
    if calib.projector is not None and calib.projector.distortion.model == "opencv":
        p_dist = "opencv " + " ".join(f"{c:.4g}" for c in calib.projector.distortion.coeffs)
    given = status.get("k1", ("",))[0] == "given"
    if d.model == "division":
        rows.append(("distortion", f"division c=({d.center[0]:.1f}, {d.center[1]:.1f})" + (" (given)" if given else ""),
                     p_dist))
        row("k1 (px^-2)", "k1", d.k1, fmt=".4g")
        row("k2 (px^-4)", "k2", d.k2, fmt=".4g")
    elif d.model == "opencv":
        rows.append(("distortion", "opencv " + " ".join(f"{c:.4g}" for c in d.coeffs) + (" (given)" if given else ""),
                     p_dist))
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
        for i, n in enumerate(("ψ", "ν", "φ")):  # the Euler angles of R: not a board's angles
            rows.append((f"R {n}_R (deg, XYZ Euler of R)", pm(eul[i], _std(calib, "R_euler_deg", i)), ""))
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
    """The parameters with their ± (:func:`parameter_rows`); a parameter that is not plainly estimated says what
    it is (:func:`parameter_status`): for a single-pose projector whether ``u0p`` / ``alpha_p`` were assumed,
    held by a prior or estimated from the background, and a row says the projector has no lens distortion. No
    projector column for a camera-only calibration."""
    rows = [list(r) for r in parameter_rows(calib)]
    st = parameter_status(calib)
    if calib.method == "single-pose" and calib.projector is not None and calib.info.get("dense") is None:
        for r in rows:
            if r[0].startswith("u0"):
                r[2] += {"estimated": " (from the background)", "assumed": " (assumed W/2)",
                         "given": " (given)"}[st["u0p"][0]]
            elif r[0].startswith("fy"):
                r[2] += {"estimated": " (from the background)", "assumed": " (assumed = f)",
                         "prior": f" (prior alpha_p = 1 ± {_alpha_prior_std(calib):g})"}[st["alpha_p"][0]]
        rows.append(["projector distortion", "", "none (assumed)"])
    for r in rows:
        if r[0].startswith(("u0", "v0")) and st.get("u0c" if r[0].startswith("u0") else "v0c", ("",))[0] == "prior":
            r[1] += " (prior: the image centre)"
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
