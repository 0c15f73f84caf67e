"""A fixed pseudo-random sample of a stack's pixels and the frames' levels on it: what every check of a capture
(:mod:`procam.capture.read`, :mod:`procam.capture.phase`) measures on, so that they agree pixel for pixel with the
phase decoder's own measurements (:func:`procam.decode.decoded.sample_index`).

The sample is pseudo-random, not a grid, so it does not alias with periodic stripes or fringes.
"""

from __future__ import annotations

import numpy as np


def _sample(stack: np.ndarray, n: int = 20000) -> np.ndarray:
    """(K, n) values at a fixed pseudo-random set of pixels (no aliasing with periodic stripes)."""
    flat = stack.reshape(len(stack), -1)
    if flat.shape[1] <= n:
        return flat.astype(np.float32)
    return np.take(flat, sample_index(flat.shape[1], n), axis=1).astype(np.float32)


def sample_index(size: int, n: int) -> np.ndarray:
    """The fixed pseudo-random set of ``n`` pixel indices (sorted) out of ``size`` every check and the phase
    decoder's measurements use (all of them when ``size <= n``)."""
    from ..decode.decoded import sample_index as _index

    return _index(size, n)


def frame_levels(stack: np.ndarray, sub: np.ndarray | None = None,
                 frames=None) -> tuple[np.ndarray, np.ndarray]:
    """Per frame, the 5th and 95th percentiles over well-lit pixels of
    ``(I_k - min_k I) / (max_k I - min_k I)``.

    A white frame is lit everywhere (5th percentile near 1), a black frame nowhere (95th near 0),
    a pattern in parts (5th near 0, 95th near 1) — whatever the scene's albedo or vignetting.
    ``sub`` is :func:`_sample` of ``stack`` if the caller has it already. ``frames``: the indices of the frames
    wanted (default all); each frame's levels are the same whichever others are asked for (the minimum and
    maximum are over all frames), and asking for two of 42 saves nine tenths of the time.
    """
    sub = _sample(stack) if sub is None else sub
    lo, hi = sub.min(axis=0), sub.max(axis=0)
    span = hi - lo
    lit = span > 0.25 * np.percentile(span, 99)
    n = len(stack) if frames is None else len(frames)
    if lit.sum() < 10:
        return np.full(n, 0.5), np.full(n, 0.5)
    norm = ((sub if frames is None else sub[list(frames)])[:, lit] - lo[lit]) / span[lit]
    return np.percentile(norm, 5, axis=1), np.percentile(norm, 95, axis=1)
