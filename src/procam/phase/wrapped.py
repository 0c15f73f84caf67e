"""The wrapped phase of an N-step block, fast: per pixel the mean ``A``, the modulation ``B`` and the phase ``psi``
of ``I_k = A + B cos(psi + d_k)``, ``d_k`` the block's shifts.

Least squares for N >= 3 equally spaced shifts: ``C = sum I_k cos d_k``, ``S = sum I_k sin d_k``,
``psi = atan2(-S, C)`` in [0, 2 pi), ``B = 2 / N sqrt(C^2 + S^2)``, ``A = mean I_k``.  With camera noise of
variance ``sigma_I^2`` per sample, ``psi`` has the standard deviation ``sigma_I sqrt(2 / N) / B`` (radians).

The sums are taken band by band of camera rows (the band stays in the cache) and in integers where the weights
allow (:func:`sum_plan`: frames with equal ``|weight|`` are added and subtracted as integers, each group scaled
once: a 4-step block is two integer differences); the phase and the magnitude are OpenCV's (``cv2.phase``: error
below 2e-4 rad, measured in ``tests/test_phase.py``).
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


def block_band(frames, shifts: np.ndarray, buf: np.ndarray | None = None):
    """``(A, B, psi)`` float32 (h, W) of one block's frames ``frames`` (N, h, W) (uint8/uint16/float); ``buf`` an
    optional (3, h, W) float32 scratch."""
    import cv2

    n = len(frames)
    h, w = frames[0].shape
    if buf is None:
        buf = np.empty((4, h, w), np.float32)
    A, C, S, tmp = buf[0], buf[1], buf[2], buf[3]
    cw, sw = weights(np.asarray(shifts, np.float64))
    A[...] = 0.0
    C[...] = 0.0
    S[...] = 0.0
    for k in range(n):
        np.copyto(tmp, frames[k], casting="unsafe")
        A += tmp
        if cw[k] == 1.0:
            C += tmp
        elif cw[k] == -1.0:
            C -= tmp
        elif cw[k] != 0.0:
            C += tmp * cw[k]
        if sw[k] == 1.0:
            S += tmp
        elif sw[k] == -1.0:
            S -= tmp
        elif sw[k] != 0.0:
            S += tmp * sw[k]
    A *= np.float32(1.0 / n)
    np.negative(S, out=S)
    psi = cv2.phase(C, S)  # atan2(-S, C) in [0, 2 pi)
    B = cv2.magnitude(C, S)
    B *= np.float32(2.0 / n)
    return A.copy(), B, psi


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


def weighted_sum(frames, groups: list, wide) -> np.ndarray:
    """float32 ``sum_k w_k frames[k]`` by :func:`sum_plan` ``groups``: integer sums (dtype ``wide``) per group."""
    out = None
    for w, plus, minus in groups:
        if len(plus) == 1 and len(minus) == 1:
            acc = np.subtract(frames[plus[0]], frames[minus[0]], dtype=wide)
        else:
            acc = np.zeros(frames[0].shape, wide)
            for k in plus:
                acc += frames[k]
            for k in minus:
                acc -= frames[k]
        f = acc.astype(np.float32)
        if w != 1.0:
            f *= np.float32(w)
        if out is None:
            out = f
        else:
            out += f
    return out if out is not None else np.zeros(frames[0].shape, np.float32)
