"""``procam patterns``: write a Gray-code sequence as PNGs."""

from __future__ import annotations

from pathlib import Path

import typer

from ..errors import OutputError
from ._app import ForceOpt, Order, app, fail, parse_size, say, user_errors, value

#: The largest projector ``procam patterns`` writes a sequence for (pixels): 16K x 8K.
MAX_PIXELS = 16384 * 8640


@app.command("patterns")
@user_errors
def patterns_cmd(
    projector: str = typer.Option(..., "--projector", "-p", help="Projector size WIDTHxHEIGHT, e.g. 1920x1080."),
    out: Path = typer.Option(..., "-o", "--out", help="Output folder (created if missing; must be new, empty or "
                                                     "an earlier 'procam patterns' output)."),
    order: Order = typer.Option(Order.opencv, "--order", help="Sequence order."),
    step: int = typer.Option(1, "--step", min=1, max=64,
                             help="Projector pixels per code (>1 against moire, as kamino410's graycode_step)."),
    force: ForceOpt = False,
):
    """Write the Gray-code sequence for a projector as zero-padded PNGs plus patterns.json."""
    from .. import capture
    from .. import patterns as pat

    w, h = parse_size(projector, "--projector", hi=16384)
    if w * h > MAX_PIXELS:
        fail(f"--projector {projector}: {w * h / 1e6:.0f} Mpx is larger than any projector (16384x8640); give the "
             "projector's native resolution")
    order = value(order)
    try:
        ps = pat.pattern_set(w, h, order, step)
    except ValueError as e:
        fail(f"--step {step}: {e}; use a smaller --step")
    try:
        capture.check_sequence_dir(out, ps, "pattern_", writer="patterns", force=force, option="-o")
    except OutputError as e:
        fail(str(e))
    paths = capture.write_sequence(out, pat.frames(ps), ps, prefix="pattern_", writer="patterns", force=force)
    say(f"wrote {len(paths)} images ({ps.col_bits} column bits, {ps.row_bits} row bits, "
        f"order {order}; white = #{ps.white}, black = #{ps.black}) and patterns.json to {out}")
