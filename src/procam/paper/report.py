"""The experiment's report (:mod:`procam.paper.experiment`): markdown, CSV tables, JSON and figures.

:func:`write_report` writes ``report.md`` (tables shaped like the paper's), one CSV per table,
``experiment.json`` (everything) and the PNG figures of :mod:`procam.plots.experiment`.
"""

from __future__ import annotations

import csv
import io as _stdio
import json
from pathlib import Path
from typing import Sequence

import numpy as np

from ..io import files as _files
from ..style import fmt_number
from .experiment import ExperimentResult

__all__ = ["markdown", "write_report"]


def _markdown_table(rows: list[dict], cols: list[tuple[str, str]], nd=2) -> str:
    head = "| " + " | ".join(h for _, h in cols) + " |"
    sep = "| " + " | ".join("---" for _ in cols) + " |"
    body = ["| " + " | ".join(fmt_number(r.get(k, ""), nd) for k, _ in cols) + " |" for r in rows]
    return "\n".join([head, sep, *body])


def _csv_text(rows: list[dict]) -> str:
    if not rows:
        return ""
    keys = list(rows[0].keys())
    for r in rows[1:]:
        keys += [k for k in r if k not in keys]
    buf = _stdio.StringIO()
    w = csv.DictWriter(buf, fieldnames=keys, lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: (repr(float(v)) if isinstance(v, (float, np.floating)) else v) for k, v in r.items()})
    return buf.getvalue()


def markdown(result: ExperimentResult, figures: Sequence[str] = ()) -> str:
    """The report as markdown: tables shaped like the paper's Tables 3–5 and per-pose tables, plus notes."""
    o = result.options
    ref, a = result.reference, result.set_a
    lines = ["# procam experiment: single-pose against multi-pose calibration", ""]
    lines.append("Poses: " + ", ".join(f"{i + 1} = `{n}`" for i, n in enumerate(result.pose_names)))
    lines.append("")
    lines.append(f"Multi-pose: every set of ≥ {o['min_set']} poses ({o['n_sets']} sets), OpenCV distortion "
                 f"camera `{o['cam_dist']}`, projector `{o['proj_dist']}`, "
                 + ("joint refinement." if o["refine"] else "Moreno–Taubin (stereoCalibrate with fixed intrinsics)."))
    lines.append(f"Reference = the set with the lowest σ_T: {ref['poses']} (σ_T = {fmt_number(ref['sigma_T'])}); "
                 f"Set A = all poses {a['poses']}. σ are sample std (ddof = 1) over the per-pose PnP extrinsics of "
                 "all poses; errors in px, lengths in board units, angles in degrees.")
    lines += ["", "## Multi-pose reprojection errors (paper Table 3)", "",
              "`cam`, `proj`, `stereo`: RMS on the set's own poses; `… all`: evaluated on all poses "
              "(mean per-pose PnP RMS; stereo RMS pooled).", ""]
    lines.append(_markdown_table(result.summary, [("row", ""), ("cam_rms", "cam"), ("proj_rms", "proj"),
                                                  ("stereo_rms", "stereo"), ("cam_rms_all", "cam all"),
                                                  ("proj_rms_all", "proj all"), ("stereo_rms_all", "stereo all")], 3))
    lines += ["", "## Multi-pose precision (paper Table 4)", ""]
    lines.append(_markdown_table(result.summary, [("row", ""), ("sigma_X", "σ_X"), ("sigma_Y", "σ_Y"),
                                                  ("sigma_Z", "σ_Z"), ("sigma_T", "σ_T"), ("sigma_abs_T", "σ_\\|T\\|")]))
    lines += ["", "## Multi-pose parameters (paper Table 5)", ""]
    lines.append(_markdown_table(result.params, [("parameter", "parameter"), ("reference", "reference"),
                                                 ("set_a", "Set A"), ("mean", "mean"), ("std", "std")]))
    lines += ["", "## Single-pose calibration of every pose (paper Tables CamAccuracy / ProAccuracy)", "",
              f"Focal errors: Δf_c against the reference f_c = {fmt_number(ref['f_c'])}, Δf_p against the reference "
              f"α_p f_p = {fmt_number(ref['fy_p'])}; errors are the mean per-pose RMS over all poses.", ""]
    lines.append(_markdown_table(result.single, [
        ("set", "set"), ("f_c", "f_c"), ("fy_c", "α_c f_c"), ("u0c", "u0c"), ("v0c", "v0c"), ("f_p", "f_p"),
        ("v0p", "v0p"), ("psi_c", "ψ_c"), ("nu_c", "ν_c"), ("abs_psi_c+abs_nu_c", "\\|ψ_c\\|+\\|ν_c\\|"),
        ("abs_df_c", "\\|Δf_c\\|"), ("cam_err", "cam err"), ("psi_p", "ψ_p"), ("nu_p", "ν_p"),
        ("abs_df_p", "\\|Δf_p\\|"), ("proj_err", "proj err"), ("verdict", "verdict")]))
    lines += ["", "Board angles of every pose under the reference calibration (PnP; unaffected by a degenerate "
              "single-pose solution; used by the focal-error plot):", ""]
    lines.append(_markdown_table(result.single, [("set", "set"), ("psi_c_ref", "ψ_c"), ("nu_c_ref", "ν_c"),
                                                 ("psi_p_ref", "ψ_p"), ("nu_p_ref", "ν_p")]))
    lines += ["", "## Single-pose procam extrinsics and precision", ""]
    lines.append(_markdown_table(result.single_extrinsics, [
        ("set", "set"), ("psi", "ψ"), ("nu", "ν"), ("phi", "φ"), ("X", "X"), ("Y", "Y"), ("Z", "Z"),
        ("sigma_abs_T", "σ_\\|T\\|"), ("sigma_T", "σ_T"), ("stereo", "stereo")]))
    if result.failures:
        lines += ["", "## Failures", ""]
        lines += [f"- {f['what']}: {f['message']}" for f in result.failures]
    if figures:
        lines += ["", "## Figures", ""]
        lines += [f"![{Path(f).stem}]({Path(f).name})" for f in figures]
    lines += ["", "Every multi-pose set is in `multi_sets.csv`.", ""]
    return "\n".join(lines)


#: The files :func:`write_report` writes (the figures of :func:`procam.plots.experiment.experiment_figures`, the
#: tables of :meth:`ExperimentResult.tables`), for a command to check before any work.
REPORT_FILES = ("focal_errors.png", "sigma_T.png", "single_pose.csv", "single_extrinsics.csv", "multi_sets.csv",
                "multi_summary.csv", "multi_params.csv", "experiment.json", "report.md")


def write_report(result: ExperimentResult, out_dir) -> list[Path]:
    """Write ``report.md``, one CSV per table, ``experiment.json`` and the PNG figures to ``out_dir``.

    Every file is written under a temporary name and renamed when complete.

    Returns
    -------
    The written paths.
    """
    from ..plots import save_figure
    from ..plots.experiment import experiment_figures

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths: list[Path] = []
    for name, fig in experiment_figures(result).items():
        paths.append(save_figure(fig, out / f"{name}.png"))
    for name, rows in result.tables().items():
        paths.append(_files.write_text(out / f"{name}.csv", _csv_text(rows)))

    paths.append(_files.write_text(out / "experiment.json", json.dumps(_files.to_jsonable(result.to_dict()), indent=1)))
    paths.append(_files.write_text(out / "report.md", markdown(result, [p.name for p in paths if p.suffix == ".png"])))
    return paths
