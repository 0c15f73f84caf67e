"""Reading a capture folder: a pose's folder -> validated image stack and its
:class:`~procam.patterns.PatternSet` (:func:`load_capture`).

Checks, each failing with a one-line :class:`~procam.errors.CaptureError` that names the
folder or file and says what to do:

* the folder exists and holds images (``_files.list_images``), all of one size and bit depth; an
  entry named like an image that is a folder or a broken link is named;
* the sequence is the frames the folder's manifest (or ``patterns.json``) lists when they are all there
  (other images, e.g. a figure written next to them, are ignored with a warning); procam's own outputs
  listed in the manifest are ignored;
* the number of images matches the projector size; when it does not, the message names the image that
  is not part of the sequence (another size), the frame that is missing or the one too many (judged
  from the pattern/inverse pairs), or hints at the projector size and step;
* the white and black frames are where the order puts them, judged from the images;
* every pattern is followed by its inverse (catches shuffled or missing frames);
* the bits come in the order the description says, most significant first unless its ``bit_order`` says
  otherwise (:func:`~procam.capture.bit_order.check_bit_order`: the finer the bit, the more stripe edges);
* when those checks fail, saturation (an over-exposed capture) and frames of another pose (a pattern
  and its inverse that do not add up like every other pair) are named as the cause.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import patterns
from ..errors import CaptureError
from ..io import files as _files
from ..io import images as _images
from .bit_order import check_bit_order
from .describe import _count_hint, read_patterns_json, resolve_pattern_set  # noqa: F401 (re-exported)
from .frames import describe_frame, frame_role
from .sample import _sample, frame_levels, sample_index  # noqa: F401 (sample_index, frame_levels: re-exported)


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
        """The board image: the white frame, or without one the mean of the phase frames
        (:func:`procam.capture.phase.board_image`)."""
        from .phase import board_image

        return board_image(self.stack, self.pattern_set)

    @property
    def fingerprint(self) -> str:
        """Which capture this is, for the files made from it (decoded maps): ``sha256:`` of the frames' size and
        of :attr:`white` as read (hex)."""
        import hashlib

        white = np.ascontiguousarray(self.white)
        h = hashlib.sha256(f"{white.shape} {white.dtype.str} {self.pattern_set.count}".encode())
        h.update(white.tobytes())
        return "sha256:" + h.hexdigest()

    def picture(self) -> np.ndarray:
        """The board as a person sees it: the white frame's file read again in colour when it is colour, else
        :attr:`white` (a phase family without a white frame: the mean of its fringes, grey)."""
        if self.pattern_set.white is None:
            return self.white
        from ..io import images as _images

        return _images.read_image(self.files[self.pattern_set.white], gray=False)

    @property
    def black(self) -> np.ndarray | None:
        """The black frame, or None when the sequence has none."""
        return None if self.pattern_set.black is None else self.stack[self.pattern_set.black]


def check_light(stack: np.ndarray, folder, min_span: float = 10.0, sub: np.ndarray | None = None) -> None:
    """Raise CaptureError when the frames hardly differ (projector off, lens cap, far too dark, or every
    frame saturated)."""
    sub = _sample(stack) if sub is None else sub
    span = np.percentile(sub.max(axis=0) - sub.min(axis=0), 99)
    fs = _files.full_scale_of(stack)
    if span < min_span * fs / 255.0 and np.median(sub) >= fs:
        raise CaptureError(f"{folder}: every frame is saturated (at full scale, {fs:.0f}, almost everywhere): the "
                           "capture is over-exposed — reduce the exposure or gain and re-capture")
    if span < min_span * fs / 255.0:
        raise CaptureError(f"{folder}: the frames hardly differ (99th percentile of max - min is {span:.0f} grey "
                           "levels): the projector's light is not visible — check that the projector shows the "
                           "sequence, the exposure, and the lens cap")


def check_white_black(stack: np.ndarray, ps: patterns.PatternSet, folder, files,
                      sub: np.ndarray | None = None) -> None:
    """Raise CaptureError when the white/black frames are not where ``ps.order`` puts them."""
    sub = _sample(stack) if sub is None else sub
    p5, p95 = frame_levels(stack, sub, frames=(ps.white, ps.black))  # the other frames' only when they are not
    if p5[0] > 0.5 and p95[1] < 0.5:
        return
    diagnose(stack, ps, folder, files, sub)
    p5, p95 = frame_levels(stack, sub)
    brightest, darkest = int(np.argmax(p5)), int(np.argmin(p95))
    if brightest == ps.white and darkest == ps.black:
        # the white and black frames are where they belong, but other frames leave their range
        w, b = sub[ps.white], sub[ps.black]
        c = w - b
        lit = c > 0.25 * np.percentile(c, 99)
        if lit.sum() >= 10:
            out = np.array([np.mean(sub[k][lit] - w[lit] > 0.25 * c[lit]) + np.mean(b[lit] - sub[k][lit] > 0.25 * c[lit])
                            for k in range(len(sub))])
            worst = [int(k) for k in np.argsort(-out)[:3] if out[k] > 0.02]
            if worst:
                names = ", ".join(f"{Path(files[k]).name} (#{k}, {frame_role(k, ps)}, {out[k]:.0%})" for k in worst)
                raise CaptureError(
                    f"{folder}: the white and black frames are where order '{ps.order}' puts them, but {names} "
                    "{} brighter than the white frame or darker than the black one on part of the lit pixels: "
                    "a frame from another pose or capture, or the exposure or the light changed during the capture "
                    "— replace the frame or re-capture".replace("{}", "is" if len(worst) == 1 else "are"))
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
        for a, i in ps.pair_indices(axis):
            p = (sub[a][lit] - bl) / cl
            q = (sub[i][lit] - bl) / cl
            sp, sq = p.std(), q.std()
            if sp < min_spread and sq < min_spread:
                continue
            corr = float(np.mean((p - p.mean()) * (q - q.mean())) / max(sp * sq, 1e-12))
            if corr > max_correlation:
                diagnose(stack, ps, folder, files, sub)
                raise CaptureError(
                    f"{folder}: images #{a} ({Path(files[a]).name}) and #{i} ({Path(files[i]).name}) do not look "
                    f"like a pattern and its inverse ({frame_role(a, ps)}, correlation {corr:+.2f}); frames may be "
                    "missing, repeated or out of order — re-capture, or check that the file names sort in "
                    "capture order")


def _pairs(ps: patterns.PatternSet) -> list[tuple[int, int]]:
    """Every (pattern, inverse) pair, and (white, black), which add up the same way."""
    return [(int(a), int(i)) for axis in ("col", "row") for a, i in ps.pair_indices(axis)] + [(ps.white, ps.black)]


def saturated_fraction(stack: np.ndarray, ps: patterns.PatternSet, sub: np.ndarray | None = None) -> float:
    """Fraction of the projector-lit pixels at full scale in the white frame."""
    sub = _sample(stack) if sub is None else sub
    span = sub.max(axis=0) - sub.min(axis=0)
    lit = span > 0.25 * np.percentile(span, 99)
    if not lit.any():
        lit = np.ones_like(span, bool)
    return float(np.mean(sub[ps.white][lit] >= _files.full_scale_of(stack)))


def foreign_frames(sub: np.ndarray, ps: patterns.PatternSet, min_error: float = 0.03,
                   ratio: float = 3.0) -> list[tuple[tuple[int, ...], tuple[int, int]]]:
    """Frames that are not of this capture (another pose, another scene), judged from the pairs.

    A pattern and its inverse add up to the same image as every other pair (and as white + black)
    wherever one of them is lit and the other dark, whatever the camera's response.  A pair whose sum
    differs there from the per-pixel median of all pairs' sums, by more than ``min_error`` of the
    pixel's range and ``ratio`` times the median pair's difference, holds a foreign frame.  Which one:
    the frame that is further from the levels (dark, lit, half-lit) every other pair shows.

    Parameters
    ----------
    sub : (K, n) pixel sample of the stack (:func:`_sample`).
    ps : the pattern set.

    Returns
    -------
    list of (suspect frame indices, the pair): one suspect when one frame of the pair stands out, both when
    neither does (e.g. a whole pair of another pose, or the finest stripes the camera cannot resolve).
    """
    pairs = _pairs(ps)
    top, bot = sub.max(axis=0), sub.min(axis=0)
    span = top - bot
    lit = span > 0.25 * np.percentile(span, 99)
    if lit.sum() < 100:
        return []
    sums = np.median(np.stack([sub[a] + sub[i] for a, i in pairs]), axis=0)
    err = np.full(len(pairs), np.nan)
    for j, (a, i) in enumerate(pairs):
        m = lit & (np.abs(sub[a] - sub[i]) > 0.5 * span)
        if m.sum() >= 100:
            err[j] = float(np.percentile(np.abs(sub[a][m] + sub[i][m] - sums[m]) / span[m], 90))
    if np.isfinite(err).sum() < 3:
        return []
    med = float(np.nanmedian(err))
    bad = [j for j in range(len(pairs)) if err[j] > max(min_error, ratio * med)]
    if not bad or len(bad) > 3:
        return []
    good = [j for j in range(len(pairs)) if j not in bad and np.isfinite(err[j])]
    hi = np.median(np.stack([np.maximum(sub[pairs[j][0]], sub[pairs[j][1]]) for j in good]), axis=0)
    lo = np.median(np.stack([np.minimum(sub[pairs[j][0]], sub[pairs[j][1]]) for j in good]), axis=0)
    c = np.maximum(hi - lo, 1e-6)
    mid = 0.5 * (hi + lo)

    def dev(k):
        d = np.minimum(np.minimum(np.abs(sub[k] - hi), np.abs(sub[k] - lo)), np.abs(sub[k] - mid)) / c
        return float(np.median(d[lit]))

    out = []
    for j in bad:
        a, i = pairs[j]
        da, di = dev(a), dev(i)
        if da > 2 * di:
            out.append(((a,), (a, i)))
        elif di > 2 * da:
            out.append(((i,), (a, i)))
        else:
            out.append(((a, i), (a, i)))
    return out


def diagnose(stack: np.ndarray, ps: patterns.PatternSet, folder, files, sub: np.ndarray | None = None,
             max_saturated: float = 0.1) -> None:
    """Raise a CaptureError that names the cause when a capture fails its checks: saturation (an
    over-exposed capture), or the frames that are not of this pose (:func:`foreign_frames`).  Returns when
    neither explains it (the caller then raises its own message)."""
    sub = _sample(stack) if sub is None else sub
    sat = saturated_fraction(stack, ps, sub)
    if sat > max_saturated:
        fs = _files.full_scale_of(stack)
        raise CaptureError(
            f"{folder}: the capture is over-exposed: {sat:.0%} of the projector-lit pixels of the white frame "
            f"(#{ps.white} {Path(files[ps.white]).name}) are at full scale ({fs:.0f}), where a pattern and its "
            "inverse look alike — reduce the exposure or gain and re-capture")
    found = foreign_frames(sub, ps)
    if not found:
        return
    parts = []
    for suspects, (a, i) in found:
        if len(suspects) == 1:
            k = suspects[0]
            parts.append(f"{Path(files[k]).name} (frame #{k}, {frame_role(k, ps)})")
        else:
            parts.append(f"{Path(files[a]).name} and/or {Path(files[i]).name} (frames #{a} and #{i}, "
                         f"{frame_role(a, ps) + ' and its inverse' if a != ps.white else 'white and black'})")
    raise CaptureError(
        f"{folder}: {'; '.join(parts)} {'does' if len(parts) == 1 and ' and/or ' not in parts[0] else 'do'} not "
        "belong to this capture: a pattern and its inverse add up to the same image in every other pair, but "
        "not there — is it from another pose or capture? Replace it with the right frame or re-capture")


def _fails(norm: np.ndarray, corr: np.ndarray, spread: np.ndarray, p5, p95, ps, idx) -> int:
    """How many checks the sequence fails when sequence frame s is file ``idx[s]`` (-1: missing)."""
    n = 0
    if idx[ps.white] >= 0 and not p5[idx[ps.white]] > 0.5:
        n += 1
    if idx[ps.black] >= 0 and not p95[idx[ps.black]] < 0.5:
        n += 1
    for axis in ("col", "row"):
        for a, i in ps.pair_indices(axis):
            fa, fi = idx[a], idx[i]
            if fa < 0 or fi < 0 or (spread[fa] < 0.15 and spread[fi] < 0.15):
                continue
            if corr[fa, fi] > -0.5:
                n += 1
    return n


def _sequence_stats(stack: np.ndarray):
    sub = _sample(stack, 8000)
    lo, hi = sub.min(axis=0), sub.max(axis=0)
    span = hi - lo
    lit = span > 0.25 * np.percentile(span, 99)
    if lit.sum() < 100:
        return None
    norm = (sub[:, lit] - lo[lit]) / span[lit]
    p5, p95 = np.percentile(norm, 5, axis=1), np.percentile(norm, 95, axis=1)
    spread = norm.std(axis=1)
    c = norm - norm.mean(axis=1, keepdims=True)
    corr = (c @ c.T) / norm.shape[1] / np.maximum(np.outer(spread, spread), 1e-12)
    return norm, corr, spread, p5, p95


def _explain_count(folder: Path, files: list, ps: patterns.PatternSet) -> str:
    """Which image is not part of the sequence, missing or extra, when the count is one off (or images of
    another size are among them); '' when that cannot be told."""
    found = len(files)
    if found == 0 or abs(found - ps.count) > 4:
        return ""
    shapes = []
    for f in files:
        img = _images.read_image(f)
        shapes.append((img.shape, img.dtype.itemsize))
    kinds: dict = {}
    for k, sh in enumerate(shapes):
        kinds.setdefault(sh, []).append(k)
    if len(kinds) > 1:
        main = max(kinds.values(), key=len)
        (h, w), size = shapes[main[0]]
        odd = [k for k in range(found) if k not in set(main)]
        desc = []
        for k in odd[:3]:
            (h2, w2), size2 = shapes[k]
            desc.append(f"{Path(files[k]).name} ({w2}x{h2}, {8 * size2}-bit)")
        return (f" — {', '.join(desc)}{' ...' if len(odd) > 3 else ''} {'is' if len(odd) == 1 else 'are'} not part "
                f"of the sequence: the other {len(main)} images are {w}x{h}, {8 * size}-bit; move "
                f"{'it' if len(odd) == 1 else 'them'} out of the pose folder")
    if abs(found - ps.count) != 1:
        return ""
    need = found * int(np.prod(shapes[0][0])) * shapes[0][1]
    avail = _files.available_memory()
    if avail is not None and need > 0.5 * avail:
        return ""
    stack = _images.read_images(files)
    stats = _sequence_stats(stack)
    if stats is None:
        return ""
    if found == ps.count - 1:
        ok = []
        for m in range(ps.count):
            idx = [s if s < m else s - 1 for s in range(ps.count)]
            idx[m] = -1
            if _fails(*stats, ps, idx) == 0:
                ok.append(m)
        if not ok or max(ok) - min(ok) > 1:
            return ""
        after = f" after {Path(files[ok[0] - 1]).name}" if ok[0] > 0 else " at the start"
        if len(ok) == 1:
            what = f"frame {describe_frame(ok[0], ps)}"
        else:
            what = f"frame {describe_frame(ok[0], ps)} or {describe_frame(ok[1], ps)}"
        return (f" — {what} seems to be missing (it would come{after}): re-capture the pose, or check that no "
                "file was deleted or renamed")
    ok = []
    for r in range(found):
        idx = [s if s < r else s + 1 for s in range(ps.count)]
        if _fails(*stats, ps, idx) == 0:
            ok.append(r)
    if not ok or max(ok) - min(ok) > 1:
        return ""
    names = " or ".join(Path(files[r]).name for r in ok)
    return (f" — {names} seems to be one frame too many (without it the patterns and their inverses pair up): "
            "move it out of the pose folder")


def _listed(folder) -> list[str] | None:
    """The frame names the folder's manifest (or patterns.json) lists, or None."""
    man = _files.read_manifest(folder)
    if man is not None:
        frames = [n for n, r in man["files"].items() if r in ("frame", "captured")]
        if frames:
            return frames
    try:
        meta = read_patterns_json(folder)
    except CaptureError:
        meta = None
    if isinstance(meta, dict) and isinstance(meta.get("files"), list) and meta["files"]:
        names = [str(f) for f in meta["files"]]
        return names if all(Path(n).name == n for n in names) else None
    return None


