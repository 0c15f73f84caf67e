"""The sections of the report page, in order (:data:`SECTIONS`); each is a function of the calibration and its
evidence that returns HTML.

The verdict in words and why (:mod:`procam.verdict`); the parameters with their ± and the model's
assumptions, and the poses (the tables :mod:`procam.summary` builds for the CLI too); the coverage of both
image planes; the residual vectors and their RMS per pose; the metric verification (:mod:`procam.verify`);
the rig in 3-D (:mod:`.rig`); for a multi-pose calibration, leave-one-pose-out per pose.
"""

from __future__ import annotations

from html import escape

import numpy as np

from ..summary import (PLUS_MINUS, datasheet_table, mounting_lines, parameter_table, plus_minus, pose_table,
                       projector_assumptions, short_name, spread_table, verification_table)
from ..verdict import Verdict
from ..verify import CalibrationVerification
from .coverage import coverage_fractions
from .elements import fmt, png, table, text_table
from .scene3d import rig_geometry, rig_svg

#: The page's sections, in order: ``id -> heading`` (``leave-one-out`` only for multi-pose calibrations).
SECTIONS = {"verdict": "Verdict", "parameters": "Parameters and assumptions", "coverage": "Coverage of the image planes",
            "residuals": "Reprojection residuals", "verification": "Metric verification", "rig": "The rig in 3-D",
            "leave-one-out": "Leave-one-pose-out verification"}


def section(sid: str, body: str, cls: str = "") -> str:
    """The ``<section>`` of id ``sid`` with its heading (:data:`SECTIONS`) over ``body`` (HTML)."""
    c = f' class="{cls}"' if cls else ""
    return f'<section id="{sid}"{c}>\n<h2>{escape(SECTIONS[sid])}</h2>\n{body}\n</section>'


def verdict_section(calib, verdict: Verdict, check: CalibrationVerification | None, flags=()) -> str:
    """The verdict in words: what it means, its reasons, and everything that was flagged
    (:func:`procam.verdict.flagged`: every warning the command line printed, rejected corners, priors, the
    verification's evidence); "nothing was flagged" only when that list is empty."""
    meaning = verdict.meaning
    parts = [f'<p><strong>{escape(meaning[:1].upper() + meaning[1:])}.</strong></p>']
    if verdict.reasons:
        parts.append("<ul>" + "".join(f"<li>{escape(r)}</li>" for r in verdict.reasons) + "</ul>")
    flags = [f for f in flags if f not in verdict.reasons]
    if flags:
        parts.append(f'<p class="warn"><strong>Flagged ({len(flags)}):</strong></p><ul class="warn" id="flagged">'
                     + "".join(f"<li>{escape(f)}</li>" for f in flags) + "</ul>")
    elif verdict.word != "good" and verdict.reasons:
        parts.append('<p id="flagged">Nothing else was flagged.</p>')
    else:
        parts.append('<p id="flagged">Nothing was flagged: no warning, no rejected corner, no prior, no verification '
                     "figure out of line.</p>")
    facts = [f"camera RMS {fmt(calib.cam_rms)} px"]
    if calib.projector is not None:
        facts += [f"projector RMS {fmt(calib.proj_rms)} px", f"stereo RMS {fmt(calib.stereo_rms)} px"]
    facts.append(f"{len(calib.poses)} pose{'s' if len(calib.poses) != 1 else ''}")
    parts.append(f"<p>{escape(', '.join(facts))}.</p>")
    if check is not None:
        for label, ver in (("held-out poses", check.held_out),
                           ("leave-one-pose-out", check.leave_one_out.held_out if check.leave_one_out else None),
                           ("its own poses (in-sample, optimistic)", check.in_sample)):
            if ver is not None:
                o = ver.overall
                parts.append(f"<p>Measured on {escape(label)}: the triangulated board's squares are "
                             f"{o.scale_error_pct:+.3f} % off the printed size and its corners lie "
                             f"{o.planarity_rms:.3f} (RMS) from a plane, in board units "
                             f"(<a href=\"#verification\">metric verification</a>).</p>")
                break
    word = f'<span class="word">{escape(verdict.word)}</span>'
    return (f'<section id="verdict" class="verdict {escape(verdict.word)}">\n<h2>Verdict: {word}</h2>\n'
            + "\n".join(parts) + "\n</section>")


