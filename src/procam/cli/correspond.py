"""``procam correspond``: chessboard corners in the camera and their projector coordinates."""

from __future__ import annotations

from pathlib import Path

import typer

from ._app import app, say, user_errors, warn
from ._options import (
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
from ._paths import FIGURE_SUFFIXES, output_path


@app.command("correspond")
@user_errors
@with_pose_options
def correspond_cmd(
    board: BoardOpt,
    square: SquareOpt,
    pose_dir: Path = typer.Argument(..., help="Folder with one pose's captured sequence."),
    out: Path = typer.Option(..., "-o", "--out", help="Write the correspondences as JSON."),
    png: Path = typer.Option(None, "--png", help="Picture: corners on the camera image and on the projector plane."),
    projector: ProjectorOpt = None,
    order: OrderOpt = None,
    step: StepOpt = None,
    **pose_args,
):
    """Camera corners (white frame) and their projector coordinates by local homographies."""
    import dataclasses
    import json

    import numpy as np

    from .. import capture, io, pipeline
    from .. import correspond as corr
    from ..io import files as _files

    brd = parse_board(board, square)
    opts = pose_options(**pose_args, poses=[pose_dir])
    output_path(out, "-o", (".json",), inputs=(pose_dir,))
    output_path(png, "--png", FIGURE_SUFFIXES, inputs=(pose_dir,))
    cap = capture.load_capture(pose_dir, optional_size(projector), value(order), step=step)
    for w in cap.warnings:
        warn(w)
    view, _ = pipeline.view_from_stack(cap.stack, cap.pattern_set, brd, name=str(pose_dir), options=opts)
    ok = view.valid
    say(f"{pose_dir}: {ok.sum()} of {len(ok)} corners with projector coordinates"
        + ("" if ok.all() else f" (failed: {corr.reason_summary(view.diagnostics['reason'])})"))
    res = view.diagnostics["residual_px"][ok]
    if ok.any():
        say(f"local homography fit RMS: median {float(np.median(res)):.2f}, max {float(res.max()):.2f} projector px")
    _files.write_text(out, json.dumps(io.view_to_dict(view, dataclasses.asdict(opts)), indent=1))
    say(f"wrote {out}")
    if png is not None:
        from ..plots import save_figure
        from ..plots.correspond import correspond_figure

        save_figure(correspond_figure(view, cap.white, title=str(pose_dir)), png)
        say(f"wrote {png}")
