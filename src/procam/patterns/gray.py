"""Gray-code pattern sequences for a projector.

Two orders are supported (see ``docs``/README):

``opencv`` (default)
    Pixel-identical to OpenCV's ``structured_light.GrayCodePattern`` for the same size:
    column bits MSB first, each followed by its inverse, then row bits likewise, then an
    all-white and an all-black frame (the order OpenCV-based capture tools use).
    Codes are not centred: column ``x`` carries ``gray(x)``.
``moreno``
    Moreno & Taubin's ``scan3d-capture`` order: white, black, then the column pairs, then
    the row pairs, with codes centred on the panel: column ``x`` carries
    ``gray(x + (2**n_x - W) // 2)``.

Bit counts are per axis: ``n_x = ceil(log2 W)`` and ``n_y = ceil(log2 H)``, so a
sequence has ``2 (n_x + n_y) + 2`` images (46 for 1920x1080, 42 for 1024x768).

``bit_order`` (default ``"msb-first"``) is the order of each axis's bits: most significant first (OpenCV's,
Moreno-Taubin's, procam's), or ``"lsb-first"`` (least significant first, as some tools show them); the pairs
(pattern, inverse) stay together either way.

``step`` (default 1) codes blocks of ``step x step`` projector pixels with one code, as
kamino410/procam-calibration's ``graycode_step`` does against moire: the codes are those of a
``ceil(W/step) x ceil(H/step)`` projector, each pattern pixel drawn ``step`` times in each direction
(code of projector column x = ``x // step``).  Decoding returns the block's centre,
``code * step + (step - 1) / 2``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from ..choices import PATTERN_ORDERS
from ..io.formats import GRAYCODE_FORMAT


ORDERS = PATTERN_ORDERS
#: The orders of a Gray code's bits in the frames (the ``bit_order`` of a description, ``docs/patterns.md``).
BIT_ORDERS = ("msb-first", "lsb-first")


def gray_encode(x: np.ndarray) -> np.ndarray:
    """Binary-reflected Gray code of non-negative integers: ``x ^ (x >> 1)``."""
    x = np.asarray(x)
    return x ^ (x >> 1)


def gray_decode(g: np.ndarray) -> np.ndarray:
    """Inverse of :func:`gray_encode` (prefix XOR over the bits), for codes < 2**32."""
    g = np.array(g, copy=True)
    shift = 1
    while shift < 32:
        g ^= g >> shift
        shift <<= 1
    return g


def bits_for(n: int) -> int:
    """Number of Gray-code bits needed for ``n`` positions: ``ceil(log2 n)`` (1 for n <= 2)."""
    if n < 1:
        raise ValueError(f"size must be positive, got {n}")
    return max(1, math.ceil(math.log2(n)))


@dataclass(frozen=True)
class PatternSet:
    """Description of a Gray-code sequence (no pixels).

    Attributes
    ----------
    width, height : projector size in pixels.
    order : ``"opencv"`` or ``"moreno"``.
    col_bits, row_bits : number of bits per axis.
    col_offset, row_offset : code offsets (the code of column x is ``gray(x + col_offset)``).
    white, black : indices of the all-white and all-black frames.
    col_start, row_start : index of the first column / row pattern; bit ``b`` (MSB = col_bits-1)
        of the column code is image ``col_start + 2 (col_bits - 1 - b)`` (``col_start + 2 b`` when
        ``bit_order`` is ``"lsb-first"``) and its inverse follows.
    count : total number of images.
    step : projector pixels per code along each axis (1 = every pixel has its own code).
    bit_order : ``"msb-first"`` (default) or ``"lsb-first"``: the order of each axis's bits in the frames.
    """

    width: int
    height: int
    order: str
    col_bits: int
    row_bits: int
    col_offset: int
    row_offset: int
    white: int
    black: int
    col_start: int
    row_start: int
    count: int
    step: int = 1
    bit_order: str = "msb-first"

    @property
    def code_width(self) -> int:
        """Number of column codes: ``ceil(width / step)``."""
        return (self.width - 1) // self.step + 1

    @property
    def code_height(self) -> int:
        """Number of row codes: ``ceil(height / step)``."""
        return (self.height - 1) // self.step + 1

    def pair_indices(self, axis: str) -> np.ndarray:
        """(n_bits, 2) indices of (pattern, inverse) pairs for ``axis`` in {'col', 'row'}, MSB first (whatever
        the order of the frames, :attr:`bit_order`)."""
        if axis == "col":
            start, n = self.col_start, self.col_bits
        elif axis == "row":
            start, n = self.row_start, self.row_bits
        else:
            raise ValueError(f"axis must be 'col' or 'row', got {axis!r}")
        j = np.arange(n)
        first = start + 2 * (j if self.bit_order == "msb-first" else n - 1 - j)
        return np.stack([first, first + 1], axis=1)

    def to_dict(self) -> dict:
        d = asdict(self)
        if self.bit_order == "msb-first":
            del d["bit_order"]  # the default: procam's own files stay as they were
        d["format"] = GRAYCODE_FORMAT
        d["version"] = 1
        d["col_pairs"] = self.pair_indices("col").tolist()
        d["row_pairs"] = self.pair_indices("row").tolist()
        d["bit_rule"] = ("image col_pairs[j][0] is white where bit (col_bits-1-j) of "
                         "gray(x // step + col_offset) is 1; col_pairs[j][1] is its inverse; rows likewise")
        return d


def pattern_set(width: int, height: int, order: str = "opencv", step: int = 1,
                bit_order: str = "msb-first") -> PatternSet:
    """Describe the sequence for a ``width`` x ``height`` projector in ``order`` (``step`` px per code), each
    axis's bits in ``bit_order`` (:data:`BIT_ORDERS`)."""
    width, height, step = int(width), int(height), int(step)
    if bit_order not in BIT_ORDERS:
        raise ValueError(f"bit_order must be one of {', '.join(BIT_ORDERS)}, got {bit_order!r}")
    if width < 2 or height < 2:
        raise ValueError(f"projector size must be at least 2x2, got {width}x{height}")
    if order not in ORDERS:
        raise ValueError(f"order must be one of {ORDERS}, got {order!r}")
    if step < 1:
        raise ValueError(f"step must be a positive integer, got {step}")
    cw, ch = (width - 1) // step + 1, (height - 1) // step + 1
    if cw < 2 or ch < 2:
        raise ValueError(f"step {step} leaves fewer than 2 codes per axis for {width}x{height}")
    nx, ny = bits_for(cw), bits_for(ch)
    npat = 2 * (nx + ny)
    if order == "opencv":
        return PatternSet(width, height, order, nx, ny, 0, 0, white=npat, black=npat + 1,
                          col_start=0, row_start=2 * nx, count=npat + 2, step=step, bit_order=bit_order)
    ox, oy = (2**nx - cw) // 2, (2**ny - ch) // 2
    return PatternSet(width, height, order, nx, ny, ox, oy, white=0, black=1,
                      col_start=2, row_start=2 + 2 * nx, count=npat + 2, step=step, bit_order=bit_order)