def _assumptions(calib) -> list[str]:
    out = []
    d = calib.camera.distortion
    if calib.method in ("single-pose", "camera-only"):
        src = calib.info.get("principal_point_source")
        pp = {"cod": "the centre of distortion", "joint": "the joint fit of all camera parameters",
              "image-center": "a PRIOR: the image centre ± 32 px per axis, refined by the fit (the centre of "
                              "distortion was not reliable)",
              "given": "given"}.get(src, None)
        out.append("Camera: pinhole, zero skew, division-model distortion (k1, k2) about the principal point"
                   + (f"; the principal point comes from {pp}" if pp else "") + ".")
    elif d.model == "opencv":
        out.append(f"Camera: pinhole, zero skew, OpenCV distortion "
                   f"({escape(str(calib.info.get('cam_dist_model', len(d.coeffs))))}).")
    if calib.projector is not None:
        if calib.method.startswith("single-pose") and calib.info.get("dense") is not None:
            out.append("Projector (single-pose, dense samples): " + "; ".join(projector_assumptions(calib)) + ". "
                       + plus_minus(calib) + ".")
        elif calib.method == "single-pose":
            out.append("Projector (single-pose model): " + "; ".join(projector_assumptions(calib)) + ". "
                       "The ± of the projector do not cover a projector that breaks what is assumed "
                       "(e.g. a lens-shifted projector with u0p far from W/2 when the background could not tell).")
        elif calib.projector.distortion.model == "opencv":
            out.append(f"Projector: pinhole, zero skew, OpenCV distortion "
                       f"({escape(str(calib.info.get('proj_dist_model', '')))}).")
        out.append("Extrinsics: x_proj = R x_cam + T (camera to projector); T in board units (the unit of the "
                   "board's square).")
    if calib.method == "multi-pose":
        out.append("Multi-pose: " + ("both devices, R, T and every board pose jointly refined (robust loss); "
                                     if calib.info.get("refined") else
                                     "per-device OpenCV calibration and stereoCalibrate with fixed intrinsics "
                                     "(no joint refinement, so no ± are available); ")
                   + "the board is flat and its squares exact.")
    else:
        out.append("The board is flat and its squares exact.")
    out.append(f"{PLUS_MINUS}. It does not cover a wrong model; see the verdict and the metric verification.")
    return out


def parameters_section(calib) -> str:
    parts = [f'<p class="note">{escape(plus_minus(calib))}.</p>', text_table(parameter_table(calib))]
    parts.append("<h3>Model and assumptions</h3><ul>" + "".join(f"<li>{escape(a)}</li>" for a in _assumptions(calib))
                 + "</ul>")
    parts += ['<h3 id="datasheet">As a projector datasheet prints it</h3>',
              '<p class="note">Throw ratio = throw distance / image width = f / W; lens shift = how far the image '
              "centre sits from the lens axis, in % of the image (+: right, above); offset = 2 x the vertical shift; "
              "the conventions and a figure are in procam's docs/datasheet.md.</p>", text_table(datasheet_table(calib))]
    mount = mounting_lines(calib)
    if mount:
        parts.append("<h3>Mounting</h3><ul>" + "".join(f"<li>{escape(m)}</li>" for m in mount) + "</ul>")
    poses = pose_table(calib)
    if poses.rows:
        parts += ["<h3>Poses</h3>", text_table(poses)]
    return "\n".join(parts)


def coverage_section(calib, views, decodes) -> str:
    if not views:
        return '<p class="note">No poses to show: the calibration file holds no corners; give the pose folders.</p>'
    from ..plots.coverage import coverage_figure

    proj_size = calib.projector.image_size if calib.projector is not None else None
    cov = coverage_fractions(views, calib.camera.image_size, proj_size)
    fig = coverage_figure(views, calib.camera.image_size, proj_size, decodes=decodes, coverage=cov)
    rows = [[k, f"{100 * v:.0f} %"] for k, v in cov.items()]
    return "\n".join([
        "<figure>" + png(fig, "coverage of the camera and projector images") + "<figcaption>Each pose's corners "
        "and their outline (convex hull)" + (", over the pixels decoded in any pose (grey)" if decodes else "")
        + ". Corners near the edges pin the lens distortion there; outside the outlines the model extrapolates."
        "</figcaption></figure>",
        table(["image", "inside the union of the corners' outlines"], rows)])


