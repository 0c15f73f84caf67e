"""``procam decode``: a captured sequence (Gray codes or a phase family) -> per-pixel projector coordinates."""

from __future__ import annotations

from pathlib import Path

import typer

from ._app import app, fail, keep_freed_memory, say, user_errors, warn
from ._options import (
    ContrastOpt,
    DecodeMethod,
    DecodeOpt,
    OrderOpt,
    ProjectorOpt,
    ShadowOpt,
    StepOpt,
    decode_options,
    number,
    optional_size,
    value,
)
from ._paths import FIGURE_SUFFIXES, output_path


@app.command("decode")
@user_errors
def decode_cmd(
    pose_dir: Path = typer.Argument(..., help="Folder with one pose's captured sequence."),
    out: Path = typer.Option(None, "-o", "--out", help="Write the maps to this .npz file."),
    png: Path = typer.Option(None, "--png", help="Write a colour-coded picture of the maps."),
    projector: ProjectorOpt = None,
    order: OrderOpt = None,
    step: StepOpt = None,
    decode_method: DecodeOpt = DecodeMethod.robust,
    shadow: ShadowOpt = 10.0,
    contrast: ContrastOpt = 3.0,
    gamma: str = typer.Option("auto", "--gamma", help="Phase families: the projector's gamma: auto (measure it from "
                              "the frames and correct the phases), none (assume a linear projector; warns when it is "
                              "not) or its value, e.g. 2.2."),
    camera_noise: float = typer.Option(None, "--camera-noise", help="Phase families: the camera's noise sigma in "
                                       "8-bit grey levels (default: measured from the frames)."),
):
    """Decode a pose: projector column and row per camera pixel, validity and reasons (and for the phase families
    each coordinate's noise, the projector's gamma and the camera's noise)."""
    import dataclasses

    from .. import capture
    from .. import decode as dec
    from ..io import save_decoded_maps

    keep_freed_memory()
    size = optional_size(projector)
    opts = decode_options(decode_method=decode_method, shadow=shadow, contrast=contrast, poses=[pose_dir])
    if gamma not in ("auto", "none"):
        try:
            gamma = float(gamma)
        except ValueError:
            fail(f"--gamma must be auto, none or a number from 0.2 to 5, got {gamma!r}")
        number(gamma, "--gamma", lo=0.2, hi=5, what="auto, none or a projector gamma")
    number(camera_noise, "--camera-noise", lo=0, hi=100, lo_open=True, unit=" DN", what="a noise sigma")
    opts = dataclasses.replace(opts, gamma=gamma, camera_noise=camera_noise)
    if out is not None and not out.suffix and not out.is_dir():  # -o maps: maps.npz (any other suffix is refused)
        out = out.with_suffix(".npz")
    output_path(out, "-o", (".npz",), inputs=(pose_dir,))
    output_path(png, "--png", FIGURE_SUFFIXES, inputs=(pose_dir,))
    from . import take_reader

    reader = take_reader([pose_dir])  # the folder's images, read from before the command line was parsed
    try:
        cap = capture.load_capture(pose_dir, size, value(order), step=step,
                                   reader=None if reader is None else reader.read)
    finally:
        if reader is not None:
            reader.close()
    for w in cap.warnings:
        warn(w)
    res = dec.decode_with(cap.stack, cap.pattern_set, opts)
    ps = cap.pattern_set
    h, w = res.col.shape
    what = f"order {ps.order}, {opts.method} classifier" if not res.subpixel else ps.describe()
    say(f"{pose_dir}: {len(cap.files)} images {w}x{h} ({cap.stack.dtype}), projector "
        f"{ps.width}x{ps.height}, {what}")
    say(f"decoded: columns {res.valid_col.mean() * 100:.1f} %, rows {res.valid_row.mean() * 100:.1f} %, "
        f"both {res.valid.mean() * 100:.1f} % of {w * h} pixels")
    for axis, counts in res.reason_counts().items():
        for text, n in counts.items():
            if not text.startswith("decoded"):
                say(f"  {axis}: {n} px {text}")
    if res.subpixel:
        from ..decode.phase import summary_lines

        for line in summary_lines(res):
            say(line)
        for line in res.phase.warnings:
            warn(line)
    if out is not None:
        save_decoded_maps(out, res, source=cap.fingerprint)
        say(f"wrote {out}")
    if png is not None:
        from ..plots import save_figure
        from ..plots.decode import decode_figure

        save_figure(decode_figure(res, cap.white, title=str(pose_dir)), png)
        say(f"wrote {png}")
