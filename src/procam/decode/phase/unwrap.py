"""Temporal phase unwrapping: from the fringe fractions of several blocks to an absolute projector coordinate, per
pixel, marking (never guessing) a pixel whose orders disagree.

Every block gives the fraction ``u`` in [0, 1) of its period ``P`` the pixel is at: ``(x - x0) / P = m + u`` with
an unknown order ``m`` (``x0`` where the block's phase is 0).  ``su`` is the fraction's standard deviation.

:func:`hierarchical` (family ``phase``)
    The coarsest block spans the panel (period >= its size): ``x = x0 + P u`` outright.  Each finer block takes the
    order that puts it nearest: ``t = (x - x0) / P - u``, ``m = round(t)``; the residual ``t - m`` (cycles) is the
    orders' disagreement.  When each period is a whole number of the next finer one, the result is taken modulo
    the coarsest (a pixel at the panel's edge whose coarse estimate wrapped to the other edge keeps its place);
    otherwise a pixel whose coarse estimate is within 4 standard deviations of the wrap is LOW_MODULATION.  Marked: a residual beyond ``tolerance`` (ORDER_DISAGREE), a coarser estimate too noisy
    to order the finer periods, ``sd(t) > max_sigma`` (LOW_MODULATION).
:func:`heterodyne` (three periods ``p1 < p2 < p3``)
    The beats ``u12 = frac(u1 - u2)`` (period ``l12 = p1 p2 / (p2 - p1)``), ``u23 = frac(u2 - u3)`` (``l23``) and
    ``u123 = frac(u12 - u23)`` (``l123 >= panel``): absolute ``x123``; it orders ``u12``, which orders each of
    ``u1``, ``u2``, ``u3``; the result is their inverse-variance mean, and the three must agree to ``tolerance`` of
    the smallest period (ORDER_DISAGREE otherwise), as must each level with the one above it.
:func:`gray_orders` (family ``gray-phase``)
    The Gray code gives the order ``m1`` of the period the pixel is in.  Near a period boundary the phase's noise
    can carry the fraction across the wrap while the Gray code stays (or the Gray bit that changes there reads the
    other side): where the fraction is within a quarter period of 0 (of 1) and the bit that changes at the Gray
    interval's end (start) is partway through its blurred edge while the other boundary bit is not, the pixel is
    at that boundary and takes the order on the phase's side of it.  An unsure bit other than the two boundary
    bits, or any unsure bit mid-period, marks LOW_CONTRAST.  With the complementary bit, ``k2 = (V2 + 1) >> 1`` from all ``n + 1``
    bits is right near the boundaries whatever the boundary bit reads (Zhang et al. 2018): the order is ``k2``
    for ``u < 1/4``, ``k2 - 1`` for ``u > 3/4``, ``m1`` between; and where both are sure (``u`` within 0.1-0.4
    or 0.6-0.9) they must agree (ORDER_DISAGREE).  Plain Gray codes have no second order to compare: their
    stripe-edge errors are what the complementary bit removes.
"""

from __future__ import annotations

import numpy as np

from ..decoded import LOW_CONTRAST, LOW_MODULATION, OK, ORDER_DISAGREE

#: Largest orders' disagreement (cycles of the finer period) a pixel may have.
TOLERANCE = 0.25
#: Largest standard deviation (cycles of the finer period) of the coarser estimate that orders it.
MAX_SIGMA = 0.1


def hierarchical(levels, reason: np.ndarray, *, tolerance: float = TOLERANCE, max_sigma: float = MAX_SIGMA):
    """``(x, sigma_x)`` from ``levels`` = ``[(u, su, period, x0), ...]`` coarsest first (the first spans the panel);
    ``reason`` (uint8) is updated in place (see the module docstring)."""
    u, su, span, x0 = levels[0]
    f = u.dtype.type
    x = f(x0) + f(span) * u
    sx = f(span) * su
    period = span
    if not _divides([lv[2] for lv in levels]):
        # the cue's wrap is not a whole number of every finer period: a pixel whose cue estimate may have wrapped
        # (within 4 of its standard deviations of the seam) cannot be placed
        near = (np.minimum(span * u, span * (1 - u)) < 4 * sx) & (reason == OK)
        reason[near] = LOW_MODULATION
    for u, su, period, x0 in levels[1:]:
        t = x - f(x0)
        t *= f(1.0 / period)
        t -= u
        m = np.rint(t)
        t -= m
        ok = reason == OK
        low = sx > f(max_sigma * period)
        low &= ok
        np.copyto(reason, np.uint8(LOW_MODULATION), where=low)
        np.abs(t, out=t)
        far = t > f(tolerance)
        far &= ok
        far &= ~low
        np.copyto(reason, np.uint8(ORDER_DISAGREE), where=far)
        m += u
        m *= f(period)
        m += f(x0)
        x = m
        sx = f(period) * su
    return (_seam(x, levels[0][3], span, period) if _divides([lv[2] for lv in levels]) else x), sx


