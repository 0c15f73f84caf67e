"""The frame vocabulary: what each frame of a Gray-code sequence shows, in the words every message uses.

A sequence (:class:`procam.patterns.PatternSet`) is pattern/inverse pairs of column bits and of row bits,
plus a white and a black frame, in the order ``ps.order`` puts them.  Bit numbers count from the least
significant, 0: ``'column bit 9'`` is the coarsest column stripe of a 1024-pixel-wide projector.
"""

from __future__ import annotations

from .. import patterns


def _find(k: int, ps: patterns.PatternSet):
    """``(axis name, bit, inverse?, partner)`` of pattern frame ``k``, or None (white, black, not in the sequence)."""
    for axis, name in (("col", "column"), ("row", "row")):
        pairs = ps.pair_indices(axis)
        for j, (a, b) in enumerate(pairs):
            if k in (a, b):
                return name, len(pairs) - 1 - j, k == b, int(b if k == a else a)
    return None


def frame_role(k: int, ps: patterns.PatternSet) -> str:
    """What sequence frame ``k`` shows: ``'white'``, ``'black'``, ``'column bit 3'``, ``'row bit 0 inverse'``
    (bit numbers count from the least significant, 0), or ``'not in the sequence'``."""
    k = int(k)
    if k == ps.white:
        return "white"
    if k == ps.black:
        return "black"
    found = _find(k, ps)
    if found is None:
        return "not in the sequence"
    name, bit, inverse, _ = found
    return f"{name} bit {bit}{' inverse' if inverse else ''}"


def describe_frame(key, ps: patterns.PatternSet) -> str:
    """``'#12 (column bit 3)'``-style label of sequence frame ``key``; a text ``key`` (a frame shown outside the
    sequence, e.g. ``'pre-flight white'``) is returned as it is."""
    if isinstance(key, str):
        return key
    return f"#{int(key)} ({frame_role(key, ps)})"


def pair_role(k: int, ps: patterns.PatternSet) -> tuple[str | None, int | None]:
    """``('first', inverse)`` for a pattern, ``('inverse', pattern)`` for its inverse (the partner's index),
    ``(None, None)`` for the white and black frames."""
    found = _find(int(k), ps)
    if found is None:
        return None, None
    return ("inverse" if found[2] else "first"), found[3]