def residuals_section(calib, per_pose, verdict: Verdict) -> str:
    if not per_pose:
        return '<p class="note">No poses to show: the calibration file holds no corners; give the pose folders.</p>'
    from ..plots.residuals import residual_figure

    has_proj = calib.projector is not None
    fig = residual_figure(per_pose, calib.camera.image_size, calib.projector.image_size if has_proj else None,
                          verdict=verdict.line())
    source = per_pose[0].get("source")
    how = {"single-pose": "each device's PnP pose with the calibrated intrinsics, on the corners the solver kept; "
                          "camera residuals in undistorted pixels, as the single-pose RMS is defined",
           "multi-pose": "the refined model at its own board poses, in distorted pixels",
           "pnp": "each device's PnP pose with the calibrated intrinsics, in distorted pixels"}.get(source, "")
    rows, classes = [], []
    pooled = {"cam": [], "proj": []}
    n_rej = {"cam": 0, "proj": 0}
    for p in per_pose:
        r = [short_name(p.get("name"))]
        for key in ("cam", "proj") if has_proj else ("cam",):
            res, used = p.get(f"{key}_res"), p.get(f"{key}_used")
            if res is None:
                r += ["", "", ""]
                continue
            fin = np.isfinite(res).all(1)
            used = fin if used is None else (np.asarray(used, bool) & fin)
            e = np.linalg.norm(res[used], axis=1)
            pooled[key].append(e)
            n_rej[key] += int((fin & ~used).sum())
            r += [fmt(float(np.sqrt(np.mean(e ** 2))) if e.size else float("nan")), str(int(used.sum())),
                  str(int((fin & ~used).sum()))]
        rows.append(r)
        classes.append("")
    if len(per_pose) > 1:
        r = ["all"]
        for key in ("cam", "proj") if has_proj else ("cam",):
            e = np.concatenate(pooled[key]) if pooled[key] else np.zeros(0)
            r += [fmt(float(np.sqrt(np.mean(e ** 2))) if e.size else float("nan")), str(e.size), str(n_rej[key])]
        rows.append(r)
        classes.append("all")
    head = ["pose", "camera RMS (px)", "corners", "rejected"]
    if has_proj:
        head += ["projector RMS (px)", "corners", "rejected"]
    return "\n".join([
        "<figure>" + png(fig, "reprojection residual vectors") + "<figcaption>Residual = observed - predicted, "
        "drawn as arrows at the observed corners, magnified as the key arrow says; red x: corners rejected as "
        f"outliers (not in the RMS). Measured as the calibration measures its RMS: {escape(how)}.</figcaption>"
        "</figure>",
        table(head, rows, row_classes=classes)])


def verification_section(calib, check: CalibrationVerification | None) -> str:
    if check is None:
        return '<p class="note">Not computed.</p>'
    parts = ['<p>The chessboard corners of every pose triangulated from the camera and the projector with this '
             "calibration, compared with the printed board: <em>scale error</em> = mean distance of adjacent corners "
             "against the printed square (positive: too large); <em>spacing RMS</em> = RMS of that distance minus the "
             "square; <em>planarity</em> = distances of the corners to their best plane; <em>rigid RMS</em> = corner "
             "distance after the best rigid fit of the printed board (the whole shape error); lengths in board units "
             "(the unit of the square, e.g. mm). A correct calibration gives a scale error near 0 and the corner "
             "noise as planarity.</p>"]
    if check.in_sample is not None:
        parts += ["<h3>On the poses the calibration was fitted to (in-sample, optimistic)</h3>",
                  text_table(verification_table(check.in_sample))]
    if check.held_out is not None:
        parts += ["<h3>On other poses (held out: the honest figure)</h3>",
                  text_table(verification_table(check.held_out))]
    if check.leave_one_out is not None and check.leave_one_out.held_out is not None:
        o = check.leave_one_out.held_out.overall
        parts.append(f'<p>Leave-one-pose-out (each pose verified by a calibration fitted without it): scale error '
                     f'{o.scale_error_pct:+.3f} %, rigid RMS {o.rigid_rms:.3f}; per pose in '
                     f'<a href="#leave-one-out">the last section</a>.</p>')
    if check.notes:
        parts.append("<ul class=\"warn\">" + "".join(f"<li>{escape(n)}</li>" for n in check.notes) + "</ul>")
    return "\n".join(parts)


