"""``procam check``: the instant verdict on one pose folder (seconds, no calibration file)."""

from __future__ import annotations

from pathlib import Path

import typer

from ._app import app, fail, user_errors
from ._options import (
    BackgroundMode,
    BackgroundOpt,
    BoardOpt,
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
from ._paths import output_path


@app.command("check")
@user_errors
@with_pose_options
def check_cmd(
    pose_dir: Path = typer.Argument(..., help="Folder with one pose's captured sequence."),
    board: BoardOpt = ...,
    square: SquareOpt = 1.0,
    png: Path = typer.Option(None, "--png", help="Overlay picture: white frame, decoded area, corners, verdict."),
    projector: ProjectorOpt = None,
    order: OrderOpt = None,
    step: StepOpt = None,
    background: BackgroundOpt = BackgroundMode.free,
    **pose_args,
):
    """Is this pose good for single-pose calibration? Checks the capture, decodes it, finds the corners,
    calibrates it from this one pose and says: good, weak, degenerate or failed, and why (exit code 3 for
    degenerate or failed)."""
    from ..check import check_pose
    from . import _show

    brd = parse_board(board, square)
    opts = pose_options(**pose_args, poses=[pose_dir])
    output_path(png, "--png", (".png", ".jpg", ".jpeg"), inputs=(pose_dir,))  # the overlay is a picture, not a plot
    check = check_pose(pose_dir, brd, optional_size(projector), value(order), options=opts, step=step,
                       background=value(background))
    _show.print_pose_check(check, png)
    if check.verdict in ("degenerate", "failed"):
        fail(f"{pose_dir}: {check.verdict} pose for single-pose calibration: "
             f"{'; '.join(r.split(': ', 1)[-1] for r in check.reasons)}", code=3, label="not good")
