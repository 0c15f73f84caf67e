"""Decoding a phase-family capture: per camera pixel a sub-pixel projector column and row, their noise, validity
and reasons (:func:`decode_phase`, returning the :class:`~procam.decode.decoded.DecodeResult` every stage downstream
reads).

Two passes.  On a fixed sample of pixels (:data:`SAMPLE`) the projector's response and the camera's noise are
measured (:func:`procam.decode.phase.response.fit_response`).  Then, band by band of camera rows, every phase block's
wrapped phase (:mod:`procam.decode.phase.wrapped`), its correction for the projector's gamma (a lookup table, one index
per pixel: :meth:`procam.decode.phase.response.PhaseLUT.apply`), the fringe fractions and their noise (the camera's noise
at the pixel's level once per axis), the masks and the unwrapping (:mod:`procam.decode.phase.unwrap`), in place where the
arrays allow.

Masks (reason codes of :data:`procam.decode.decoded.REASONS`)
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
import threading
import warnings
from concurrent.futures import ThreadPoolExecutor
from contextlib import nullcontext
from dataclasses import dataclass

import numpy as np

from ...errors import ProcamWarning
from ...io import files as _files
from ...patterns.phase import PhaseSet
from .. import decoded as _d
from . import response as _resp
from . import unwrap as _unwrap
from . import wrapped as _wrapped

#: Pixels of the sample the response and the noise are measured on (and :mod:`procam.decode.phase.diagnose` judges).
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
    tolerance, max_sigma : the unwrapping's (:mod:`procam.decode.phase.unwrap`), cycles of the finer period.
    neighbours : order the pixels whose own coarser fringes are too faint (LOW_MODULATION: a black square, a dim
        wall) from the decoded pixels around them (:func:`procam.decode.phase.unwrap.neighbour_orders`), with the
        same two limits; False: each pixel from its own fringes only.
    """

    gamma: str | float = "auto"
    camera_noise: float | None = None
    shadow_threshold: float = 10.0
    contrast_threshold: float = 3.0
    tolerance: float = _unwrap.TOLERANCE
    max_sigma: float = _unwrap.MAX_SIGMA
    neighbours: bool = True

    def __post_init__(self):
        _d.check_phase_options(self.gamma, self.camera_noise, self.shadow_threshold, self.contrast_threshold)
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


def summary_lines(result: _d.DecodeResult) -> list[str]:
    """What a phase decode measured, in lines for a person: the coordinates' noise, the projector's gamma and how
    it was handled, the camera's noise, each block's modulation."""
    info = result.phase
    out = []
    for label, s in (("columns", result.sigma_col), ("rows", result.sigma_row)):
        ok = s[np.isfinite(s)]
        if ok.size:
            out.append(f"{label}: predicted noise of the decoded coordinate (camera noise and modulation only) median "
                       f"{np.median(ok):.3f} px, 90th percentile {np.percentile(ok, 90):.3f} px")
    if np.isfinite(info.gamma):
        how = ("corrected" if abs(info.gamma_used - 1.0) > 1e-6 else "not corrected") + \
              f", it leaves at most {info.gamma_error_px:.3f} px uncorrected"
        out.append(f"projector gamma {info.gamma:.2f} +- {info.gamma_std:.2f} measured from the frames ({how})")
    else:
        out.append(f"projector gamma not measured; the phases assume {info.gamma_used:g}")
    a, b = info.noise
    out.append(f"camera noise: sigma^2 = {a:.2f} + {b:.4f} x level (grey levels^2 at the input scale)")
    for st in info.blocks:
        out.append(f"  {'column' if st.axis == 'col' else 'row'} fringes #{st.frames[0]}-#{st.frames[-1]} (period "
                   f"{st.period:.4g} px, {st.steps} steps): median modulation {st.modulation:.1f} grey levels")
    return out


def _lut_px(lut, period: float) -> float:
    return 0.0 if lut is None else lut.max_error * period / (2.0 * np.pi)


#: The last few pass-1 results by their inputs: the description check (:mod:`procam.decode.phase.diagnose`)
#: decodes the capture's sample, then the decode fits the same sample again; the response is fitted once.
_PASS1: dict = {}
_PASS1_LOCK = threading.Lock()