def spread_html(calib, refits) -> str:
    """The leave-one-pose-out spread of each parameter next to its ± from the fit (the table the command line
    prints, :func:`procam.summary.spread_table`), or "" without refits."""
    from ..multi_pose.evidence import parameter_spread

    spread = parameter_spread(calib, refits or ())
    if not spread:
        return ""
    return ("<h3>Uncertainty: ± from the fit vs the spread of the leave-one-pose-out refits</h3>"
            "<p>± fit: 1σ from the fit's Jacobian (assumes the model and i.i.d. corner noise). ± leave-one-out: the "
            "jackknife standard error of the refits without each pose (no noise model). A spread many times the "
            "fit's ± means the poses do not determine the parameter.</p>" + text_table(spread_table(spread)))


def loo_section(check: CalibrationVerification | None, calib=None) -> str:
    loo = check.leave_one_out if check is not None else None
    if loo is None or loo.held_out is None:
        why = [n for n in (check.notes if check is not None else ()) if "leave-one" in n]
        refits = [r for r in (calib.info.get("leave_one_out_refits") or ()) if not isinstance(r, BaseException)] \
            if calib is not None else []
        return '<p class="note">' + escape(why[0] if why else "Not available.") + "</p>" + \
            (spread_html(calib, refits) if refits else "")
    held = {p.name: p for p in loo.held_out.poses}
    rows, classes = [], []
    for p in loo.in_sample.poses:
        h = held.get(p.name)

        def g(attr, fmt, q=None):
            return "" if q is None else f"{getattr(q, attr):{fmt}}"

        rows.append([short_name(p.name), g("scale_error_pct", "+.3f", p), g("scale_error_pct", "+.3f", h),
                     g("planarity_rms", ".3f", p), g("planarity_rms", ".3f", h), g("rigid_rms", ".3f", p),
                     g("rigid_rms", ".3f", h), g("reproj_rms", ".3f", p), g("reproj_rms", ".3f", h)])
        classes.append("")
    i, o = loo.in_sample.overall, loo.held_out.overall
    rows.append(["all", f"{i.scale_error_pct:+.3f}", f"{o.scale_error_pct:+.3f}", f"{i.planarity_rms:.3f}",
                 f"{o.planarity_rms:.3f}", f"{i.rigid_rms:.3f}", f"{o.rigid_rms:.3f}", f"{i.reproj_rms:.3f}",
                 f"{o.reproj_rms:.3f}"])
    classes.append("all")
    groups = ["scale error (%)", "planarity RMS", "rigid RMS", "reproj RMS (px)"]
    grid = table(["pose"] + ["in-sample", "left out"] * len(groups), rows, row_classes=classes)
    top = '<tr><th class="l"></th>' + "".join(f'<th colspan="2">{escape(g)}</th>' for g in groups) + "</tr>"
    grid = grid.replace("<thead>", "<thead>" + top, 1)
    parts = ["<p>For every pose, the calibration is refitted without it (same options) and the left-out pose is "
             "verified with the refit: the figure to expect on a new capture. In-sample: the calibration from all "
             "poses on the same pose. A left-out figure much worse than the in-sample one means the calibration "
             "depends on that pose.</p>", grid]
    if loo.failures:
        parts.append("<ul class=\"warn\">" + "".join(f"<li>refit without {escape(short_name(n))} failed: "
                                                      f"{escape(m)}</li>" for n, m in loo.failures) + "</ul>")
    if calib is not None and loo.refits:
        parts.append(spread_html(calib, loo.refits))
    return "\n".join(parts)


def rig_section(calib, views) -> str:
    geom = rig_geometry(calib, views)
    n_boards = sum(1 for p in geom["paths"] if p["cls"] == "board")
    T = calib.T
    facts = []
    if T is not None:
        facts.append(f"baseline |T| = {np.linalg.norm(T):.1f}")
        if calib.R is not None:
            facts.append("projector centre in the camera frame = ("
                         + ", ".join(f"{c:.1f}" for c in (-np.asarray(calib.R).T @ np.asarray(T))) + ")")
    if n_boards:
        facts.append(f"mean board distance {geom['distance']:.0f}")
    return "\n".join([
        "<figure>" + rig_svg(geom) + "<figcaption>Camera (blue) and projector (orange) frustums and the "
        f"{n_boards} board pose{'s' if n_boards != 1 else ''} (grey; red tick: the first corner) in the camera "
        "frame (x right, y down, z forward; axes grey), board units. Drag to turn, double-click to reset.</figcaption>"
        "</figure>",
        f"<p>{escape('; '.join(facts))}.</p>" if facts else ""])
