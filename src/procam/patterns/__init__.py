"""Pattern sequences for a projector: what each frame shows (no pixels until asked), in four families
(``docs/patterns.md``):

``gray`` (:mod:`~procam.patterns.gray`)
    Gray codes with inverses, a white and a black frame, in OpenCV's or Moreno-Taubin's order
    (:class:`PatternSet`, :func:`pattern_set`): one integer projector pixel per camera pixel.
``phase``, ``heterodyne``, ``gray-phase`` (:mod:`~procam.patterns.phase`)
    N-step sinusoidal fringes along the columns and the rows, unwrapped by a unit-frequency cue, by
    three-frequency heterodyne, or by a Gray code (with or without inverses, optionally complementary)
    (:class:`PhaseSet`, :func:`phase_set`): a sub-pixel projector coordinate per camera pixel.

:func:`from_dict` reads a ``patterns.json`` (procam's own, or a hand-written description of another tool's
capture, :mod:`~procam.patterns.describe`); :func:`frames` and :func:`generate` draw any sequence.
"""

from __future__ import annotations

import numpy as np

from ..choices import PATTERN_FAMILIES
from . import gray as _gray
from . import phase as _phase
from .describe import family_of, from_dict
from .gray import ORDERS, PatternSet, bit_planes, bits_for, gray_decode, gray_encode
from .phase import Block, Fringe, PhaseSet, phase_set

__all__ = ["ORDERS", "FAMILIES", "PatternSet", "PhaseSet", "Block", "Fringe", "pattern_set", "phase_set",
           "frames", "generate", "from_dict", "family_of", "gray_encode", "gray_decode", "bits_for", "bit_planes",
           "is_phase"]

#: The pattern families (:data:`procam.choices.PATTERN_FAMILIES`).
FAMILIES = PATTERN_FAMILIES


def is_phase(ps) -> bool:
    """True for a sequence of a phase family (:class:`PhaseSet`), False for a Gray-code :class:`PatternSet`."""
    return isinstance(ps, PhaseSet)


def pattern_set(width: int, height: int, order: str = "opencv", step: int = 1, *, family: str = "gray",
                **phase) -> PatternSet | PhaseSet:
    """Describe procam's sequence for a ``width`` x ``height`` projector.

    ``family="gray"`` (default): the Gray-code sequence in ``order`` with ``step`` px per code, its bits in
    ``bit_order`` (keyword, default ``"msb-first"``; :func:`procam.patterns.gray.pattern_set`).  Any other family:
    :func:`phase_set` with the keywords ``phase`` (``steps``, ``period``, ``periods``, ``inverse``,
    ``complementary``, ``white_black``, ``fringe``, ``bit_order``).
    """
    if family == "gray":
        bit_order = phase.pop("bit_order", "msb-first")
        if phase:
            raise ValueError(f"the Gray family takes no {', '.join(sorted(phase))}")
        return _gray.pattern_set(width, height, order, step, bit_order)
    if family not in FAMILIES:
        raise ValueError(f"family must be one of {', '.join(FAMILIES)}, got {family!r}")
    if step != 1:
        raise ValueError(f"step applies to the Gray family only, got step {step} for family {family!r}")
    return phase_set(width, height, family, **phase)


def frames(ps, white: int = 255, black: int = 0, dtype=np.uint8):
    """The frames of the sequence ``ps`` one (height, width) image at a time, in order (the images of
    :func:`generate` without holding them all in memory).  ``white`` / ``black`` are the Gray family's levels."""
    if isinstance(ps, PhaseSet):
        if (white, black) != (255, 0):
            raise ValueError("a phase sequence's levels are its fringes' (Fringe.levels), not white/black")
        return _phase.frames(ps, dtype)
    return _gray.frames(ps, white, black, dtype)


def generate(width: int, height: int, order: str = "opencv", white: int = 255, black: int = 0, dtype=np.uint8,
             step: int = 1, *, family: str = "gray", **phase) -> np.ndarray:
    """The full sequence as an array ``(count, height, width)`` of ``dtype`` (see :func:`pattern_set`).

    Nothing is written to disk; see :func:`procam.capture.write_sequence`.
    """
    if family == "gray":
        return _gray.generate(width, height, order, white, black, dtype, step)
    ps = pattern_set(width, height, order, step, family=family, **phase)
    out = np.empty((ps.count, ps.height, ps.width), dtype=dtype)
    for k, img in enumerate(_phase.frames(ps, dtype)):
        out[k] = img
    return out
