"""Decoding a captured Gray-code sequence into per-pixel projector coordinates.

Per camera pixel and per axis: the projector column (row) that lit it, as float (NaN where
invalid), a validity mask, a reason code and a confidence.  Whole-frame and vectorised; the
image stack is processed in horizontal bands so the working set stays in cache.

Classifiers
-----------
``simple``
    bit = [pattern > inverse]; a bit is uncertain when ``|pattern - inverse| < contrast_threshold``.
``robust`` (default)
    Moreno & Taubin's rule with Nayar et al.'s direct/global separation from the
    high-frequency pairs (bits 3 and 2), computed on black-subtracted values (the black frame holds
    the ambient light): ``L_d = (L+ - L-)/(1 - b)``, ``L_g = 2 (L- - b L+)/(1 - b^2)``.  If
    ``L_d < m`` the pixel is uncertain; if ``L_d > L_g``, bit = [p > p_inv]; otherwise, for the
    low-frequency bits (above the separation bits, where global light depends on the pattern),
    bit 0 when ``p <= L_d - e and p_inv >= L_g + e``, bit 1 when ``p >= L_g + e and p_inv <= L_d - e``
    (``e`` = contrast_threshold, a noise margin the original rule lacks), or, wherever it cannot be
    wrong, by the sign of ``p - p_inv`` (when ``|p - p_inv| >= L_g - (1 - b) L_d + e``, since the
    global parts of a pattern and its inverse differ by at most ``L_g``), otherwise uncertain; the
    high-frequency bits keep the plain comparison, where global light is the same for a pattern
    and its inverse (the separation's own premise).  Under strong interreflections it marks pixels
    uncertain where the simple rule decodes them wrongly.

Both also require ``white - black >= shadow_threshold`` (shadow / unlit mask) and mark codes
outside the projector invalid.  Where only the finest bits are uncertain (stripes the camera cannot
resolve, a pixel on a stripe edge) the leading certain bits still fix the code to a block of
``2^dropped`` codes and the pixel gets the block's centre (up to ``max_dropped_bits``; measured in
``tests/test_decode.py`` and ``benchmarks/correspond.py``: without it a slightly blurred capture of a
high-resolution projector decodes nowhere).

Thresholds are in **8-bit grey levels (DN)** and are scaled to the input's full scale: for
``uint16`` input the full scale is the smallest of 2^10-1, 2^12-1, 2^14-1, 2^16-1 that holds
the stack's maximum (so 10/12/14-bit cameras stored in 16-bit files work), or pass
``full_scale`` explicitly.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from . import decoded as _decoded
from ..io import files as _files
from ..patterns import PatternSet
from ..choices import DECODE_METHODS

#: Reason codes and the decoded maps' type live in :mod:`procam.decode.decoded` (shared with the phase decoder).
REASONS, DecodeResult = _decoded.REASONS, _decoded.DecodeResult
OK, SHADOW, LOW_CONTRAST, AMBIGUOUS, OUT_OF_RANGE = range(5)


def _hf_bits(ps: PatternSet) -> list:
    """The bits used for the direct/global estimate: 3 and 2 (Moreno & Taubin), lower ones for tiny projectors."""
    n = min(ps.col_bits, ps.row_bits)
    return [3, 2] if n >= 4 else list(range(min(n, 2)))[::-1]


def _hf_pairs(ps: PatternSet) -> list:
    """Image indices of the pattern/inverse pairs of :func:`_hf_bits`, both axes."""
    idx = []
    for axis, n in (("col", ps.col_bits), ("row", ps.row_bits)):
        pairs = ps.pair_indices(axis)  # MSB first: bit b is row n-1-b
        for b in _hf_bits(ps):
            idx.extend(pairs[n - 1 - b].tolist())
    return idx


#: Bit classifiers: ``robust`` (direct/global separation, Moreno & Taubin) or ``simple`` (pattern > inverse).
METHODS = DECODE_METHODS


@dataclass(frozen=True)
class DecodeOptions:
    """The decoding options a user sets (:func:`decode` has the rest).

    ``method`` one of :data:`METHODS`; ``shadow_threshold`` minimum ``white - black`` and
    ``contrast_threshold`` minimum ``|pattern - inverse|`` per bit, in 8-bit grey levels (scaled for
    16-bit data). Raises ``ValueError`` for an unknown method or a threshold that is not a finite
    number from 0 to 255.
    """

    method: str = "robust"
    shadow_threshold: float = 10.0
    contrast_threshold: float = 3.0
    gamma: str | float = "auto"
    camera_noise: float | None = None

    def __post_init__(self):
        if self.method not in METHODS:
            raise ValueError(f"decode method must be one of {', '.join(METHODS)}, got {self.method!r}")
        # the thresholds, gamma and camera noise: the phase decoder's own checks (without importing that decoder)
        _decoded.check_phase_options(self.gamma, self.camera_noise, self.shadow_threshold, self.contrast_threshold)

    def phase_options(self):
        """The :class:`procam.decode.phase.PhaseOptions` of these options (for the phase families)."""
        from .phase import PhaseOptions

        return PhaseOptions(gamma=self.gamma, camera_noise=self.camera_noise, shadow_threshold=self.shadow_threshold,
                            contrast_threshold=self.contrast_threshold)


def decode_with(stack: np.ndarray, pattern_set, options: DecodeOptions = DecodeOptions(), *,
                extras: bool = True) -> DecodeResult:
    """Decode ``stack`` with the user's ``options``, whatever the family: :func:`decode` for a Gray code,
    :func:`procam.decode.phase.decode_phase` for the phase families."""
    if isinstance(pattern_set, PatternSet):
        return decode(stack, pattern_set, options.method, shadow_threshold=options.shadow_threshold,
                      contrast_threshold=options.contrast_threshold, extras=extras)
    from .phase import decode_phase

    return decode_phase(stack, pattern_set, options.phase_options(), extras=extras)


def decode(stack: np.ndarray, pattern_set: PatternSet, method: str = "robust", *,
           shadow_threshold: float = 10.0, contrast_threshold: float = 3.0,
           direct_threshold: float = 5.0, black_fraction: float = 0.0,
           full_scale: float | None = None, max_dropped_bits: int = 3, band: int = 64,
           threads: int | None = None, extras: bool = True) -> DecodeResult:
    """Decode a Gray-code image stack (a phase family's goes to :func:`procam.decode.phase.decode_phase`, with
    ``shadow_threshold`` and ``contrast_threshold``; see :func:`decode_with` for its other options).

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
        Robust only: Nayar's ``b``, the fraction of light a black projector pixel still emits, *after* the
        black frame has been subtracted (which removes ambient light and the projector's black level).
        Default 0.  Moreno's code uses 0.5 on raw images; measured on synthetic interreflections
        (tests/test_decode.py), 0.5 doubles the direct-light estimate, so the robust rule falls back to the
        plain comparison exactly where global light makes it wrong.
    full_scale : float, optional
        The input's full-scale value; thresholds are multiplied by ``full_scale / 255``.
    max_dropped_bits : int
        How many of the finest bits may be uncertain at a pixel (stripes the camera cannot resolve,
        a pixel on a stripe edge) before the pixel is invalid; the certain bits above them still give
        the code to within ``2^dropped`` codes, and the value is that block's centre
        (``dropped_col``/``dropped_row`` say how many were left out).  0 = every bit must be certain.
    band, threads : int
        Rows processed at a time and worker threads (speed only; default 1 thread: on 2 cores a second
        thread gained nothing measurable, see benchmarks/decode.py).
    extras : bool
        Compute ``confidence``, ``direct`` and ``global_`` (else they are None: a quarter of the time when only
        the projector coordinates are needed, as for the corners).

    Returns
    -------
    DecodeResult
    """
    if not isinstance(pattern_set, PatternSet):  # a phase family: its own decoder, with the default options
        return decode_with(stack, pattern_set, DecodeOptions(method, shadow_threshold, contrast_threshold),
                           extras=extras)
    ps = pattern_set
    stack = _decoded.checked_stack(stack, ps.count)
    if method not in METHODS:
        raise ValueError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    fs = _files.full_scale_of(stack) if full_scale is None else float(full_scale)
    scale = fs / 255.0
    K, H, W = stack.shape
    robust = method == "robust"
    out = {
        "col": np.empty((H, W), np.float32), "row": np.empty((H, W), np.float32),
        "rcol": np.empty((H, W), np.uint8), "rrow": np.empty((H, W), np.uint8),
        "conf": np.empty((H, W), np.float32) if extras else None,
        "dcol": np.empty((H, W), np.uint8), "drow": np.empty((H, W), np.uint8),
        "direct": np.empty((H, W), np.float32) if robust and extras else None,
        "global": np.empty((H, W), np.float32) if robust and extras else None,
    }
    wide = np.int16 if stack.dtype == np.uint8 else np.int32
    params = dict(ps=ps, robust=robust, hf=_hf_pairs(ps), hf_bit=_hf_bits(ps)[0] + 1,
                  tshadow=_int_threshold(shadow_threshold * scale, wide),
                  tcontrast=contrast_threshold * scale, tcontrast_int=_int_threshold(contrast_threshold * scale,
                                                                                    stack.dtype),
                  tdirect=direct_threshold * scale, b=float(black_fraction), wide=wide,
                  max_dropped=int(max_dropped_bits))
    bands = [slice(y0, min(H, y0 + band)) for y0 in range(0, H, band)]
    if threads is None:
        threads = 1
    if threads > 1 and len(bands) > 1:
        with ThreadPoolExecutor(threads) as ex:
            hists = list(ex.map(lambda sl: _decode_band(stack, sl, out, **params), bands))
    else:
        hists = [_decode_band(stack, sl, out, **params) for sl in bands]
    codes_col = np.sum([h[0] for h in hists], axis=0)
    codes_row = np.sum([h[1] for h in hists], axis=0)
    rcol, rrow = out["rcol"], out["rrow"]
    return DecodeResult(out["col"], out["row"], rcol == OK, rrow == OK, rcol, rrow, out["conf"],
                        out["direct"], out["global"], ps, out["dcol"], out["drow"], codes_col, codes_row)


def _int_threshold(t: float, dtype):
    """``t`` as a scalar of the integer ``dtype`` that compares the same with its values (``x >= ceil(t)`` is
    ``x >= t`` for integers): comparing an integer array with a float makes a float64 copy of it."""
    import math

    info = np.iinfo(dtype)
    ti = math.ceil(t)
    return np.dtype(dtype).type(ti) if info.min <= ti <= info.max else t


def _decode_band(stack, sl, out, *, ps, robust, hf, hf_bit, tshadow, tcontrast, tcontrast_int, tdirect, b, wide,
                 max_dropped):
    """Decode rows ``sl`` of ``stack`` into the arrays of ``out`` (see :func:`decode`); returns the band's
    histograms of decoded codes (column, row) in projector pixels, out-of-range codes included."""
    import cv2

    blk = stack[:, sl, :]
    white = blk[ps.white].astype(wide)
    span = white - blk[ps.black].astype(wide)
    shadow = span < tshadow
    if robust:
        # Direct/global separation on black-subtracted values: the black frame carries the ambient light,
        # which would otherwise count as "global" light.
        mx, mn = blk[hf[0]].copy(), blk[hf[0]].copy()
        for k in hf[1:]:
            np.maximum(mx, blk[k], out=mx)
            np.minimum(mn, blk[k], out=mn)
        if b == 0.0:  # the default: integer arithmetic, L_d = L+ - L-, L_g = 2 L-
            blackw = blk[ps.black].astype(wide)
            lpw = mx.astype(wide) - blackw
            lmw = np.maximum(mn.astype(wide) - blackw, 0)
            ld = (lpw - lmw).astype(np.float32)
            lg = (2 * lmw).astype(np.float32)
            blackf = blackw
        else:
            blackf = blk[ps.black].astype(np.float32)
            lp = mx.astype(np.float32) - blackf
            lm = np.maximum(mn.astype(np.float32) - blackf, 0.0)
            ld = (lp - lm) * np.float32(1.0 / (1.0 - b))
            lg = (lm - np.float32(b) * lp) * np.float32(2.0 / (1.0 - b * b))
            neg = lg <= 0
            ld[neg] = lp[neg]
            lg[neg] = 0.0
        if out["direct"] is not None:
            out["direct"][sl] = ld
            out["global"][sl] = lg
        weak = ld < tdirect
        # pixels where direct light does not dominate: Moreno's rule decides their low-frequency bits
        hard = np.flatnonzero(~(ld > lg) & ~weak & ~shadow)
        ld_h, lg_h, bl_h = ld.ravel()[hard], lg.ravel()[hard], blackf.ravel()[hard]
    minabs = None
    hists = []
    for axis, key, rkey, dkey, size, full, offset in (
            ("col", "col", "rcol", "dcol", ps.code_width, ps.width, ps.col_offset),
            ("row", "row", "rrow", "drow", ps.code_height, ps.height, ps.row_offset)):
        code = np.zeros(span.shape, np.uint16 if max(ps.col_bits, ps.row_bits) <= 16 else np.uint32)
        prev = np.zeros(span.shape, bool)
        amin = None
        certain = np.empty(span.shape, bool)
        prefix = ~shadow  # all bits so far certain
        if robust:  # too little direct light: no bit is certain
            prefix &= ~weak
            amb_break = weak & ~shadow
        else:
            amb_break = np.zeros(span.shape, bool)
        used = np.zeros(span.shape, np.uint8)  # number of leading certain bits
        nbits = ps.col_bits if axis == "col" else ps.row_bits
        for j, (a, i) in enumerate(ps.pair_indices(axis)):
            bitno = nbits - 1 - j
            p = blk[a]
            q = blk[i]
            bit = p > q
            ad = cv2.absdiff(p, q)
            if out["conf"] is not None:
                amin = ad if amin is None else np.minimum(amin, ad, out=amin)
            np.greater_equal(ad, tcontrast_int, out=certain)
            if robust and hard.size and bitno >= hf_bit:
                ph, qh = p.ravel()[hard] - bl_h, q.ravel()[hard] - bl_h
                # Moreno's rule, with a noise margin (at its boundary, all global light on one side, it has none)
                zero = (ph <= ld_h - tcontrast) & (qh >= lg_h + tcontrast)
                one = (ph >= lg_h + tcontrast) & (qh <= ld_h - tcontrast)
                # and the comparison wherever it cannot be wrong: p - p_inv = +-(1-b) L_d + (g_p - g_inv)
                # with |g_p - g_inv| <= L_g, so a difference beyond L_g - (1-b) L_d fixes the sign
                dh = ph - qh
                sure = np.abs(dh) >= lg_h - (1.0 - b) * ld_h + tcontrast
                one |= sure & (dh > 0)
                zero |= sure & (dh < 0)
                bit.ravel()[hard] = one
                ambh = ~zero & ~one
                certain.ravel()[hard] &= ~ambh
                amb_break.ravel()[hard] |= prefix.ravel()[hard] & ambh
            prefix &= certain
            used += prefix
            prev ^= bit  # Gray -> binary: b_i = b_(i+1) xor g_i
            code <<= 1
            code |= prev
        if amin is not None:
            minabs = amin if minabs is None else np.minimum(minabs, amin)
        # Keep the leading certain bits: the code is then known to a block of 2^dropped codes (a Gray-code
        # prefix fixes the binary prefix); the value is the centre of the block's projector pixels.
        dropped = np.uint8(nbits) - used
        d32 = dropped.astype(np.int32)
        code = code.astype(np.int32)
        lo = (code >> d32) << d32
        hi = lo + (1 << d32) - 1
        lo -= offset
        hi -= offset
        r = out[rkey][sl]
        r.fill(0)
        r[(hi < 0) | (lo >= size)] = OUT_OF_RANGE
        too_coarse = dropped > max_dropped
        counted = ~too_coarse & ~shadow & (hi >= 0)   # codes known well enough, in range or not
        nbins = (1 << nbits) * ps.step
        if ps.step > 1:  # projector pixels from codes (one code per step x step pixels)
            lo *= ps.step
            hi *= ps.step
            hi += ps.step - 1
        hists.append(np.bincount(np.clip(lo[counted], 0, nbins - 1), minlength=nbins))
        if robust:
            r[too_coarse & amb_break] = AMBIGUOUS
        r[too_coarse & ~amb_break] = LOW_CONTRAST
        r[shadow] = SHADOW
        # the block's projector pixels on the panel; the value is their centre, written where it goes (as the
        # reasons above): fresh arrays for each would cost a tenth of the decode
        np.maximum(lo, 0, out=lo)
        np.minimum(hi, full - 1, out=hi)
        val = out[key][sl]
        np.multiply(lo + hi, np.float32(0.5), out=val, dtype=np.float32)
        ok = r == OK
        np.copyto(val, np.float32(np.nan), where=~ok)
        np.multiply(dropped, ok, out=out[dkey][sl])  # the bits left out, where decoded
    if out["conf"] is not None:
        spanf = span.astype(np.float32)
        with np.errstate(divide="ignore", invalid="ignore"):
            conf = np.where(span > 0, minabs / np.maximum(spanf, 1.0), 0.0)
        out["conf"][sl] = np.clip(conf, 0.0, 1.0)
    return hists
