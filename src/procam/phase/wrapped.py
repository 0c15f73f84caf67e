"""The wrapped phase of an N-step block, fast: per pixel the mean ``A``, the modulation ``B`` and the phase ``psi``
of ``I_k = A + B cos(psi + d_k)``, ``d_k`` the block's shifts.

Least squares for N >= 3 equally spaced shifts: ``C = sum I_k cos d_k``, ``S = sum I_k sin d_k``,
``psi = atan2(-S, C)`` in [0, 2 pi), ``B = 2 / N sqrt(C^2 + S^2)``, ``A = mean I_k``.  With camera noise of
variance ``sigma_I^2`` per sample, ``psi`` has the standard deviation ``sigma_I sqrt(2 / N) / B`` (radians).

The sums are taken band by band of camera rows (the band stays in the cache): the block's frames converted to
float32 once into a reused buffer, and the three sums one matrix product (:func:`block_sums`); the phase and the
magnitude are OpenCV's (``cv2.phase``: error below 2e-4 rad, measured in ``tests/test_phase.py``).
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


class Scratch:
    """Buffers the band pass reuses for one block's sums: the frames widened to a signed integer type (int16 for
    8-bit frames, which holds sums of up to 128 of them; int32 otherwise), an integer accumulator and three float32
    results, for ``rows`` x ``width`` pixels and blocks of up to ``steps`` frames."""

    def __init__(self, rows: int, width: int, steps: int, dtype):
        self.wide = np.int16 if np.dtype(dtype) == np.uint8 and steps <= 128 else np.int32
        self.ints = np.empty((steps, rows * width), self.wide)
        self.acc = np.empty(rows * width, self.wide)
        self.sums = np.empty((3, rows * width), np.float32)
        self.tmp = np.empty(rows * width, np.float32)


def block_sums(frames, plans, scratch: Scratch, mean: bool = False):
    """``(C, S, A)`` float32 (h, W) of one block's frames ``frames`` (N arrays (h, W), uint8 or uint16): the sums
    of ``plans`` (two :func:`sum_plan` groups, for ``sum I cos d`` and ``-sum I sin d``) and, when ``mean``, the
    frames' mean (else None).  The frames are widened once; each group is added and subtracted in integers (exact)
    and scaled once.  C, S and A are views into ``scratch``: valid until its next use."""
    n = len(frames)
    h, width = frames[0].shape
    P = h * width
    ints = scratch.ints[:n, :P]
    for k, f in enumerate(frames):
        np.copyto(ints[k].reshape(h, width), f, casting="unsafe")
    acc, tmp = scratch.acc[:P], scratch.tmp[:P]
    out = []
    for r, groups in enumerate(plans):
        res = scratch.sums[r, :P]
        first = True
        for w, plus, minus in groups:
            # acc = sum of plus - sum of minus, in integers
            if plus and minus:
                np.subtract(ints[plus[0]], ints[minus[0]], out=acc)
                plus, minus = plus[1:], minus[1:]
            elif plus:
                np.copyto(acc, ints[plus[0]])
                plus = plus[1:]
            else:
                np.negative(ints[minus[0]], out=acc)
                minus = minus[1:]
            for k in plus:
                acc += ints[k]
            for k in minus:
                acc -= ints[k]
            dst = res if first else tmp
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
        np.add.reduce(ints, axis=0, out=acc)
        A = scratch.sums[2, :P]
        np.copyto(A, acc, casting="unsafe")
        A *= np.float32(1.0 / n)
        A = A.reshape(h, width)
    return out[0], out[1], A
