"""A phase-family capture folder: its checks and its board image.

* :func:`check_phase_capture` - the white and black frames where the description puts them (when it has them),
  every Gray bit followed by its inverse (when it says so), the Gray bits in the described order
  (:func:`procam.capture.bit_order.check_bit_order`), and the description itself against the frames
  (:func:`procam.decode.phase.diagnose.check_description`: the fringes' modulation, each frame's fit to its block's
  sinusoid, the frequencies' (or the Gray code's) consistency, the decoded coordinates' range); each failure is a
  one-line :class:`~procam.errors.CaptureError` naming the frame and how it disagrees.  Returns the exposure
  warnings (clipped fringes).
* :func:`board_image` - the image the chessboard is found in: the white frame, or without one the mean of the
  phase frames (every fringe block lights each pixel on average by its mean level: a uniformly lit board).
* :func:`count_error` - the message for a folder with the wrong number of frames.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import CaptureError
from ..io import files as _files
from .bit_order import check_bit_order
from .frames import describe_frame
from .sample import _sample, frame_levels


def board_image(stack: np.ndarray, ps) -> np.ndarray:
    """(H, W) image of the board in the stack's dtype: the white frame, else the mean of the phase frames."""
    if ps.white is not None:
        return stack[ps.white]
    acc = np.zeros(stack.shape[1:], np.float32)
    frames = ps.phase_frames()
    for k in frames:
        acc += stack[k]
    acc /= len(frames)
    return np.rint(acc).astype(stack.dtype)


def count_error(folder, files, ps, missing) -> str:
    """The one-line message for ``files`` (found) that are not the ``ps.count`` frames of ``ps``."""
    why = ""
    if missing and len(files) + len(missing) == ps.count:
        why = (f" — {', '.join(missing[:4])}{' ...' if len(missing) > 4 else ''}, listed in the folder's manifest or "
               f"patterns.json, {'is' if len(missing) == 1 else 'are'} missing: re-capture the pose, or restore the file")
    elif _inverse_hint(ps, len(files)):
        why = _inverse_hint(ps, len(files))
    elif len(files) == ps.count - 2 and ps.white is not None and ps.black is not None:
        why = (" — two short: are the white and black frames missing? If the capture has none, drop them from the "
               "description's sequence")
    else:
        why = " — check the description's sequence (docs/patterns.md) and that no frame is missing or extra"
    return (f"{folder}: expected {ps.count} images for the sequence its patterns.json describes ({ps.describe()}), "
            f"found {len(files)}" + why)


def _inverse_hint(ps, found: int) -> str:
    """The hint for a count that the Gray blocks' inverses explain: frames with inverses described without them,
    or the other way round; '' otherwise."""
    gray = [(i, b) for i, b in enumerate(ps.blocks) if b.kind == "gray"]
    bits = sum(b.bits + int(b.complementary) for _, b in gray)
    if not gray or bits == 0:
        return ""
    where = ", ".join(f"sequence[{i}]" for i, _ in gray)
    if all(not b.inverse for _, b in gray) and found == ps.count + bits:
        return (f" — {bits} more, one per Gray bit: the capture seems to show each Gray bit with its inverse; say "
                f"\"inverse\": true in {where} (docs/patterns.md)")
    if all(b.inverse for _, b in gray) and found == ps.count - bits:
        return (f" — {bits} fewer, one per Gray bit: the capture seems to have no inverse Gray frames; say "
                f"\"inverse\": false in {where} (docs/patterns.md)")
    return ""


def _levels_check(stack, ps, folder, files, sub) -> None:

    p5, p95 = frame_levels(stack, sub)
    for idx, want in ((ps.white, "white"), (ps.black, "black")):
        if idx is None:
            continue
        ok = p5[idx] > 0.5 if want == "white" else p95[idx] < 0.5
        if ok:
            continue
        best = int(np.argmax(p5)) if want == "white" else int(np.argmin(p95))
        where = (f"; the {'brightest' if want == 'white' else 'darkest'} frame is {describe_frame(best, ps)} "
                 f"({Path(files[best]).name})" if best != idx else "")
        raise CaptureError(f"{folder}: frame {describe_frame(idx, ps)} ({Path(files[idx]).name}) is not {want} "
                           f"(its lit pixels are at {p5[idx]:.0%}-{p95[idx]:.0%} of their range over the frames)"
                           f"{where}: the description's sequence does not match the frames' order — fix patterns.json "
                           "(docs/patterns.md) or the file names' order")


def _pairs_check(ps, folder, files, sub) -> None:
    lo, hi = sub.min(axis=0), sub.max(axis=0)
    span = hi - lo
    lit = span > 0.25 * np.percentile(span, 99)
    if lit.sum() < 100:
        return
    for axis in ("col", "row"):
        for a, i in ps.pair_indices(axis):
            p = (sub[a][lit] - lo[lit]) / span[lit]
            q = (sub[i][lit] - lo[lit]) / span[lit]
            sp, sq = p.std(), q.std()
            if sp < 0.15 and sq < 0.15:
                continue
            corr = float(np.mean((p - p.mean()) * (q - q.mean())) / max(sp * sq, 1e-12))
            if corr > -0.5:
                raise CaptureError(
                    f"{folder}: images {describe_frame(a, ps)} ({Path(files[a]).name}) and {describe_frame(i, ps)} "
                    f"({Path(files[i]).name}) do not look like a Gray bit and its inverse (correlation {corr:+.2f}); "
                    "frames may be missing or out of order, or the Gray code has no inverses (say \"inverse\": false "
                    "in patterns.json)")


def check_phase_capture(stack: np.ndarray, ps, folder, files, sub: np.ndarray | None = None) -> tuple:
    """Raise :class:`CaptureError` when the frames are not the sequence ``ps`` describes (see the module
    docstring); returns warnings about the exposure."""
    from ..decode.phase.diagnose import check_description

    sub = _sample(stack) if sub is None else sub
    _levels_check(stack, ps, folder, files, sub)
    _pairs_check(ps, folder, files, sub)
    check_bit_order(stack, ps, folder, files)
    check_description(stack, ps, str(folder), files)
    fs = _files.full_scale_of(stack)
    frames = ps.phase_frames()
    clipped = (sub[frames] >= fs).any(axis=0)
    lit = (sub[frames].max(axis=0) - sub[frames].min(axis=0)) > 0.25 * np.percentile(np.ptp(sub[frames], axis=0), 99)
    frac = float(clipped[lit].mean()) if lit.any() else 0.0
    if frac > 0.02:
        return (f"{folder}: {frac:.1%} of the projector-lit pixels reach full scale ({fs:.0f}) in a phase frame: the "
                "fringes are clipped there and those pixels are not decoded; reduce the exposure",)
    return ()
