"""Are a Gray code's bits in the order the description says?  Judged from the frames themselves.

Bit ``b`` (0 = least significant) of a Gray code changes every ``2 ** (b + 1)`` codes, so across the panel the
least significant bit has the most stripe edges and every more significant one about half as many.  In the camera
image this shows as the share of neighbouring pixels whose bit differs (the **edge density**), whatever the
camera's view of the panel.  Read in the order the description gives (most significant first by default), the
densities must grow; when they fall, the bits come least significant first (or the other way round), which no
other check sees: a pattern still has its inverse beside it, and the XOR of all bits (the only cross-check a
Gray-phase capture has between its Gray code and its fringes) does not depend on their order.

:func:`check_bit_order` raises a one-line :class:`~procam.errors.CaptureError` naming the axis, the frames, the
densities and the ``bit_order`` to write.  Every Gray block is judged: the Gray family's two axes
(:class:`~procam.patterns.PatternSet`) and each Gray block of a hybrid (:class:`~procam.patterns.PhaseSet`).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .. import patterns
from ..errors import CaptureError

#: Rank correlation (Spearman) of the edge densities with the bits' described significance below which the
#: order is judged reversed (a right order gives about +1, a reversed one about -1).
REVERSED_BELOW = -0.6
#: Fewest neighbouring pixel pairs, both sure of their bit, for a bit's edge density to count.
MIN_PAIRS = 200


def _bits_in_described_order(ps, axis: str) -> tuple[list[tuple[int, int | None]], str, str] | None:
    """``([(frame, inverse frame or None), ...] most significant first as described, bit_order, where)`` of the
    Gray bits of ``axis``, or None when the axis has no Gray code."""
    if not patterns.is_phase(ps):
        pairs = [(int(a), int(i)) for a, i in ps.pair_indices(axis)]
        return pairs, ps.bit_order, "patterns.json"
    g = ps.gray_block(axis)
    if g is None:
        return None
    per = 2 if g.inverse else 1
    by_bit = {}
    for j in range(0, g.count, per):
        bit, _, comp = g.gray_frame(j)
        if not comp:
            by_bit[bit] = (g.first + j, g.first + j + 1 if g.inverse else None)
    index = ps.blocks.index(g)
    return [by_bit[b] for b in range(g.bits - 1, -1, -1)], g.bit_order, f"sequence[{index}] in patterns.json"


def _every(img: np.ndarray, stride: int) -> np.ndarray:
    """``img[::stride, ::stride]`` of an (H, W) image, contiguous.  For 8-bit images and a stride of 2, 4 or 8 (a
    width it divides) each group of ``stride`` bytes of a row is read as one little-endian integer and cast to its
    low byte, the group's first pixel: one vectorised pass where numpy gathers the bytes one by one (the larger
    part of this check's time)."""
    rows = img[::stride]
    wide = {2: "<u2", 4: "<u4", 8: "<u8"}.get(stride)
    if rows.dtype != np.uint8 or wide is None or rows.shape[1] % stride or rows.strides[1] != 1:
        return np.ascontiguousarray(rows[:, ::stride])
    return rows.view(wide).astype(np.uint8)


def _edge_densities(stack: np.ndarray, frames, stride: int) -> np.ndarray:
    """(n,) share of neighbouring pixels (across and down, every ``stride``-th pixel) whose bit differs, among
    those sure of it; NaN where fewer than :data:`MIN_PAIRS` are."""
    integer = stack.dtype.kind in "ui"
    if frames[0][1] is None:
        p = np.stack([_every(stack[a], stride).astype(np.float32) for a, _ in frames])
        lo, hi = p.min(axis=0), p.max(axis=0)
        span = hi - lo
        thr = (lo + hi) / 2.0
        sure_lit = span > 0.25 * float(np.percentile(span, 99))
    out = np.full(len(frames), np.nan)
    for k, (a, i) in enumerate(frames):
        if i is None:
            a = p[k]
            bit, sure = a > thr, sure_lit & (np.abs(a - thr) > 0.25 * span)
        elif integer:  # the same test on the integers: no float copies, the percentile from their histogram
            a, i, c, counts = _absdiff_and_histogram(_every(stack[a], stride), _every(stack[i], stride))
            # an integer exceeds a real t exactly when it exceeds floor(t): no float copy of c
            bit, sure = a > i, c > math.floor(0.25 * _percentile99_of_counts(counts, c.size))
        else:
            a, i = _every(stack[a], stride).astype(np.float32), _every(stack[i], stride).astype(np.float32)
            c = np.abs(a - i)
            bit, sure = a > i, c > 0.25 * float(np.percentile(c, 99))
        n, d = 0, 0
        for ax in (0, 1):
            s0 = [slice(None), slice(None)]
            s1 = [slice(None), slice(None)]
            s0[ax], s1[ax] = slice(None, -1), slice(1, None)
            both = sure[tuple(s0)] & sure[tuple(s1)]
            n += int(np.count_nonzero(both))
            d += int(np.count_nonzero(both & (bit[tuple(s0)] != bit[tuple(s1)])))
        if n >= MIN_PAIRS:
            out[k] = d / n
    return out


