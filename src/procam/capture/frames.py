"""The frame vocabulary: what each frame of a Gray-code sequence shows, in the words every message uses.

A sequence (:class:`procam.patterns.PatternSet`) is pattern/inverse pairs of column bits and of row bits,
plus a white and a black frame, in the order ``ps.order`` puts them.  Bit numbers count from the least
significant, 0: ``'column bit 9'`` is the coarsest column stripe of a 1024-pixel-wide projector.
"""

from __future__ import annotations

from .. import patterns


def frame_role(k: int, ps: patterns.PatternSet) -> str:
    """What sequence frame ``k`` shows: ``'white'``, ``'black'``, ``'column bit 3'``, ``'row bit 0 inverse'``
    (bit numbers count from the least significant, 0)."""
    k = int(k)
    if k == ps.white:
        return "white"
    if k == ps.black:
        return "black"
    for axis, name in (("col", "column"), ("row", "row")):
        pairs = ps.pair_indices(axis)
        for j, (a, b) in enumerate(pairs):
            if k in (a, b):
                return f"{name} bit {len(pairs) - 1 - j}{' inverse' if k == b else ''}"
    return "not in the sequence"


def describe_frame(k: int, ps: patterns.PatternSet) -> str:
    """``'#12 (column bit 3)'``-style label of sequence frame ``k``."""
    return f"#{int(k)} ({frame_role(k, ps)})"
