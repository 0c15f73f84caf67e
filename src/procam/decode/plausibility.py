"""Is a decoded capture a plausible picture of a projector? Checks that blame the capture, not the pose (the
plausibility gates every calibration passes are :mod:`procam.verdict.gates`).

A capture can pass every frame-level check and still be wrong in a way that gives a confident wrong
calibration: the projector size given is not the projector's, a pattern was swapped with its own inverse
(the pair is still anti-correlated), the camera or the projector mirrors its image. Each leaves a mark in
the decoded maps or the corners:

* **codes beyond the projector** (:func:`check_projector_size`): with the wrong width or height but the same
  bit count, many pixels decode to columns/rows past the edge; their extent names the real size;
* **a swapped pair** (:func:`check_swapped_bits`): decoding a Gray-code bit the wrong way round reverses the
  order of the codes inside each block of ``2^(b+1)`` codes, so the map is full of jumps of about that size;
  decoding that bit the other way round makes it continuous again;
* **a mirror** (:func:`check_orientation`): a camera and a projector looking at the same side of a plane map it
  onto each other preserving orientation; a mirrored camera image, a mirroring projector setting, or the most
  significant pattern swapped with its inverse (which mirrors the codes) reverses it.

* **columns and rows exchanged** (:func:`check_projector_size`): codes that fit the projector only with its
  columns and rows exchanged are a sequence captured rows first when the decoded "columns" change along the
  camera's vertical, a projector size given the wrong way round when they change along its horizontal;
* **several swapped pairs**: found one at a time, each from the map with the ones before flipped back, and all
  named.

The checks raise :class:`~procam.errors.CaptureError` naming the frames or the setting to check;
:func:`check_decoded` runs those of the capture's family (a phase family's: :func:`check_phase_maps`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import DecodeResult
from ..errors import CaptureError

#: Fraction of the decoded pixels beyond the projector's edge above which the size is called wrong.
MAX_BEYOND = 0.02


def _frame(k: int, files) -> str:
    return f"#{k} ({Path(files[k]).name})" if files is not None and k < len(files) else f"#{k}"


def code_extent(hist: np.ndarray, fraction: float = 0.999) -> int:
    """The number of projector pixels (columns or rows) that hold ``fraction`` of the decoded codes, rounded up
    to a multiple of 8 when it is within 8 of one (projector panels have such sizes)."""
    c = np.cumsum(hist)
    if c[-1] == 0:
        return 0
    e = int(np.searchsorted(c, fraction * c[-1]) + 1)
    up = -(-e // 8) * 8
    return up if up - e < 8 else e


def beyond_fraction(maps: DecodeResult) -> tuple[float, float]:
    """Fractions of the decoded camera pixels whose codes point beyond the projector's width / height."""
    out = []
    for hist, size in ((maps.codes_col, maps.pattern_set.width), (maps.codes_row, maps.pattern_set.height)):
        total = hist.sum() if hist is not None else 0
        out.append(float(hist[size:].sum() / total) if total else 0.0)
    return out[0], out[1]


def _axes(maps: DecodeResult):
    ps = maps.pattern_set
    return (("column", "col", maps.codes_col, ps.width, ps.col_bits, ps.col_offset),
            ("row", "row", maps.codes_row, ps.height, ps.row_bits, ps.row_offset))


def _flipped_beyond(hist: np.ndarray, size: int, bit: int, step: int, offset: int) -> float:
    """Fraction of the codes in ``hist`` beyond ``[0, size)`` after decoding Gray-code ``bit`` the other way."""
    px = np.flatnonzero(hist)
    code = px // step + offset
    px2 = ((code ^ ((1 << (bit + 1)) - 1)) - offset) * step
    out = (px2 < 0) | (px2 >= size)
    return float(hist[px][out].sum() / hist.sum())


