"""The paper's real-data experiment: single-pose calibration of every pose against multi-pose
calibrations of every pose set, measured as the paper measures them.

For ``n`` poses:

* **single-pose**: :func:`procam.single_pose.calibrate` on every pose, each evaluated on all ``n``
  poses with :func:`procam.evaluate.evaluate` (per-device error = mean over the poses of the per-pose
  PnP RMS; stereo RMS; σ_T, σ_|T|) — the paper's Tables "CamAccuracy", "ProAccuracy" and its
  per-set extrinsics table;
* **multi-pose**: :func:`procam.multi_pose.calibrate` on every subset of at least ``min_set`` poses
  (99 sets for 7 poses, 16 for 5), with the RMS values on the set itself and σ_T, σ_|T| evaluated on
  all ``n`` poses (the paper's Tables 3–5);
* **Set A** = all poses; the **reference** = the set with the lowest σ_T (the paper's "Set B");
  |Δf_c| is measured against the reference f_c and |Δf_p| against the reference α_p f_p (the
  convention the paper's Table ProAccuracy follows).

Sets are numbered in lexicographic order of their pose indices, by size (all 3-sets first).
:func:`procam.paper.report.write_report` writes markdown, CSV and PNG files.
"""

from __future__ import annotations

import itertools
import warnings
from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np

from .. import evaluate as _evaluate
from .. import models
from .. import multi_pose
from ..calibration import Calibration
from ..errors import CalibrationError, DegeneratePoseError, ProcamError, ProcamWarning
from ..view import View

#: Progress callback: ``progress(done, total, label)``.
Progress = Callable[[int, int, str], None]

_PARAMS = [("f_c", "f_c"), ("fy_c", "α_c f_c"), ("u0c", "u0c"), ("v0c", "v0c"), ("f_p", "f_p"),
           ("fy_p", "α_p f_p"), ("u0p", "u0p"), ("v0p", "v0p"), ("psi", "ψ"), ("nu", "ν"), ("phi", "φ"),
           ("X", "X"), ("Y", "Y"), ("Z", "Z")]
_SUMMARY_COLS = ["cam_rms", "proj_rms", "stereo_rms", "cam_rms_all", "proj_rms_all", "stereo_rms_all",
                 "sigma_X", "sigma_Y", "sigma_Z", "sigma_T", "sigma_abs_T"]


@dataclass(frozen=True)
class ExperimentResult:
    """Tables of the experiment (lists of flat dicts; NaN where a calibration failed).

    Attributes
    ----------
    pose_names : the poses, numbered 1..n in this order in every table.
    single : per pose, the single-pose intrinsics, board angles (from the single-pose solution, and
        ``*_ref`` from PnP under the reference calibration: reliable even when the single-pose
        solution is degenerate), focal errors and mean errors.
    single_extrinsics : per pose, the single-pose R (Euler), T, σ_|T|, σ_T and the stereo RMS.
    sets : per pose set, the multi-pose parameters and metrics.
    summary : Set A, reference, mean and std over the sets of the RMS and σ columns (Tables 3 + 4).
    params : per parameter, reference / Set A / mean / std over the sets (Table 5).
    reference, set_a : the ``sets`` rows of the reference (lowest σ_T) and of all poses.
    failures : ``{"what": ..., "message": ...}`` for every calibration that raised.
    options : the options of the run.
    set_a_calibration : the multi-pose :class:`~procam.calibration.Calibration` of all poses (Set A), or None
        when it failed (then in ``failures``); not in the tables or :meth:`to_dict`.
    """

    pose_names: tuple[str, ...]
    single: list
    single_extrinsics: list
    sets: list
    summary: list
    params: list
    reference: dict
    set_a: dict
    failures: list = field(default_factory=list)
    options: dict = field(default_factory=dict)
    set_a_calibration: Calibration | None = field(default=None, repr=False, compare=False)

    def tables(self) -> dict[str, list]:
        """``name -> rows`` of every table (the CSV files of :func:`procam.paper.report.write_report`)."""
        return {"single_pose": self.single, "single_extrinsics": self.single_extrinsics,
                "multi_sets": self.sets, "multi_summary": self.summary, "multi_params": self.params}

    def to_dict(self) -> dict:
        return {"pose_names": list(self.pose_names), **self.tables(), "reference": self.reference,
                "set_a": self.set_a, "failures": self.failures, "options": self.options}


def pose_sets(n: int, min_set: int = 3) -> list[tuple[int, ...]]:
    """Every subset of ``range(n)`` with at least ``min_set`` elements, by size then lexicographic.

    ``len(pose_sets(7)) == 99`` (35 + 35 + 21 + 7 + 1), ``len(pose_sets(5)) == 16``.
    """
    return [c for k in range(min_set, n + 1) for c in itertools.combinations(range(n), k)]


def _label(s: Sequence[int]) -> str:
    return "{" + ",".join(str(i + 1) for i in s) + "}"


def _nan_row(keys) -> dict:
    return {k: float("nan") for k in keys}


