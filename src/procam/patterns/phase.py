"""Phase-shift sequences: N-step sinusoidal fringes along the projector's columns and rows, unwrapped by a
coarser frequency, by three-frequency heterodyne or by a Gray code (the families of ``docs/patterns.md``).

A sequence is a list of **blocks** in frame order (:class:`Block`): a phase block of ``N >= 3`` frames (one
fringe period ``P`` in projector pixels, shifted by ``2 pi / N`` from frame to frame), a Gray-code block (the
order of the fringe period, most significant bit first, each bit optionally followed by its inverse, optionally
one complementary bit), a white or a black frame.  :class:`PhaseSet` holds the blocks of one sequence and says
what each frame is; :func:`phase_set` makes procam's own sequences, :func:`procam.patterns.describe.from_dict`
reads a description another tool's capture comes with.

Conventions (:class:`Fringe`; the figure in ``docs/patterns.md``)
    Projector pixel ``i`` is centred at coordinate ``i`` (procam's convention everywhere).  Frame ``k`` of a
    phase block shows, at pixel ``i``, ``lo + (hi - lo) * ((1 + cos t) / 2) ** (1 / gamma)`` rounded to an
    integer, with ``t = 2 pi sign (i + pixel_center - origin) / P + start + shift 2 pi k / N``.  The phase is
    therefore 0 at projector coordinate ``x0 = origin - pixel_center`` and grows with the coordinate when
    ``sign = +1``.  procam's own sequences: ``sign = +1``, ``origin = -0.5``, ``pixel_center = 0`` (phase 0 on
    the left / top edge of pixel 0, so that fringe period ``m`` covers pixels ``m P .. (m + 1) P - 1`` when ``P``
    is a whole number, the pixels Gray-code stripe ``m`` covers), ``shift = +1``, ``start = 0``, levels
    ``(0, 255)``, ``gamma = 1`` (not pre-corrected).
Gray blocks
    Frame ``b`` (most significant first) is white (255) where bit ``bits - 1 - b`` of ``gray(m)`` is 1, black (0)
    elsewhere (bit ``b`` when the block's ``bit_order`` is ``"lsb-first"``), with ``m = floor((x - x0) / P)`` the fringe period of the axis's phase block (``x0`` and ``P``
    are that block's); the complementary bit is the least significant bit of ``gray(floor(2 (x - x0) / P))``,
    whose stripes change in the middle of the fringe periods.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..choices import PATTERN_FAMILIES
from ..io.formats import PATTERNS_FORMAT
from .gray import BIT_ORDERS, bits_for, gray_encode

#: Block kinds of a sequence.
KINDS = ("phase", "gray", "white", "black")
AXES = ("col", "row")
#: The phase families (every family but ``gray``).
PHASE_FAMILIES = tuple(f for f in PATTERN_FAMILIES if f != "gray")
#: procam's own sequences' defaults (measured in ``benchmarks/phase.py`` at the paper's rig): fringe periods
#: (projector pixels, finest first; ``phase`` adds the unit-frequency cue above them), steps, and the heterodyne's
#: counts of periods across the panel.  Chosen so that the dim wall behind the board decodes (the single-pose dense
#: fit needs it): the cue's noise times the ratio of the periods must stay below a tenth of a period, so ``phase``
#: has a middle level (16 and 128 px under the cue; 64 px under the cue alone left the wall undecoded) and 8 steps,
#: and the heterodyne 8 steps (with 4 its beats' noise left the wall undecoded).
DEFAULT_PERIODS = {"phase": (16.0, 128.0), "gray-phase": (16.0,)}
DEFAULT_STEPS = {"phase": 8, "heterodyne": 8, "gray-phase": 4}
DEFAULT_HETERODYNE_COUNTS = (70, 64, 59)


@dataclass(frozen=True)
class Fringe:
    """How a phase block's frames are drawn (the conventions of the module docstring).

    sign : +1 or -1, the phase grows (+1) or falls with the projector coordinate.
    origin : where the phase is 0, in the description's coordinate of the projector (pixel ``i`` is at
        ``i + pixel_center``).
    pixel_center : 0 (pixel ``i`` centred at ``i``, procam) or 0.5 (pixel ``i`` spans ``[i, i + 1]``).
    shift : +1 or -1, frame ``k`` adds ``shift * 2 pi k / N`` to the phase.
    start : phase added to every frame of the block, radians (``-pi / 2`` turns the cosine into a sine).
    levels : (lo, hi) pattern values at the fringes' trough and crest, 0-255.
    gamma : the patterns are pre-corrected for a projector of this gamma (1 = not pre-corrected).
    """

    sign: int = 1
    origin: float = -0.5
    pixel_center: float = 0.0
    shift: int = 1
    start: float = 0.0
    levels: tuple = (0.0, 255.0)
    gamma: float = 1.0

    def __post_init__(self):
        if self.sign not in (1, -1):
            raise ValueError(f"sign must be +1 or -1, got {self.sign!r}")
        if self.shift not in (1, -1):
            raise ValueError(f"shift must be +1 or -1, got {self.shift!r}")
        if self.pixel_center not in (0, 0.5):
            raise ValueError(f"pixel_center must be 0 or 0.5, got {self.pixel_center!r}")
        for what, v in (("origin", self.origin), ("start", self.start), ("gamma", self.gamma)):
            if not (isinstance(v, (int, float)) and math.isfinite(v)):
                raise ValueError(f"{what} must be a finite number, got {v!r}")
        if not 0.2 <= self.gamma <= 5:
            raise ValueError(f"gamma must be from 0.2 to 5, got {self.gamma!r}")
        lo, hi = (float(v) for v in self.levels)
        if not (0 <= lo < hi <= 255):
            raise ValueError(f"levels must be (lo, hi) with 0 <= lo < hi <= 255, got {self.levels!r}")
        object.__setattr__(self, "levels", (lo, hi))

    @property
    def x0(self) -> float:
        """Projector coordinate (pixel ``i`` centred at ``i``) where the phase is 0."""
        return float(self.origin) - float(self.pixel_center)

    def shape(self, t) -> np.ndarray:
        """Pattern value, as a fraction of 255, at phase ``t`` (radians): ``(lo + (hi - lo) s ** (1/gamma)) / 255``
        with ``s = (1 + cos t) / 2``."""
        lo, hi = self.levels
        s = 0.5 + 0.5 * np.cos(t)
        return (lo + (hi - lo) * s ** (1.0 / self.gamma)) / 255.0

    def to_dict(self) -> dict:
        return {"sign": self.sign, "origin": self.origin, "pixel_center": self.pixel_center, "shift": self.shift,
                "start": self.start, "levels": list(self.levels), "gamma": self.gamma}


@dataclass(frozen=True)
class Block:
    """A run of frames of one kind (see the module docstring).

    kind : ``"phase"``, ``"gray"``, ``"white"`` or ``"black"``.
    axis : ``"col"`` (the pattern varies along the projector's x) or ``"row"``; None for white and black.
    first : index of the block's first frame in the sequence.
    steps : phase: the number of phase shifts ``N``.
    period : phase: the fringe period in projector pixels; gray: the period of the phase block it orders.
    bits : gray: the number of ordinary bits.
    inverse : gray: every bit is followed by its inverse.
    complementary : gray: one more bit (stripes half a period wide, changing mid-period) after the others.
    fringe : phase: the conventions (:class:`Fringe`); gray: those of the phase block it orders.
    bit_order : gray: ``"msb-first"`` (default) or ``"lsb-first"``, the order of the ordinary bits in the frames
        (the complementary bit comes last either way).
    """

    kind: str
    axis: str | None = None
    first: int = 0
    steps: int = 0
    period: float = 0.0
    bits: int = 0
    inverse: bool = True
    complementary: bool = False
    fringe: Fringe = field(default_factory=Fringe)
    bit_order: str = "msb-first"

    @property
    def count(self) -> int:
        """Number of frames of the block."""
        if self.kind == "phase":
            return self.steps
        if self.kind == "gray":
            return (self.bits + int(self.complementary)) * (2 if self.inverse else 1)
        return 1

    @property
    def frames(self) -> range:
        return range(self.first, self.first + self.count)

    def shifts(self) -> np.ndarray:
        """Phase block: (N,) the phase each frame adds, ``start + shift 2 pi k / N`` (radians)."""
        f = self.fringe
        return f.start + f.shift * 2.0 * np.pi * np.arange(self.steps) / self.steps

    def gray_frame(self, j: int) -> tuple[int, bool, bool]:
        """Gray block: frame ``j`` of the block as ``(bit, inverse, complementary)``; ``bit`` counts from the
        least significant ordinary bit, 0 (the complementary bit is reported as bit -1)."""
        per = 2 if self.inverse else 1
        b, inv = divmod(j, per)
        if b == self.bits:
            return -1, bool(inv), True
        return (self.bits - 1 - b if self.bit_order == "msb-first" else b), bool(inv), False

    def to_dict(self) -> dict:
        d = {"kind": self.kind}
        if self.axis is not None:
            d["axis"] = self.axis
        if self.kind == "phase":
            d.update(steps=self.steps, period=self.period, **self.fringe.to_dict())
        elif self.kind == "gray":
            d.update(bits=self.bits, inverse=self.inverse, complementary=self.complementary, period=self.period)
            if self.bit_order != "msb-first":
                d["bit_order"] = self.bit_order
        return d


@dataclass(frozen=True)
class PhaseSet:
    """A phase-family sequence (no pixels): its projector size, family and blocks in frame order.

    Attributes
    ----------
    width, height : projector size in pixels.
    family : ``"phase"`` (fringes unwrapped by coarser ones, the coarsest one period or more across the panel:
        the two-frequency scheme with a unit-frequency cue), ``"heterodyne"`` (three frequencies), or
        ``"gray-phase"`` (a Gray code orders the fringe periods).
    blocks : the :class:`Block` s in frame order.
    order : ``"procam"`` for procam's own sequences, ``"custom"`` for one described by hand.
    upside_down : the projector shows its image upside down to the camera (a description's
        ``"upside_down": true``; a sequence without a Gray code is checked to decode upright otherwise,
        :mod:`procam.decode.phase.diagnose`).
    """

    width: int
    height: int
    family: str
    blocks: tuple
    order: str = "procam"
    upside_down: bool = False

    def __post_init__(self):
        _check_set(self)

    step = 1  # every projector pixel is coded (the Gray family's step)

    @property
    def count(self) -> int:
        return sum(b.count for b in self.blocks)

    def _single(self, kind):
        found = [b.first for b in self.blocks if b.kind == kind]
        return found[0] if found else None

    @property
    def white(self) -> int | None:
        """Index of the white frame, or None when the sequence has none."""
        return self._single("white")

    @property
    def black(self) -> int | None:
        """Index of the black frame, or None when the sequence has none."""
        return self._single("black")

    def size(self, axis: str) -> int:
        """The panel's size along ``axis``: width for ``"col"``, height for ``"row"``."""
        return self.width if axis == "col" else self.height

    def phase_blocks(self, axis: str) -> list:
        """The phase blocks of ``axis``, coarsest (longest period) first."""
        return sorted((b for b in self.blocks if b.kind == "phase" and b.axis == axis), key=lambda b: -b.period)

    def gray_block(self, axis: str):
        """The Gray block of ``axis`` (gray-phase), or None."""
        found = [b for b in self.blocks if b.kind == "gray" and b.axis == axis]
        return found[0] if found else None

    def block_of(self, k: int) -> tuple:
        """``(block, j)``: the block frame ``k`` belongs to and its index there; ``(None, None)`` outside."""
        for b in self.blocks:
            if b.first <= k < b.first + b.count:
                return b, k - b.first
        return None, None

    def phase_frames(self) -> list[int]:
        """Indices of every phase frame."""
        return [k for b in self.blocks if b.kind == "phase" for k in b.frames]

    def pair_indices(self, axis: str) -> np.ndarray:
        """(n, 2) indices of the (pattern, inverse) pairs of the Gray bits of ``axis`` (none without inverses)."""
        g = self.gray_block(axis)
        if g is None or not g.inverse:
            return np.zeros((0, 2), int)
        first = g.first + 2 * np.arange(g.bits + int(g.complementary))
        return np.stack([first, first + 1], axis=1)

    def role(self, k: int) -> str:
        """What frame ``k`` shows, in the words of every message (:mod:`procam.capture.frames`): ``'white'``,
        ``'column phase 2 of 4, period 32 px'`` (steps counted from 1), ``'row Gray bit 3 inverse'``,
        ``'column complementary Gray bit'``, or ``'not in the sequence'``."""
        b, j = self.block_of(int(k))
        if b is None:
            return "not in the sequence"
        if b.kind in ("white", "black"):
            return b.kind
        name = "column" if b.axis == "col" else "row"
        if b.kind == "phase":
            cue = ", the unit-frequency cue" if b.period >= self.size(b.axis) else ""
            return f"{name} phase {j + 1} of {b.steps}, period {b.period:.4g} px{cue}"
        bit, inverse, comp = b.gray_frame(j)
        what = "complementary Gray bit" if comp else f"Gray bit {bit}"
        return f"{name} {what}{' inverse' if inverse else ''}"

    def line(self, k: int) -> tuple[str | None, np.ndarray | None]:
        """``(axis, values)`` of frame ``k``: the 1-D pattern (uint8, projector width or height values) of a
        phase or Gray frame; ``(None, None)`` for the white and black frames."""
        b, j = self.block_of(k)
        if b is None:
            raise IndexError(f"frame {k} is outside the sequence of {self.count} frames")
        if b.kind in ("white", "black"):
            return None, None
        x = np.arange(self.size(b.axis), dtype=np.float64)
        if b.kind == "phase":
            f = b.fringe
            t = 2.0 * np.pi * f.sign * (x - f.x0) / b.period + b.shifts()[j]
            return b.axis, np.rint(255.0 * f.shape(t)).astype(np.uint8)
        bit, inverse, comp = b.gray_frame(j)
        on = gray_bit(x, b, bit, comp)
        return b.axis, np.where(on != inverse, 255, 0).astype(np.uint8)

    def describe(self) -> str:
        """One line: ``'phase: columns 4 steps at 32 px + 4 steps at 1920 px; rows ...; white, black'``."""
        parts = []
        for axis, name in (("col", "columns"), ("row", "rows")):
            items = []
            for b in self.blocks:
                if b.axis != axis:
                    continue
                if b.kind == "phase":
                    items.append(f"{b.steps} steps at {_num(b.period)} px")
                else:
                    items.append(f"Gray {b.bits} bits{' + complementary' if b.complementary else ''}"
                                 f"{' with inverses' if b.inverse else ''}")
            parts.append(f"{name} " + " + ".join(items))
        extra = [k for k in ("white", "black") if getattr(self, k) is not None]
        return f"{self.family}: " + "; ".join(parts) + (f"; {', '.join(extra)}" if extra else "; no white or black")

    def to_dict(self) -> dict:
        """The ``patterns.json`` of the sequence (``docs/file-formats.md``)."""
        d = {"format": PATTERNS_FORMAT, "version": 1, "family": self.family, "width": self.width,
             "height": self.height, "order": self.order, "count": self.count, "white": self.white,
             "black": self.black, "sequence": [b.to_dict() for b in self.blocks]}
        if self.upside_down:
            d["upside_down"] = True
        return d


def _num(v: float) -> str:
    return f"{v:g}" if abs(v - round(v)) > 1e-9 else str(int(round(v)))


def gray_bit(x: np.ndarray, block: Block, bit: int, complementary: bool = False) -> np.ndarray:
    """(n,) bool: Gray bit ``bit`` (0 = least significant ordinary bit) of the fringe period of projector
    coordinates ``x``, or the complementary bit."""
    u = (np.asarray(x, np.float64) - block.fringe.x0) / block.period
    if complementary:
        return (gray_encode(np.floor(2.0 * u + 1e-9).astype(np.int64)) & 1).astype(bool)
    return ((gray_encode(np.floor(u + 1e-9).astype(np.int64)) >> bit) & 1).astype(bool)


def _periods_needed(n: int, period: float, x0: float) -> int:
    """How many fringe periods the pixels ``0 .. n - 1`` reach into, counted from the phase zero ``x0``."""
    return int(math.floor((n - 1 - x0) / period + 1e-9)) + 1


def heterodyne_beats(periods) -> tuple[float, float, float]:
    """``(lambda_12, lambda_23, lambda_123)``: the beat periods of three periods ``p1 < p2 < p3`` (pixels),
    ``lambda_ab = pa pb / (pb - pa)`` and ``lambda_123 = lambda_12 lambda_23 / (lambda_23 - lambda_12)``
    (infinite when the beats coincide)."""
    p1, p2, p3 = sorted(float(p) for p in periods)
    l12 = p1 * p2 / (p2 - p1) if p2 > p1 else math.inf
    l23 = p2 * p3 / (p3 - p2) if p3 > p2 else math.inf
    l123 = l12 * l23 / (l23 - l12) if l23 > l12 and math.isfinite(l23) else math.inf
    return l12, l23, l123


def _check_set(ps: PhaseSet) -> None:
    """Raise ValueError when the blocks do not make a sequence of ``ps.family`` (what is wrong, in words)."""
    if ps.family not in PHASE_FAMILIES:
        raise ValueError(f"family must be one of {', '.join(PHASE_FAMILIES)}, got {ps.family!r}")
    if not (isinstance(ps.width, int) and isinstance(ps.height, int) and ps.width >= 2 and ps.height >= 2):
        raise ValueError(f"projector size must be at least 2x2, got {ps.width}x{ps.height}")
    first = 0
    for i, b in enumerate(ps.blocks):
        where = f"sequence[{i}]"
        if b.kind not in KINDS:
            raise ValueError(f"{where}: kind must be one of {', '.join(KINDS)}, got {b.kind!r}")
        if b.first != first:
            raise ValueError(f"{where}: starts at frame {b.first}, the blocks before it end at {first}")
        first += b.count
        if b.kind in ("white", "black"):
            continue
        if b.axis not in AXES:
            raise ValueError(f"{where}: axis must be 'col' or 'row', got {b.axis!r}")
        n = ps.size(b.axis)
        if not (math.isfinite(b.period) and b.period >= 2):
            raise ValueError(f"{where}: period must be at least 2 projector pixels, got {b.period!r}")
        if b.kind == "phase" and not 3 <= b.steps <= 64:
            raise ValueError(f"{where}: a phase block needs 3 to 64 steps, got {b.steps!r}")
        if b.kind == "gray":
            need = _periods_needed(n, b.period, b.fringe.x0)
            if b.bits < 1 or 2 ** b.bits < need:
                raise ValueError(f"{where}: {b.bits} Gray bits order {2 ** b.bits} periods of {_num(b.period)} px, "
                                 f"fewer than the {need} the panel's {n} pixels need")
            if b.bit_order not in BIT_ORDERS:
                raise ValueError(f"{where}: bit_order must be one of {', '.join(BIT_ORDERS)}, got {b.bit_order!r}")
            if b.complementary and abs(b.period / 2 - round(b.period / 2)) > 1e-9:
                raise ValueError(f"{where}: a complementary Gray bit needs an even whole period, got "
                                 f"{_num(b.period)} px")
    for kind in ("white", "black"):
        if sum(b.kind == kind for b in ps.blocks) > 1:
            raise ValueError(f"the sequence has more than one {kind} frame")
    for axis, name in (("col", "columns"), ("row", "rows")):
        phase, gray = ps.phase_blocks(axis), [b for b in ps.blocks if b.kind == "gray" and b.axis == axis]
        n = ps.size(axis)
        if not phase:
            raise ValueError(f"no phase block along the {name}: procam needs both projector coordinates")
        periods = [b.period for b in phase]
        if len(set(periods)) != len(periods):
            raise ValueError(f"two phase blocks along the {name} have the same period")
        if ps.family == "phase":
            if gray:
                raise ValueError(f"family 'phase' has no Gray code (the {name} have one): use 'gray-phase'")
            if len(phase) < 2 or periods[0] < n:
                raise ValueError(f"family 'phase' needs along the {name} fringes with a period of at least the panel's "
                                 f"{n} px (the unit-frequency cue) and finer ones; the periods are "
                                 f"{', '.join(_num(p) for p in periods)}")
        elif ps.family == "heterodyne":
            if gray or len(phase) != 3:
                raise ValueError(f"family 'heterodyne' needs three phase blocks (and no Gray code) along the {name}, "
                                 f"got {len(phase)} phase and {len(gray)} Gray")
            x0s = {(b.fringe.x0, b.fringe.sign) for b in phase}
            if len(x0s) > 1:
                raise ValueError(f"the three heterodyne fringes along the {name} must share origin, pixel_center and "
                                 "sign (their beats are taken from the phase differences)")
            l12, l23, l123 = heterodyne_beats(periods)
            if not (math.isfinite(l12) and math.isfinite(l23) and l23 > l12 * (1 + 1e-9)):
                raise ValueError(f"the heterodyne periods along the {name} ({', '.join(_num(p) for p in periods)} px) "
                                 f"give beats of {l12:.1f} and {l23:.1f} px: the second must be longer than the "
                                 "first for their beat to order them (counts c1 > c2 > c3 across the panel with "
                                 "c1 - c2 = c2 - c3 + 1, such as 70, 64, 59)")
            if not l123 >= n - 1e-6:
                raise ValueError(f"the heterodyne periods along the {name} ({', '.join(_num(p) for p in periods)} px) "
                                 f"beat to {l123:.1f} px, less than the panel's {n}: the coordinate would not be "
                                 "absolute")
        else:
            if len(phase) != 1 or len(gray) != 1:
                raise ValueError(f"family 'gray-phase' needs one phase block and one Gray block along the {name}, got "
                                 f"{len(phase)} and {len(gray)}")
            if abs(gray[0].period - phase[0].period) > 1e-9 or gray[0].fringe.x0 != phase[0].fringe.x0:
                raise ValueError(f"the Gray code along the {name} orders periods of {_num(gray[0].period)} px, the "
                                 f"fringes have {_num(phase[0].period)} px (or another origin)")


def phase_set(width: int, height: int, family: str = "phase", *, steps: int | None = None,
              period: float | None = None, periods=None, inverse: bool = True, complementary: bool = True,
              white_black: bool = True, fringe: Fringe = Fringe(), bit_order: str = "msb-first") -> PhaseSet:
    """procam's own sequence of ``family`` for a ``width`` x ``height`` projector.

    Columns first, then rows; per axis the Gray block (gray-phase) and the phase blocks finest first, the
    unit-frequency cue (:func:`cue_period`: one period across the panel, or a little more when the panel is not
    a whole number of fringe periods) or the heterodyne's longest period last; then the white and the black frame.

    Parameters
    ----------
    family : ``"phase"``, ``"heterodyne"`` or ``"gray-phase"``.
    steps : phase shifts per block, ``N >= 3`` (default :data:`DEFAULT_STEPS`: 8 for phase and heterodyne, 4
        for gray-phase).
    period : fringe period in projector pixels (phase: the one level under the cue; gray-phase: default 16).
    periods : family ``phase``: the fringe periods of every level but the cue (default ``(period,)`` when
        ``period`` is given, else :data:`DEFAULT_PERIODS`: 16 and 128);
        ``heterodyne``: three counts of periods across the panel (default ``(70, 64, 59)``; the periods are the
        panel's size over them, so rows get finer fringes than columns).
    inverse, complementary : gray-phase: every Gray bit followed by its inverse; one complementary bit (default
        both: the complementary bit removes the stripe-edge errors of the plain hybrid).
    white_black : end with a white and a black frame.
    fringe : the conventions (default procam's).
    bit_order : gray-phase: the order of the Gray bits, ``"msb-first"`` (default) or ``"lsb-first"``.
    """
    if family not in PHASE_FAMILIES:
        raise ValueError(f"family must be one of {', '.join(PHASE_FAMILIES)}, got {family!r}")
    width, height = int(width), int(height)
    steps = int(DEFAULT_STEPS[family] if steps is None else steps)
    blocks = []
    first = 0

    def add(**kw):
        nonlocal first
        b = Block(first=first, fringe=fringe, **kw)
        blocks.append(b)
        first += b.count

    for axis in AXES:
        n = width if axis == "col" else height
        if family == "heterodyne":
            counts = DEFAULT_HETERODYNE_COUNTS if periods is None else tuple(periods)
            if len(counts) != 3 or not all(float(c) > 0 for c in counts):
                raise ValueError(f"heterodyne needs three positive period counts, got {counts!r}")
            for c in sorted(counts, reverse=True):
                add(kind="phase", axis=axis, steps=steps, period=n / float(c))
            continue
        p = float(period if period is not None else DEFAULT_PERIODS[family][0])
        if family == "gray-phase":
            add(kind="gray", axis=axis, bits=bits_for(_periods_needed(n, p, fringe.x0)), inverse=bool(inverse),
                complementary=bool(complementary), period=p, bit_order=bit_order)
            add(kind="phase", axis=axis, steps=steps, period=p)
            continue
        if periods is not None:
            levels = tuple(float(v) for v in periods)
        else:
            levels = (p,) if period is not None else DEFAULT_PERIODS[family]
        for q in sorted(levels):
            add(kind="phase", axis=axis, steps=steps, period=q)
        add(kind="phase", axis=axis, steps=steps, period=cue_period(n, sorted(levels)))
    if white_black:
        add(kind="white")
        add(kind="black")
    return PhaseSet(width, height, family, tuple(blocks))


def cue_period(n: int, periods) -> float:
    """The unit-frequency cue's period for a panel of ``n`` pixels above fringes of ``periods`` (finest first):
    the panel's size when it is a whole number of the coarsest of them, else the smallest such multiple beyond it
    (every level then repeats with the cue, so a pixel at the panel's edge whose cue wrapped keeps its place)."""
    top = float(max(periods))
    k = math.ceil(n / top - 1e-9)
    if any(abs(top / q - round(top / q)) > 1e-9 for q in periods):
        return float(n)
    return top * k


def frames(ps: PhaseSet, dtype=np.uint8):
    """The frames of ``ps`` one (height, width) image at a time, in order."""
    for k in range(ps.count):
        yield frame(ps, k, dtype)


def frame(ps: PhaseSet, k: int, dtype=np.uint8) -> np.ndarray:
    """Frame ``k`` of ``ps`` as a (height, width) image."""
    axis, line = ps.line(k)
    if axis is None:
        return np.full((ps.height, ps.width), 255 if k == ps.white else 0, dtype)
    line = line.astype(dtype)
    return np.ascontiguousarray(np.broadcast_to(line[None, :] if axis == "col" else line[:, None],
                                                (ps.height, ps.width)))


def with_size(ps: PhaseSet, width: int, height: int) -> PhaseSet:
    """``ps`` for another projector size (the blocks unchanged; raises ValueError when they no longer fit)."""
    return replace(ps, width=int(width), height=int(height))