def _missing_listed(folder, files) -> list[str]:
    """Listed frames that are not in the folder, when the others are (a frame deleted or renamed)."""
    listed = _listed(folder) or []
    have = {Path(f).name for f in files}
    gone = [n for n in listed if n not in have]
    return sorted(gone, key=_files.natural_key) if gone and len(gone) < len(listed) else []


def sequence_files(folder, images) -> tuple[list[Path], tuple]:
    """The frames of the sequence among ``images`` (the folder's image files), and warnings.

    procam's own outputs listed in the folder's manifest are left out.  When the manifest (or
    ``patterns.json``) lists the frames and they are all there, those are the sequence, and any other
    image is ignored with a warning that names it.
    """
    folder = Path(folder)
    by_name = {Path(p).name: Path(p) for p in images}
    man = _files.read_manifest(folder)
    if man is not None:
        own = {n for n, r in man["files"].items() if r in ("output", "sidecar")}
        images = [p for p in images if Path(p).name not in own]
    listed = _listed(folder)
    if listed and all(n in by_name for n in listed):
        keep = set(listed)
        extra = [Path(p).name for p in images if Path(p).name not in keep]
        files = sorted((by_name[n] for n in keep), key=lambda p: _files.natural_key(p.name))
        warn = ()
        if extra:
            warn = ((f"{folder}: ignored {', '.join(extra[:4])}{' ...' if len(extra) > 4 else ''}: not among the "
                     f"{len(files)} frames the folder's {'manifest' if man is not None else 'patterns.json'} lists"),)
        return files, warn
    return list(images), ()