def _metrics(ev) -> dict:
    return {"cam_rms_all": ev.cam_rms, "proj_rms_all": ev.proj_rms, "stereo_rms_all": ev.stereo_rms,
            "sigma_X": float(ev.sigma_xyz[0]), "sigma_Y": float(ev.sigma_xyz[1]), "sigma_Z": float(ev.sigma_xyz[2]),
            "sigma_T": ev.sigma_T, "sigma_abs_T": ev.sigma_abs_T, "sigma_T_ddof0": ev.sigma_T_ddof0,
            "sigma_abs_T_ddof0": ev.sigma_abs_T_ddof0}


def _params(calib) -> dict:
    Kc, Kp = calib.camera.K, calib.projector.K
    e = models.euler_deg(calib.R)
    T = np.asarray(calib.T, float)
    return {"f_c": Kc[0, 0], "fy_c": Kc[1, 1], "u0c": Kc[0, 2], "v0c": Kc[1, 2], "f_p": Kp[0, 0], "fy_p": Kp[1, 1],
            "u0p": Kp[0, 2], "v0p": Kp[1, 2], "psi": e[0], "nu": e[1], "phi": e[2], "X": T[0], "Y": T[1], "Z": T[2]}


def _err(e: Exception) -> str:
    return str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__


def run(views: Sequence[View], proj_size=None, *, min_set: int = 3, progress: Progress | None = None,
        cam_dist: str = "k1k2p1p2k3", proj_dist: str = "k1k2p1p2k3", refine: bool = False,
        single_options: dict | None = None) -> ExperimentResult:
    """Run the experiment on ``views`` (one per pose).

    Parameters
    ----------
    views : the poses (at least ``min_set``; the paper has 7).
    proj_size : projector (width, height); default from the views.
    min_set : smallest pose set calibrated with the multi-pose method (the paper: 3).
    progress : optional callback ``progress(done, total, label)`` after every calibration.
    cam_dist, proj_dist : OpenCV distortion models of the multi-pose calibrations (Moreno–Taubin:
        ``k1k2p1p2k3`` for both).
    refine : joint refinement of the multi-pose calibrations.  Default ``False``: the reference is
        Moreno & Taubin's (``calibrateCamera`` per device, then ``stereoCalibrate`` with fixed
        intrinsics), as in the paper.  Note that ``procam calibrate`` (multi-pose) refines by default
        (``--no-refine`` turns it off), so its result for the same poses differs from this reference.
    single_options : keyword options of :func:`procam.single_pose.calibrate` (``camera=CameraOptions(...)``, ...).

    Returns
    -------
    :class:`ExperimentResult`

    Raises
    ------
    CalibrationError
        Too few poses, or no pose set could be calibrated.
    """
    from .. import single_pose

    views = list(views)
    multi_pose.check_distinct(views)
    n = len(views)
    if n < max(min_set, 2):
        raise CalibrationError(f"the experiment needs at least {max(min_set, 2)} poses, got {n}")
    proj_size = tuple(proj_size) if proj_size is not None else views[0].proj_size
    names = tuple(v.name or f"pose{i + 1}" for i, v in enumerate(views))
    sets = pose_sets(n, min_set)
    total = n + len(sets)
    done = 0
    failures = []

    def tick(label):
        nonlocal done
        done += 1
        if progress is not None:
            progress(done, total, label)

    # --- multi-pose over every set --------------------------------------------------------------
    set_rows = []
    set_evals = {}
    set_a_calib = None
    for k, s in enumerate(sets):
        row = {"set": k + 1, "poses": _label(s), "size": len(s)}
        try:
            calib = multi_pose.calibrate([views[i] for i in s], proj_size=proj_size, cam_dist=cam_dist,
                                         proj_dist=proj_dist, refine=refine, leave_one_out=False)
            if len(s) == n:
                set_a_calib = calib
            ev = _evaluate.evaluate(calib, views)
            set_evals[k] = ev
            row.update(_params(calib))
            row.update({"cam_rms": calib.cam_rms, "proj_rms": calib.proj_rms, "stereo_rms": calib.stereo_rms})
            row.update(_metrics(ev))
        except ProcamError as e:
            failures.append({"what": f"multi-pose set {k + 1} {_label(s)}", "message": _err(e)})
            row.update(_nan_row([p for p, _ in _PARAMS] + _SUMMARY_COLS + ["sigma_T_ddof0", "sigma_abs_T_ddof0"]))
        set_rows.append(row)
        tick(f"multi-pose set {_label(s)}")
    ok_rows = [r for r in set_rows if np.isfinite(r["sigma_T"])]
    if not ok_rows:
        raise CalibrationError("no pose set could be calibrated with the multi-pose method: "
                               + "; ".join(f["message"] for f in failures[:3]))
    reference = min(ok_rows, key=lambda r: r["sigma_T"])
    set_a = set_rows[-1]
    ref_poses = set_evals[reference["set"] - 1].poses  # board angles under the reference calibration

    # --- single-pose on every pose ----------------------------------------------------------------
    f_ref, fy_p_ref = reference["f_c"], reference["fy_p"]
    single_rows, ext_rows = [], []
    for j, v in enumerate(views):
        row = {"set": j + 1, "pose": names[j]}
        ext = {"set": j + 1, "pose": names[j]}
        ref_angles = {"psi_c_ref": ref_poses[j].cam_angles[0], "nu_c_ref": ref_poses[j].cam_angles[1],
                      "psi_p_ref": ref_poses[j].proj_angles[0], "nu_p_ref": ref_poses[j].proj_angles[1]}
        try:
            with warnings.catch_warnings():  # each pose's verdict goes into its row
                warnings.simplefilter("ignore", ProcamWarning)
                calib = single_pose.calibrate(v, proj_size, **(single_options or {}))
            row["verdict"] = calib.verdict
            ev = _evaluate.evaluate(calib, views)
            p = _params(calib)
            ca = calib.poses[0].get("camera_angles_deg") if calib.poses else None
            pa = calib.poses[0].get("projector_angles_deg") if calib.poses else None
            ca = ca if ca is not None else ev.poses[j].cam_angles
            pa = pa if pa is not None else ev.poses[j].proj_angles
            row.update({"f_c": p["f_c"], "fy_c": p["fy_c"], "u0c": p["u0c"], "v0c": p["v0c"], "f_p": p["f_p"],
                        "v0p": p["v0p"], "psi_c": ca[0], "nu_c": ca[1], "abs_psi_c+abs_nu_c": abs(ca[0]) + abs(ca[1]),
                        "abs_df_c": abs(p["f_c"] - f_ref), "cam_err": ev.cam_rms, "psi_p": pa[0], "nu_p": pa[1],
                        "abs_df_p": abs(p["f_p"] - fy_p_ref), "proj_err": ev.proj_rms, "u0p": p["u0p"]})
            row.update(ref_angles)
            ext.update({"psi": p["psi"], "nu": p["nu"], "phi": p["phi"], "X": p["X"], "Y": p["Y"], "Z": p["Z"],
                        "sigma_abs_T": ev.sigma_abs_T, "sigma_T": ev.sigma_T, "stereo": ev.stereo_rms,
                        "sigma_T_ddof0": ev.sigma_T_ddof0, "sigma_abs_T_ddof0": ev.sigma_abs_T_ddof0})
        except ProcamError as e:
            if isinstance(e, DegeneratePoseError):  # no solution at a degenerate pose: a verdict, not a failure
                row["verdict"] = "degenerate"
            else:
                row["verdict"] = "error"
                failures.append({"what": f"single-pose {j + 1} ({names[j]})", "message": _err(e)})
            row.update(_nan_row(["f_c", "fy_c", "u0c", "v0c", "f_p", "v0p", "psi_c", "nu_c", "abs_psi_c+abs_nu_c",
                                 "abs_df_c", "cam_err", "psi_p", "nu_p", "abs_df_p", "proj_err", "u0p"]))
            row.update(ref_angles)
            ext.update(_nan_row(["psi", "nu", "phi", "X", "Y", "Z", "sigma_abs_T", "sigma_T", "stereo",
                                 "sigma_T_ddof0", "sigma_abs_T_ddof0"]))
        single_rows.append(row)
        ext_rows.append(ext)
        tick(f"single-pose {names[j]}")

    # --- summaries ------------------------------------------------------------------------------------
    def stat(fn, key):
        vals = np.array([r[key] for r in ok_rows], float)
        vals = vals[np.isfinite(vals)]
        if len(vals) == 0:
            return float("nan")
        return float(fn(vals))

    def sd(x):
        return np.std(x, ddof=1) if len(x) > 1 else float("nan")

    summary = []
    for label, src in ((f"Set A {set_a['poses']}", set_a), (f"reference (lowest σ_T) {reference['poses']}", reference)):
        summary.append({"row": label, **{c: src[c] for c in _SUMMARY_COLS}})
    summary.append({"row": f"mean over {len(ok_rows)} sets", **{c: stat(np.mean, c) for c in _SUMMARY_COLS}})
    summary.append({"row": "std", **{c: stat(sd, c) for c in _SUMMARY_COLS}})
    params = [{"parameter": label, "key": key, "reference": reference[key], "set_a": set_a[key],
               "mean": stat(np.mean, key), "std": stat(sd, key)} for key, label in _PARAMS]
    options = {"min_set": min_set, "cam_dist": cam_dist, "proj_dist": proj_dist, "refine": refine,
               "proj_size": list(proj_size) if proj_size else None, "n_sets": len(sets),
               "single_options": {k: str(v) for k, v in (single_options or {}).items()}}
    return ExperimentResult(pose_names=names, single=single_rows, single_extrinsics=ext_rows, sets=set_rows,
                            summary=summary, params=params, reference=dict(reference), set_a=dict(set_a),
                            failures=failures, options=options, set_a_calibration=set_a_calib)
