"""``procam experiment``: the paper's real-data experiment on a set of pose folders."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import typer

from ..style import fmt_number
from ._app import app, console, err_console, fail, is_tty, plain, say, user_errors
from ._options import (
    BoardOpt,
    DistModel,
    ForceOpt,
    OrderOpt,
    ProjectorOpt,
    SquareOpt,
    StepOpt,
    optional_size,
    parse_board,
    pose_options,
    value,
    with_pose_options,
)
from ._paths import distinct_poses, output_dir, output_path

if TYPE_CHECKING:  # annotations only: rich is imported where a table is drawn
    from rich.table import Table

#: Most pose sets the experiment calibrates (every subset of at least --min-set poses).
MAX_SETS = 2000


def summary_tables(result) -> list[Table]:
    """Rich versions of the paper's Tables 3 + 4 and the single-pose focal errors."""
    from rich.table import Table

    t = Table(title="multi-pose sets: RMS on the set (px) and PnP precision on all poses")
    for c in ("", "cam", "proj", "stereo", "σ_X", "σ_Y", "σ_Z", "σ_T", "σ_|T|"):
        t.add_column(c, justify="left" if c == "" else "right", overflow="fold")
    for r in result.summary:
        t.add_row(plain(r["row"]), *(fmt_number(r[k], 3) for k in ("cam_rms", "proj_rms", "stereo_rms")),
                  *(fmt_number(r[k], 2) for k in ("sigma_X", "sigma_Y", "sigma_Z", "sigma_T", "sigma_abs_T")))
    s = Table(title="single-pose calibration of every pose (errors: mean over all poses)")
    for c in ("set", "f_c", "Δf_c", "ψc+νc", "cam", "f_p", "Δf_p", "|νp|", "proj", "σ_T", "verdict"):
        s.add_column(c, justify="right", overflow="fold")
    for r, e in zip(result.single, result.single_extrinsics):
        s.add_row(str(r["set"]), fmt_number(r["f_c"], 1), fmt_number(r["abs_df_c"], 1),
                  fmt_number(abs(r["psi_c_ref"]) + abs(r["nu_c_ref"]), 1), fmt_number(r["cam_err"], 2),
                  fmt_number(r["f_p"], 1), fmt_number(r["abs_df_p"], 1), fmt_number(abs(r["nu_p_ref"]), 1),
                  fmt_number(r["proj_err"], 2), fmt_number(e["sigma_T"], 2), r.get("verdict", ""))
    return [t, s]


class _LineProgress:
    """Progress for a pipe or a log (stderr not a terminal): one plain line per finished step, on stderr, with the
    two methods of :class:`rich.progress.Progress` the experiment uses."""

    def __init__(self):
        self._tasks = []

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def add_task(self, description, total=None, label=""):
        self._tasks.append([description, total])
        return len(self._tasks) - 1

    def update(self, task, completed, total=None, label=""):
        desc = self._tasks[task]
        if total is not None:
            desc[1] = total
        err_console.print(f"{desc[0]} {completed}/{desc[1]}" + (f": {label}" if label else ""), markup=False,
                          highlight=False)