def check_memory(folder, n_images: int, shape, itemsize: int) -> None:
    """Raise CaptureError when ``n_images`` of ``shape`` (H, W) would not fit in the available memory with
    the decoder's per-pixel maps."""
    h, w = shape[:2]
    need = n_images * h * w * itemsize + 48 * h * w
    avail = _files.available_memory()
    if avail is not None and need > 0.8 * avail:
        raise CaptureError(f"{folder}: {n_images} images of {w}x{h} need about {_files.fmt_bytes(need)} of memory "
                           f"to decode, more than the {_files.fmt_bytes(avail)} available; downscale the captures "
                           "or free memory")


def load_capture(folder, projector=None, order=None, check: bool = True, step=None, reader=None) -> Capture:
    """Read and validate a pose folder (a phase family's checks: :func:`procam.capture.phase.check_phase_capture`).

    Parameters
    ----------
    folder : path of the pose's folder.
    projector : (width, height) of the projector, or None to read it from ``patterns.json``.
    order : "opencv" (default) or "moreno", or None for ``patterns.json``'s / the default.
    check : run the image-based checks (white/black position, pattern/inverse pairs).
    step : projector pixels per code (None: patterns.json's, else 1).
    reader : ``reader(files) -> stack``, default :func:`procam.io.images.read_images` (e.g.
        :meth:`procam.stream.Prefetcher.read`, which has them read already).
    """
    from .rig import is_rig_pose, rig_without_manifest

    folder = Path(folder)
    why = rig_without_manifest(folder)
    if why is not None:
        raise CaptureError(why)
    try:
        images = _files.list_images(folder)
    except CaptureError:
        if not is_rig_pose(folder):
            raise
        subs = sorted(d.name for d in folder.iterdir() if (d / "patterns.json").is_file())
        raise CaptureError(f"{folder}: a rig pose folder (one pose folder per projector: {', '.join(subs[:4])}"
                           f"{', ...' if len(subs) > 4 else ''}); this reads one pose: give one of them, e.g. "
                           f"{folder / (subs or ['NAME'])[0]} (procam calibrate {folder} calibrates the rig)") from None
    ps = resolve_pattern_set(folder, projector, order, step)
    files, notes = sequence_files(folder, images)
    if len(files) != ps.count and patterns.is_phase(ps):
        from .phase import count_error

        raise CaptureError(count_error(folder, files, ps, _missing_listed(folder, files)))
    if len(files) != ps.count:
        gone = _missing_listed(folder, files)
        why = ""
        if gone and len(files) + len(gone) == ps.count:
            why = (f" — {', '.join(gone[:4])}{' ...' if len(gone) > 4 else ''}, listed in the folder's "
                   f"{'manifest' if _files.read_manifest(folder) else 'patterns.json'}, "
                   f"{'is' if len(gone) == 1 else 'are'} missing: re-capture the pose, or restore the file")
        why = why or _explain_count(folder, files, ps)
        raise CaptureError(f"{folder}: expected {ps.count} images for a {ps.width}x{ps.height} projector"
                           + (f" with step {ps.step}" if ps.step > 1 else "") + " "
                           f"({ps.col_bits} column + {ps.row_bits} row bits, pattern + inverse each, plus white "
                           f"and black; the same count for --order opencv and moreno), found {len(files)}"
                           + (why or _count_hint(len(files), ps)))
    head = _images.png_header(files[0])  # size and depth without decoding a frame the reader reads anyway
    if head is None:
        first = _images.read_image(files[0])
        head = (*first.shape[:2], first.dtype.itemsize)
    check_memory(folder, len(files), head[:2], head[2])
    stack = (reader or _images.read_images)(files)
    warnings = notes
    if check and patterns.is_phase(ps):
        from .phase import check_phase_capture

        sub = _sample(stack)
        check_light(stack, folder, sub=sub)
        warnings = notes + check_phase_capture(stack, ps, folder, files, sub)
    elif check:
        sub = _sample(stack)  # one pixel sample serves every check
        check_light(stack, folder, sub=sub)
        check_white_black(stack, ps, folder, files, sub=sub)
        check_pairs(stack, ps, folder, files, sub=sub)
        check_bit_order(stack, ps, folder, files)
        warnings = notes + exposure_warnings(stack, ps, folder, files)
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
