"""What the Gray-code decoder (:mod:`procam.decode`) and the phase decoder (:mod:`procam.decode.phase`) share: the
decoded maps of one pose (:class:`DecodeResult`), the reason codes of a pixel that did not decode (:data:`REASONS`),
the fixed sample of pixels the phase decoder measures on (:func:`sample_index`) and the check of the phase options
(:func:`check_phase_options`), so that a Gray capture's decode and checks import nothing of the phase decoder.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from ..patterns import PatternSet


#: Reason codes of :attr:`DecodeResult.reason_col` / ``reason_row``.
REASONS = {
    0: "decoded",
    1: "shadow: white - black below shadow_threshold (not lit by the projector)",
    2: "low contrast: some bit's pattern and inverse differ by less than contrast_threshold",
    3: "ambiguous bit: direct light too weak against global light (robust classifier)",
    4: "code outside the projector's columns/rows",
    5: "saturated: a phase frame is at full scale (the fringes are clipped)",
    6: "low modulation: the fringes are too faint to tell their periods apart (the coarser level's predicted "
       "error is above max_order_sigma of the finer period)",
    7: "orders disagree: the frequencies (or the Gray code and the phase) give different fringe periods",
}
OK, SHADOW, LOW_CONTRAST, AMBIGUOUS, OUT_OF_RANGE, SATURATED, LOW_MODULATION, ORDER_DISAGREE = range(8)


def sample_index(size: int, n: int) -> np.ndarray:
    """The fixed pseudo-random sample of pixels the phase decoder measures the projector's response and the
    camera's noise on, and the capture checks judge a capture on (:func:`procam.capture.sample_index`), so that
    the two agree pixel for pixel: ``n`` of ``size`` flat indices, sorted (all of them when ``size <= n``)."""
    if size <= n:
        return np.arange(size)
    return _sample_index(size, n)


@lru_cache(maxsize=8)
def _sample_index(size: int, n: int) -> np.ndarray:
    idx = np.sort(np.random.default_rng(0).choice(size, n, replace=False))
    idx.flags.writeable = False
    return idx


def check_phase_options(gamma, camera_noise, shadow_threshold, contrast_threshold) -> None:
    """Raise ``ValueError`` for a phase decoder's option out of its range (:class:`procam.decode.phase.PhaseOptions`
    checks its own with it, and :class:`procam.decode.DecodeOptions` the ones it passes on, without importing the
    phase decoder): ``gamma`` ``"auto"``, ``"none"`` or a number from 0.2 to 5; ``camera_noise`` None or a sigma
    in (0, 100] grey levels; the thresholds numbers of grey levels from 0 to 255."""
    import math

    g = gamma
    if isinstance(g, str):
        if g not in ("auto", "none"):
            raise ValueError(f"gamma must be 'auto', 'none' or a number from 0.2 to 5, got {g!r}")
    elif not (isinstance(g, (int, float)) and math.isfinite(g) and 0.2 <= g <= 5):
        raise ValueError(f"gamma must be 'auto', 'none' or a number from 0.2 to 5, got {g!r}")
    if camera_noise is not None and not (math.isfinite(camera_noise) and 0 < camera_noise <= 100):
        raise ValueError(f"camera noise must be a positive number of grey levels (at most 100), got "
                         f"{camera_noise!r}")
    for what, v in (("shadow threshold", shadow_threshold), ("contrast threshold", contrast_threshold)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and 0 <= v <= 255):
            raise ValueError(f"{what} must be a number of grey levels from 0 to 255, got {v!r}")


@dataclass(frozen=True)
class DecodeResult:
    """Decoded maps of one pose, all (H, W).

    Attributes
    ----------
    col, row : float32
        Projector column / row (pixels, centre of projector pixel = integer) of each camera
        pixel; NaN where invalid.  With ``pattern_set.step > 1`` the centre of the code's block.
    valid_col, valid_row : bool
    reason_col, reason_row : uint8
        Codes of :data:`REASONS` (0 = decoded).
    confidence : float32 or None
        Smallest ``|pattern - inverse|`` over all bits divided by ``white - black``, in [0, 1] (None when
        decoded with ``extras=False``).
    direct, global_ : float32 or None
        The robust classifier's direct and global light estimates (DN at the input scale; None for the simple
        classifier or ``extras=False``).
    pattern_set : the decoded sequence's :class:`PatternSet`.
    dropped_col, dropped_row : uint8
        Number of trailing (finest) bits that were uncertain and left out (0 = full precision); the
        value is then the centre of the block of ``2^dropped`` codes the certain bits leave.
    codes_col, codes_row : int64 (n,) or None
        How many camera pixels decoded to each projector column / row (index = the projector pixel of
        the code's block start), **including codes outside the projector** (index >= width/height): the
        extent of the codes tells the projector's real size when the given one is wrong.  A phase decode counts
        its coordinates rounded to whole pixels.
    sigma_col, sigma_row : float32 or None
        Phase families: the predicted standard deviation of ``col`` / ``row`` (projector pixels) from the
        fringes' modulation and the camera's noise, ``sigma_I sqrt(2 / N) / B * P / (2 pi)`` of the finest fringes
        (:mod:`procam.decode.phase`); NaN where invalid.  None for a Gray code (:meth:`coordinate_sigma` has its
        quantisation instead).
    modulation_col, modulation_row : float32 or None
        Phase families: the finest fringes' modulation ``B`` (half their peak-to-peak, DN at the input scale).
    phase : :class:`procam.decode.phase.PhaseInfo` or None
        Phase families: what the decoder measured and assumed (projector gamma, camera noise, per-block
        statistics, warnings).
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
    dropped_col: np.ndarray | None = None
    dropped_row: np.ndarray | None = None
    codes_col: np.ndarray | None = None
    codes_row: np.ndarray | None = None
    sigma_col: np.ndarray | None = None
    sigma_row: np.ndarray | None = None
    modulation_col: np.ndarray | None = None
    modulation_row: np.ndarray | None = None
    phase: object | None = None

    @property
    def valid(self) -> np.ndarray:
        """(H, W) bool: both column and row decoded."""
        return self.valid_col & self.valid_row

    @property
    def subpixel(self) -> bool:
        """True when the maps hold sub-pixel coordinates with a noise estimate (a phase family)."""
        return self.sigma_col is not None

    @property
    def noise(self) -> np.ndarray | None:
        """(H, W) float32 per-pixel noise of the projector coordinate, px (the RMS of the column's and the row's
        noise estimates, NaN where either is undecoded) for a phase family; None for a Gray code, whose
        quantisation is no independent per-pixel noise (:func:`procam.correspond.samples.window_means` then measures it)."""
        if self.sigma_col is None or self.sigma_row is None:
            return None
        return np.sqrt(np.float32(0.5) * (self.sigma_col ** 2 + self.sigma_row ** 2)).astype(np.float32)

    def coordinate_sigma(self, axis: str) -> np.ndarray:
        """(H, W) float32: the standard deviation of ``col`` (``axis="col"``) or ``row`` in projector pixels, NaN
        where invalid: the phase decode's noise estimate, or for a Gray code the quantisation of its value, the
        width of the block of codes it stands for over sqrt(12) (``step 2^dropped / sqrt(12)``)."""
        if axis not in ("col", "row"):
            raise ValueError(f"axis must be 'col' or 'row', got {axis!r}")
        sigma = self.sigma_col if axis == "col" else self.sigma_row
        if sigma is not None:
            return sigma
        valid = self.valid_col if axis == "col" else self.valid_row
        dropped = self.dropped_col if axis == "col" else self.dropped_row
        width = np.float32(getattr(self.pattern_set, "step", 1)) * (
            np.float32(1.0) if dropped is None else np.left_shift(1, dropped.astype(np.int32)).astype(np.float32))
        return np.where(valid, width / np.float32(np.sqrt(12.0)), np.float32(np.nan)).astype(np.float32)

    def reason_counts(self) -> dict:
        """``{axis: {reason text: pixel count}}`` for the non-zero counts."""
        out = {}
        for axis, r in (("col", self.reason_col), ("row", self.reason_row)):
            counts = np.bincount(r.ravel(), minlength=len(REASONS))
            out[axis] = {REASONS[k]: int(c) for k, c in enumerate(counts) if c}
        return out


def checked_stack(stack, count: int) -> np.ndarray:
    """``stack`` as an array, refused (``ValueError``) unless it is ``(count, H, W)`` of uint8 or uint16: the input
    check of every decoder."""
    stack = np.asarray(stack)
    if stack.ndim != 3 or stack.shape[0] != count:
        raise ValueError(f"stack must be ({count}, H, W) for this pattern set, got {stack.shape}")
    if stack.dtype not in (np.uint8, np.uint16):
        raise ValueError(f"stack must be uint8 or uint16, got {stack.dtype}")
    return stack
