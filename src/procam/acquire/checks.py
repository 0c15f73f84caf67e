"""Checks while capturing: the pre-flight exposure check and per-frame verification.

Plain functions on arrays, so each can be tested on its own; the capture loop
(:mod:`procam.acquire.session`) decides what to do with the verdicts (re-grab, stop).

Pre-flight (:func:`preflight`)
    From a white, a black and a second white frame: is the projector's light visible, how much of
    the white frame is saturated on the board (or on the lit area when the board is not known), the
    dark level, the contrast, whether the two white frames agree, and exposure suggestions.  Its
    :class:`Reference` holds a fixed sample of lit pixels with their white and black values, so
    every later frame is judged normalised, ``p = (I - black) / (white - black)`` (0 where the
    projector is black, 1 where it is white, whatever the albedo or vignetting).

Per frame (:func:`check_frame`)
    The white frame must be at ``p`` ~ 1, the black one at ~ 0, a pattern within [0, 1].  The
    inverse of a pair must be anti-correlated with its pattern (else it is a stale copy of it).
    The first frame of a pair that matches the frame before it is suspect: stale, or the two
    patterns coincide where the camera looks (the capture loop re-grabs to tell).

Per pair (:func:`check_pair`)
    A pattern and its inverse: where the pattern is clearly white or black, the difference
    ``pattern - inverse`` must follow the pattern (the code), and ``p_pattern + p_inverse`` must be
    1 (a camera is linear in the light: a sum away from 1 means the exposure, gain or the
    projector's brightness changed since the pre-flight).

Thresholds are fractions of the pre-flight ``white - black`` unless said otherwise.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from ..capture import describe_frame, pair_role
from ..board import board_region

#: Smallest visible projector light: 99th percentile of white - black, in 8-bit grey levels
#: (as :func:`procam.capture.check_light`).
MIN_SPAN_DN = 10.0
#: Largest saturated fraction of the white frame on the board (as :func:`procam.capture.exposure_warnings`).
MAX_SATURATED = 0.02


def full_scale(*images: np.ndarray) -> float:
    """Full-scale value: 255 for uint8, else the smallest 2^b - 1 (b = 10, 12, 14, 16) holding the maximum."""
    from ..io.files import full_scale_of

    return full_scale_of(np.stack([np.asarray(i) for i in images]))


@dataclass(frozen=True)
class Reference:
    """The pre-flight's white and black at a fixed sample of lit pixels.

    Attributes
    ----------
    idx : (n,) int64 flat indices (row-major) of the sampled pixels.
    white, black : (n,) float32 grey values there.
    shape : (H, W) of the camera frames.
    full_scale : the frames' full-scale value.
    noise : standard deviation of ``p`` from noise, estimated from the two white frames (0 if one).
    """

    idx: np.ndarray
    white: np.ndarray
    black: np.ndarray
    shape: tuple
    full_scale: float
    noise: float = 0.0

    def normalise(self, image: np.ndarray) -> np.ndarray:
        """(n,) float32 ``(I - black) / (white - black)`` of ``image`` (H, W) at the sampled pixels."""
        image = np.asarray(image)
        if image.shape != tuple(self.shape):
            raise ValueError(f"frame of shape {image.shape}, the pre-flight frames were {tuple(self.shape)}")
        v = image.reshape(-1)[self.idx].astype(np.float32)
        return (v - self.black) / (self.white - self.black)


@dataclass(frozen=True)
class Preflight:
    """Verdict of :func:`preflight` (levels are fractions of full scale unless said otherwise).

    ok, reason : whether the capture may start, and if not the one-line reason with what to do.
    region : where the levels were measured: ``"board"`` or ``"lit area"`` (the projector's light).
    region_fraction : the region's share of the image.
    white_saturated : fraction of the region at full scale in the white frame.
    black_saturated : fraction of the whole black frame at full scale.
    white_level : 99th percentile of the white frame on the region.
    dark_level : median of the black frame on the region.
    contrast, contrast_low : median and 5th percentile of white - black on the region.
    span_dn : 99th percentile of white - black over the image, in 8-bit grey levels.
    repeat : median ``|white1 - white2| / (white - black)`` on the lit area (None with one white).
    noise : noise of ``p`` (see :class:`Reference`).
    exposure_factor : suggested exposure multiplier (None when the exposure is fine).
    suggestions : warnings and suggestions, one line each.
    reference : for the per-frame checks (None when refused before it could be built).
    """

    ok: bool
    reason: str
    full_scale: float
    region: str = "lit area"
    region_fraction: float = 0.0
    white_saturated: float = 0.0
    black_saturated: float = 0.0
    white_level: float = 0.0
    dark_level: float = 0.0
    contrast: float = 0.0
    contrast_low: float = 0.0
    span_dn: float = 0.0
    repeat: float | None = None
    noise: float = 0.0
    exposure_factor: float | None = None
    suggestions: tuple = ()
    reference: Reference | None = field(default=None, repr=False)

    def to_dict(self) -> dict:
        d = asdict(self)
        d.pop("reference")
        d["suggestions"] = list(self.suggestions)
        return {k: (round(v, 5) if isinstance(v, float) else v) for k, v in d.items()}


def _exposure_text(factor: float, exposure_ms: float | None) -> str:
    if exposure_ms:
        return f"about {exposure_ms * factor:.3g} ms (now {exposure_ms:.3g} ms)"
    return f"about {factor:.0%} of the current exposure"


def preflight(white: np.ndarray, black: np.ndarray, white2: np.ndarray | None = None, *,
              board_corners: np.ndarray | None = None, exposure_ms: float | None = None,
              max_saturated: float = MAX_SATURATED, min_span: float = MIN_SPAN_DN, max_repeat: float = 0.1,
              target: float = 0.8, sample: int = 20000, seed: int = 0) -> Preflight:
    """Judge the exposure from white and black frames before the sequence (never raises).

    Parameters
    ----------
    white, black : (H, W) uint8/uint16 frames of the projector showing all white / all black.
    white2 : a second white frame taken after ``black`` (catches a stale first frame and unstable
        exposure; gives the noise), or None.
    board_corners : (N, 2) camera pixels of the board's corners, to measure on the board; None =
        on the area the projector lights.
    exposure_ms : the camera's exposure, to word the suggestions in milliseconds.
    max_saturated : refuse when more of the region than this is saturated in the white frame.
    min_span : refuse when the 99th percentile of white - black is below this (8-bit grey levels).
    max_repeat : refuse when the two white frames differ by more than this (fraction of white - black).
    target : the white level (fraction of full scale) the exposure suggestions aim at.
    sample, seed : size and seed of the pixel sample kept in the :class:`Reference`.
    """
    white = np.asarray(white)
    black = np.asarray(black)
    if white.shape != black.shape or white.ndim != 2:
        raise ValueError(f"white and black must be (H, W) of one shape, got {white.shape} and {black.shape}")
    fs = full_scale(white, black) if white2 is None else full_scale(white, black, white2)
    W = white.astype(np.float32)
    B = black.astype(np.float32)
    if white2 is not None:
        W = 0.5 * (W + np.asarray(white2, np.float32))
    D = W - B
    span = float(np.percentile(D, 99))
    span_dn = span * 255.0 / fs
    black_sat = float(np.mean(black >= fs))
    if span_dn < min_span:
        return Preflight(False, "the projector's light is not visible to the camera: the white and black frames differ by "
                         f"at most {span_dn:.0f} grey levels (of 255) — check that the projector is on and shows the "
                         "patterns on the chosen display, its lens cap and input, and the camera's exposure",
                         fs, span_dn=span_dn, black_saturated=black_sat)
    if black_sat > 0.5:
        return Preflight(False, f"the black frame is saturated on {black_sat:.0%} of the image: nothing can be decoded — "
                         f"lower the exposure or gain ({_exposure_text(0.25, exposure_ms)})", fs,
                         span_dn=span_dn, black_saturated=black_sat, exposure_factor=0.25)
    lit = D > max(0.25 * span, 0.5 * min_span * fs / 255.0)
    lit_frac = float(lit.mean())
    if lit_frac < 0.005:
        return Preflight(False, f"the projector lights only {lit_frac:.1%} of the camera image: aim the camera at the "
                         "projected area (and the board into it)", fs, span_dn=span_dn, black_saturated=black_sat)
    if board_corners is not None:
        region, name = board_region(board_corners, (white.shape[1], white.shape[0])), "board"
        if region.sum() < 100:
            region, name = lit, "lit area"
    else:
        region, name = lit, "lit area"
    w_reg, b_reg, d_reg = white[region], B[region], D[region]
    sat = float(np.mean(w_reg >= fs))
    white_level = float(np.percentile(w_reg, 99)) / fs
    dark = float(np.median(b_reg)) / fs
    contrast = float(np.median(d_reg)) / fs
    contrast_low = float(np.percentile(d_reg, 5)) / fs
    repeat = noise = None
    if white2 is not None:
        diff = (white.astype(np.float32) - np.asarray(white2, np.float32))[lit]
        scale = float(np.median(D[lit]))
        repeat = float(np.median(np.abs(diff))) / scale
        noise = float(np.std(diff)) / np.sqrt(2.0) / scale
    common = dict(full_scale=fs, region=name, region_fraction=float(region.mean()), white_saturated=sat,
                  black_saturated=black_sat, white_level=white_level, dark_level=dark, contrast=contrast,
                  contrast_low=contrast_low, span_dn=span_dn, repeat=repeat, noise=noise or 0.0)
    if repeat is not None and repeat > max_repeat:
        return Preflight(False, f"the two white pre-flight frames differ by {repeat:.0%} of white - black: the camera "
                         "delivered a stale frame or its exposure is changing — switch off auto exposure and auto gain, "
                         "or raise --settle-ms", **common)
    suggestions = []
    factor = None
    if sat > max_saturated:
        factor = 0.5 if sat < 0.25 else 0.25
        return Preflight(False, f"the white frame is {sat:.0%} saturated on the {name} (more than {max_saturated:.0%}): "
                         f"lower the exposure to {_exposure_text(factor, exposure_ms)}, or lower the gain or the "
                         "projector's brightness", exposure_factor=factor, **common)
    if sat > 0:
        suggestions.append(f"the white frame is {sat:.1%} saturated on the {name}: corners there lose accuracy; "
                      f"consider lowering the exposure to {_exposure_text(0.8, exposure_ms)}")
    if white_level < 0.35:
        factor = min(8.0, target / max(white_level, 1e-3))
        suggestions.append(f"the white frame reaches only {white_level:.0%} of full scale on the {name}: raise the exposure "
                      f"to {_exposure_text(factor, exposure_ms)} for more contrast")
    if contrast_low * 255.0 < 3.0 and name == "board":
        suggestions.append(f"the darkest parts of the board differ by only {contrast_low * 255:.1f} grey levels between the "
                      "white and black frames: they will not decode; raise the exposure or the projector's brightness")
    if dark > 0.25:
        suggestions.append(f"the black frame is at {dark:.0%} of full scale on the {name}: ambient light or the projector's "
                      "black level is high; darken the room")
    ref = _reference(W, B, lit, fs, noise or 0.0, sample, seed)
    return Preflight(True, "", exposure_factor=factor, suggestions=tuple(suggestions), reference=ref, **common)


def _reference(W, B, lit, fs, noise, n, seed) -> Reference:
    flat = np.flatnonzero(lit.reshape(-1))
    if len(flat) > n:
        flat = np.sort(np.random.default_rng(seed).choice(flat, n, replace=False))
    return Reference(flat.astype(np.int64), W.reshape(-1)[flat].astype(np.float32),
                     B.reshape(-1)[flat].astype(np.float32), tuple(W.shape), fs, noise)


# --------------------------------------------------------------------------------------------
# per frame
# --------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class FrameCheck:
    """Verdict on one frame or pair.

    ok : the frame may be kept.  status : ``"ok"``, ``"unverified"`` (the camera does not resolve
    the stripes well enough to tell; kept), ``"stale"``, ``"level"`` (brightness off the pre-flight's)
    or ``"not-inverse"``.  reason : one line when not ok.  stats : the numbers behind it.
    """

    ok: bool
    status: str
    reason: str = ""
    stats: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {"ok": self.ok, "status": self.status, "reason": self.reason,
                "stats": {k: (round(float(v), 4) if isinstance(v, (float, np.floating)) else v)
                          for k, v in self.stats.items()}}


def modulation(p: np.ndarray) -> float:
    """``mean |2 p - 1|``: 1 for a frame that is fully white or black at every pixel (white, black, a
    resolved stripe pattern), near 0 for stripes the camera blurs to grey."""
    return float(np.mean(np.abs(2.0 * p - 1.0)))


def check_frame(p: np.ndarray, key, ps, previous=None, partner: np.ndarray | None = None, *, level_tol: float = 0.25,
                stale_frac: float = 0.25, min_modulation: float = 0.2) -> FrameCheck:
    """Judge one normalised frame ``p`` (:meth:`Reference.normalise`) of sequence frame ``key``.

    Parameters
    ----------
    p : (n,) normalised values of the frame.
    key : its index in the sequence ``ps`` (:class:`procam.patterns.PatternSet`).
    previous : ``(key, q)`` of the frame shown just before it (``key`` may be a label such as
        ``"pre-flight white"``), or None.
    partner : for the inverse of a pair, the accepted ``p`` of its pattern; None otherwise.
    level_tol : tolerance on the white (1) and black (0) levels and on the range of a pattern.
    stale_frac : "matches" means ``mean |p - q| < stale_frac * max(modulation(p), modulation(q))``.
    min_modulation : frames less modulated than this cannot be told apart (no verdict from them).

    Returns
    -------
    FrameCheck with status

    * ``"ok"`` / ``"unverified"`` (kept);
    * ``"level"``: white or black off its level, or a pattern outside [0, 1] (the exposure changed);
    * ``"stale"``: the inverse of a pair correlates positively with its pattern (an inverse has -1,
      whatever the exposure), or the white/black frame is off its level and matches the frame before it;
    * ``"same"``: the first frame of a pair matches the frame before it.  Either a stale frame, or
      the two patterns happen to coincide where the camera looks (the top bits, when the camera sees
      part of the projector's image); the capture loop re-grabs and, if the camera insists, keeps it.
    """
    m = modulation(p)
    stats = {"modulation": m}
    label = describe_frame(key, ps)
    match = None
    if previous is not None:
        pkey, q = previous
        mq = modulation(q)
        d = float(np.mean(np.abs(p - q)))
        stats["distance_to_previous"] = d
        if max(m, mq) >= min_modulation and d < stale_frac * max(m, mq):
            match = describe_frame(pkey, ps)
            stats["matches"] = match
    if key == ps.white or key == ps.black:
        want = 1.0 if key == ps.white else 0.0
        med = float(np.median(p))
        stats["level"] = med
        if abs(med - want) <= level_tol:
            return FrameCheck(True, "ok", "", stats)
        if match is not None:
            return FrameCheck(False, "stale", f"frame {label} looks like {match} shown before it instead of being "
                              f"{'white' if want else 'black'}: a stale frame from the camera's buffer", stats)
        return FrameCheck(False, "level", f"frame {label} is at {med:.2f} of the pre-flight white - black, expected "
                          f"{want:.0f}: the exposure, gain or projector brightness changed (switch off auto exposure "
                          "and auto gain)", stats)
    hi, lo = float(np.percentile(p, 99)), float(np.percentile(p, 1))
    stats.update(p99=hi, p1=lo)
    if hi > 1.0 + level_tol:
        return FrameCheck(False, "level", f"frame {label} is brighter than the pre-flight white (99th percentile at "
                          f"{hi:.2f} of white - black): the exposure or gain went up (switch off auto exposure and auto gain)",
                          stats)
    if lo < -level_tol:
        return FrameCheck(False, "level", f"frame {label} is darker than the pre-flight black (1st percentile at "
                          f"{lo:.2f} of white - black): the exposure or gain changed (switch off auto exposure and "
                          "auto gain)", stats)
    role, other = pair_role(key, ps)
    if role == "inverse" and partner is not None:
        sa, sb = float(partner.std()), float(p.std())
        if modulation(partner) >= min_modulation and min(sa, sb) > 0.05:
            corr = float(np.mean((p - p.mean()) * (partner - partner.mean())) / (sa * sb))
            stats["correlation_with_pattern"] = corr
            if corr > 0:
                return FrameCheck(False, "stale", f"frame {label} looks like {describe_frame(other, ps)} shown before it "
                                  f"rather than its inverse (correlation {corr:+.2f}, an inverse has -1): a stale frame "
                                  "from the camera's buffer", stats)
            return FrameCheck(True, "ok", "", stats)
        return FrameCheck(True, "unverified", "", stats)
    if match is not None:
        return FrameCheck(False, "same", f"frame {label} looks like {match} shown before it (mean difference "
                          f"{stats['distance_to_previous']:.2f} of white - black): a stale frame, or the two patterns "
                          "coincide where the camera looks", stats)
    if max(m, 0.0) < min_modulation:
        return FrameCheck(True, "unverified", "", stats)
    return FrameCheck(True, "ok", "", stats)


def check_pair(p_a: np.ndarray, p_b: np.ndarray, a: int, b: int, ps, *, min_agreement: float = 0.9,
               level_tol: float = 0.25, margin: float = 0.02, min_resolved: int = 50) -> FrameCheck:
    """Judge a pattern ``a`` and its inverse ``b`` (normalised, :meth:`Reference.normalise`).

    Where frame ``a`` is clearly white or black (``|p_a - 0.5| > 0.25``), the difference
    ``p_a - p_b`` must have the sign of ``p_a - 0.5`` (the code), by more than ``margin`` (noise),
    on at least ``min_agreement`` of the pixels, and the median of ``p_a + p_b`` must be within ``level_tol``
    of 1 among the white and among the black pixels separately (the sensor is linear in the light:
    another sum means the exposure, gain or projector brightness changed).  Fewer than
    ``min_resolved`` such pixels: ``"unverified"``.
    """
    res = np.abs(p_a - 0.5) > 0.25
    n = int(res.sum())
    stats = {"resolved": n}
    la, lb = describe_frame(a, ps), describe_frame(b, ps)
    if n < min_resolved:
        return FrameCheck(True, "unverified", "", stats)
    bit_a = p_a[res] > 0.5
    signed = np.where(bit_a, 1.0, -1.0) * (p_a[res] - p_b[res])
    agree = float(np.mean(signed > margin))
    stats["agreement"] = agree
    if agree < min_agreement:
        return FrameCheck(False, "not-inverse", f"frames {la} and {lb} are not a pattern and its inverse (their difference "
                          f"follows the code on only {agree:.0%} of the pixels): a stale or skipped frame", stats)
    s = (p_a + p_b)[res]
    for name, sel in (("white", bit_a), ("black", ~bit_a)):
        if sel.sum() >= min_resolved:
            lev = float(np.median(s[sel]))
            stats[f"sum_{name}"] = lev
            if abs(lev - 1.0) > level_tol:
                return FrameCheck(False, "level", f"pattern {la} and its inverse {lb} add up to {lev:.2f} of the pre-flight "
                                  "white - black where the pattern is " + name + ", expected 1: the exposure, gain or the "
                                  "projector's brightness changed mid-sequence (switch off auto exposure, auto gain and the "
                                  "projector's dynamic contrast)", stats)
    return FrameCheck(True, "ok", "", stats)


def check_drift(p_white_after: np.ndarray, *, level_tol: float = 0.25) -> FrameCheck:
    """A white frame taken after the sequence against the pre-flight's (normalised): its median must be 1."""
    lev = float(np.median(p_white_after))
    stats = {"level": lev}
    if abs(lev - 1.0) > level_tol:
        return FrameCheck(False, "level", f"the white frame after the sequence is at {lev:.2f} of the one before it: the "
                          "exposure or the projector's brightness drifted during the capture (switch off auto exposure; "
                          "let the projector warm up)", stats)
    return FrameCheck(True, "ok", "", stats)
