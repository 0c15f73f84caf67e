"""``procam calibrate``: single-pose (one folder), multi-pose (several) or camera-only (one photo)."""

from __future__ import annotations

from contextlib import nullcontext
from pathlib import Path

import numpy as np
import typer
from rich.table import Table

from .. import io
from ..errors import BoardNotFoundError
from ._app import (BoardOpt, EstimatorOpt, FIGURE_SUFFIXES, OrderOpt, ProjectorOpt, SquareOpt, StepOpt,
    WindowOpt, app, console, fail, optional_size, output_path, parse_square, user_errors)
from .correspond import load_views, parse_board


def _pm(value, std, fmt=".2f"):
    if std is None or not np.isfinite(std):
        return f"{value:{fmt}}"
    return f"{value:{fmt}} ± {std:{fmt}}"


def _std(calib, key, idx=None):
    v = calib.std.get(key)
    if v is None:
        return None
    try:
        return float(v[idx]) if idx is not None else float(v)
    except (TypeError, IndexError, ValueError):
        return None


def summary_table(calib) -> Table:
    """Rich table: parameters ± std, RMS per device, and per pose the angles and the verdict."""
    t = Table(title=f"procam calibration ({calib.method})", show_lines=False)
    t.add_column("parameter")
    t.add_column("camera", justify="right")
    t.add_column("projector", justify="right")
    cK = calib.camera.K
    pK = calib.projector.K if calib.projector is not None else None

    def row(name, ckey, cval, pkey=None, pval=None, fmt=".2f"):
        t.add_row(name, _pm(cval, _std(calib, ckey), fmt) if cval is not None else "",
                  _pm(pval, _std(calib, pkey), fmt) if pval is not None else "")

    row("f (px)", "f_c", cK[0, 0], "f_p", None if pK is None else pK[0, 0])
    row("fy (px)", "fy_c", cK[1, 1], "fy_p", None if pK is None else pK[1, 1])
    row("u0 (px)", "u0c", cK[0, 2], "u0p", None if pK is None else pK[0, 2])
    row("v0 (px)", "v0c", cK[1, 2], "v0p", None if pK is None else pK[1, 2])
    d = calib.camera.distortion
    if d.model == "division":
        t.add_row("distortion", f"division c=({d.center[0]:.1f}, {d.center[1]:.1f})", "")
        row("k1 (px^-2)", "k1", d.k1, fmt=".4g")
        row("k2 (px^-4)", "k2", d.k2, fmt=".4g")
    elif d.model == "opencv":
        t.add_row("distortion", "opencv " + " ".join(f"{c:.4g}" for c in d.coeffs), "")
    if calib.projector is not None and calib.projector.distortion.model == "opencv":
        t.add_row("distortion", "", "opencv " + " ".join(f"{c:.4g}" for c in calib.projector.distortion.coeffs))
    t.add_row("RMS reprojection (px)", f"{calib.cam_rms:.3f}", "" if pK is None else f"{calib.proj_rms:.3f}")
    if calib.R is not None:
        from ..models import euler_deg

        eul = euler_deg(calib.R)
        for i, n in enumerate(("psi", "nu", "phi")):
            t.add_row(f"R {n} (deg)", _pm(eul[i], _std(calib, "R_euler_deg", i)), "")
        for i, n in enumerate("XYZ"):
            t.add_row(f"T {n}", _pm(float(calib.T[i]), _std(calib, "T", i)), "")
        t.add_row("|T| (baseline)", f"{np.linalg.norm(calib.T):.2f}", "")
        t.add_row("stereo RMS (px)", f"{calib.stereo_rms:.3f}", "")
    return t


def pose_verdict(adv: dict) -> str:
    """One line from an advice dict (single_pose.advice): the devices' messages."""
    if not adv:
        return ""
    parts = [adv[k]["message"] for k in ("camera", "projector") if isinstance(adv.get(k), dict) and adv[k].get("message")]
    return "; ".join(parts) or str(adv.get("message", ""))


def pose_table(calib) -> Table | None:
    if not calib.poses:
        return None
    t = Table(title="poses")
    for c in ("pose", "camera ψ, ν, φ (deg)", "projector ψ, ν, φ (deg)", "verdict"):
        t.add_column(c)
    for p in calib.poses:
        ca = p.get("camera_angles_deg")
        pa = p.get("projector_angles_deg")
        verdict = pose_verdict(p.get("advice") or {})
        t.add_row(Path(str(p.get("name", ""))).name, ", ".join(f"{a:.1f}" for a in ca) if ca else "",
                  ", ".join(f"{a:.1f}" for a in pa) if pa else "", str(verdict))
    return t


def print_summary(calib):
    console.print(summary_table(calib))
    pt = pose_table(calib)
    if pt is not None:
        console.print(pt)
    for w in calib.warnings:
        console.print(f"[yellow]warning:[/yellow] {w}", highlight=False)