def _divides(periods) -> bool:
    """Every period (coarsest first) a whole number of times in the one before it."""
    return all(abs(a / b - round(a / b)) < 1e-6 for a, b in zip(periods[:-1], periods[1:]))


def _seam(x, x0: float, span: float, period: float):
    """Coordinates modulo the absolute level's ``span`` when it is a whole number of the finest ``period`` s (the
    finest fringes repeat with it): a pixel whose coarse estimate wrapped across the panel's edge keeps its place
    (the fine phase is exact to a multiple of the span)."""
    k = span / period
    if abs(k - round(k)) > 1e-6:
        return x
    f = x.dtype.type
    v = x - f(x0)  # within a period of [0, span): np.mod's result by one addition or subtraction
    np.add(v, f(span), out=v, where=v < 0)
    np.subtract(v, f(span), out=v, where=v >= f(span))
    v += f(x0)
    return v


def heterodyne(levels, reason: np.ndarray, *, tolerance: float = TOLERANCE, max_sigma: float = MAX_SIGMA):
    """``(x, sigma_x)`` from three ``levels`` ``(u, su, period, x0)`` (any order; one ``x0``); ``reason`` updated in
    place (see the module docstring).  Coordinates are computed relative to ``x0`` and in place where the arrays
    allow (the decoder's band pass calls it per band)."""
    (u1, s1, p1, x0), (u2, s2, p2, _), (u3, s3, p3, _) = sorted(levels, key=lambda lv: lv[2])
    l12 = p1 * p2 / (p2 - p1)
    l23 = p2 * p3 / (p3 - p2)
    l123 = l12 * l23 / (l23 - l12)
    f = np.asarray(u1).dtype.type
    q1, q2, q3 = s1 * s1, s2 * s2, s3 * s3  # the fractions' variances
    u12 = _frac_inplace(u1 - u2)
    u23 = _frac_inplace(u2 - u3)
    x = _frac_inplace(u12 - u23)  # u123
    x *= f(l123)  # x - x0 of the beat of the beats
    var = q2 * f(4.0)
    var += q1
    var += q3
    bad_sigma = var > f((max_sigma * l12 / l123) ** 2)
    # level 1: the beat of the beats orders the first beat
    x *= f(1.0 / l12)
    x -= u12
    bad_order = _order_off(x, tolerance)  # x is now the order m12
    x += u12
    x *= f(l12)  # x12 - x0
    np.add(q1, q2, out=var)
    bad_sigma |= var > f((max_sigma * p3 / l12) ** 2)
    # level 2: the first beat orders each fringe; the result is their inverse-variance mean
    lo = hi = None
    num = wsum = None
    for u, q, p in ((u1, q1, p1), (u2, q2, p2), (u3, q3, p3)):
        t = x * f(1.0 / p)
        t -= u
        bad_order |= _order_off(t, tolerance)
        t += u
        t *= f(p)  # x_i - x0
        w = np.maximum(q, f(1e-12 / p ** 2))
        np.divide(f(1.0 / p ** 2), w, out=w)  # 1 / var(x_i)
        if num is None:
            num, wsum, lo, hi = t * w, w, t.copy(), t
        else:
            num += t * w
            wsum += w
            np.minimum(lo, t, out=lo)
            np.maximum(hi, t, out=hi)
    # the three fringes must land on one coordinate
    hi -= lo
    bad_order |= hi > f(tolerance * p1)
    num /= wsum
    num += f(x0)
    x = num
    if all(abs(l123 / p - round(l123 / p)) < 1e-6 for p in (p1, p2, p3)):
        x = _seam(x, x0, l123, p1)
    ok = reason == OK
    np.copyto(reason, np.uint8(LOW_MODULATION), where=bad_sigma & ok)
    np.copyto(reason, np.uint8(ORDER_DISAGREE), where=bad_order & ok & ~bad_sigma)
    np.sqrt(wsum, out=wsum)
    return x, np.divide(f(1.0), wsum, out=wsum)