@app.command("experiment")
@user_errors
@with_pose_options
def experiment_cmd(
    board: BoardOpt,
    square: SquareOpt,
    poses: list[Path] = typer.Argument(..., help="Pose folders (captured sequences), at least 3."),
    out: Path = typer.Option(..., "-o", "--out", help="Report folder (created if missing)."),
    html_report: Path = typer.Option(None, "--report", help="Also write the HTML report of the multi-pose "
                                                            "calibration from all poses (self-contained .html)."),
    min_set: int = typer.Option(3, "--min-set", help="Smallest pose set for the multi-pose calibrations."),
    joint_refine: bool = typer.Option(False, "--refine", help="Jointly refine every multi-pose calibration. Off by default "
                                                        "here (Moreno-Taubin's frozen-intrinsics stereo, as the paper), "
                                                        "unlike `procam calibrate`, which refines unless --no-refine."),
    cam_dist: DistModel = typer.Option("k1k2p1p2k3", "--cam-dist", help="Multi-pose camera distortion model."),
    proj_dist: DistModel = typer.Option("k1k2p1p2k3", "--proj-dist", help="Multi-pose projector distortion model."),
    projector: ProjectorOpt = None,
    order: OrderOpt = None,
    step: StepOpt = None,
    force: ForceOpt = False,
    **pose_args,
):
    """Single-pose calibration of every pose against multi-pose calibration of every pose set: the paper's
    tables (markdown + CSV), σ_T per set, focal errors against the pose angles (PNG)."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from .. import pipeline
    from ..multi_pose import DIST_CHOICES
    from ..paper import experiment, report
    from ..paper.report import REPORT_FILES

    brd = parse_board(board, square)
    distinct_poses(poses)
    opts = pose_options(**pose_args, poses=poses)
    if min_set < 2:
        fail(f"--min-set must be at least 2, got {min_set}")
    if len(poses) < min_set:
        fail(f"the experiment needs at least {min_set} pose folders (--min-set), got {len(poses)}")
    import math

    n_sets = sum(math.comb(len(poses), k) for k in range(min_set, len(poses) + 1))
    if n_sets > MAX_SETS:
        fail(f"{len(poses)} poses with --min-set {min_set} make {n_sets} pose sets to calibrate (at most {MAX_SETS}); "
             "raise --min-set or give fewer poses")
    output_dir(out, "-o", "experiment", force, inputs=poses)
    cam_dist, proj_dist = value(cam_dist), value(proj_dist)
    for name, d in (("--cam-dist", cam_dist), ("--proj-dist", proj_dist)):
        if d not in DIST_CHOICES:
            fail(f"{name} must be one of {', '.join(DIST_CHOICES)}, got {d!r}")
    size = optional_size(projector)
    for name in REPORT_FILES:  # with --force the folder may hold a user's file of one of these names
        output_path(out / name, "-o", (Path(name).suffix,), inputs=poses)
    output_path(html_report, "--report", (".html", ".htm"), inputs=poses)
    bar = (Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                    TextColumn("{task.fields[label]}", markup=False), console=err_console.real, transient=True)
           if is_tty() else _LineProgress())
    with bar:
        t_dec = bar.add_task("decoding", total=len(poses), label="")
        views = pipeline.views_from_folders(
            poses, brd, size, value(order), options=opts, step=step,
            progress=lambda d, t, label: bar.update(t_dec, completed=d, label=Path(label).name))
        t_cal = bar.add_task("calibrating", total=n_sets + len(poses), label="")
        result = experiment.run(views, size or views[0].proj_size, min_set=min_set, refine=joint_refine,
                                cam_dist=cam_dist, proj_dist=proj_dist,
                                progress=lambda d, t, label: bar.update(t_cal, completed=d, total=t, label=label))
        output_dir(out, "-o", "experiment", force, create=True)
        paths = report.write_report(result, out)
    for t in summary_tables(result):
        console.print(t)
    for f in result.failures:
        console.print(plain(f"failed: {f['what']}: {f['message']}"))
    say(f"reference (lowest σ_T) = set {result.reference['set']} {result.reference['poses']}; "
        f"wrote {len(paths)} files to {out} (report.md, CSV tables, PNG figures)")
    if html_report is not None:  # Set A (all poses), as the experiment calibrated it
        from . import _show

        calib = result.set_a_calibration
        if calib is None:
            label = f"multi-pose set {result.set_a['set']} "
            why = [f["message"] for f in result.failures if f["what"].startswith(label)]
            fail(f"no HTML report: the multi-pose calibration of all {len(views)} poses failed"
                 + (f": {why[0]}" if why else ""))
        _show.write_calibration_report(calib, html_report, name=f"{Path(out).name}: all {len(views)} poses (Set A)")
