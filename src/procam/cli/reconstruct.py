"""``procam reconstruct``: a coloured point cloud (binary PLY) of one captured pose."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Optional

import typer

from .. import choices
from ._app import app, console, fail, plain, refuse, say, user_errors, warn
from ._options import OrderOpt, ProjectorOpt, StepOpt, choice, parse_size, value
from ._paths import distrust, load_pose, output_path

Use = choice("Use", choices.TRIANGULATION_USES)


@app.command("reconstruct")
@user_errors
def reconstruct_cmd(
    calibration: Path = typer.Argument(..., help="Calibration file (JSON or OpenCV YAML) of this camera and "
                                                 "projector."),
    pose_dir: Path = typer.Argument(..., help="Folder with one pose's captured sequence."),
    out: Path = typer.Option(..., "-o", "--out", help="Point cloud, binary PLY (x, y, z in the camera frame, "
                                                    "calibration units; colour from the white frame)."),
    board: Optional[str] = typer.Option(None, "--board", help="Inner corners COLSxROWS: fit the board's plane "
                                                            "and report how flat the reconstruction is."),
    residuals: Path = typer.Option(None, "--residuals", help="PNG of the board's distances to its plane "
                                                             "(needs --board)."),
    use: Use = typer.Option(Use.both, "--use", help="Projector coordinates: both (column and row where decoded), "
                                                  "col or row."),
    max_residual: float = typer.Option(2.0, "--max-residual", help="Drop points whose projector column and row "
                                                                   "disagree by more than this many projector px."),
    projector: ProjectorOpt = None,
    order: OrderOpt = None,
    step: StepOpt = None,
):
    """Decode a pose and triangulate every decoded camera pixel (camera ray x projector planes)."""
    import numpy as np
    from rich.table import Table

    from .. import board as _board
    from .. import decode, io, pipeline
    from .. import reconstruct as rc
    from ..io import files as _files
    from ..io.formats import PLY_COMMENT

    output_path(out, "-o", (".ply",), inputs=(calibration, pose_dir))
    from ..io.ply import require_plyfile

    require_plyfile()          # before the decoding, not after it
    output_path(residuals, "--residuals", (".png",), inputs=(calibration, pose_dir))
    use = value(use)
    if not (math.isfinite(max_residual) and 0 < max_residual <= 10000):
        fail(f"--max-residual must be a positive number of projector pixels (at most 10000), got {max_residual}")
    if use != "both":
        refuse(("max_residual",), f"compares the projector column and row of a point; --use {use} triangulates "
                                  "with one of them only")
    if residuals is not None and board is None:
        fail("--residuals needs --board (the plane is fitted to the board's points)")
    lo, hi = _board.CORNERS_PER_SIDE
    pattern = parse_size(board, "--board", lo=lo, hi=hi) if board is not None else None
    calib = io.load_calibration(calibration)
    if calib.projector is None or calib.R is None:
        fail(f"{calibration}: a camera-only calibration cannot triangulate; give a procam calibration")
    cap, calib = load_pose(pose_dir, projector, calib, order, step)
    ps = cap.pattern_set
    H, W = cap.stack.shape[1:]
    maps = decode.decode(cap.stack, ps)
    from ..decode import plausibility  # the capture's own faults first: they, not the calibration, explain a bad cloud

    for w in plausibility.check_decoded(maps, str(pose_dir), cap.files):
        warn(w)
    cloud = rc.reconstruct(calib, maps, cap.picture(), use=use, max_residual_px=max_residual)
    if len(cloud) == 0:
        fail(f"{pose_dir}: no camera pixel could be triangulated (nothing decoded in front of both devices); "
             "check the decode picture (procam decode --png)")
    if pattern is not None:  # the board found before anything is written: a failure leaves no cloud behind
        corners = pipeline.find_board(cap.stack, ps, pattern, name=str(pose_dir))
        on_board = cloud.image_mask(_board.board_region(corners, (W, H)))
        if on_board.sum() < 3:
            fail(f"{pose_dir}: fewer than 3 points on the board; is it lit by the projector?")
        plane = rc.fit_plane(cloud.points[on_board])
    accounted, dropped_warnings, misfit = rc.dropped_lines(cloud)
    doubt = distrust(calib, calibration)
    if doubt:
        warn(doubt)
    untrusted = ("most decoded pixels do not fit the calibration" if misfit
                 else f"the calibration's verdict is {calib.verdict}" if doubt else "")
    io.write_ply(out, cloud.points, cloud.colours,
                 comments=[PLY_COMMENT, "procam reconstruct", f"calibration {Path(calibration).name}",
                           f"pose {Path(pose_dir).name}", "frame: camera (x right, y down, z forward), units of the calibration's T"]
                 + ([f"NOT TRUSTED: {misfit or doubt}"] if untrusted else []))
    t = Table(title=plain(f"{Path(pose_dir).name}: point cloud"))
    t.add_column("quantity")
    t.add_column("value", justify="right")
    t.add_row("points", f"{len(cloud)}")
    if untrusted:
        t.add_row("verdict", f"NOT TRUSTED: {untrusted}")
    for line in accounted:
        name, val = line.split(": ", 1)
        t.add_row(name, val)
    t.add_row("from column and row", f"{np.mean(cloud.both):.1%}")
    t.add_row("median depth z", f"{np.median(cloud.points[:, 2]):.1f}")
    if pattern is not None:
        t.add_row("board points", f"{int(on_board.sum())}")
        t.add_row("board plane RMS (inliers)", f"{plane.rms:.3f}")
        t.add_row("board plane robust sigma", f"{plane.sigma:.3f}")
        t.add_row("board plane inliers", f"{np.mean(plane.inliers):.1%}")
        t.add_row("board plane distance from camera", f"{plane.offset:.1f}")
        if residuals is not None:
            res = rc.residual_map(cloud.subset(on_board), plane)
            _files.write_image(residuals, rc.residual_image(res))
    console.print(t)
    for w in dropped_warnings:
        warn(w)
    say(f"wrote {out}")
    if residuals is not None:
        say(f"wrote {residuals} (board distance to its plane, ±3 robust sigma: blue below, red above)")
    if untrusted:
        fail(f"the point cloud in {out} must not be trusted: {untrusted} (see the warning above)", code=3,
             label="not trusted")