def check_projector_size(maps: DecodeResult, name: str, files=None) -> list[str]:
    """Raise when many codes point beyond the given projector size: naming the swapped pattern pair when
    decoding one bit the other way round brings them all inside, else the size the codes point to. Returns
    warnings when the codes use only part of the given size."""
    ps = maps.pattern_set
    warnings = []
    fractions = beyond_fraction(maps)
    bad = []
    for (label, axis, hist, size, nbits, offset), f in zip(_axes(maps), fractions):
        if f <= MAX_BEYOND:
            continue
        flips = [(_flipped_beyond(hist, size, b, ps.step, offset), b) for b in range(nbits)]
        f2, b = min(flips)
        if f2 < MAX_BEYOND / 4:
            pairs = _code_pairs(maps, 4).get(axis)  # other pairs swapped too: each named, not only this one
            more = [] if pairs is None else [c for c, _ in _swapped(*pairs[:4], nbits, ps.step, flipped=(b,))]
            raise CaptureError(
                f"{name}: {_pairs_text(ps, axis, label, [b] + more, files)} look swapped: as captured {f:.0%} of the "
                f"decoded pixels point to projector {label}s beyond the {size} of the projector, with "
                f"{'those pairs' if more else 'that pair'} the other way round {f2:.1%}"
                + (" and the map continuous" if more else "") + " — a pattern and its inverse were exchanged (or "
                "come from another capture); re-capture, or check that the file names sort in capture order")
        bad.append((label, f, code_extent(hist), size))
    if bad:
        transposed = _transposed(maps)
        if transposed is not None:
            raise CaptureError(f"{name}: {transposed}")
        what = "; ".join(f"{f:.0%} of the decoded pixels point to projector {label}s beyond the given {size} "
                         f"(up to {e - 1})" for label, f, e, size in bad)
        real = [ps.width, ps.height]
        for label, f, e, size in bad:
            real[0 if label == "column" else 1] = max(e, size)
        raise CaptureError(f"{name}: the projector is larger than {ps.width}x{ps.height}: {what}; the codes point to "
                           f"a projector of about {real[0]}x{real[1]} — check --projector (or the folder's "
                           "patterns.json)")
    return warnings + _extent_warnings(maps, name)


def _extent_warnings(maps: DecodeResult, name: str) -> list[str]:
    """Warnings when the decoded coordinates use only part of the given projector size."""
    out = []
    ps = maps.pattern_set
    for label, hist, size in (("column", maps.codes_col, ps.width), ("row", maps.codes_row, ps.height)):
        e = code_extent(hist)
        if 0 < e < 0.8 * size:
            out.append(f"{name}: the decoded projector {label}s span only 0-{e - 1} of the given {size}: if the "
                       f"projector has {e} {label}s (not {size}), pass the right --projector; otherwise part of "
                       "the projection is outside the camera's view")
    return out


def _slopes(m: np.ndarray, sample: int = 4) -> tuple[float, float]:
    """Median |change| of a decoded map per camera pixel along x and along y (every ``sample``-th line)."""
    v = m[::sample, ::sample]
    dx, dy = np.diff(v, axis=1) / sample, np.diff(v, axis=0) / sample
    dx, dy = dx[np.isfinite(dx)], dy[np.isfinite(dy)]
    return (float(np.median(np.abs(dx))) if dx.size else 0.0, float(np.median(np.abs(dy))) if dy.size else 0.0)


