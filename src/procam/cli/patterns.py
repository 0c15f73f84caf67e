"""``procam patterns``: write a Gray-code sequence as PNGs."""

from __future__ import annotations

from pathlib import Path

import typer

from ._app import Order, app, parse_size, say, user_errors, value


@app.command("patterns")
@user_errors
def patterns_cmd(
    projector: str = typer.Option(..., "--projector", "-p", help="Projector size WIDTHxHEIGHT, e.g. 1920x1080."),
    out: Path = typer.Option(..., "-o", "--out", help="Output folder (created if missing)."),
    order: Order = typer.Option(Order.opencv, "--order", help="Sequence order."),
    step: int = typer.Option(1, "--step", min=1, max=64,
                             help="Projector pixels per code (>1 against moire, as kamino410's graycode_step)."),
):
    """Write the Gray-code sequence for a projector as zero-padded PNGs plus patterns.json."""
    from .. import capture
    from .. import patterns as pat

    w, h = parse_size(projector, "--projector")
    order = value(order)
    ps = pat.pattern_set(w, h, order, step)
    paths = capture.write_sequence(out, pat.generate(w, h, order, step=step), ps, prefix="pattern_")
    say(f"wrote {len(paths)} images ({ps.col_bits} column bits, {ps.row_bits} row bits, "
        f"order {order}; white = #{ps.white}, black = #{ps.black}) and patterns.json to {out}")