def _response(sub, ps: PhaseSet, opts: PhaseOptions, fs: float, scale: float):
    """:func:`_fit_pass1` of the sample, fitted once per sample, sequence and options (the same inputs give the
    same bytes: a cached result is the one the fit would give again)."""
    import hashlib
    import json

    key = (hashlib.blake2b(np.ascontiguousarray(sub).tobytes(), digest_size=20).digest(), sub.shape, sub.dtype.str,
           json.dumps(ps.to_dict(), sort_keys=True, default=str), repr(opts), float(fs), float(scale))
    with _PASS1_LOCK:
        hit = _PASS1.get(key)
    if hit is None:
        hit = _fit_pass1(sub, ps, opts, fs, scale)
        with _PASS1_LOCK:
            while len(_PASS1) >= 4:
                _PASS1.pop(next(iter(_PASS1)))
            _PASS1[key] = hit
    resp, measured, used, err_px, noise, luts, notes, lit, stats = hit
    return resp, measured, used, err_px, noise, dict(luts), list(notes), lit.copy(), list(stats)


def _fit_pass1(sub, ps: PhaseSet, opts: PhaseOptions, fs: float, scale: float):
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
    return resp, measured, used, err_px, noise, luts, notes, lit, stats


def decode_phase(stack: np.ndarray, ps: PhaseSet, options: PhaseOptions = PhaseOptions(), *,
                 full_scale: float | None = None, band: int = 64, extras: bool = True,
                 method: str = "simple", threads: int = 2) -> _d.DecodeResult:
    """Decode a phase-family stack (see the module docstring).

    Parameters
    ----------
    stack : (K, H, W) uint8 or uint16 in ``ps``'s order (``K == ps.count``).
    ps : the sequence (:class:`procam.patterns.PhaseSet`).
    options : :class:`PhaseOptions`.
    full_scale : the input's full scale (default: from the stack, as :func:`procam.decode.decode`).
    band : camera rows processed at a time (speed only; 64: a 1280x800 decode in two threads 102 -> 87 ms against 32,
        whose smaller arrays cost more calls, each letting the interpreter lock go; 256 is slower again).
    threads : worker threads (speed only): the camera's bands and then the two axes' neighbour orders side by side
        (the same bits as one thread).
    extras : compute ``confidence`` (min over the axes of ``B / A`` of the finest fringes).
    method : the Gray bits' classifier; only the comparison of a pattern with its inverse (or a threshold) is
        implemented for the hybrid's Gray code, which its phase checks.

    Returns
    -------
    :class:`~procam.decode.decoded.DecodeResult` with sub-pixel ``col``/``row`` and ``sigma_col``/``sigma_row``,
    ``modulation_col``/``row`` and ``phase`` (:class:`PhaseInfo`).  Warns (:class:`~procam.errors.ProcamWarning`)
    with what ``phase.warnings`` holds.
    """
    stack = _d.checked_stack(stack, ps.count)
    fs = _files.full_scale_of(stack) if full_scale is None else float(full_scale)
    scale = fs / 255.0
    K, H, W = stack.shape
    idx = _d.sample_index(H * W, SAMPLE)
    sub = stack.reshape(K, -1)[:, idx].astype(np.float64)
    resp, measured, used, err_px, noise, luts, notes, lit, nsteps = _response(sub, ps, options, fs, scale)
    plan = _plan(ps, luts, noise)
    ctx = dict(ps=ps, opts=options, fs=fs, scale=scale, noise=noise, luts=luts, plan=plan)
    out = {k: np.empty((H, W), np.float32) for k in ("col", "row", "scol", "srow", "mcol", "mrow")}
    out["rcol"], out["rrow"] = np.empty((H, W), np.uint8), np.empty((H, W), np.uint8)
    out["conf"] = np.empty((H, W), np.float32) if extras else None
    hists = {"col": np.zeros(2 * W + 2, np.int64), "row": np.zeros(2 * H + 2, np.int64)}
    spatial = options.neighbours and ps.family == "phase"
    if spatial:   # the finest fringes' fraction, the coarsest estimate, their noise: for the neighbours' orders
        out.update({k: np.empty((H, W), np.float32) for k in ("ucol", "urow", "sucol", "surow", "acol", "arow",
                                                                "sacol", "sarow")})
    bands = [slice(y0, min(H, y0 + band)) for y0 in range(0, H, band)]
    n = max(1, int(threads))
    workers = min(n, len(bands))

    def run(share):               # every workers-th band, with its own scratch and histograms (summed after)
        scratch = _wrapped.Scratch(min(band, H), W, plan["steps"], stack.dtype)
        mine = {k: np.zeros_like(v) for k, v in hists.items()}
        for sl in bands[share::workers]:
            _band(stack[:, sl, :], sl, out, mine, scratch=scratch, **ctx)
        return mine

    window = 2 * max(15, min(H, W) // 20) + 1

    def order(axis):              # each axis its own arrays: the two run side by side
        finest = min(plan["axes"][axis], key=lambda bl: bl.period)
        before = out["r" + axis] == _d.OK
        _unwrap.neighbour_orders(out[axis], out["s" + axis], out["r" + axis], out["u" + axis], out["su" + axis],
                                 out["a" + axis], out["sa" + axis], finest.period, finest.fringe.x0, ps.size(axis),
                                 window=window, tolerance=options.tolerance, max_sigma=options.max_sigma)
        _count(hists[axis], out[axis], (out["r" + axis] == _d.OK) & ~before)

    with ThreadPoolExecutor(n) if n > 1 else nullcontext() as ex:
        each = map if ex is None else ex.map
        for part in each(run, range(workers)):
            for k in hists:
                hists[k] += part[k]
        if spatial:
            list(each(order, ("col", "row")))
    phase_blocks = [b for b in ps.blocks if b.kind == "phase"]
    stats = _block_stats(ps, lit, {b.first: st for b, st in zip(phase_blocks, nsteps)})
    info = PhaseInfo(measured, resp.gamma_std, used, err_px, resp.blur, noise, stats, tuple(notes))
    for w in notes:
        warnings.warn(w, ProcamWarning, stacklevel=2)
    rcol, rrow = out["rcol"], out["rrow"]
    zeros = np.zeros((H, W), np.uint8)
    return _d.DecodeResult(out["col"], out["row"], rcol == _d.OK, rrow == _d.OK, rcol, rrow, out["conf"], None, None,
                           ps, zeros, zeros.copy(), hists["col"], hists["row"], out["scol"], out["srow"],
                           out["mcol"], out["mrow"], info)


def _block_stats(ps: PhaseSet, lit, nsteps: dict) -> tuple:
    """:class:`BlockStats` of every phase block from its N-step estimates on the sample (``nsteps``: ``{first
    frame: (A, B, psi)}``)."""
    out = []
    for axis in ("col", "row"):
        blocks = ps.phase_blocks(axis)
        meds = []
        for b in blocks:
            B = nsteps[b.first][1]
            meds.append(float(np.median(B[lit])) if lit.any() else 0.0)
        typical = float(np.median(meds)) if meds else 0.0
        for b, m in zip(blocks, meds):
            out.append(BlockStats(axis, tuple(b.frames), b.period, b.steps, m, m / typical if typical > 0 else 0.0))
    return tuple(out)


def _plan(ps: PhaseSet, luts: dict, noise) -> dict:
    """What every band reuses: per phase block how to form its sums (:class:`procam.decode.phase.wrapped.SumPlan`),
    the constant of its noise, its lookup table; per axis its blocks coarsest first."""
    blocks = {}
    for b in ps.blocks:
        if b.kind != "phase":
            continue
        blocks[b.first] = {"sums": _wrapped.SumPlan(b.shifts()),
                           "k": np.float32(math.sqrt(2.0 / b.steps) / (2.0 * math.pi)),
                           "turn": np.float32(b.fringe.sign / (2.0 * math.pi)), "lut": luts.get(b.first)}
    return {"blocks": blocks, "axes": {a: ps.phase_blocks(a) for a in ("col", "row")},
            "steps": max(b.steps for b in ps.blocks if b.kind == "phase"),
            "a": np.float32(noise[0]), "b": np.float32(noise[1]), "sd0": np.float32(math.sqrt(noise[0]))}


def _phase_of(blk, bl, pb, scratch, mean: bool = False):
    """``(B, u, slope, A)`` float32 of one phase block's frames in the band ``blk`` (``slope`` None without a
    lookup table, ``A`` the frames' mean when ``mean``, else None)."""
    import cv2

    C, S, M = _wrapped.block_sums([blk[k] for k in bl.frames], pb["sums"], scratch, mean)
    u = cv2.phase(C, S)  # atan2(-sum I sin d, sum I cos d) in [0, 2 pi]
    B = _wrapped.magnitude(C, S)
    B *= np.float32(2.0 / bl.steps)
    A = M.copy() if mean else None
    slope = None
    if pb["lut"] is not None:
        u, slope = pb["lut"].apply(u)
    u *= pb["turn"]
    np.floor(u, out=C)  # C is spent: its buffer takes the floor
    u -= C
    return B, u, slope, A


def _level_noise(A, plan):
    """float32 standard deviation of the camera's noise at the level ``A`` (one per axis and band), or a
    scalar when it does not depend on the level."""
    if plan["b"] > 0:
        sd = np.maximum(A, np.float32(0.0))
        sd *= plan["b"]
        sd += plan["a"]
        return np.sqrt(sd, out=sd)
    return plan["sd0"]


def _noise_of(B, sd, slope, pb):
    """float32 standard deviation of a block's fringe fraction (cycles) from its modulation ``B`` and the
    camera's noise ``sd`` at the pixel's level (:func:`_level_noise`)."""
    if np.ndim(sd) == 0:
        su = (sd * pb["k"]) / B
    else:
        su = sd * pb["k"]
        su /= B
    if slope is not None:
        su *= slope
    return su


def _mark(reason, code, mask):
    """``reason = code`` where ``mask`` and the pixel is still OK (in place)."""
    mask &= reason == _d.OK
    np.copyto(reason, np.uint8(code), where=mask)


def _band(blk, sl, out, hists, *, ps: PhaseSet, opts: PhaseOptions, fs, scale, noise, luts, plan, scratch=None):
    """Decode the rows ``sl`` (frames ``blk`` (K, h, W)) into ``out`` (see :func:`decode_phase`)."""
    h, w = blk.shape[1:]
    if scratch is None:
        scratch = _wrapped.Scratch(h, w, plan["steps"], blk.dtype)
    span = dark = None
    # the pixel's level (the finest fringes' mean) is needed for shot noise, the confidence and the hybrid's Gray
    # thresholds only
    need_level = plan["b"] > 0 or out["conf"] is not None or ps.family == "gray-phase"
    shadow_t = np.float32(opts.shadow_threshold * scale / 2.0)
    if ps.white is not None and ps.black is not None:
        span = blk[ps.white].astype(np.float32) - blk[ps.black]
        dark = span < 2.0 * shadow_t
    conf = None
    with np.errstate(divide="ignore", invalid="ignore"):
        for axis, key, rkey, skey, mkey in (("col", "col", "rcol", "scol", "mcol"),
                                            ("row", "row", "rrow", "srow", "mrow")):
            n = ps.size(axis)
            blocks = plan["axes"][axis]  # coarsest first
            peak = blk[blocks[0].first].copy()
            phases = []
            for bl in blocks:
                for k in bl.frames:
                    np.maximum(peak, blk[k], out=peak)
                phases.append(_phase_of(blk, bl, plan["blocks"][bl.first], scratch,
                                        mean=bl is blocks[-1] and need_level))
            B, A = phases[-1][0], phases[-1][3]  # the pixel's level: the finest fringes' mean
            shadow = phases[0][0] < shadow_t
            sd = _level_noise(A, plan)
            levels = [(u, _noise_of(Bk, sd, slope, plan["blocks"][bl.first]), bl.period, bl.fringe.x0)
                      for bl, (Bk, u, slope, _) in zip(blocks, phases)]
            reason = np.zeros((h, w), np.uint8)
            if dark is not None:
                shadow |= dark
            np.copyto(reason, np.uint8(_d.SHADOW), where=shadow)
            _mark(reason, _d.SATURATED, peak >= fs)
            if ps.family == "phase":
                x, sx = _unwrap.hierarchical(levels, reason, tolerance=opts.tolerance, max_sigma=opts.max_sigma)
            elif ps.family == "heterodyne":
                x, sx = _unwrap.heterodyne(levels, reason, tolerance=opts.tolerance, max_sigma=opts.max_sigma)
            else:
                x, sx = _gray_phase(blk, ps, axis, levels[0], (A, B), span, reason, opts, scale, noise)
            off = x < np.float32(-0.5)
            off |= x > np.float32(n - 0.5)
            _mark(reason, _d.OUT_OF_RANGE, off)
            bad = reason != _d.OK
            fin = bad & (reason != _d.OUT_OF_RANGE) & (reason != _d.ORDER_DISAGREE)
            np.logical_not(fin, out=fin)  # OK, OUT_OF_RANGE or ORDER_DISAGREE: a coordinate was decoded
            _count(hists[axis], x, fin)
            xo, so = out[key][sl], out[skey][sl]
            np.copyto(xo, x, casting="unsafe")
            np.copyto(so, sx, casting="unsafe")
            np.copyto(xo, np.float32(np.nan), where=bad)
            np.copyto(so, np.float32(np.nan), where=bad)
            out[mkey][sl] = B
            out[rkey][sl] = reason
            if "u" + axis in out:
                fine = min(range(len(blocks)), key=lambda i: blocks[i].period)
                out["u" + axis][sl], out["su" + axis][sl] = levels[fine][0], levels[fine][1]
                u0, su0, span, x00 = levels[0]      # the coarsest: absolute (it spans the panel)
                out["a" + axis][sl], out["sa" + axis][sl] = x00 + span * u0, span * su0
            if out["conf"] is not None:
                c = np.clip(B / np.maximum(A, np.float32(1e-6)), 0.0, 1.0)
                conf = c if conf is None else np.minimum(conf, c)
    if out["conf"] is not None:
        out["conf"][sl] = conf


def _count(hist: np.ndarray, x: np.ndarray, where: np.ndarray) -> None:
    """``hist[k] +=`` the number of pixels ``where`` whose ``x`` rounds to ``k`` (clipped to the histogram's
    ends)."""
    v = x[where]
    np.clip(v, 0, len(hist) - 1, out=v)
    hist += np.bincount(np.rint(v, out=v).astype(np.intp), minlength=len(hist))


def _gray_phase(blk, ps, axis, level, finest, span, reason, opts, scale, noise):
    """The gray-phase coordinate of one axis: Gray bits, their orders, the fringe fraction (see
    :func:`procam.decode.phase.unwrap.gray_orders`)."""
    u, su, period, x0 = level
    A, B = finest
    g = ps.gray_block(axis)
    t = opts.contrast_threshold * scale
    nb = g.bits + int(g.complementary)
    # the camera's noise at the pixel's level: sure bits differ by more than 3 of its standard deviations
    if noise[1] > 0:
        sd = np.sqrt(np.float32(noise[0]) + np.float32(noise[1]) * np.maximum(A, 0.0))
    else:
        sd = np.float32(math.sqrt(noise[0]))
    if g.inverse:
        p = blk[g.first:g.first + 2 * nb:2]
        q = blk[g.first + 1:g.first + 2 * nb:2]
        bits = p > q
        contrast = np.maximum(p, q)
        contrast -= np.minimum(p, q)  # |p - q|, exact in the frames' own type
        sd = sd * np.float32(math.sqrt(2.0))
        need = np.maximum(np.float32(t), 3.0 * sd)
    else:
        p = blk[g.first:g.first + nb].astype(np.float32)
        if span is not None:
            thr = (blk[ps.white].astype(np.float32) + blk[ps.black]) / 2.0
        else:
            # midway between the pixel's dark and lit levels, from the fringes' mean and modulation
            c = _resp.harmonics(ps.phase_blocks(axis)[-1].fringe, 1.0)
            thr = A + B * np.float32((0.5 - c[0]) / max(c[1], 1e-6))
        diff = p - thr
        bits, contrast = diff > 0, np.abs(diff)
        need = np.maximum(np.float32(t / 2.0), 3.0 * sd)
    certain = contrast >= need
    comp = comp_c = None
    if g.complementary:
        comp, comp_c = bits[-1], certain[-1]
        bits, contrast, certain = bits[:-1], contrast[:-1], certain[:-1]
    if g.bit_order == "lsb-first":  # the orders below take the bits most significant first
        bits, contrast, certain = bits[::-1], contrast[::-1], certain[::-1]
    m = _unwrap.gray_orders(bits, contrast, certain, u, reason, comp, comp_c, margin=4.0 * sd, su=su)
    x = m.astype(np.float32)
    x += u
    x *= np.float32(period)
    x += np.float32(x0)
    return x, period * su
