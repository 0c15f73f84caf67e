"""The capture-folder format, both ways: a pose's folder -> validated image stack and its
:class:`~procam.patterns.PatternSet` (:func:`load_capture`), and a pattern/capture sequence -> a folder
of zero-padded PNGs plus ``patterns.json`` (:func:`write_sequence`).

Checks, each failing with a one-line :class:`~procam.errors.CaptureError` that names the
folder or file and says what to do:

* the folder exists and holds images (``_files.list_images``), all of one size and bit depth;
* the number of images matches the projector size (with hints when it does not);
* the white and black frames are where the order puts them, judged from the images;
* every pattern is followed by its inverse (catches shuffled or missing frames).
"""

from __future__ import annotations

import functools
import json
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import _files, patterns
from .errors import CaptureError


@dataclass(frozen=True)
class Capture:
    """A validated capture: ``stack`` (K, H, W) uint8/uint16, its ``files`` and ``pattern_set``."""

    stack: np.ndarray
    files: tuple
    pattern_set: patterns.PatternSet
    folder: Path
    warnings: tuple = ()

    @property
    def white(self) -> np.ndarray:
        return self.stack[self.pattern_set.white]

    @property
    def black(self) -> np.ndarray:
        return self.stack[self.pattern_set.black]


def resolve_pattern_set(folder, projector=None, order=None, step=None) -> patterns.PatternSet:
    """The PatternSet for ``folder``: from ``projector`` (w, h), ``order`` and ``step``, else from its
    patterns.json, else the defaults (opencv order, step 1)."""
    meta = _files.read_sidecar(folder, "patterns.json")
    if meta is not None and not isinstance(meta, dict):
        meta = {}
    if projector is None:
        if meta is None:
            raise CaptureError(f"{folder}: the projector size is unknown; pass --projector WIDTHxHEIGHT "
                               "(no patterns.json in the folder)")
        try:
            projector = (int(meta["width"]), int(meta["height"]))
        except (KeyError, TypeError, ValueError):
            raise CaptureError(f"{Path(folder) / 'patterns.json'}: no valid width/height; fix it or pass "
                               "--projector WIDTHxHEIGHT") from None
    if order is None:
        order = meta.get("order", "opencv") if meta else "opencv"
        if order not in patterns.ORDERS:
            raise CaptureError(f"{Path(folder) / 'patterns.json'}: unknown order {order!r}; fix it or pass --order")
    if step is None:
        try:
            step = int(meta.get("step", 1)) if meta else 1
        except (TypeError, ValueError):
            raise CaptureError(f"{Path(folder) / 'patterns.json'}: invalid step; fix it or pass --step") from None
    try:
        return patterns.pattern_set(projector[0], projector[1], order, step)
    except ValueError as e:
        raise CaptureError(f"{folder}: {e}") from None


def _count_hint(found: int, ps: patterns.PatternSet) -> str:
    w, h = ps.width, ps.height
    if found == ps.count - 2:
        return (" — two short: the white and black frames seem to be missing (OpenCV's GrayCodePattern.generate() "
                "does not include them; capture them as the last two frames, or use 'procam patterns')")
    n = min(ps.col_bits, ps.row_bits)
    if ps.col_bits != ps.row_bits and found == 2 + 4 * n:
        return (f" — this matches scan3d-capture's sequence with {n} bits on both axes, which drops column bits; "
                "re-capture with the sequence from 'procam patterns'")
    guesses = [f"{a}x{b}" for a, b in [(1920, 1080), (1280, 800), (1280, 720), (1024, 768), (800, 600),
                                        (1920, 1200), (3840, 2160), (1400, 1050), (1366, 768), (912, 1140)]
               if patterns.pattern_set(a, b).count == found and (a, b) != (w, h)]
    steps = [k for k in (2, 3, 4, 8) if ps.step == 1 and patterns.pattern_set(w, h, ps.order, k).count == found]
    hints = []
    if guesses:
        hints.append(f"that count fits a projector of {', '.join(guesses[:3])}: check --projector")
    if steps:
        hints.append(f"it fits this projector with --step {steps[0]} (one code per {steps[0]}x{steps[0]} pixels, "
                     "kamino410's graycode_step)")
    if hints:
        return " — " + "; or ".join(hints)
    return " — check --projector and that no frames are missing or extra"


def _sample(stack: np.ndarray, n: int = 20000) -> np.ndarray:
    """(K, n) values at a fixed pseudo-random set of pixels (no aliasing with periodic stripes)."""
    flat = stack.reshape(len(stack), -1)
    if flat.shape[1] <= n:
        return flat.astype(np.float32)
    return np.take(flat, _sample_index(flat.shape[1], n), axis=1).astype(np.float32)