def _transposed(maps: DecodeResult) -> str | None:
    """Why the decoded codes point beyond the projector when the reason is the axes, not the size: the codes fit
    the projector with columns and rows exchanged. Rows captured first (the decoded "columns" then hold row codes
    and change along the camera's vertical, the "rows" along its horizontal), or the projector's size given
    the wrong way round (the maps change as a camera and projector side by side make them). None otherwise."""
    ps = maps.pattern_set
    total_c = maps.codes_col.sum() if maps.codes_col is not None else 0
    total_r = maps.codes_row.sum() if maps.codes_row is not None else 0
    if not (total_c and total_r):
        return None
    swapped_c = float(maps.codes_col[ps.height:].sum() / total_c)
    swapped_r = float(maps.codes_row[ps.width:].sum() / total_r)
    if max(swapped_c, swapped_r) > MAX_BEYOND:
        return None
    ec, er = code_extent(maps.codes_col), code_extent(maps.codes_row)
    (cx, cy), (rx, ry) = _slopes(maps.col), _slopes(maps.row)
    if cy > cx and rx > ry:
        cp, rp = ps.pair_indices("col"), ps.pair_indices("row")
        return (f"the column and row patterns look exchanged (captured rows first?): the codes decoded as projector "
                f"columns span 0-{ec - 1} and change along the camera's vertical, those decoded as rows span "
                f"0-{er - 1} and change along its horizontal -- a {ps.width}x{ps.height} projector's rows and columns "
                f"the other way round. procam reads frames #{cp[0][0]}-#{cp[-1][1]} as the column pairs and "
                f"#{rp[0][0]}-#{rp[-1][1]} as the row pairs ({ps.order} order); put the column frames first (rename "
                "the files so they sort in capture order) or re-capture columns first; --projector is not the problem")
    return (f"the projector's size looks given the wrong way round: the decoded columns span 0-{ec - 1} and the rows "
            f"0-{er - 1}, which fit a {ps.height}x{ps.width} projector, not {ps.width}x{ps.height}; pass --projector "
            f"{ps.height}x{ps.width} (width x height) if that is the panel")


