"""Decoding a captured Gray-code sequence into per-pixel projector coordinates.

Per camera pixel and per axis: the projector column (row) that lit it, as float (NaN where
invalid), a validity mask, a reason code and a confidence.  Whole-frame and vectorised; the
image stack is processed in horizontal bands so the working set stays in cache.

Classifiers
-----------
``simple``
    bit = [pattern > inverse]; a bit is uncertain when ``|pattern - inverse| < contrast_threshold``.
``robust`` (default)
    Moreno & Taubin's rule (METHOD §3) with Nayar et al.'s direct/global separation from the
    high-frequency pairs (bits 3 and 2): ``L_d = (L+ - L-)/(1 - b)``, ``L_g = 2 (L- - b L+)/(1 - b^2)``;
    if ``L_d < m`` the bit is uncertain; if ``L_d > L_g``, bit = [p > p_inv]; else bit 0 when
    ``p <= L_d and p_inv >= L_g``, bit 1 when ``p >= L_g and p_inv <= L_d``, otherwise uncertain.
    Under strong interreflections it marks pixels uncertain where the simple rule decodes them
    wrongly.

Both also require ``white - black >= shadow_threshold`` (shadow / unlit mask) and mark codes
outside the projector invalid.

Thresholds are in **8-bit grey levels (DN)** and are scaled to the input's full scale: for
``uint16`` input the full scale is the smallest of 2^10-1, 2^12-1, 2^14-1, 2^16-1 that holds
the stack's maximum (so 10/12/14-bit cameras stored in 16-bit files work), or pass
``full_scale`` explicitly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .patterns import PatternSet

#: Reason codes of :attr:`DecodeResult.reason_col` / ``reason_row``.
REASONS = {
    0: "decoded",
    1: "shadow: white - black below shadow_threshold (not lit by the projector)",
    2: "low contrast: some bit's pattern and inverse differ by less than contrast_threshold",
    3: "ambiguous bit: direct light too weak against global light (robust classifier)",
    4: "code outside the projector's columns/rows",
}
OK, SHADOW, LOW_CONTRAST, AMBIGUOUS, OUT_OF_RANGE = range(5)


@dataclass(frozen=True)
class DecodeResult:
    """Decoded maps of one pose, all (H, W).

    Attributes
    ----------
    col, row : float32
        Projector column / row (pixels, centre of projector pixel = integer) of each camera
        pixel; NaN where invalid.
    valid_col, valid_row : bool
    reason_col, reason_row : uint8
        Codes of :data:`REASONS` (0 = decoded).
    confidence : float32
        Smallest ``|pattern - inverse|`` over all bits divided by ``white - black``, in [0, 1].
    direct, global_ : float32 or None
        The robust classifier's direct and global light estimates (DN at the input scale).
    pattern_set : the decoded sequence's :class:`PatternSet`.
    """

    col: np.ndarray
    row: np.ndarray
    valid_col: np.ndarray
    valid_row: np.ndarray
    reason_col: np.ndarray
    reason_row: np.ndarray
    confidence: np.ndarray
    direct: np.ndarray | None
    global_: np.ndarray | None
    pattern_set: PatternSet

    @property
    def valid(self) -> np.ndarray:
        """(H, W) bool: both column and row decoded."""
        return self.valid_col & self.valid_row

    def reason_counts(self) -> dict:
        """``{axis: {reason text: pixel count}}`` for the non-zero counts."""
        out = {}
        for axis, r in (("col", self.reason_col), ("row", self.reason_row)):
            counts = np.bincount(r.ravel(), minlength=len(REASONS))
            out[axis] = {REASONS[k]: int(c) for k, c in enumerate(counts) if c}
        return out


def full_scale_of(stack: np.ndarray) -> float:
    """Full-scale value of a stack: 255 for uint8; for uint16 the smallest 2^b - 1 (b in 10, 12, 14, 16)
    that holds its maximum."""
    if stack.dtype == np.uint8:
        return 255.0
    mx = int(stack.max())
    for bits in (10, 12, 14, 16):
        if mx <= 2**bits - 1:
            return float(2**bits - 1)
    return 65535.0


def _hf_pairs(ps: PatternSet) -> list:
    """Pairs for the direct/global estimate: bits 3 and 2 of both axes (the lowest two if fewer bits)."""
    idx = []
    for axis, n in (("col", ps.col_bits), ("row", ps.row_bits)):
        pairs = ps.pair_indices(axis)  # MSB first: bit b is row n-1-b
        bits = [3, 2] if n >= 4 else list(range(min(n, 2)))[::-1]
        for b in bits:
            idx.extend(pairs[n - 1 - b].tolist())
    return idx


def decode(stack: np.ndarray, pattern_set: PatternSet, method: str = "robust", *,
           shadow_threshold: float = 10.0, contrast_threshold: float = 3.0,
           direct_threshold: float = 5.0, black_fraction: float = 0.5,
           full_scale: float | None = None, band: int = 64) -> DecodeResult:
    """Decode a Gray-code image stack.

    Parameters
    ----------
    stack : (K, H, W) uint8 or uint16
        The captured sequence in ``pattern_set``'s order (``K == pattern_set.count``).
    pattern_set : :class:`~procam.patterns.PatternSet`
    method : ``"robust"`` (default) or ``"simple"``; see the module docstring.
    shadow_threshold : float, DN (8-bit scale)
        Minimum ``white - black`` for a pixel to count as lit by the projector. Default 10.
    contrast_threshold : float, DN (8-bit scale)
        Minimum ``|pattern - inverse|`` for a bit to be certain. Default 3.
    direct_threshold : float, DN (8-bit scale)
        Robust only: minimum direct light ``L_d`` (Moreno's ``m``). Default 5.
    black_fraction : float
        Robust only: fraction of light a black projector pixel still emits (Moreno's ``b``). Default 0.5.
    full_scale : float, optional
        The input's full-scale value; thresholds are multiplied by ``full_scale / 255``.
    band : int
        Rows processed at a time (speed only).

    Returns
    -------
    DecodeResult
    """
    stack = np.asarray(stack)
    ps = pattern_set
    if stack.ndim != 3 or stack.shape[0] != ps.count:
        raise ValueError(f"stack must be ({ps.count}, H, W) for this pattern set, got {stack.shape}")
    if method not in ("robust", "simple"):
        raise ValueError(f"method must be 'robust' or 'simple', got {method!r}")
    if stack.dtype not in (np.uint8, np.uint16):
        raise ValueError(f"stack must be uint8 or uint16, got {stack.dtype}")
    fs = full_scale_of(stack) if full_scale is None else float(full_scale)
    scale = fs / 255.0
    K, H, W = stack.shape
    col = np.empty((H, W), np.float32)
    row = np.empty((H, W), np.float32)
    rcol = np.empty((H, W), np.uint8)
    rrow = np.empty((H, W), np.uint8)
    conf = np.empty((H, W), np.float32)
    robust = method == "robust"
    direct = np.empty((H, W), np.float32) if robust else None
    glob = np.empty((H, W), np.float32) if robust else None
    hf = _hf_pairs(ps)
    tshadow = shadow_threshold * scale
    tcontrast = contrast_threshold * scale
    tdirect = direct_threshold * scale
    b = float(black_fraction)
    wide = np.int32

    for y0 in range(0, H, band):
        sl = slice(y0, min(H, y0 + band))
        blk = stack[:, sl, :]
        white = blk[ps.white].astype(wide)
        black = blk[ps.black].astype(wide)
        span = white - black
        shadow = span < tshadow
        if robust:
            hfs = blk[hf]
            lp = hfs.max(axis=0).astype(np.float32)
            lm = hfs.min(axis=0).astype(np.float32)
            ld = (lp - lm) / (1.0 - b)
            lg = 2.0 * (lm - b * lp) / (1.0 - b * b)
            neg = lg <= 0
            ld = np.where(neg, lp, ld)
            lg = np.where(neg, 0.0, lg).astype(np.float32)
            direct[sl] = ld
            glob[sl] = lg
            weak = ld < tdirect
            strong = ld > lg
        minabs = np.full(span.shape, np.iinfo(wide).max, wide)
        for axis, out, reason, size, offset in (("col", col, rcol, ps.width, ps.col_offset),
                                                 ("row", row, rrow, ps.height, ps.row_offset)):
            code = np.zeros(span.shape, np.int32)
            prev = np.zeros(span.shape, bool)
            lowc = np.zeros(span.shape, bool)
            amb = np.zeros(span.shape, bool)
            for a, i in ps.pair_indices(axis):
                p = blk[a].astype(wide)
                q = blk[i].astype(wide)
                d = p - q
                ad = np.abs(d)
                np.minimum(minabs, ad, out=minabs)
                lowc |= ad < tcontrast
                bit = d > 0
                if robust:
                    zero = (p <= ld) & (q >= lg)
                    one = (p >= lg) & (q <= ld)
                    bit = np.where(strong, bit, one)
                    amb |= weak | (~strong & ~zero & ~one)
                    # where the direct light dominates, fall back to the plain comparison
                prev = prev ^ bit  # Gray -> binary: b_i = b_{i+1} xor g_i
                code = (code << 1) | prev
            value = code - offset
            outside = (value < 0) | (value >= size)
            r = np.zeros(span.shape, np.uint8)
            r[outside] = OUT_OF_RANGE
            r[amb & ~lowc] = AMBIGUOUS if robust else OK
            r[lowc] = LOW_CONTRAST
            r[shadow] = SHADOW
            reason[sl] = r
            out[sl] = np.where(r == OK, value, np.nan).astype(np.float32)
        with np.errstate(divide="ignore", invalid="ignore"):
            conf[sl] = np.clip(np.where(span > 0, minabs / np.maximum(span, 1), 0.0), 0.0, 1.0)

    return DecodeResult(col, row, rcol == OK, rrow == OK, rcol, rrow, conf, direct, glob, ps)
