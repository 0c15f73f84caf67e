"""``procam patterns``: write a pattern sequence (Gray codes or a phase family) as PNGs."""

from __future__ import annotations

from pathlib import Path

import typer

from ..errors import OutputError
from ._app import app, fail, say, user_errors
from ._options import (ComplementaryOpt, CountsOpt, Family, FamilyOpt, ForceOpt, InverseOpt, Order, PeriodOpt,
                       StepsOpt, WhiteBlackOpt, parse_size, pattern_sequence, value)

#: The largest projector ``procam patterns`` writes a sequence for (pixels): 16K x 8K.
MAX_PIXELS = 16384 * 8640


@app.command("patterns")
@user_errors
def patterns_cmd(
    projector: str = typer.Option(..., "--projector", "-p", help="Projector size WIDTHxHEIGHT, e.g. 1920x1080."),
    out: Path = typer.Option(..., "-o", "--out", help="Output folder (created if missing; must be new, empty or "
                                                     "an earlier 'procam patterns' output)."),
    order: Order = typer.Option(Order.opencv, "--order", help="Gray family: sequence order."),
    step: int = typer.Option(1, "--step", min=1, max=64,
                             help="Gray family: projector pixels per code (>1 against moire, as kamino410's "
                                  "graycode_step)."),
    family: FamilyOpt = Family.gray,
    steps: StepsOpt = None,
    period: PeriodOpt = None,
    counts: CountsOpt = None,
    inverse: InverseOpt = True,
    complementary: ComplementaryOpt = True,
    white_black: WhiteBlackOpt = True,
    force: ForceOpt = False,
):
    """Write a pattern sequence for a projector as zero-padded PNGs plus patterns.json (Gray codes by default; a
    phase family with --family, docs/patterns.md)."""
    from .. import capture
    from .. import patterns as pat

    w, h = parse_size(projector, "--projector", hi=16384)
    if w * h > MAX_PIXELS:
        fail(f"--projector {projector}: {w * h / 1e6:.0f} Mpx is larger than any projector (16384x8640); give the "
             "projector's native resolution")
    order = value(order)
    ps = pattern_sequence((w, h), family=family, order=order, step=step, steps=steps, period=period, counts=counts,
                          inverse=inverse, complementary=complementary, white_black=white_black)
    try:
        capture.check_sequence_dir(out, ps, "pattern_", writer="patterns", force=force, option="-o")
    except OutputError as e:
        fail(str(e))
    paths = capture.write_sequence(out, pat.frames(ps), ps, prefix="pattern_", writer="patterns", force=force)
    if pat.is_phase(ps):
        say(f"wrote {len(paths)} images ({ps.describe()}) and patterns.json to {out}")
        return
    say(f"wrote {len(paths)} images ({ps.col_bits} column bits, {ps.row_bits} row bits, "
        f"order {order}; white = #{ps.white}, black = #{ps.black}) and patterns.json to {out}")