def _median_of_hist(h: np.ndarray, lo: int) -> float:
    """``np.median`` of the integers whose histogram is ``h`` (bin ``k`` counts the value ``lo + k``)."""
    c = np.cumsum(h)
    n = round(c[-1])
    a = int(np.searchsorted(c, (n - 1) // 2 + 0.5))  # the ((n-1)//2)-th and (n//2)-th smallest values
    b = int(np.searchsorted(c, n // 2 + 0.5))
    return (a + b + 2 * lo) / 2.0


def _hist_scores(d2: np.ndarray, weights: np.ndarray | None = None) -> tuple[float, int]:
    """``(roughness, breaks)`` of a decoded map from its neighbouring differences ``d2``, given as twice their
    value (integers, so that the half pixels of block centres are exact), each counted ``weights`` times.

    ``roughness`` is the mean deviation (capped) of the absolute differences from their median (the slope),
    ``breaks`` the number of differences that depart from the median difference by more than the decoding noise.
    Medians, mean and count come from histograms: the numbers sorting gives, at a fraction of the cost.
    """
    if d2.size == 0:
        return 0.0, 0
    n = float(d2.size if weights is None else weights.sum())
    ha = np.bincount(np.abs(d2), weights)
    slope = _median_of_hist(ha, 0) / 2.0
    k = np.arange(len(ha)) / 2.0
    rough = float(np.dot(ha, np.minimum(np.abs(k - slope), 8.0 + 4.0 * slope)) / n)
    lo = int(d2.min())
    hs = np.bincount(d2 - lo, weights)
    med = _median_of_hist(hs, lo) / 2.0
    ks = (np.arange(len(hs)) + lo) / 2.0
    breaks = round(hs[np.abs(ks - med) > 2.5 + 1.5 * slope].sum())
    return rough, breaks


def _neighbour_pairs(code: np.ndarray, ok: np.ndarray, axis: int, reach: int = 32):
    """The distinct pairs of values (non-negative integers) of neighbours along ``axis`` that are both ``ok``,
    and how often each occurs: ``(first, second, count)``, 1-D.  Neighbours of a decoded map mostly differ by a
    few codes, so a few thousand distinct pairs stand for the ~10^5 pairs of a map."""
    a = [slice(None)] * 2
    b = [slice(None)] * 2
    a[axis], b[axis] = slice(None, -1), slice(1, None)
    both = ok[tuple(a)] & ok[tuple(b)]
    c1, c2 = code[tuple(a)][both], code[tuple(b)][both]
    d = c2 - c1
    near = np.abs(d) < reach
    h = np.bincount(c1[near] * (2 * reach) + (d[near] + reach))
    k = np.flatnonzero(h)
    first = k // (2 * reach)
    far = ~near
    return (np.concatenate([first, c1[far]]), np.concatenate([first + k % (2 * reach) - reach, c2[far]]),
            np.concatenate([h[k], np.ones(int(far.sum()), np.int64)]).astype(float))


def _code_pairs(maps: DecodeResult, sample: int):
    """Per axis: the distinct pairs of neighbouring codes of the decoded map (full-precision pixels only) and
    their counts ``(c1, c2, w, n_pixels, dv)`` (``dv`` the decoded values' differences, twice over), or None when
    fewer than 2000 pixels count (see :func:`swap_scores`)."""
    ps = maps.pattern_set
    out = {}
    for axis, vals, dropped, offset, cam_axis in (("col", maps.col, maps.dropped_col, ps.col_offset, 1),
                                                 ("row", maps.row, maps.dropped_row, ps.row_offset, 0)):
        v = vals[::sample, :] if cam_axis == 1 else vals[:, ::sample]
        ok = np.isfinite(v)
        if dropped is not None:
            ok &= (dropped[::sample, :] if cam_axis == 1 else dropped[:, ::sample]) == 0
        n_ok = int(np.count_nonzero(ok))
        if n_ok < 2000:
            out[axis] = None
            continue
        # twice the decoded values are integers (block centres are whole or half pixels)
        v1, v2, w = _neighbour_pairs(np.rint(2.0 * np.where(ok, v, 0.0)).astype(np.int64), ok, cam_axis)
        # the codes of the pairs' ends (a decoded value is its block's centre)
        c1, c2 = (np.rint((x - (ps.step - 1)) / (2.0 * ps.step)).astype(np.int64) + offset for x in (v1, v2))
        out[axis] = (c1, c2, w, n_ok, v2 - v1)
    return out


def swap_scores(maps: DecodeResult, sample: int = 4) -> dict:
    """The smoothness of the decoded maps as decoded and with each Gray-code bit decoded the other way round.

    The column map is read on every ``sample``-th camera row (differences along the row), the row map on every
    ``sample``-th camera column. Only pixels decoded to full precision count.

    Returns
    -------
    dict ``{"col": ..., "row": ...}``, each None when fewer than 2000 pixels count, else a dict with ``n``
    (pixels), ``scores`` ``(roughness, breaks)`` as decoded and ``flipped``, a list of them with bit
    ``b = 0 .. nbits - 2`` flipped (see :func:`_hist_scores`).
    """
    ps = maps.pattern_set
    out = {}
    for axis, pairs in _code_pairs(maps, sample).items():
        if pairs is None:
            out[axis] = None
            continue
        c1, c2, w, n_ok, dv = pairs
        nbits = ps.col_bits if axis == "col" else ps.row_bits
        out[axis] = {"n": n_ok, "scores": _hist_scores(dv, w),
                     "flipped": [_hist_scores(((c2 ^ m) - (c1 ^ m)) * (2 * ps.step), w)
                                 for m in ((1 << (b + 1)) - 1 for b in range(nbits - 1))]}
    return out


def check_decoded(maps: DecodeResult, name: str, files=None) -> list[str]:
    """The checks of a decoded capture for its family; raises :class:`CaptureError`, returns warnings.

    Gray codes: :func:`check_projector_size` and :func:`check_swapped_bits`.  Phase families (the description
    itself is judged against the frames when the folder is read, :func:`procam.capture.check_phase_capture`):
    :func:`check_phase_maps` and the decoder's own warnings (an uncorrected projector gamma).
    """
    if not maps.subpixel:
        warnings = check_projector_size(maps, name, files)
        check_swapped_bits(maps, name, files)
        return warnings
    return check_phase_maps(maps, name) + list(maps.phase.warnings if maps.phase is not None else ())


#: Largest fraction of a phase decode's lit pixels whose orders disagree or that fall off the panel.
MAX_PHASE_DISAGREEMENT = 0.2


def check_phase_maps(maps: DecodeResult, name: str) -> list[str]:
    """Raise when a phase decode's frequencies disagree (or its coordinates fall off the panel) at more than
    :data:`MAX_PHASE_DISAGREEMENT` of the pixels the projector lights: the sequence's description does not match
    its frames.  Returns a warning when the decoded coordinates use only part of the panel."""
    from .decoded import LOW_CONTRAST, ORDER_DISAGREE

    ps = maps.pattern_set
    out = []
    for label, r in (("column", maps.reason_col), ("row", maps.reason_row)):
        judged = np.isin(r, (0, 4, LOW_CONTRAST, ORDER_DISAGREE))
        n = int(judged.sum())
        if n < 1000:
            continue
        bad = float(np.isin(r[judged], (4, ORDER_DISAGREE)).mean())
        if bad > MAX_PHASE_DISAGREEMENT:
            raise CaptureError(
                f"{name}: {bad:.0%} of the decoded pixels' fringe orders disagree or fall off the panel along the "
                f"{label}s: the sequence's description ({ps.describe()}) does not match the frames — "
                "'procam decode' on the pose folder names the frames that disagree; fix patterns.json "
                "(docs/patterns.md)")
    return out + _extent_warnings(maps, name)
def _swapped(c1, c2, w, n, nbits, step, flipped=()) -> list[tuple[int, str]]:
    """The Gray-code bits decoded the wrong way round, found one at a time: the bit whose flip makes the map
    clearly smoother (1.6 times) or removes two thirds of its breaks is taken, and the search goes on from the map
    with it flipped (two swapped pairs each hide the other's improvement). ``[(bit, how)]``."""
    found = []
    mask = 0
    for b in flipped:
        mask ^= (1 << (b + 1)) - 1
    while len(found) < nbits - 1:
        rough0, breaks0 = _hist_scores(((c2 ^ mask) - (c1 ^ mask)) * (2 * step), w)
        candidates = []
        for b in range(nbits - 1):
            if b in flipped or any(b == f for f, _ in found):
                continue
            m = mask ^ ((1 << (b + 1)) - 1)
            rough, breaks = _hist_scores(((c2 ^ m) - (c1 ^ m)) * (2 * step), w)
            smoother = rough * 1.6 < rough0 and rough0 - rough > 0.2 * step
            fewer = breaks * 3 < breaks0 and breaks0 - breaks > 0.002 * n
            if smoother or fewer:
                how = (f"{rough0 / max(rough, 1e-9):.0f} times smoother" if smoother else
                       f"continuous ({breaks} breaks instead of {breaks0})")
                candidates.append((breaks, rough, b, how))
        if not candidates:
            break
        _, _, b, how = min(candidates)
        found.append((b, how))
        mask ^= (1 << (b + 1)) - 1
    return found


def _pairs_text(ps, axis, label, bits, files) -> str:
    nbits = ps.col_bits if axis == "col" else ps.row_bits
    parts = []
    for b in bits:
        a, i = ps.pair_indices(axis)[nbits - 1 - b]
        parts.append(f"{_frame(a, files)} and {_frame(i, files)} ({label} bit {b})")
    return ("images " + " and ".join(parts) if len(parts) == 1 else
            f"{len(parts)} pairs of images: " + "; ".join(parts))


def check_swapped_bits(maps: DecodeResult, name: str, files=None, *, sample: int = 4) -> None:
    """Raise when decoding Gray-code bits the other way round makes the decoded map clearly continuous: those
    bits' patterns and inverses were swapped in the capture (or one of them comes from another sequence).

    A swapped bit ``b`` reverses the order of the codes inside every block of ``2^(b+1)`` codes. Small blocks
    make the map rough (neighbouring differences far from the slope); large blocks leave it smooth inside and
    break it at every block boundary. A correct decoding only gets worse when a bit is flipped; a swapped bit
    gets at least 1.6 times smoother, or loses two thirds of its breaks, when it is flipped back. Bits are found
    one at a time, each from the map with the ones before flipped back (:func:`_swapped`), so that every swapped
    pair is named, not only the first. (The most significant bits are also caught by
    :func:`check_projector_size`, the most significant alone by :func:`check_orientation`.) The maps are read on
    every ``sample``-th line.
    """
    ps = maps.pattern_set
    for axis, pairs in _code_pairs(maps, sample).items():
        if pairs is None:
            continue
        label = "column" if axis == "col" else "row"
        c1, c2, w, n, _ = pairs
        found = _swapped(c1, c2, w, n, ps.col_bits if axis == "col" else ps.row_bits, ps.step)
        if found:
            how = ", then ".join(h for _, h in found)
            raise CaptureError(
                f"{name}: {_pairs_text(ps, axis, label, [b for b, _ in found], files)} look swapped: the decoded "
                f"projector {label}s are {how} with {'those pairs' if len(found) > 1 else 'that pair'} the other way "
                "round — a pattern and its inverse were exchanged (or come from another capture); re-capture, or "
                "check that the file names sort in capture order")


def check_orientation(cam_pts: np.ndarray, proj_pts: np.ndarray, cols: int, rows: int, name: str, maps=None,
                      files=None) -> None:
    """Raise when the camera -> projector map of the board reverses orientation (a mirror somewhere).

    For every square of the corner grid, the sign of its oriented area in the camera times that in the
    projector; a camera and a projector on the same side of a plane give +1.
    """
    c = np.asarray(cam_pts, float).reshape(rows, cols, 2)
    p = np.asarray(proj_pts, float).reshape(rows, cols, 2)

    def area(g):
        a, b, d = g[:-1, :-1], g[:-1, 1:], g[1:, :-1]
        return (b[..., 0] - a[..., 0]) * (d[..., 1] - a[..., 1]) - (b[..., 1] - a[..., 1]) * (d[..., 0] - a[..., 0])

    with np.errstate(invalid="ignore"):
        s = np.sign(area(c)) * np.sign(area(p))
    s = s[np.isfinite(s) & (s != 0)]
    if len(s) < 4 or np.count_nonzero(s < 0) <= 0.75 * len(s):
        return
    hint = ""
    if maps is not None and not maps.subpixel:
        fc, fr = beyond_fraction(maps)
        ps = maps.pattern_set
        if max(fc, fr) > 0.005:
            axis = "col" if fc >= fr else "row"
            a, i = ps.pair_indices(axis)[0]
            hint = (f"; {max(fc, fr):.0%} of the pixels also decode beyond the projector's edge, which is what "
                    f"swapping the most significant {'column' if axis == 'col' else 'row'} pattern with its inverse "
                    f"({_frame(a, files)} and {_frame(i, files)}) does: check those two frames first")
    if maps is not None and maps.subpixel:
        hint = ("; for a phase-family capture described by hand, also check the phase's \"sign\" in patterns.json "
                "(a sign of the wrong way round mirrors the decoded coordinates along that axis)")
    raise CaptureError(
        f"{name}: the camera and projector images of the board are mirror images of each other ({int(np.sum(s < 0))} "
        f"of {len(s)} squares reversed): the camera image looks mirrored (some webcams flip left-right: turn the "
        "mirror/flip setting off), or the projector mirrors its image (rear-projection setting), or the most "
        f"significant pattern of an axis was swapped with its inverse{hint}")
