"""``procam patterns``: write a Gray-code sequence as PNGs."""

from __future__ import annotations

from pathlib import Path

import typer

from .. import capture, patterns as pat
from ._app import app, console, fail, parse_size, user_errors


@app.command("patterns")
@user_errors
def patterns_cmd(
    projector: str = typer.Option(..., "--projector", "-p", help="Projector size WIDTHxHEIGHT, e.g. 1920x1080."),
    out: Path = typer.Option(..., "-o", "--out", help="Output folder (created if missing)."),
    order: str = typer.Option("opencv", "--order", help="Sequence order: opencv (default) or moreno."),
    step: int = typer.Option(1, "--step", help="Projector pixels per code (>1 against moire, as kamino410's "
                                               "graycode_step)."),
):
    """Write the Gray-code sequence for a projector as zero-padded PNGs plus patterns.json."""
    w, h = parse_size(projector, "--projector")
    if order not in pat.ORDERS:
        fail(f"--order must be one of {', '.join(pat.ORDERS)}, got {order!r}")
    if step < 1:
        fail(f"--step must be a positive integer, got {step}")
    ps = pat.pattern_set(w, h, order, step)
    paths = capture.write_sequence(out, pat.generate(w, h, order, step=step), ps, prefix="pattern_")
    console.print(f"wrote {len(paths)} images ({ps.col_bits} column bits, {ps.row_bits} row bits, "
                  f"order {order}; white = #{ps.white}, black = #{ps.black}) and patterns.json to {out}")
