"""``procam patterns``: write a pattern sequence (Gray codes or a phase family) as PNGs."""

from __future__ import annotations

from pathlib import Path

import typer

from ..errors import OutputError
from ._app import app, fail, say, user_errors
from ._options import ForceOpt, parse_size, pattern_sequence, value, with_pattern_options

#: The largest projector ``procam patterns`` writes a sequence for (pixels): 16K x 8K.
MAX_PIXELS = 16384 * 8640


@app.command("patterns")
@user_errors
@with_pattern_options()
def patterns_cmd(
    projector: str = typer.Option(..., "--projector", "-p", help="Projector size WIDTHxHEIGHT, e.g. 1920x1080."),
    out: Path = typer.Option(..., "-o", "--out", help="Output folder (created if missing; must be new, empty or "
                                                     "an earlier 'procam patterns' output)."),
    force: ForceOpt = False,
    **pattern_args,
):
    """Write a pattern sequence for a projector as zero-padded PNGs plus patterns.json (Gray codes by default; a
    phase family with --family, docs/patterns.md)."""
    from .. import capture
    from .. import patterns as pat

    w, h = parse_size(projector, "--projector", hi=16384)
    if w * h > MAX_PIXELS:
        fail(f"--projector {projector}: {w * h / 1e6:.0f} Mpx is larger than any projector (16384x8640); give the "
             "projector's native resolution")
    order = value(pattern_args["order"])
    ps = pattern_sequence((w, h), **pattern_args)
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
