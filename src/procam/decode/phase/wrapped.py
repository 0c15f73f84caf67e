"""The wrapped phase of an N-step block, fast: per pixel the mean ``A``, the modulation ``B`` and the phase ``psi``
of ``I_k = A + B cos(psi + d_k)``, ``d_k`` the block's shifts.

Least squares for N >= 3 equally spaced shifts: ``C = sum I_k cos d_k``, ``S = sum I_k sin d_k``,
``psi = atan2(-S, C)`` in [0, 2 pi), ``B = 2 / N sqrt(C^2 + S^2)``, ``A = mean I_k``.  With camera noise of
variance ``sigma_I^2`` per sample, ``psi`` has the standard deviation ``sigma_I sqrt(2 / N) / B`` (radians).

The sums are taken band by band of camera rows (the band stays in the cache), in buffers reused from band to band
(:class:`Scratch`): the block's frames widened to a signed integer type once, frames of equal ``|weight|`` added
and subtracted in integers (exact; a 4-step block is two differences) and each such group scaled once
(:func:`sum_plan`, :func:`block_sums`).  The phase and the magnitude are OpenCV's (``cv2.phase``: error below
2e-4 rad, measured in ``tests/test_phase.py``).
"""

from __future__ import annotations

import numpy as np


def weights(shifts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(cos d_k, sin d_k)`` as float32, exact zeros and ones where the shift is a multiple of pi / 2 (so that
    4-step blocks add and subtract frames without rounding)."""
    c, s = np.cos(shifts), np.sin(shifts)
    c = np.where(np.abs(c) < 1e-12, 0.0, np.where(np.abs(np.abs(c) - 1) < 1e-12, np.sign(c), c))
    s = np.where(np.abs(s) < 1e-12, 0.0, np.where(np.abs(np.abs(s) - 1) < 1e-12, np.sign(s), s))
    return c.astype(np.float32), s.astype(np.float32)


def sum_plan(weights_row: np.ndarray, tol: float = 1e-6) -> list:
    """The groups of a weighted sum ``sum_k w_k I_k``: ``[(|w|, plus frames, minus frames), ...]`` (indices into the
    block), frames of equal ``|w|`` together, zero weights left out."""
    groups: list = []
    for k, w in enumerate(np.asarray(weights_row, np.float64)):
        if abs(w) < tol:
            continue
        for g in groups:
            if abs(g[0] - abs(w)) < tol:
                (g[1] if w > 0 else g[2]).append(k)
                break
        else:
            groups.append((abs(float(w)), [k] if w > 0 else [], [] if w > 0 else [k]))
    return groups


class SumPlan:
    """How :func:`block_sums` forms one block's sums ``C = sum I_k cos d_k`` and ``S = -sum I_k sin d_k``.

    When every shift has a partner half a turn away (N even and equally spaced, in any frame order), both weights
    change sign between partners, so the sums are taken over the ``N / 2`` differences ``I_k - I_j`` of the
    ``pairs`` (half the additions); otherwise over the frames themselves.  ``c`` and ``s`` are the :func:`sum_plan`
    groups over those terms.
    """

    def __init__(self, shifts: np.ndarray, tol: float = 1e-6):
        c, s = weights(np.asarray(shifts, np.float64))
        n = len(c)
        partner = {}
        for k in range(n):
            if k in partner:
                continue
            j = next((j for j in range(k + 1, n) if j not in partner and abs(c[j] + c[k]) < tol
                      and abs(s[j] + s[k]) < tol), None)
            if j is None:
                break
            partner[k], partner[j] = j, k
        self.steps = n
        if len(partner) == n:
            self.pairs = tuple((k, j) for k, j in sorted(partner.items()) if k < j)
            first = [k for k, _ in self.pairs]
            self.c, self.s = sum_plan(c[first]), sum_plan(-s[first])
        else:
            self.pairs = None
            self.c, self.s = sum_plan(c), sum_plan(-s)


#: Byte alignment of the float32 sums a block's magnitude is taken of, and of the magnitude itself.  OpenCV's
#: ``magnitude`` (its IPP kernel) rounds the last bit of some pixels differently depending on where its inputs and
#: output start in memory, so buffers at whatever address the allocator happened to return made a phase decode's
#: modulation and confidence differ by one float32 ulp at a few thousand pixels from run to run; at fixed
#: alignments the same frames give the same bits.
ALIGN = 64


def aligned(n: int, size: int) -> np.ndarray:
    """Uninitialised ``(n, size)`` float32 whose rows each start at an :data:`ALIGN`-byte boundary (a view into a
    padded buffer)."""
    per = ALIGN // 4
    stride = -(-size // per) * per
    raw = np.empty(n * stride + per, np.float32)
    skip = (-raw.ctypes.data % ALIGN) // 4
    return raw[skip:skip + n * stride].reshape(n, stride)[:, :size]


def magnitude(C: np.ndarray, S: np.ndarray) -> np.ndarray:
    """``sqrt(C**2 + S**2)`` float32 (h, W) of the sums ``C``, ``S`` (:func:`block_sums`), by OpenCV, into a new
    aligned array: the same inputs give the same bits in every run (:data:`ALIGN`)."""
    import cv2

    out = aligned(1, C.size)[0].reshape(C.shape)
    cv2.magnitude(C, S, out)
    return out


class Scratch:
    """Buffers the band pass reuses for one block's sums: the frames widened to a signed integer type (int16 for
    8-bit frames, which holds sums of up to 128 of them; int32 otherwise), an integer accumulator and three float32
    results, for ``rows`` x ``width`` pixels and blocks of up to ``steps`` frames."""

    def __init__(self, rows: int, width: int, steps: int, dtype):
        self.wide = np.int16 if np.dtype(dtype) == np.uint8 and steps <= 128 else np.int32
        self.ints = np.empty((steps, rows * width), self.wide)
        self.acc = np.empty(rows * width, self.wide)
        self.sums = aligned(3, rows * width)
        self.tmp = np.empty(rows * width, np.float32)


def block_sums(frames, plan: SumPlan, scratch: Scratch, mean: bool = False):
    """``(C, S, A)`` float32 (h, W) of one block's frames ``frames`` (N arrays (h, W), uint8 or uint16): the sums
    of ``plan`` (:class:`SumPlan`) and, when ``mean``, the frames' mean (else None).  The terms (the frames
    widened to a signed integer type, or the differences of their pairs) are formed once; each group of equal
    ``|weight|`` is added and subtracted in integers (exact) and scaled once.  C, S and A are views into
    ``scratch``: valid until its next use."""
    n = len(frames)
    h, width = frames[0].shape
    P = h * width
    wide = scratch.wide
    if plan.pairs is not None:
        terms = scratch.ints[:len(plan.pairs), :P]
        for i, (k, j) in enumerate(plan.pairs):
            np.subtract(frames[k], frames[j], out=terms[i].reshape(h, width), dtype=wide)
    else:
        terms = scratch.ints[:n, :P]
        for k, f in enumerate(frames):
            np.copyto(terms[k].reshape(h, width), f, casting="unsafe")
    acc, tmp = scratch.acc[:P], scratch.tmp[:P]
    out = []
    for r, groups in enumerate((plan.c, plan.s)):
        res = scratch.sums[r, :P]
        first = True
        for w, plus, minus in groups:
            dst = res if first else tmp
            if len(plus) + len(minus) <= 2:  # straight into float32
                if plus and minus:
                    np.subtract(terms[plus[0]], terms[minus[0]], out=dst, dtype=np.float32)
                elif len(plus) == 2 or len(minus) == 2:
                    a, b = plus or minus
                    np.add(terms[a], terms[b], out=dst, dtype=np.float32)
                    if minus:
                        np.negative(dst, out=dst)
                else:
                    np.copyto(dst, terms[(plus or minus)[0]], casting="unsafe")
                    if minus:
                        np.negative(dst, out=dst)
            else:  # acc = sum of plus - sum of minus, in integers
                if plus and minus:
                    np.subtract(terms[plus[0]], terms[minus[0]], out=acc)
                    rest_p, rest_m = plus[1:], minus[1:]
                elif plus:
                    np.copyto(acc, terms[plus[0]])
                    rest_p, rest_m = plus[1:], ()
                else:
                    np.negative(terms[minus[0]], out=acc)
                    rest_p, rest_m = (), minus[1:]
                for k in rest_p:
                    acc += terms[k]
                for k in rest_m:
                    acc -= terms[k]
                np.copyto(dst, acc, casting="unsafe")
            if w != 1.0:
                dst *= np.float32(w)
            if not first:
                res += tmp
            first = False
        if first:
            res[...] = 0.0
        out.append(res.reshape(h, width))
    A = None
    if mean:
        A = scratch.sums[2, :P]
        np.copyto(acc, frames[0].reshape(-1), casting="unsafe")
        for f in frames[1:]:
            np.add(acc, f.reshape(-1), out=acc, dtype=wide)
        np.copyto(A, acc, casting="unsafe")
        A *= np.float32(1.0 / n)
        A = A.reshape(h, width)
    return out[0], out[1], A
