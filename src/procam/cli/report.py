"""``procam report``: a calibration as one self-contained HTML page (also ``--report`` on calibrate / experiment)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from ._app import app, console, fail, refuse, say, user_errors, warn
from ._options import (
    POSE_OPTIONS,
    OrderOpt,
    ProjectorOpt,
    StepOpt,
    optional_size,
    parse_board,
    pose_options,
    value,
    with_pose_options,
)
from ._paths import output_path, pose_sizes

REPORT_SUFFIXES = (".html", ".htm")


@app.command("report")
@user_errors
@with_pose_options
def report_cmd(
    calibration: Path = typer.Argument(..., help="Calibration file (procam JSON, a rig's JSON, or OpenCV YAML/XML, "
                                                          "another tool's too, with pose folders)."),
    poses: Optional[list[Path]] = typer.Argument(None, help="Pose folders to show and verify (default: the poses "
                                                            "stored in the calibration JSON)."),
    out: Path = typer.Option(..., "-o", "--out", help="The report (.html): one self-contained file."),
    board: Optional[str] = typer.Option(None, "--board", help="Inner corners COLSxROWS, e.g. 10x6 (with pose "
                                                              "folders)."),
    square: Optional[float] = typer.Option(None, "--square", help="Square size, the length unit (with pose folders)."),
    projector: ProjectorOpt = None,
    order: OrderOpt = None,
    step: StepOpt = None,
    **pose_args,
):
    """One HTML page a person reads top to bottom: the verdict, the parameters with their uncertainty and
    assumptions, coverage, residuals, the metric verification, the rig in 3-D and (multi-pose) leave-one-out."""
    import contextlib

    from .. import io, pipeline
    from . import _show

    output_path(out, "-o", REPORT_SUFFIXES, inputs=(calibration, *(poses or ())))
    views = decodes = None
    if poses:
        if board is None or square is None:
            fail("give --board COLSxROWS and --square with the pose folders (the board they show)")
        brd = parse_board(board, square)
        opts = pose_options(**pose_args, poses=poses)
    else:
        refuse(("board", "square", "projector", "order", "step", *(o[0] for o in POSE_OPTIONS)),
               "is how pose folders are read; this report has none (give pose folders after the calibration file to "
               "show and verify them)")
    from ..io.rig import is_rig_calibration

    if is_rig_calibration(calibration):  # several projectors / cameras (procam.rig): the rig's page
        from . import _rig

        return _rig.report(calibration, poses, out=out, brd=brd if poses else None, projector=optional_size(projector),
                           order=value(order), step=step, options=opts if poses else None)
    calib = io.load_calibration(calibration)
    if poses:
        size = optional_size(projector)
        if size is None and calib.projector is not None and not all((Path(p) / "patterns.json").exists()
                                                                    for p in poses):
            size = tuple(calib.projector.image_size)
        views, decodes = [], []
        with console.status("decoding poses ...") if console.is_terminal else contextlib.nullcontext():
            for p in poses:
                v, maps = pipeline.view_from_folder(p, brd, size, value(order), options=opts, step=step)
                calib = pose_sizes(calib, calibration, v.cam_size, v.proj_size)  # sizes the file did not store
                if v.cam_size is not None and tuple(v.cam_size) != tuple(calib.camera.image_size):
                    fail(f"{p}: camera images are {v.cam_size[0]}x{v.cam_size[1]} but the calibration is for "
                         f"{calib.camera.image_size[0]}x{calib.camera.image_size[1]}; use captures of the same camera")
                views.append(v)
                decodes.append(maps)
                say(f"{v.name}: {int(v.valid.sum())} of {len(v.valid)} corners")
    elif not calib.views:
        warn(f"{calibration} holds no poses: the report has no coverage, residuals or verification; give the pose "
             "folders (procam report CALIB POSE_DIR... --board ... --square ...)")
    _show.write_calibration_report(calib, out, views=views, decodes=decodes, name=calibration.name)
