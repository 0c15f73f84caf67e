"""``procam correspond``: chessboard corners in the camera and their projector coordinates."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Optional

import numpy as np
import typer

from .. import capture, correspond as corr, io, pipeline
from ._app import (BoardOpt, EstimatorOpt, FIGURE_SUFFIXES, OrderOpt, ProjectorOpt, SquareOpt, StepOpt,
    WindowOpt, app, console, fail, optional_size, output_path, parse_size, parse_square, user_errors)


def parse_board(text: str) -> tuple[int, int]:
    cols, rows = parse_size(text, "--board")
    return cols, rows


def pose_options(estimator: str, window: int, refine: int | None, detector: str, method: str,
                 min_corners: int = 10) -> pipeline.PoseOptions:
    if estimator not in corr.ESTIMATORS:
        fail(f"--estimator must be one of {', '.join(corr.ESTIMATORS)}, got {estimator!r}")
    if detector not in ("auto", "classic", "sb"):
        fail(f"--detector must be auto, classic or sb, got {detector!r}")
    if method not in ("robust", "simple"):
        fail(f"--method must be robust or simple, got {method!r}")
    if window < 6:
        fail(f"--window must be at least 6 px, got {window}")
    return pipeline.PoseOptions(decode_method=method, detector=detector, refine_window=refine,
                                corners=corr.CornerOptions(window=window, estimator=estimator),
                                min_corners=min_corners)


def load_views(poses, cols, rows, square, projector, order, estimator, window, *, progress=None, step=None):
    """Decode every pose folder into a View (``progress(done, total, label)`` after each)."""
    opts = pose_options(estimator, window, None, "auto", "robust")
    views = []
    for k, p in enumerate(poses):
        v, _ = pipeline.view_from_folder(p, (cols, rows), square, projector, order, options=opts, step=step)
        views.append(v)
        if progress is not None:
            progress(k + 1, len(poses), str(p))
    return views


@app.command("correspond")
@user_errors
def correspond_cmd(
    board: BoardOpt,
    square: SquareOpt,
    pose_dir: Path = typer.Argument(..., help="Folder with one pose's captured sequence."),
    out: Path = typer.Option(..., "-o", "--out", help="Write the correspondences as JSON."),
    png: Path = typer.Option(None, "--png", help="Picture: corners on the camera image and on the projector plane."),
    window: WindowOpt = 60,
    estimator: EstimatorOpt = "ransac",
    refine: Optional[int] = typer.Option(None, "--refine-window",
                                         help="Corner fit half-window, px (default 15; 0 = none)."),
    detector: str = typer.Option("auto", "--detector", help="Corner detector: auto, classic or sb."),
    method: str = typer.Option("robust", "--method", help="Decode classifier: robust or simple."),
    projector: ProjectorOpt = None,
    order: OrderOpt = None,
    step: StepOpt = None,
):
    """Camera corners (white frame) and their projector coordinates by local homographies."""
    square = parse_square(square)
    cols, rows = parse_board(board)
    opts = pose_options(estimator, window, refine, detector, method)
    output_path(out, "-o", (".json",))
    output_path(png, "--png", FIGURE_SUFFIXES)
    cap = capture.load_capture(pose_dir, optional_size(projector), order,
                               step=step)
    for w in cap.warnings:
        console.print(f"[yellow]warning:[/yellow] {w}", highlight=False)
    view, _ = pipeline.view_from_stack(cap.stack, cap.pattern_set, (cols, rows), square, name=str(pose_dir),
                                       options=opts)
    ok = view.valid
    console.print(f"{pose_dir}: {ok.sum()} of {len(ok)} corners with projector coordinates"
                  + ("" if ok.all() else f" (failed: {corr.reason_summary(view.diagnostics['reason'])})"))
    res = view.diagnostics["residual_px"][ok]
    if ok.any():
        console.print(f"local homography fit RMS: median {float(np.median(res)):.2f}, "
                      f"max {float(res.max()):.2f} projector px")
    opt = dataclasses.asdict(opts)
    io.write_text(out, json.dumps(io.view_to_dict(view, (cols, rows), square, opt), indent=1))
    console.print(f"wrote {out}")
    if png is not None:
        from ..plots.correspond import correspond_figure
        from ..plots import save_figure

        save_figure(correspond_figure(view, cap.white, title=str(pose_dir)), png)
        console.print(f"wrote {png}")