def _frac_inplace(v):
    """``v - floor(v)`` in place."""
    v -= np.floor(v)
    return v


def _order_off(t, tolerance: float):
    """Round ``t`` to the nearest order in place; where it was further than ``tolerance`` from it (bool)."""
    m = np.rint(t)
    t -= m
    np.abs(t, out=t)
    off = t > tolerance
    np.copyto(t, m)
    return off


def gray_value(bits: np.ndarray) -> np.ndarray:
    """Binary value (int32) of Gray-code bits ``bits`` (n <= 31, ...) bool, most significant first: the code as an
    integer of the narrowest unsigned type, then the prefix XOR ``b = g ^ (g >> 1) ^ (g >> 2) ...`` in ``log2 n``
    shifts."""
    n = len(bits)
    if n > 31:
        raise ValueError(f"at most 31 Gray bits, got {n}")
    kind = np.uint8 if n <= 8 else np.uint16 if n <= 16 else np.uint32
    g = np.zeros(bits.shape[1:], kind)
    for b in bits:
        g += g  # a shift by one, faster than numpy's shift of small integers
        g |= b.view(np.uint8) if kind is np.uint8 else b
    shift = 1
    while shift < n:
        g ^= g >> shift
        shift <<= 1
    return g.astype(np.int32)


def _low_bit(m: np.ndarray) -> np.ndarray:
    """Index (0 = least significant) of the lowest set bit of ``m`` (> 0): the Gray bit that changes between
    ``m - 1`` and ``m``; -1 where ``m <= 0``."""
    m = np.asarray(m, np.int64)
    low = m & -m
    out = np.full(m.shape, -1, np.int64)
    pos = low > 0
    out[pos] = np.log2(low[pos].astype(np.float64)).round().astype(np.int64)
    return out