@app.command("calibrate")
@user_errors
def calibrate_cmd(
    board: BoardOpt,
    square: SquareOpt,
    poses: list[Path] = typer.Argument(..., help="One pose folder (single-pose), several (multi-pose), or with "
                                               "--camera-only one image."),
    method: str = typer.Option(None, "--method", help="single or multi (default: single for one pose, multi for several)."),
    camera_only: bool = typer.Option(False, "--camera-only", help="Camera intrinsics from one photo of the board."),
    out: Path = typer.Option(..., "-o", "--out", help="Calibration JSON file."),
    yaml: Path = typer.Option(None, "--yaml", help="Also write OpenCV FileStorage YAML (cam_K, cam_kc, ...)."),
    png: Path = typer.Option(None, "--png", help="Residual plot."),
    cod: str = typer.Option("auto", "--cod", help="Single-pose principal point: auto (centre of distortion if "
                                                  "reliable, else fallback), paper (always the COD), center."),
    cam_dist: str = typer.Option("k1k2p1p2k3", "--cam-dist", help="Multi-pose camera distortion model."),
    proj_dist: str = typer.Option("k1k2p1p2k3", "--proj-dist", help="Multi-pose projector distortion model."),
    no_refine: bool = typer.Option(False, "--no-refine", help="Multi-pose: skip the joint refinement."),
    window: WindowOpt = 60,
    estimator: EstimatorOpt = "ransac",
    projector: ProjectorOpt = None,
    order: OrderOpt = None,
    step: StepOpt = None,
):
    """Calibrate a projector-camera pair (or, with --camera-only, a camera) and write JSON/YAML."""
    from ..plots import save_figure
    from ..plots.residuals import residual_figure
    from ..report import pose_residuals

    square = parse_square(square)
    cols, rows = parse_board(board)
    if cod not in ("auto", "paper", "center"):
        fail(f"--cod must be auto, paper or center, got {cod!r}")
    # everything that can be checked is checked before the (slow) decoding
    output_path(out, "-o", (".json", ".yml", ".yaml"))
    output_path(yaml, "--yaml", (".yml", ".yaml"))
    output_path(png, "--png", FIGURE_SUFFIXES)
    if camera_only:
        if yaml is not None or out.suffix.lower() in (".yml", ".yaml"):
            fail("a camera-only calibration has no projector, so no OpenCV procam YAML; write it as JSON (-o cam.json)")
        calib = _camera_only(poses, cols, rows, square, cod)
    else:
        if method is None:
            method = "single" if len(poses) == 1 else "multi"
        if method not in ("single", "multi"):
            fail(f"--method must be single or multi, got {method!r}")
        if method == "single" and len(poses) != 1:
            fail(f"--method single takes one pose folder, got {len(poses)}; use --method multi")
        if method == "multi":
            from ..multi_pose import DIST_MODELS

            if len(poses) < 2:
                fail("--method multi needs at least two pose folders (three or more recommended)")
            for opt, val in (("--cam-dist", cam_dist), ("--proj-dist", proj_dist)):
                if val not in DIST_MODELS:
                    fail(f"{opt} must be one of {', '.join(DIST_MODELS)}, got {val!r}")
        with console.status("decoding poses ...") if console.is_terminal else nullcontext():
            views = load_views(poses, cols, rows, square, optional_size(projector), order, estimator, window,
                               step=step)
        for v in views:
            console.print(f"{v.name}: {int(v.valid.sum())} of {len(v.valid)} corners")
            for w in v.diagnostics.get("warnings", []):
                console.print(f"[yellow]warning:[/yellow] {w}", highlight=False)
        if method == "single":
            from .. import single_pose

            calib = single_pose.calibrate(views[0], cod=cod)
        else:
            from .. import multi_pose

            calib = multi_pose.calibrate(views, cam_dist=cam_dist, proj_dist=proj_dist, refine=not no_refine)
    print_summary(calib)
    io.save_calibration(calib, out)
    console.print(f"wrote {out}")
    if yaml is not None:
        io.save_opencv_yaml(calib, yaml)
        console.print(f"wrote {yaml}")
    if png is not None:
        fig = residual_figure(pose_residuals(calib, calib.views), calib.camera.image_size,
                              calib.projector.image_size if calib.projector is not None else None,
                              title=f"{out.name}: {calib.method}")
        save_figure(fig, png)
        console.print(f"wrote {png}")


def _camera_only(images, cols, rows, square, cod):
    from .. import board as _board
    from .. import single_pose
    from ..view import View

    if len(images) != 1:
        fail(f"--camera-only takes one image, got {len(images)}")
    path = images[0]
    img = io.read_image(path)
    c, hint = _board.find_corners([img], (cols, rows))
    if hint is not None:
        raise BoardNotFoundError(f"{path}: chessboard with {cols}x{rows} inner corners not found; "
                                 f"{_board.size_hint_text((cols, rows), hint)}")
    if c is None:
        raise BoardNotFoundError(f"{path}: chessboard with {cols}x{rows} inner corners not found; check --board "
                                 f"(inner corners, not squares: {cols + 1}x{rows + 1} squares have {cols}x{rows} "
                                 "inner corners), the exposure, and that the whole board is in view")
    obj = _board.object_points(cols, rows, square)
    h, w = img.shape[:2]
    calib = single_pose.calibrate_camera_only(obj, c, (w, h), name=str(path), cod=cod)
    view = View(obj, c, np.full_like(c, np.nan), str(path), (w, h), None)
    return calib.replace(views=(view,))