def _absdiff_and_histogram(a: np.ndarray, i: np.ndarray):
    """``(a, i, |a - i|, its histogram)`` of two (H, W) integer images (samples of a stack's frames): 8-bit ones
    differenced by OpenCV in 8 bits (no wider copy), others in 32-bit integers; the histogram counts 0, 1, 2, ..."""
    if a.dtype == np.uint8 and i.dtype == np.uint8:
        import cv2

        a, i = np.ascontiguousarray(a), np.ascontiguousarray(i)
        c = cv2.absdiff(a, i)
        if c.size < 2 ** 24:  # OpenCV's float32 counts are exact
            return a, i, c, cv2.calcHist([c], [0], None, [256], [0, 256]).ravel().astype(np.int64)
        return a, i, c, np.bincount(c.ravel(), minlength=256)
    c = np.abs(a.astype(np.int32) - i)
    return a, i, c, np.bincount(c.ravel())


def _percentile99_of_integers(c: np.ndarray) -> float:
    """``float(np.percentile(c.astype(np.float32), 99))`` of non-negative integers ``c``, without sorting them
    (:func:`_percentile99_of_counts` of their histogram)."""
    return _percentile99_of_counts(np.bincount(c.ravel()), c.size)


def _percentile99_of_counts(counts: np.ndarray, n: int) -> float:
    """``float(np.percentile(c.astype(np.float32), 99))`` of the ``n`` non-negative integers ``c`` whose histogram
    is ``counts``: the two order statistics the linear rule interpolates are read off the histogram, and numpy
    interpolates them with the same weight (the same float32 arithmetic, so the same bits)."""
    pos = (n - 1) * 0.99  # numpy's virtual index of the linear rule (q = 99 / 100)
    lo = int(np.floor(pos))
    cum = np.cumsum(counts)
    v_lo, v_hi = np.searchsorted(cum, [lo, min(lo + 1, n - 1)], side="right")
    return float(np.quantile(np.array([v_lo, v_hi], np.float32), pos - lo))


def _spearman(x: np.ndarray) -> float:
    """Rank correlation of ``x`` with its index (ties ranked by order)."""
    n = len(x)
    rx = np.argsort(np.argsort(x, kind="stable"), kind="stable").astype(float)
    ri = np.arange(n, dtype=float)
    rx -= rx.mean()
    ri -= ri.mean()
    return float(np.sum(rx * ri) / np.sqrt(np.sum(rx * rx) * np.sum(ri * ri)))


def check_bit_order(stack: np.ndarray, ps, folder, files) -> None:
    """Raise :class:`CaptureError` when an axis's Gray bits come in the other order than the description's
    ``bit_order`` (module docstring).  ``stack`` is the (K, H, W) capture, ``files`` its frames' paths."""
    H, W = stack.shape[1:3]
    stride = max(1, min(H, W) // 400)
    for axis, name in (("col", "column"), ("row", "row")):
        found = _bits_in_described_order(ps, axis)
        if found is None or len(found[0]) < 3:
            continue
        frames, order, where = found
        dens = _edge_densities(stack, frames, stride)
        ok = np.isfinite(dens)
        if ok.sum() < 3 or _spearman(dens[ok]) >= REVERSED_BELOW:
            continue
        kept = sorted((f[0], d) for f, d, k in zip(frames, dens, ok) if k)  # (frame, density) in frame order
        (first, d_first), (last, d_last) = kept[0], kept[-1]
        said, seen = (("most", "least") if order == "msb-first" else ("least", "most"))
        fix = "lsb-first" if order == "msb-first" else "msb-first"
        raise CaptureError(
            f"{folder}: the {name} Gray bits come {seen} significant first, the description says {said} "
            f"(bit_order {order}): from frame to frame their stripes get {'coarser' if d_first > d_last else 'finer'} "
            f"— stripe edges at {d_first:.1%} of neighbouring pixels in frame #{first} ({Path(files[first]).name}), "
            f"{d_last:.1%} in #{last} ({Path(files[last]).name}) — write \"bit_order\": \"{fix}\" in {where} "
            "(docs/patterns.md), or check that the file names sort in capture order")