@functools.lru_cache(maxsize=8)
def _sample_index(size: int, n: int) -> np.ndarray:
    idx = np.sort(np.random.default_rng(0).choice(size, n, replace=False))
    idx.flags.writeable = False
    return idx


def frame_levels(stack: np.ndarray, sub: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Per frame, the 5th and 95th percentiles over well-lit pixels of
    ``(I_k - min_k I) / (max_k I - min_k I)``.

    A white frame is lit everywhere (5th percentile near 1), a black frame nowhere (95th near 0),
    a pattern in parts (5th near 0, 95th near 1) — whatever the scene's albedo or vignetting.
    ``sub`` is :func:`_sample` of ``stack`` if the caller has it already.
    """
    sub = _sample(stack) if sub is None else sub
    lo, hi = sub.min(axis=0), sub.max(axis=0)
    span = hi - lo
    lit = span > 0.25 * np.percentile(span, 99)
    if lit.sum() < 10:
        return np.full(len(stack), 0.5), np.full(len(stack), 0.5)
    norm = (sub[:, lit] - lo[lit]) / span[lit]
    return np.percentile(norm, 5, axis=1), np.percentile(norm, 95, axis=1)


def check_light(stack: np.ndarray, folder, min_span: float = 10.0, sub: np.ndarray | None = None) -> None:
    """Raise CaptureError when the frames hardly differ (projector off, lens cap, far too dark)."""
    sub = _sample(stack) if sub is None else sub
    span = np.percentile(sub.max(axis=0) - sub.min(axis=0), 99)
    if span < min_span * _files.full_scale_of(stack) / 255.0:
        raise CaptureError(f"{folder}: the frames hardly differ (99th percentile of max - min is {span:.0f} grey "
                           "levels): the projector's light is not visible — check that the projector shows the "
                           "sequence, the exposure, and the lens cap")


def check_white_black(stack: np.ndarray, ps: patterns.PatternSet, folder, files,
                      sub: np.ndarray | None = None) -> None:
    """Raise CaptureError when the white/black frames are not where ``ps.order`` puts them."""
    p5, p95 = frame_levels(stack, sub)
    if p5[ps.white] > 0.5 and p95[ps.black] < 0.5:
        return
    brightest, darkest = int(np.argmax(p5)), int(np.argmin(p95))
    other = [o for o in patterns.ORDERS if o != ps.order][0]
    ps2 = patterns.pattern_set(ps.width, ps.height, other, ps.step)
    if brightest == ps2.white and darkest == ps2.black:
        suggestion = f"; they look like order '{other}' (white #{ps2.white}, black #{ps2.black}): pass --order {other}"
    else:
        suggestion = (f"; the brightest frame is #{brightest} ({Path(files[brightest]).name}) and the darkest "
                      f"#{darkest} ({Path(files[darkest]).name}): frames may be out of order, or the projector "
                      "was not showing the sequence")
    raise CaptureError(
        f"{folder}: the white and black frames are not where order '{ps.order}' puts them "
        f"(#{ps.white} {Path(files[ps.white]).name} and #{ps.black} {Path(files[ps.black]).name})" + suggestion)


def check_pairs(stack: np.ndarray, ps: patterns.PatternSet, folder, files, min_spread: float = 0.15,
                max_correlation: float = -0.5, sub: np.ndarray | None = None) -> None:
    """Raise CaptureError when a pattern is not followed by its inverse.

    On well-lit pixels both images are normalised, ``p' = (p - black) / (white - black)``.  A
    pattern and its inverse are strongly anti-correlated; two unrelated frames are not.  Pairs
    the camera does not resolve (spread of ``p'`` below ``min_spread``, e.g. the finest stripes of
    a high-resolution projector) are skipped: decoding marks them as low contrast anyway.
    """
    sub = _sample(stack) if sub is None else sub
    w, b = sub[ps.white], sub[ps.black]
    c = w - b
    lit = c > 0.25 * np.percentile(c, 99)
    if lit.sum() < 100:
        raise CaptureError(f"{folder}: the projector's light is not visible in the captures (white and black frames "
                           "look the same); check exposure and that the projector shows the sequence")
    bl, cl = b[lit], c[lit]
    for axis in ("col", "row"):
        for j, (a, i) in enumerate(ps.pair_indices(axis)):
            p = (sub[a][lit] - bl) / cl
            q = (sub[i][lit] - bl) / cl
            sp, sq = p.std(), q.std()
            if sp < min_spread and sq < min_spread:
                continue
            corr = float(np.mean((p - p.mean()) * (q - q.mean())) / max(sp * sq, 1e-12))
            if corr > max_correlation:
                raise CaptureError(
                    f"{folder}: images #{a} ({Path(files[a]).name}) and #{i} ({Path(files[i]).name}) do not look "
                    f"like a pattern and its inverse ({axis} bit {j}, correlation {corr:+.2f}); frames may be "
                    "missing, repeated or out of order — re-capture, or check that the file names sort in "
                    "capture order")


def load_capture(folder, projector=None, order=None, check: bool = True, step=None, reader=None) -> Capture:
    """Read and validate a pose folder.

    Parameters
    ----------
    folder : path of the pose's folder.
    projector : (width, height) of the projector, or None to read it from ``patterns.json``.
    order : "opencv" (default) or "moreno", or None for ``patterns.json``'s / the default.
    check : run the image-based checks (white/black position, pattern/inverse pairs).
    step : projector pixels per code (None: patterns.json's, else 1).
    reader : ``reader(files) -> stack``, default :func:`procam._files.read_images` (e.g.
        :meth:`procam.stream.Prefetcher.read`, which has them read already).
    """
    folder = Path(folder)
    files = _files.list_images(folder)
    ps = resolve_pattern_set(folder, projector, order, step)
    if len(files) != ps.count:
        raise CaptureError(f"{folder}: expected {ps.count} images for a {ps.width}x{ps.height} projector"
                           + (f" with step {ps.step}" if ps.step > 1 else "") + " "
                           f"({ps.col_bits} column + {ps.row_bits} row bits, pattern + inverse each, plus white "
                           f"and black; the same count for --order opencv and moreno), found {len(files)}"
                           + _count_hint(len(files), ps))
    stack = (reader or _files.read_images)(files)
    warnings = ()
    if check:
        sub = _sample(stack)  # one pixel sample serves every check
        check_light(stack, folder, sub=sub)
        check_white_black(stack, ps, folder, files, sub=sub)
        check_pairs(stack, ps, folder, files, sub=sub)
        warnings = exposure_warnings(stack, ps, folder, files)
    return Capture(stack, tuple(files), ps, folder, warnings)


def exposure_warnings(stack: np.ndarray, ps: patterns.PatternSet, folder, files,
                      max_saturated: float = 0.02) -> tuple:
    """Warnings about over-exposure: saturated pixels in the white frame (corners and stripe edges lose
    accuracy there) or in the black frame (nothing decodes there).  Raises CaptureError when the black
    frame is saturated over most of the image."""
    fs = _files.full_scale_of(stack)
    out = []
    for idx, what in ((ps.white, "white"), (ps.black, "black")):
        frac = float(np.mean(stack[idx] >= fs))
        if what == "black" and frac > 0.5:
            raise CaptureError(f"{files[idx]}: the black frame is saturated on {frac:.0%} of the image; nothing can "
                               "be decoded there — reduce the exposure or gain and re-capture")
        if frac > max_saturated:
            out.append(f"{Path(folder) / Path(files[idx]).name}: {frac:.1%} of the {what} frame is saturated (value {fs:.0f}); "
                       "reduce the exposure so the white frame stays below full scale")
    return tuple(out)


# ------------------------------------------------------------------------------------------------
# writing
def remove_stale(out_dir, keep, prefix: str = "") -> list[Path]:
    """Delete ``{prefix}NN.png`` files in ``out_dir`` that are not in ``keep``.

    An earlier run with a longer sequence (e.g. a 1920x1200 projector after a 1024x768 one)
    leaves ``pattern_44.png`` ... behind, which a loader would read as part of the new
    sequence.  Only names made of ``prefix``, decimal digits and ``.png`` are touched.

    Parameters
    ----------
    out_dir : the folder.
    keep : paths (or names) just written.
    prefix : file-name prefix of the sequence (``""`` for a capture folder of ``00.png`` ...).

    Returns
    -------
    list of the deleted paths.
    """
    keep = {Path(p).name for p in keep}
    pat = re.compile(re.escape(prefix) + r"\d+\.png")
    stale = sorted(p for p in Path(out_dir).iterdir()
                   if p.is_file() and pat.fullmatch(p.name) and p.name not in keep)
    for p in stale:
        p.unlink()
    return stale


def write_sequence(out_dir, stack: np.ndarray, ps: patterns.PatternSet, prefix: str = "") -> list[Path]:
    """Write ``stack`` as zero-padded PNGs plus ``patterns.json`` into ``out_dir``.

    Each file is written under a hidden temporary name and renamed (:func:`procam._files.write_image`),
    so an interrupted run leaves no half-written image.  ``{prefix}NN.png`` files of an earlier,
    longer sequence are deleted (:func:`remove_stale`).  Returns the image paths.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    digits = max(2, len(str(ps.count - 1)))
    paths = [_files.write_image(out / f"{prefix}{i:0{digits}d}.png", img) for i, img in enumerate(stack)]
    remove_stale(out, paths, prefix)
    meta = ps.to_dict()
    meta["files"] = [p.name for p in paths]
    _files.write_text(out / "patterns.json", json.dumps(meta, indent=2))
    return paths
