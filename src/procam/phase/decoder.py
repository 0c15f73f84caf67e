"""Decoding a phase-family capture: per camera pixel a sub-pixel projector column and row, their noise, validity
and reasons (:func:`decode_phase`, returning the :class:`~procam.decoded.DecodeResult` every stage downstream
reads).

Two passes.  On a fixed sample of pixels (:data:`SAMPLE`) the projector's response and the camera's noise are
measured (:func:`procam.phase.response.fit_response`).  Then, band by band of camera rows, every phase block's
wrapped phase (:mod:`procam.phase.wrapped`), its correction for the projector's gamma (a lookup table), the fringe
fractions and their noise, the masks and the unwrapping (:mod:`procam.phase.unwrap`).

Masks (reason codes of :data:`procam.decoded.REASONS`)
    SHADOW: the coarsest fringes' peak-to-peak ``2 B`` (and ``white - black`` when the sequence has them) below
    ``shadow_threshold``.  SATURATED: a phase frame of the axis at full scale (a clipped sinusoid has a wrong
    phase).  LOW_CONTRAST: a Gray bit that is not sure (``|pattern - inverse|`` below ``contrast_threshold``, or
    without inverses ``|pattern - threshold|`` below half of it, the threshold midway between the pixel's dark
    and lit levels as the fringes give them).  LOW_MODULATION, ORDER_DISAGREE: the unwrapping's.  OUT_OF_RANGE:
    a coordinate off the panel, outside ``[-0.5, size - 0.5]``.
Noise
    ``sigma_x = sqrt(a + b A) sqrt(2 / N) / B * P / (2 pi) * d phase / d estimate`` of the finest fringes (the
    heterodyne's three combined), with ``a + b A`` the camera's noise variance at the pixel's level (measured, or
    ``camera_noise^2``): what the noise alone explains, not a bound on other errors (a pixel straddling two
    albedos, interreflections, a wrong gamma).
Gamma
    ``"auto"`` measures it and corrects the phase; a number corrects with that gamma; ``"none"`` assumes a linear
    projector and warns (:class:`~procam.errors.ProcamWarning`) when the frames say otherwise by more than
    :data:`GAMMA_WARN_PX`.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from .. import decoded as _d
from ..errors import ProcamWarning
from ..io import files as _files
from ..patterns.phase import PhaseSet
from . import response as _resp
from . import unwrap as _unwrap
from .wrapped import block_band

#: Pixels of the sample the response and the noise are measured on (and :mod:`procam.phase.diagnose` judges).
SAMPLE = 20000
#: A gamma that leaves a larger coordinate error (projector pixels) is corrected (``"auto"``) or warned about.
GAMMA_WARN_PX = 0.05
#: Below this coordinate error (projector pixels) the gamma correction is not applied (it changes nothing).
GAMMA_SKIP_PX = 0.003


@dataclass(frozen=True)
class PhaseOptions:
    """The phase decoder's options (defaults in 8-bit grey levels, scaled to the input's full scale).

    gamma : ``"auto"`` (measure and correct), ``"none"`` (assume a linear projector, warn when it is not) or the
        projector's gamma.
    camera_noise : the camera's noise sigma in DN; None measures it from the frames.
    shadow_threshold : minimum peak-to-peak of the coarsest fringes (and white - black), DN.
    contrast_threshold : minimum ``|pattern - inverse|`` of a Gray bit, DN.
    tolerance, max_sigma : the unwrapping's (:mod:`procam.phase.unwrap`), cycles of the finer period.
    """

    gamma: str | float = "auto"
    camera_noise: float | None = None
    shadow_threshold: float = 10.0
    contrast_threshold: float = 3.0
    tolerance: float = _unwrap.TOLERANCE
    max_sigma: float = _unwrap.MAX_SIGMA

    def __post_init__(self):
        g = self.gamma
        if isinstance(g, str):
            if g not in ("auto", "none"):
                raise ValueError(f"gamma must be 'auto', 'none' or a number from 0.2 to 5, got {g!r}")
        elif not (isinstance(g, (int, float)) and math.isfinite(g) and 0.2 <= g <= 5):
            raise ValueError(f"gamma must be 'auto', 'none' or a number from 0.2 to 5, got {g!r}")
        if self.camera_noise is not None and not (math.isfinite(self.camera_noise) and 0 < self.camera_noise <= 100):
            raise ValueError(f"camera noise must be a positive number of grey levels (at most 100), got "
                             f"{self.camera_noise!r}")
        for what, v in (("shadow threshold", self.shadow_threshold), ("contrast threshold", self.contrast_threshold)):
            if not (isinstance(v, (int, float)) and math.isfinite(v) and 0 <= v <= 255):
                raise ValueError(f"{what} must be a number of grey levels from 0 to 255, got {v!r}")
        if not 0 < self.tolerance < 0.5 or not 0 < self.max_sigma < 0.5:
            raise ValueError("tolerance and max_sigma must be fractions of a period between 0 and 0.5")


@dataclass(frozen=True)
class BlockStats:
    """One phase block on the sample: its frames, period, steps, the median modulation ``B`` (DN) over the pixels
    the projector lights, and that over the median of all blocks of its axis (1 = typical)."""

    axis: str
    frames: tuple
    period: float
    steps: int
    modulation: float
    relative: float


@dataclass(frozen=True)
class PhaseInfo:
    """What the phase decoder measured and assumed (``DecodeResult.phase``).

    gamma, gamma_std : the projector's gamma measured from the frames (NaN when the sequence does not determine
        it) and its standard deviation.
    gamma_used : the gamma the phases were corrected for (1 = none).
    gamma_error_px : the largest coordinate error (projector pixels, finest fringes) the measured gamma leaves when
        not corrected (0 when unmeasured).
    blur : effective blur of the fringes' harmonics, projector pixels.
    noise : ``(a, b)``, the camera's noise variance ``a + b * level`` (DN^2 at the input scale).
    blocks : :class:`BlockStats` per phase block.
    sample_reasons : ``{axis: (n,) uint8}`` the reasons on the sample pixels (for :mod:`procam.phase.diagnose`).
    warnings : what the result should be read with.
    """

    gamma: float
    gamma_std: float
    gamma_used: float
    gamma_error_px: float
    blur: float
    noise: tuple
    blocks: tuple = ()
    warnings: tuple = ()
    sample: dict = field(default_factory=dict, compare=False, repr=False)


def _sample_index(size: int, n: int) -> np.ndarray:
    if size <= n:
        return np.arange(size)
    return np.sort(np.random.default_rng(0).choice(size, n, replace=False))


def _lut_px(lut, period: float) -> float:
    return 0.0 if lut is None else lut.max_error * period / (2.0 * np.pi)


def _response(sub, ps: PhaseSet, opts: PhaseOptions, fs: float, scale: float):
    """Pass 1 on the sample ``sub`` (K, n): the response, the gamma to correct for, the lookup tables, warnings."""
    blocks = [b for b in ps.blocks if b.kind == "phase"]
    stats = [_resp.nstep(sub[list(b.frames)], b.shifts()) for b in blocks]
    sat = (sub[ps.phase_frames()] >= fs).any(axis=0)
    lit = ~sat
    for (A, B, _), b in zip(stats, blocks):
        lit &= 2.0 * B >= max(opts.shadow_threshold * scale, 0.25 * np.percentile(2.0 * B, 95))
    white = sub[ps.white] if ps.white is not None else None
    black = sub[ps.black] if ps.black is not None else None
    notes = []
    if lit.sum() >= 100:
        fixed = None if opts.gamma in ("auto", "none") else float(opts.gamma)
        resp = _resp.fit_response([(b, sub[list(b.frames)][:, lit]) for b in blocks],
                                  None if white is None else white[lit], None if black is None else black[lit],
                                  gamma=fixed)
    else:
        resp = _resp.Response(float("nan"), float("nan"), 0.0, (1.0, 0.0), int(lit.sum()), False,
                              "too few well-lit pixels to measure the projector's response")
    noise = resp.noise
    if opts.camera_noise is not None:
        noise = ((opts.camera_noise * scale) ** 2 + 1.0 / 12.0, 0.0)
    measured = resp.gamma if resp.measurable or opts.gamma not in ("auto", "none") else float("nan")
    # what the measured gamma does to the finest fringes when left uncorrected
    err_px = 0.0
    if np.isfinite(measured):
        for b in blocks:
            lut = _resp.phase_lut(_resp.waveform(b.fringe, measured, b.period, resp.blur), b.shifts())
            err_px = max(err_px, math.inf if lut is None else _lut_px(lut, min(bb.period for bb in blocks
                                                                              if bb.axis == b.axis)))
    if opts.gamma == "auto":
        used = measured if np.isfinite(measured) else 1.0
        if not np.isfinite(measured):
            few = min(b.steps for b in blocks) <= 4
            if few:
                notes.append("the projector's gamma could not be measured from this sequence "
                             f"({resp.note or 'too few pixels'}); the phases assume a linear projector, which "
                             "leaves an error at N times the fringe frequency if it is not: give the gamma "
                             "(--gamma), add white and black frames, or use 5 or more steps")
    elif opts.gamma == "none":
        used = 1.0
        if np.isfinite(measured) and err_px > GAMMA_WARN_PX:
            notes.append(f"the projector is not linear (gamma {measured:.2f} +- {resp.gamma_std:.2f} measured from the "
                         f"frames): uncorrected, it leaves a phase error at N times the fringe frequency of up to "
                         f"{err_px:.2f} projector px; decode with the gamma correction (gamma 'auto') or "
                         "pre-correct the patterns")
    else:
        used = float(opts.gamma)
    luts = {}
    for b in blocks:
        lut = _resp.phase_lut(_resp.waveform(b.fringe, used, b.period, resp.blur), b.shifts())
        if lut is None:
            notes.append(f"the fringes of frames #{b.first}-#{b.first + b.count - 1} are too distorted by the "
                         f"projector's gamma ({used:.2f}) to be corrected with {b.steps} steps: pre-correct the "
                         "patterns or use more steps")
        elif _lut_px(lut, b.period) >= GAMMA_SKIP_PX:
            luts[b.first] = lut
    return resp, measured, used, err_px, noise, luts, notes, lit


def decode_phase(stack: np.ndarray, ps: PhaseSet, options: PhaseOptions = PhaseOptions(), *,
                 full_scale: float | None = None, band: int = 32, extras: bool = True,
                 method: str = "simple") -> _d.DecodeResult:
    """Decode a phase-family stack (see the module docstring).

    Parameters
    ----------
    stack : (K, H, W) uint8 or uint16 in ``ps``'s order (``K == ps.count``).
    ps : the sequence (:class:`procam.patterns.PhaseSet`).
    options : :class:`PhaseOptions`.
    full_scale : the input's full scale (default: from the stack, as :func:`procam.decode.decode`).
    band : camera rows processed at a time (speed only).
    extras : compute ``confidence`` (min over the axes of ``B / A`` of the finest fringes).
    method : the Gray bits' classifier; only the comparison of a pattern with its inverse (or a threshold) is
        implemented for the hybrid's Gray code, which its phase checks.

    Returns
    -------
    :class:`~procam.decoded.DecodeResult` with sub-pixel ``col``/``row`` and ``sigma_col``/``sigma_row``,
    ``modulation_col``/``row`` and ``phase`` (:class:`PhaseInfo`).  Warns (:class:`~procam.errors.ProcamWarning`)
    with what ``phase.warnings`` holds.
    """
    stack = np.asarray(stack)
    if stack.ndim != 3 or stack.shape[0] != ps.count:
        raise ValueError(f"stack must be ({ps.count}, H, W) for this pattern set, got {stack.shape}")
    if stack.dtype not in (np.uint8, np.uint16):
        raise ValueError(f"stack must be uint8 or uint16, got {stack.dtype}")
    fs = _files.full_scale_of(stack) if full_scale is None else float(full_scale)
    scale = fs / 255.0
    K, H, W = stack.shape
    idx = _sample_index(H * W, SAMPLE)
    sub = stack.reshape(K, -1)[:, idx].astype(np.float64)
    resp, measured, used, err_px, noise, luts, notes, lit = _response(sub, ps, options, fs, scale)
    ctx = dict(ps=ps, opts=options, fs=fs, scale=scale, noise=noise, luts=luts)
    out = {k: np.empty((H, W), np.float32) for k in ("col", "row", "scol", "srow", "mcol", "mrow")}
    out["rcol"], out["rrow"] = np.empty((H, W), np.uint8), np.empty((H, W), np.uint8)
    out["conf"] = np.empty((H, W), np.float32) if extras else None
    hists = {"col": np.zeros(2 * W + 2, np.int64), "row": np.zeros(2 * H + 2, np.int64)}
    for y0 in range(0, H, band):
        sl = slice(y0, min(H, y0 + band))
        _band(stack[:, sl, :], sl, out, hists, **ctx)
    # the sample's own decode, for the description checks (procam.phase.diagnose)
    sample = {"index": idx}
    view = np.ascontiguousarray(sub.astype(stack.dtype)[:, None, :])
    sout = {k: np.empty((1, len(idx)), np.float32) for k in ("col", "row", "scol", "srow", "mcol", "mrow")}
    sout["rcol"], sout["rrow"], sout["conf"] = np.empty((1, len(idx)), np.uint8), np.empty((1, len(idx)), np.uint8), None
    _band(view, slice(0, 1), sout, {"col": np.zeros(2 * W + 2, np.int64), "row": np.zeros(2 * H + 2, np.int64)}, **ctx)
    sample.update({k: sout[k][0] for k in ("col", "row", "rcol", "rrow")})
    stats = _block_stats(sub, ps, lit)
    info = PhaseInfo(measured, resp.gamma_std, used, err_px, resp.blur, noise, stats, tuple(notes), sample)
    for w in notes:
        warnings.warn(w, ProcamWarning, stacklevel=2)
    rcol, rrow = out["rcol"], out["rrow"]
    zeros = np.zeros((H, W), np.uint8)
    return _d.DecodeResult(out["col"], out["row"], rcol == _d.OK, rrow == _d.OK, rcol, rrow, out["conf"], None, None,
                           ps, zeros, zeros.copy(), hists["col"], hists["row"], out["scol"], out["srow"],
                           out["mcol"], out["mrow"], info)


def _block_stats(sub, ps: PhaseSet, lit) -> tuple:
    out = []
    for axis in ("col", "row"):
        blocks = ps.phase_blocks(axis)
        meds = []
        for b in blocks:
            _, B, _ = _resp.nstep(sub[list(b.frames)], b.shifts())
            meds.append(float(np.median(B[lit])) if lit.any() else 0.0)
        typical = float(np.median(meds)) if meds else 0.0
        for b, m in zip(blocks, meds):
            out.append(BlockStats(axis, tuple(b.frames), b.period, b.steps, m, m / typical if typical > 0 else 0.0))
    return tuple(out)


def _band(blk, sl, out, hists, *, ps: PhaseSet, opts: PhaseOptions, fs, scale, noise, luts):
    """Decode the rows ``sl`` (frames ``blk`` (K, h, W)) into ``out`` (see :func:`decode_phase`)."""
    a, b = noise
    h, w = blk.shape[1:]
    buf = np.empty((4, h, w), np.float32)
    span = None
    if ps.white is not None and ps.black is not None:
        span = blk[ps.white].astype(np.float32) - blk[ps.black].astype(np.float32)
    conf = None
    for axis, key, rkey, skey, mkey in (("col", "col", "rcol", "scol", "mcol"), ("row", "row", "rrow", "srow", "mrow")):
        n = ps.size(axis)
        blocks = ps.phase_blocks(axis)  # coarsest first
        levels, finest = [], None
        reason = np.zeros((h, w), np.uint8)
        sat = np.zeros((h, w), bool)
        Bc = None
        for bl in blocks:
            frames = blk[bl.first:bl.first + bl.count]
            for f in frames:
                sat |= f >= fs
            A, B, psi = block_band(frames, bl.shifts(), buf)
            if Bc is None:
                Bc = B.copy()
            slope = 1.0
            lut = luts.get(bl.first)
            if lut is not None:
                psi, slope = lut(psi.astype(np.float64))
            u = (bl.fringe.sign * np.asarray(psi, np.float64)) / (2.0 * np.pi)
            u -= np.floor(u)
            var = np.maximum(a + b * A, 1e-6)
            with np.errstate(divide="ignore", invalid="ignore"):
                su = np.sqrt(var * (2.0 / bl.steps)) / np.maximum(B, 1e-6) / (2.0 * np.pi) * slope
            levels.append((u, su.astype(np.float64), bl.period, bl.fringe.x0))
            finest = (A, B, u)
        reason[2.0 * Bc < opts.shadow_threshold * scale] = _d.SHADOW
        if span is not None:
            reason[span < opts.shadow_threshold * scale] = _d.SHADOW
        reason[sat & (reason == _d.OK)] = _d.SATURATED
        if ps.family == "phase":
            x, sx = _unwrap.hierarchical(levels, reason, tolerance=opts.tolerance, max_sigma=opts.max_sigma)
        elif ps.family == "heterodyne":
            x, sx = _unwrap.heterodyne(levels, reason, tolerance=opts.tolerance, max_sigma=opts.max_sigma)
        else:
            x, sx = _gray_phase(blk, ps, axis, levels[0], finest, span, reason, opts, scale, noise)
        reason[((x < -0.5) | (x > n - 0.5)) & (reason == _d.OK)] = _d.OUT_OF_RANGE
        fin = np.isfinite(x) & (reason != _d.SHADOW) & (reason != _d.SATURATED)
        hists[axis] += np.bincount(np.clip(np.rint(x[fin]), 0, len(hists[axis]) - 1).astype(np.int64),
                                   minlength=len(hists[axis]))
        ok = reason == _d.OK
        out[key][sl] = np.where(ok, x, np.nan)
        out[skey][sl] = np.where(ok, sx, np.nan)
        out[mkey][sl] = finest[1]
        out[rkey][sl] = reason
        if out["conf"] is not None:
            with np.errstate(divide="ignore", invalid="ignore"):
                c = np.clip(finest[1] / np.maximum(finest[0], 1e-6), 0.0, 1.0)
            conf = c if conf is None else np.minimum(conf, c)
    if out["conf"] is not None:
        out["conf"][sl] = conf


def _gray_phase(blk, ps, axis, level, finest, span, reason, opts, scale, noise):
    """The gray-phase coordinate of one axis: Gray bits, their orders, the fringe fraction (see
    :func:`procam.phase.unwrap.gray_orders`)."""
    u, su, period, x0 = level
    A, B, _ = finest
    g = ps.gray_block(axis)
    t = opts.contrast_threshold * scale
    nb = g.bits + int(g.complementary)
    var = noise[0] + noise[1] * np.maximum(A, 0.0)  # the camera's noise variance at the pixel's level
    if g.inverse:
        p = blk[g.first:g.first + 2 * nb:2].astype(np.float32)
        q = blk[g.first + 1:g.first + 2 * nb:2].astype(np.float32)
        diff = p - q
        sd = np.sqrt(2.0 * var)  # noise of pattern - inverse
    else:
        p = blk[g.first:g.first + nb].astype(np.float32)
        if span is not None:
            thr = (blk[ps.white].astype(np.float32) + blk[ps.black].astype(np.float32)) / 2.0
        else:
            # midway between the pixel's dark and lit levels, from the fringes' mean and modulation
            c = _resp.harmonics(ps.phase_blocks(axis)[-1].fringe, 1.0)
            thr = A + B * (0.5 - c[0]) / max(c[1], 1e-6)
        diff = p - thr
        sd = np.sqrt(var)
    bits, contrast = diff > 0, np.abs(diff)
    certain = contrast >= np.maximum(t if g.inverse else t / 2.0, 3.0 * sd)
    comp = comp_c = None
    if g.complementary:
        comp, comp_c = bits[-1], certain[-1]
        bits, contrast, certain = bits[:-1], contrast[:-1], certain[:-1]
    m = _unwrap.gray_orders(bits, contrast, certain, u, reason, comp, comp_c, margin=3.0 * sd)
    return x0 + period * (m + u), period * su