def gray_orders(bits: np.ndarray, contrast: np.ndarray, certain: np.ndarray, u: np.ndarray, reason: np.ndarray,
                comp=None, comp_certain=None, margin=0.0, su=None) -> np.ndarray:
    """The fringe order ``m`` (int32) of every pixel from its Gray bits (see the module docstring).

    Parameters
    ----------
    bits, contrast, certain : (n_bits, ...) most significant first: the bits read (bool), their contrast (the
        pattern's distance from its inverse or threshold, >= 0, any unit) and whether each is sure.
    u : (...) the fringe fraction.
    reason : (...) uint8, updated in place.
    comp, comp_certain : (...) bool, the complementary bit and its certainty, or None.
    margin : (...) or scalar, how much lower (units of ``contrast``) a boundary bit's contrast must be than the
        pixel's typical one and than the other boundary bit's for the pixel to be at that boundary (a few standard
        deviations of the contrast's noise).
    su : (...) the fraction's standard deviation: the phase can have crossed the wrap only within 4 of them of it
        (None: within a quarter period).
    """
    n = len(bits)
    m1 = gray_value(bits)
    near = (u < 0.25) | (u > 0.75)
    if comp is not None:
        unsure = ~certain
        n_unsure = unsure[0].astype(np.uint8)
        for b in unsure[1:]:
            n_unsure += b.view(np.uint8)
        which = np.zeros(u.shape, np.int32)  # the first unsure bit, most significant first (0 when none)
        for b in range(n - 1, 0, -1):
            np.copyto(which, b, where=unsure[b])
        np.copyto(which, 0, where=unsure[0])
        np.subtract(n, which, out=which)
        m1_alt = np.left_shift(np.int32(1), which)
        m1_alt -= 1
        m1_alt ^= m1  # that bit read the other way round
        # the order from all n + 1 bits, k2 = (v2 + 1) >> 1 with v2 = 2 m1 + (comp ^ parity(m1)), is m1 + e with
        # e = comp ^ parity(m1)
        c = comp.view(np.uint8) if comp.dtype == bool else comp.astype(np.uint8)
        e = (m1 & 1).astype(np.uint8)
        e ^= c
        e_alt = (m1_alt & 1).astype(np.uint8)
        e_alt ^= c
        k2_moved = (m1 + e) != (m1_alt + e_alt)  # k2 depends on the unsure bit
        # m = k2 for u < 1/4, k2 - 1 for u > 3/4, m1 between
        low8, high8 = (u < 0.25).view(np.uint8), (u > 0.75).view(np.uint8)
        m = m1 + (e & low8)
        m -= (e ^ 1) & high8
        # near a boundary k2 must not depend on an unsure bit and the complementary bit must be sure; mid-period
        # every ordinary bit must be sure
        unsure_near = near & ((n_unsure > 1) | ((n_unsure == 1) & k2_moved) | ~comp_certain)
        ok = reason == OK
        np.copyto(reason, np.uint8(LOW_CONTRAST), where=(unsure_near | (~near & (n_unsure > 0))) & ok)
        both = (n_unsure == 0) & comp_certain & (((u > 0.1) & (u < 0.4)) | ((u > 0.6) & (u < 0.9)))
        # where both orders are sure they must agree: m1 is k2 (e = 0) below the middle of the period, k2 - 1
        # (e = 1) above
        e ^= (u >= 0.5).view(np.uint8)
        both &= e.view(bool)
        np.copyto(reason, np.uint8(ORDER_DISAGREE), where=both & (reason == OK))
        return m
    # plain Gray code: which of the interval's two boundaries is the pixel at? The bit that changes there is
    # partway through its blurred edge: its contrast under 0.7 of the pixel's typical one and clearly (by
    # `margin`) below that of the other boundary's bit
    start_bit, end_bit = _low_bit(m1), _low_bit(m1 + 1)
    idx = np.arange(n)

    def contrast_of(bit):
        row = np.clip(n - 1 - bit, 0, n - 1)
        c = np.take_along_axis(contrast, row[None], axis=0)[0]
        return np.where((bit >= 0) & (bit < n), c, np.inf), row

    c_start, start_row = contrast_of(start_bit)
    c_end, end_row = contrast_of(end_bit)
    full = np.median(contrast, axis=0)  # most bits are far from their edges
    reach = 0.25 if su is None else np.minimum(4.0 * su, 0.25)
    edge = np.minimum(0.7 * full, full - margin)
    near0, near1 = u < reach, u > 1 - reach
    start_edge, end_edge = c_start < edge, c_end < edge
    up = near0 & end_edge & (c_end < c_start - margin)   # the phase wrapped past the interval's end
    down = near1 & start_edge & (c_start < c_end - margin)  # ... or back past its start
    m = m1 + up.astype(np.int64) - down.astype(np.int64)
    # the phase at a wrap that no Gray bit shows an edge next to: either side is possible, so neither is taken
    ambiguous = (near0 & ~up & ~start_edge) | (near1 & ~down & ~end_edge)
    reason[ambiguous & (reason == OK)] = ORDER_DISAGREE
    # an unsure bit is allowed only where it is one of the two boundary bits
    boundary = (idx.reshape((-1,) + (1,) * u.ndim) == start_row) & (start_bit >= 0)
    boundary |= (idx.reshape((-1,) + (1,) * u.ndim) == end_row) & (end_bit >= 0) & (end_bit < n)
    other_unsure = (~certain & ~boundary).any(axis=0)
    reason[(other_unsure | (~near & ~certain.all(axis=0))) & (reason == OK)] = LOW_CONTRAST
    return m


