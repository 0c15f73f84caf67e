"""``procam decode``: captured Gray-code sequence -> per-pixel projector coordinates."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import typer

from .. import _files, capture, decode as dec
from ..patterns import ORDERS
from ._app import (FIGURE_SUFFIXES, OrderOpt, ProjectorOpt, StepOpt, app, console, fail, optional_size,
    output_path, user_errors)


@app.command("decode")
@user_errors
def decode_cmd(
    pose_dir: Path = typer.Argument(..., help="Folder with one pose's captured sequence."),
    projector: ProjectorOpt = None,
    order: OrderOpt = None,
    step: StepOpt = None,
    method: str = typer.Option("robust", "--method", help="Bit classifier: robust (direct/global) or simple."),
    shadow: float = typer.Option(10.0, "--shadow-threshold", help="Min white-black, 8-bit DN (scaled for 16-bit)."),
    contrast: float = typer.Option(3.0, "--contrast-threshold", help="Min |pattern-inverse| per bit, 8-bit DN."),
    out: Path = typer.Option(None, "-o", "--out", help="Write the maps to this .npz file."),
    png: Path = typer.Option(None, "--png", help="Write a colour-coded picture of the maps."),
):
    """Decode a pose: projector column and row per camera pixel, validity and reasons."""
    size = optional_size(projector)
    if order is not None and order not in ORDERS:
        fail(f"--order must be one of {', '.join(ORDERS)}, got {order!r}")
    if out is not None and out.suffix != ".npz":
        out = out.with_suffix(".npz")
    output_path(out, "-o", (".npz",))
    output_path(png, "--png", FIGURE_SUFFIXES)
    if method not in ("robust", "simple"):
        fail(f"--method must be robust or simple, got {method!r}")
    cap = capture.load_capture(pose_dir, size, order, step=step)
    for w in cap.warnings:
        console.print(f"[yellow]warning:[/yellow] {w}", highlight=False)
    res = dec.decode(cap.stack, cap.pattern_set, method, shadow_threshold=shadow, contrast_threshold=contrast)
    ps = cap.pattern_set
    h, w = res.col.shape
    console.print(f"{pose_dir}: {len(cap.files)} images {w}x{h} ({cap.stack.dtype}), projector "
                  f"{ps.width}x{ps.height}, order {ps.order}, {method} classifier")
    console.print(f"decoded: columns {res.valid_col.mean() * 100:.1f} %, rows {res.valid_row.mean() * 100:.1f} %, "
                  f"both {res.valid.mean() * 100:.1f} % of {w * h} pixels")
    for axis, counts in res.reason_counts().items():
        for text, n in counts.items():
            if not text.startswith("decoded"):
                console.print(f"  {axis}: {n} px {text}", highlight=False)
    if out is not None:
        with _files.atomic_path(out) as tmp:
            with open(tmp, "wb") as f:
                np.savez_compressed(f, col=res.col, row=res.row, valid_col=res.valid_col,
                                    valid_row=res.valid_row, reason_col=res.reason_col,
                                    reason_row=res.reason_row, confidence=res.confidence,
                                    dropped_col=res.dropped_col, dropped_row=res.dropped_row,
                                    projector_size=np.array([ps.width, ps.height]), order=np.array(ps.order))
        console.print(f"wrote {out}")
    if png is not None:
        from ..plots import save_figure
        from ..plots.decode import decode_figure

        save_figure(decode_figure(res, cap.white, title=str(pose_dir)), png)
        console.print(f"wrote {png}")
