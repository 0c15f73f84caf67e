"""The frame vocabulary: what each frame of a sequence shows, in the words every message uses.

A Gray-code sequence (:class:`procam.patterns.PatternSet`) is pattern/inverse pairs of column bits and of row
bits, plus a white and a black frame, in the order ``ps.order`` puts them.  Bit numbers count from the least
significant, 0: ``'column bit 9'`` is the coarsest column stripe of a 1024-pixel-wide projector.

A phase-family sequence (:class:`procam.patterns.PhaseSet`) has fringes, ``'column phase 2 of 4, period 32 px'``
(steps counted from 1, the frame that adds ``2 pi (k - 1) / N``), Gray bits ordering the fringe periods,
``'row Gray bit 3 inverse'``, ``'column complementary Gray bit'``, and the white and black frames if it has them.
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
    (bit numbers count from the least significant, 0), a phase family's ``'column phase 2 of 4, period 32 px'``,
    ``'row Gray bit 3 inverse'``, or ``'not in the sequence'``."""
    k = int(k)
    if patterns.is_phase(ps):
        return ps.role(k)
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
    ``(None, None)`` for the white and black frames (and a phase family's fringes and Gray bits without inverses)."""
    if patterns.is_phase(ps):
        for a, b in (p for axis in ("col", "row") for p in ps.pair_indices(axis)):
            if int(k) in (a, b):
                return ("inverse", int(a)) if int(k) == b else ("first", int(b))
        return None, None
    found = _find(int(k), ps)
    if found is None:
        return None, None
    return ("inverse" if found[2] else "first"), found[3]