def bit_planes(n: int, bits: int, offset: int) -> np.ndarray:
    """(bits, n) bool: Gray-code bits of positions 0..n-1, MSB first."""
    g = gray_encode(np.arange(n, dtype=np.int64) + offset)
    shifts = np.arange(bits - 1, -1, -1)
    return ((g[None, :] >> shifts[:, None]) & 1).astype(bool)


def frames(ps: PatternSet, white: int = 255, black: int = 0, dtype=np.uint8):
    """The sequence of ``ps`` one (height, width) image at a time, in order (the same images as
    :func:`generate`, without holding them all in memory)."""
    cols = bit_planes(ps.code_width, ps.col_bits, ps.col_offset)[:, np.arange(ps.width) // ps.step]
    rows = bit_planes(ps.code_height, ps.row_bits, ps.row_offset)[:, np.arange(ps.height) // ps.step]
    role = {ps.white: ("white", 0, False), ps.black: ("black", 0, False)}
    for j, (a, b) in enumerate(ps.pair_indices("col")):
        role[int(a)], role[int(b)] = ("col", j, False), ("col", j, True)
    for j, (a, b) in enumerate(ps.pair_indices("row")):
        role[int(a)], role[int(b)] = ("row", j, False), ("row", j, True)
    for k in range(ps.count):
        kind, j, inverse = role[k]
        if kind in ("white", "black"):
            yield np.full((ps.height, ps.width), white if kind == "white" else black, dtype)
            continue
        bits = cols[j] if kind == "col" else rows[j]
        line = np.where(bits != inverse, white, black).astype(dtype)
        yield np.ascontiguousarray(np.broadcast_to(line[None, :] if kind == "col" else line[:, None],
                                                   (ps.height, ps.width)))


def generate(width: int, height: int, order: str = "opencv", white: int = 255,
             black: int = 0, dtype=np.uint8, step: int = 1, bit_order: str = "msb-first") -> np.ndarray:
    """The full sequence as an array ``(count, height, width)`` of ``dtype``.

    Nothing is written to disk; see :func:`save`.
    """
    ps = pattern_set(width, height, order, step, bit_order)
    out = np.empty((ps.count, ps.height, ps.width), dtype=dtype)
    out[ps.white] = white
    out[ps.black] = black
    cols = bit_planes(ps.code_width, ps.col_bits, ps.col_offset)[:, np.arange(ps.width) // ps.step]
    rows = bit_planes(ps.code_height, ps.row_bits, ps.row_offset)[:, np.arange(ps.height) // ps.step]
    for j, (a, b) in enumerate(ps.pair_indices("col")):
        line = np.where(cols[j], white, black).astype(dtype)
        out[a] = line[None, :]
        out[b] = (white + black - line.astype(np.int64)).astype(dtype)[None, :]
    for j, (a, b) in enumerate(ps.pair_indices("row")):
        line = np.where(rows[j], white, black).astype(dtype)
        out[a] = line[:, None]
        out[b] = (white + black - line.astype(np.int64)).astype(dtype)[:, None]
    return out