def neighbour_orders(x, sx, reason, u, su, coarse, coarse_sd, period: float, x0: float, size: int, *, window: int,
                     tolerance: float = TOLERANCE, max_sigma: float = MAX_SIGMA, passes: int = 2) -> int:
    """Order the pixels whose own coarser fringes were too faint (LOW_MODULATION) from their decoded neighbours.

    The projector coordinate is smooth over a surface, so where a pixel's coarse estimate is too noisy to order its
    finest fringes (a black square of the board, a dim wall), the decoded pixels around it predict it: a plane
    ``x = a + b dX + c dY`` fitted (least squares) to the decoded (OK) pixels of the ``window`` x ``window`` camera
    pixels around it gives ``a`` and its standard deviation (the fit's residual scatter through the fit's own
    covariance). That orders the pixel's finest fraction as a coarser level does (:func:`hierarchical`), where

    * the decoded pixels surround it (each quadrant of the window is 5 % decoded): a prediction, never an
      extrapolation across a depth edge from one side (the board's pixels do not predict the wall behind it);
    * the neighbours lie on their plane to half of ``max_sigma`` of the finest period (RMS; a window across a depth
      edge does not) and the prediction's standard deviation is at most ``max_sigma`` of it;
    * it agrees with the pixel's own coarse estimate ``coarse`` (absolute, px, standard deviation ``coarse_sd``:
      too noisy to order the fringes, not to catch a wrong period) within 4 standard deviations; and
    * the order's residual is at most ``tolerance``.

    ``x, sx``: (H, W) float32 coordinates and their standard deviations (NaN where not decoded), ``reason`` (H, W)
    uint8, all updated in place; ``u, su``: (H, W) the finest block's fraction and its standard deviation (cycles);
    ``period, x0``: that block's; ``size``: the panel's size along the axis (the coarse estimate is compared modulo
    it). ``passes``: pixels ordered in one pass help the next. Returns the number of pixels ordered.
    """
    import cv2

    H, W = reason.shape
    # the sums run over 2 x 2 blocks of pixels (at their centres): a quarter of the work, and a plane whose moments
    # move by a fraction of a per cent
    f = 2
    Hb, Wb = H // f, W // f
    wb = max(3, (window // f) | 1)
    h = wb // 2

    def box(a):
        return cv2.boxFilter(a, cv2.CV_64F, (wb, wb), normalize=False, borderType=cv2.BORDER_CONSTANT)

    first = (reason == LOW_MODULATION) & np.isfinite(u) & (su <= max_sigma) & np.isfinite(coarse)
    first[Hb * f:] = False
    first[:, Wb * f:] = False
    rows, cols = np.flatnonzero(first.any(axis=1)), np.flatnonzero(first.any(axis=0))
    if not len(rows):
        return 0
    # the sums are taken over the blocks the candidates' windows reach, not the whole image: the candidates (a board's
    # black squares, a dim wall) are a part of it.  A window inside that part sums the same blocks, and where it
    # reaches the image's edge the part does too.  A later pass's candidates are among the first's.
    by0, by1 = max(0, rows[0] // f - h), min(Hb, rows[-1] // f + h + 1)
    bx0, bx1 = max(0, cols[0] // f - h), min(Wb, cols[-1] // f + h + 1)
    part = (slice(by0 * f, by1 * f), slice(bx0 * f, bx1 * f))
    first = first[part]
    # the blocks' centres, as a column and a row (broadcast: the same products as full grids, at a fraction of the work)
    Yb = np.arange(by0, by1, dtype=np.float64)[:, None] * f + (f - 1) / 2.0
    Xb = np.arange(bx0, bx1, dtype=np.float64)[None, :] * f + (f - 1) / 2.0

    def binned(a):
        return cv2.resize(np.ascontiguousarray(a, np.float64), (bx1 - bx0, by1 - by0),
                          interpolation=cv2.INTER_AREA) * float(f * f)

    done = 0
    for one in range(passes):
        cand = first if one == 0 else first & (reason[part] == LOW_MODULATION)
        ok = reason[part] == OK
        # decoded pixels per block: the block's sum of 0s and 1s (what the area resize of binned() gives, exactly)
        o = ok.view(np.uint8)
        n_b = sum(o[i::f, j::f] for i in range(f) for j in range(f)).astype(np.float64)
        # each quadrant of the window holds decoded pixels (judged per block, then kept at the blocks' pixels)
        least = max(5.0, 0.05 * (h * f) ** 2)
        around = np.ones(n_b.shape, bool)
        for ay, ax in ((h, h), (h, 0), (0, h), (0, 0)):
            q = cv2.boxFilter(n_b, cv2.CV_64F, (h + 1, h + 1), anchor=(ax, ay), normalize=False,
                              borderType=cv2.BORDER_CONSTANT)
            around &= q >= least
        cand = cand & np.repeat(np.repeat(around, f, axis=0), f, axis=1)
        py, px = np.nonzero(cand)
        if not len(py):
            break
        at = (py // f) * (bx1 - bx0) + px // f  # each candidate's block, a flat index of the part's
        iy, ix = py + by0 * f, px + bx0 * f
        xv = np.zeros(ok.shape, np.float64)  # x - x0 in float32 where decoded (as the coordinates are), else 0
        np.subtract(x[part], np.float32(x0), out=xv, where=ok, dtype=np.float32)
        x_b, xx_b = binned(xv), binned(xv * xv)
        S = {k: box(v).ravel()[at] for k, v in (("1", n_b), ("X", n_b * Xb), ("Y", n_b * Yb), ("XX", n_b * Xb * Xb),
                                             ("YY", n_b * Yb * Yb), ("XY", n_b * Xb * Yb), ("x", x_b),
                                             ("xX", x_b * Xb), ("xY", x_b * Yb), ("xx", xx_b))}
        take, xn = _ordered(S, iy, ix, u, coarse, coarse_sd, period, x0, size, tolerance, max_sigma)
        iy, ix = iy[take], ix[take]
        if not len(iy):
            break
        x[iy, ix] = xn[take]
        sx[iy, ix] = period * su[iy, ix]
        reason[iy, ix] = OK
        done += len(iy)
    return done


def _ordered(S, iy, ix, u, coarse, coarse_sd, period, x0, size, tolerance, max_sigma):
    """The plane ``x = a + b dX + c dY`` through each candidate's window from its sums ``S`` (dict of (n,) arrays:
    the decoded pixels' count ``1``, their moments ``X, Y, XX, YY, XY`` and the coordinates' ``x, xX, xY, xx``, ``x``
    taken from ``x0``) and the rules of :func:`neighbour_orders`: ``(take (n,) bool, the ordered coordinate (n,))``
    for the candidates at ``iy, ix``."""
    n = S["1"]
    xc, yc = ix.astype(np.float64), iy.astype(np.float64)
    # moments about the candidate pixel
    sx_, sy_ = S["X"] - xc * n, S["Y"] - yc * n
    sxx = S["XX"] - 2 * xc * S["X"] + xc * xc * n
    syy = S["YY"] - 2 * yc * S["Y"] + yc * yc * n
    sxy = S["XY"] - xc * S["Y"] - yc * S["X"] + xc * yc * n
    bx = S["x"]
    bX, bY = S["xX"] - xc * bx, S["xY"] - yc * bx
    # the normal equations [[n, sx, sy], [sx, sxx, sxy], [sy, sxy, syy]] beta = [bx, bX, bY], by cofactors
    c00, c01, c02 = sxx * syy - sxy * sxy, sy_ * sxy - sx_ * syy, sx_ * sxy - sy_ * sxx
    c11, c12, c22 = n * syy - sy_ * sy_, sx_ * sy_ - n * sxy, n * sxx - sx_ * sx_
    det = n * c00 + sx_ * c01 + sy_ * c02
    with np.errstate(divide="ignore", invalid="ignore"):
        good = det > 1e-8 * n * sxx * syy          # the window's pixels span a plane (not a line)
        inv00 = np.where(good, c00 / det, np.inf)
        a0 = (c00 * bx + c01 * bX + c02 * bY) / det
        a1 = (c01 * bx + c11 * bX + c12 * bY) / det
        a2 = (c02 * bx + c12 * bX + c22 * bY) / det
        rss = np.maximum(S["xx"] - (a0 * bx + a1 * bX + a2 * bY), 0.0)
        scatter = np.sqrt(rss / np.maximum(n - 3, 1.0))                  # the neighbours about their plane
        sd_pred = np.where(good, scatter * np.sqrt(inv00), np.inf)
    a = np.where(good, a0, 0.0)
    pred = a + x0
    t = a / period - u[iy, ix]
    m = np.rint(t)
    xn = x0 + period * (m + u[iy, ix])
    gap = np.abs(xn - coarse[iy, ix])
    gap = np.minimum(gap, np.abs(size - gap))         # the coarse estimate wraps at the panel's edges
    # one surface: the neighbours lie on their plane to their own noise (a few pixels of another surface in the
    # window would not move the plane's standard deviation, they do its scatter)
    take = (scatter <= 0.5 * max_sigma * period) & (sd_pred <= max_sigma * period) & (np.abs(t - m) <= tolerance)
    take &= gap <= 4.0 * np.hypot(coarse_sd[iy, ix], sd_pred)
    take &= np.abs(pred - xn) <= tolerance * period
    take &= (xn >= -0.5) & (xn <= size - 0.5)
    return take, xn
