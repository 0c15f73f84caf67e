"""``procam evaluate``: reprojection, stereo and PnP-precision metrics of a calibration on pose folders."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import typer

from ._app import app, console, fail, plain, say, user_errors, warn
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
from ._paths import assumed_size, distinct_poses, output_path, pose_sizes

if TYPE_CHECKING:  # annotations only: rich is imported where a table is drawn
    from rich.table import Table


def evaluation_tables(ev) -> tuple[Table, Table]:
    """Rich tables: one row per pose, and the summary (RMS, σ_T, σ_|T|)."""
    from rich.table import Table

    t = Table(title="per pose (errors in px; T in board units; angles in degrees)")
    for c in ("pose", "n", "cam RMS", "proj RMS", "stereo RMS", "camera ψ, ν, φ", "projector ψ, ν, φ",
              "T_j = (X, Y, Z)"):
        t.add_column(c, justify="right" if c not in ("pose",) else "left")
    for p in ev.poses:
        t.add_row(plain(Path(p.name).name or p.name), str(p.n_points), f"{p.cam_rms:.3f}", f"{p.proj_rms:.3f}",
                  f"{p.stereo_rms:.3f}", ", ".join(f"{a:.1f}" for a in p.cam_angles),
                  ", ".join(f"{a:.1f}" for a in p.proj_angles), ", ".join(f"{x:.2f}" for x in p.T))
    s = Table(title="summary")
    s.add_column("metric")
    s.add_column("value", justify="right")
    s.add_row("camera RMS, mean over poses (px)", f"{ev.cam_rms:.3f}")
    s.add_row("projector RMS, mean over poses (px)", f"{ev.proj_rms:.3f}")
    s.add_row("stereo RMS, all points (px)", f"{ev.stereo_rms:.3f}")
    s.add_row("σ_X, σ_Y, σ_Z", ", ".join(f"{x:.3f}" for x in ev.sigma_xyz))
    s.add_row("σ_T (ddof 1 / ddof 0)", f"{ev.sigma_T:.3f} / {ev.sigma_T_ddof0:.3f}")
    s.add_row("σ_|T| (ddof 1 / ddof 0)", f"{ev.sigma_abs_T:.3f} / {ev.sigma_abs_T_ddof0:.3f}")
    s.add_row("calibration T (X, Y, Z)", ", ".join(f"{x:.2f}" for x in ev.T_calib))
    s.add_row("mean per-pose T_j", ", ".join(f"{x:.2f}" for x in ev.T_mean))
    s.add_row("calibration R (ψ, ν, φ)", ", ".join(f"{a:.2f}" for a in ev.R_angles))
    return t, s


@app.command("evaluate")
@user_errors
@with_pose_options
def evaluate_cmd(
    board: BoardOpt,
    square: SquareOpt,
    calibration: Path = typer.Argument(..., help="Calibration file (procam JSON, OpenCV YAML/XML, another "
                                                 "tool's result file: docs/file-formats.md) to evaluate."),
    poses: list[Path] = typer.Argument(..., help="Pose folders (captured sequences) to evaluate on."),
    out: Path = typer.Option(None, "-o", "--out", help="Write the metrics as JSON here."),
    projector: ProjectorOpt = None,
    order: OrderOpt = None,
    step: StepOpt = None,
    **pose_args,
):
    """Per pose: camera/projector RMS (PnP, intrinsics fixed), stereo RMS, the procam extrinsics from
    per-pose PnP; overall: the spread σ_T and σ_|T| of those extrinsics, the board angles in both device frames."""
    import contextlib
    import json

    from .. import io, pipeline
    from ..evaluate import check_baseline, evaluate
    from ..io import files as _files

    brd = parse_board(board, square)
    distinct_poses(poses)
    opts = pose_options(**pose_args, min_corners=6, background=False, poses=poses)  # the evaluation reads no background
    output_path(out, "-o", (".json",), inputs=(calibration, *poses))
    calib = io.load_calibration(calibration)
    if calib.projector is None or calib.R is None:
        fail(f"{calibration}: a camera-only calibration cannot be evaluated against projector points; "
             "give a procam calibration")
    size = optional_size(projector)
    if size is None and not all((Path(p) / "patterns.json").exists() for p in poses):
        size = tuple(calib.projector.image_size)
    with console.status("decoding poses ...") if console.is_terminal else contextlib.nullcontext():
        views = pipeline.views_from_folders(poses, brd, size, value(order), options=opts, step=step)
    calib = pose_sizes(calib, calibration, views[0].cam_size, views[0].proj_size)  # sizes the file did not store
    for v in views:
        if v.cam_size is not None and tuple(v.cam_size) != tuple(calib.camera.image_size):
            fail(f"{v.name}: camera images are {v.cam_size[0]}x{v.cam_size[1]} but the calibration is for "
                 f"{calib.camera.image_size[0]}x{calib.camera.image_size[1]}"
                 + (assumed_size(calib, "cam_size") or "; use captures of the same camera"))
    ev = evaluate(calib, views)
    check_baseline(ev)
    t, s = evaluation_tables(ev)
    console.print(t)
    console.print(s)
    # the metric verification: the given poses the calibration was fitted to (in-sample) and the others (held
    # out); a multi-pose calibration that holds >= 4 poses also leave-one-pose-out
    from ..verify import verify_calibration
    from . import _show

    check = verify_calibration(calib, views)
    _show.print_verification(check)
    from ..verdict import evidence_reasons  # what these poses say about the calibration's own verdict

    evidence = evidence_reasons(check)
    for level, reason in evidence:
        warn(f"{level}: {reason}")
    if evidence:
        from ..verdict import LEVELS

        worst = max([calib.verdict if calib.verdict in LEVELS else "good"] + [lv for lv, _ in evidence],
                    key=LEVELS.index)
        say(f"verdict on these poses: {worst} (the file says {calib.verdict})")
    if out is not None:
        from ..io.formats import EVALUATION_FORMAT

        d = {"format": EVALUATION_FORMAT, "version": 1, "calibration": str(calibration), "method": calib.method,
             **ev.to_dict(), "verification": check.to_dict(),
             "evidence": [{"level": lv, "reason": r} for lv, r in evidence]}
        _files.write_text(out, json.dumps(_files.portable_names(_files.to_jsonable(d), out.parent), indent=1))
        say(f"wrote {out}")
