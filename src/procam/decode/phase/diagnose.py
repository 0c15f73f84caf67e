"""Does a phase-family description match its frames?  :func:`check_description` judges the frames against what
the description says they are, on the decoder's sample of pixels (:data:`procam.decode.phase.SAMPLE`), and raises a
one-line :class:`~procam.errors.CaptureError` naming the frame and how it disagrees:

* **modulation**: a phase block whose fringes are almost invisible (median modulation under
  :data:`MIN_RELATIVE_MODULATION` of the strongest block of its axis): not fringes, or a period the camera does
  not resolve;
* **frames off their block's sinusoid** (blocks of 4 or more steps, the sinusoid through the projector's response
  as decoded): a frame's typical residual over :data:`MAX_FRAME_RESIDUAL` of the modulation -- the frames that
  stand out are named (from 5 steps; with 4 the one degree of freedom left shows a wrong frame in all four), else
  the block: out of order, repeated or from another sequence;
* **anything decoded**: under :data:`MIN_DECODED` of the lit pixels decode along an axis -- a frame of the other
  axis among its frames, frames out of order, or fringes too faint for the camera to tell their periods apart;
* **the cue's consistency**: the frequencies (or the Gray code and the fringes) give different fringe periods at
  over :data:`MAX_DISAGREEMENT` of the well-lit pixels -- a wrong period, phase sign, shift direction or frame
  order.  procam then tries the description with the shift direction and the phase sign of that axis's blocks
  flipped, with their ``start`` turned by a quarter or a half period (a sine described as a cosine), and with
  the axes exchanged, and names the change that makes them agree;
* **the decoded coordinate range**: over :data:`MAX_DISAGREEMENT` of the well-lit pixels decode off the panel
  (a period or a projector size that is not the capture's);
* **the direction the fringes move** (a sequence without a Gray code, described by hand): a ``shift`` (or a
  ``sign``) of the wrong way round in every block agrees with itself at every frequency and turns the decoded
  projector image by 180 degrees; a decoded image upside down in the camera (turned by more than about 135
  degrees) is refused unless the description says ``"upside_down": true`` (and an upright one then is).

A capture that passes can still be decoded wrongly in ways no frame shows (a consistent but shifted origin moves
every coordinate by the same amount; it shows in the calibration, not here; one axis's sign or shift of the wrong
way round mirrors the decoded image, which the calibration's orientation check names).
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np

from .. import decoded as _d
from ...errors import CaptureError, ProcamWarning
from ...patterns.phase import Fringe, PhaseSet
from . import response as _resp

MIN_RELATIVE_MODULATION = 0.15
#: Fewest of the lit pixels (not in shadow, not saturated) of the decoder's sample that must decode along each axis:
#: below it nothing can be ordered (a frame of the other axis swapped in decoded 0.0 %, and was written with exit 0)
MIN_DECODED = 0.01
MAX_FRAME_RESIDUAL = 0.3
MAX_DISAGREEMENT = 0.2


def _decode_sample(view, ps, options):
    from .decoder import decode_phase

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ProcamWarning)
        return decode_phase(view, ps, options)


def _frames(b) -> str:
    return f"#{b.first}-#{b.first + b.count - 1}"


def _block_name(b, ps) -> str:
    cue = ", the unit-frequency cue" if b.period >= ps.size(b.axis) else ""
    return f"frames {_frames(b)} ({'column' if b.axis == 'col' else 'row'} phase, period {b.period:.4g} px{cue})"


def _fractions(res, lit) -> dict:
    """Per axis: ``(disagree, off_panel)`` fractions of the lit, judged pixels."""
    out = {}
    for axis, r in (("col", res.reason_col[0]), ("row", res.reason_row[0])):
        judged = lit & np.isin(r, (_d.OK, _d.ORDER_DISAGREE, _d.OUT_OF_RANGE, _d.LOW_CONTRAST))
        n = max(int(judged.sum()), 1)
        out[axis] = (float(np.sum(judged & (r == _d.ORDER_DISAGREE))) / n,
                     float(np.sum(judged & (r == _d.OUT_OF_RANGE))) / n, n)
    return out


def _variants(ps: PhaseSet, axis: str):
    """``(words, PhaseSet)`` of the description with one convention of ``axis``'s blocks changed."""
    def flip(**how):
        blocks = []
        for b in ps.blocks:
            if b.axis == axis and b.kind in ("phase", "gray"):
                f = b.fringe
                f = replace(f, **{k: -getattr(f, k) for k in how})
                b = replace(b, fringe=f)
            blocks.append(b)
        return replace(ps, blocks=tuple(blocks))

    def turn(by):
        blocks = tuple(replace(b, fringe=replace(b.fringe, start=_wrap(b.fringe.start + by)))
                       if b.axis == axis and b.kind in ("phase", "gray") else b for b in ps.blocks)
        return replace(ps, blocks=blocks)

    name = "column" if axis == "col" else "row"
    yield f'"shift": -1 (the phase steps the other way) in the {name} blocks', flip(shift=True)
    starts = {b.fringe.start for b in ps.blocks if b.axis == axis and b.kind == "phase"}
    if len(starts) == 1:
        start = starts.pop()
        for by, what in ((-np.pi / 2, "a sine where a cosine was said"), (np.pi / 2, "a sine of the other sign"),
                         (np.pi, "the fringes' crests and troughs exchanged")):
            yield (f'"start": {_wrap(start + by):.4f} ({what}) in the {name} blocks', turn(by))
    yield f'"sign": -1 (the phase falls along the {name}s) in the {name} blocks', flip(sign=True)
    yield f'"shift" and "sign" both flipped in the {name} blocks', flip(shift=True, sign=True)
    swapped = tuple(replace(b, axis={"col": "row", "row": "col"}.get(b.axis)) for b in ps.blocks)
    try:
        yield "the columns and rows exchanged (each block's axis)", replace(ps, blocks=swapped)
    except ValueError:
        return


def _wrap(t: float) -> float:
    """``t`` (radians) wrapped to (-pi, pi]."""
    t = float(np.mod(t + np.pi, 2.0 * np.pi) - np.pi)
    return np.pi if t == -np.pi else t


def check_description(stack: np.ndarray, ps: PhaseSet, name: str, files=None, options=None) -> None:
    """Raise :class:`CaptureError` when the frames are not the sequence ``ps`` describes (the module docstring)."""
    from ..decoded import sample_index
    from .decoder import SAMPLE, PhaseOptions

    options = options or PhaseOptions()
    K, H, W = stack.shape
    idx = sample_index(H * W, SAMPLE)
    sub = stack.reshape(K, -1)[:, idx]
    subf = sub.astype(np.float64)
    res = _decode_sample(np.ascontiguousarray(sub[:, None, :]), ps, options)
    lit = np.ones(len(idx), bool)
    for r in (res.reason_col[0], res.reason_row[0]):
        lit &= (r != _d.SHADOW) & (r != _d.SATURATED)
    if lit.sum() < 200:
        return
    # modulation and each frame's fit, block by block (the fit through the projector's response as decoded)
    gamma = res.phase.gamma_used
    for axis in ("col", "row"):
        blocks = ps.phase_blocks(axis)
        fits = [_resp.nstep(subf[list(b.frames)], b.shifts()) for b in blocks]
        meds = [float(np.median(B[lit])) for _, B, _ in fits]
        strongest = max(meds)
        for b, m in zip(blocks, meds):
            if m < MIN_RELATIVE_MODULATION * strongest:
                raise CaptureError(
                    f"{name}: {_block_name(b, ps)} show almost no fringes (median modulation {m:.1f} grey levels, "
                    f"{m / strongest:.0%} of the strongest {'column' if axis == 'col' else 'row'} block's): they are not "
                    "fringes of that axis and period, or the camera does not resolve that period — check "
                    "patterns.json (docs/patterns.md)")
        for b, (_, _, psi) in zip(blocks, fits):
            if b.steps >= 4:
                _frame_fit(subf[list(b.frames)][:, lit], psi[lit], b, gamma, res.phase.blur, ps, name, files)
    fr = _fractions(res, lit)
    for axis in ("col", "row"):
        disagree, off, n = fr[axis]
        if disagree <= MAX_DISAGREEMENT and off <= MAX_DISAGREEMENT:
            continue
        label = "column" if axis == "col" else "row"
        blocks = [b for b in ps.blocks if b.axis == axis]
        what = " and ".join(_block_name(b, ps) if b.kind == "phase" else f"the Gray code {_frames(b)}" for b in blocks)
        if disagree > MAX_DISAGREEMENT:
            how = (f"{what} give different fringe periods at {disagree:.0%} of the well-lit pixels (more than "
                   f"{options.tolerance:g} of a period apart)")
        else:
            how = (f"{off:.0%} of the well-lit pixels decode off the panel's {ps.size(axis)} {label}s from {what}: a "
                   "period, a Gray bit count or a projector size that is not the capture's")
        hint = ""
        fixed = dict(gamma=res.phase.gamma_used) if np.isfinite(res.phase.gamma_used) else {}
        opts2 = replace(options, **fixed)
        best = None
        for words, alt in _variants(ps, axis):
            f2 = _fractions(_decode_sample(np.ascontiguousarray(sub[:, None, :]), alt, opts2), lit)[axis]
            bad = f2[0] + f2[1]
            # judged at as many pixels (a variant under which almost nothing decodes agrees at the few that do: one
            # pixel of a capture with a frame of the other axis swapped in "agreed at 100 %")
            if bad < 0.05 and f2[2] >= 0.5 * n and (best is None or bad < best[0]):
                best = (bad, words)
        if best is not None:
            hint = f"; with {best[1]} they agree at {1 - best[0]:.0%} of them"
        raise CaptureError(f"{name}: the description does not match the frames: along the {label}s {how}{hint} — fix "
                           "patterns.json (docs/patterns.md: the conventions and the frame order)")
    for axis, r in (("col", res.reason_col[0]), ("row", res.reason_row[0])):
        ok = float(np.mean(r[lit] == _d.OK))
        if ok < MIN_DECODED:
            label = "column" if axis == "col" else "row"
            raise CaptureError(
                f"{name}: {ok:.1%} of the lit pixels decode along the {label}s (the fringes' periods cannot be told "
                f"apart anywhere): a frame that is not the described one (a frame of the other axis among them, frames "
                f"out of order) or fringes too faint for the camera — check the frame order in patterns.json "
                f"(docs/patterns.md) and the capture's exposure and focus")
    _check_upright(res, idx, lit, ps, W, name)


#: The decoded projector image counts as turned when the cosine of its rotation in the camera image is below this
#: (turned by more than about 135 degrees), as upright when above its negative.
TURNED_COS = -0.7


def _rotation_cos(res, idx, lit, W: int) -> float | None:
    """Cosine of the angle the decoded projector image is turned by in the camera image (1: upright, -1: upside
    down), from the least-squares affine map of the camera pixel to the projector coordinates at the well-decoded
    sample pixels; None when they are too few or the map reverses orientation (a mirror: the calibration's
    orientation check names it)."""
    ok = lit & (res.reason_col[0] == _d.OK) & (res.reason_row[0] == _d.OK)
    if ok.sum() < 200:
        return None
    v, u = np.divmod(idx[ok].astype(np.float64), W)
    A = np.stack([u - u.mean(), v - v.mean(), np.ones_like(u)], axis=1)
    (a, b, _), *_ = np.linalg.lstsq(A, res.col[0][ok].astype(np.float64), rcond=None)
    (d, e, _), *_ = np.linalg.lstsq(A, res.row[0][ok].astype(np.float64), rcond=None)
    n1, n2 = np.hypot(a, b), np.hypot(d, e)
    if n1 == 0 or n2 == 0 or a * e - b * d <= 0:
        return None
    return float((a / n1 + e / n2) / 2.0)


def _check_upright(res, idx, lit, ps: PhaseSet, W: int, name: str) -> None:
    """Raise when a sequence without a Gray code, described by hand, decodes to a projector image turned upside
    down in the camera (or upright when the description says ``"upside_down": true``).  procam's own sequences
    (order ``procam``, its conventions unchanged) are what it projected and are not judged: a ceiling-mounted
    projector decodes upside down, rightly.  A shift (or a sign) of the wrong way round in
    every block turns the decoded image by 180 degrees and nothing else: every frequency still agrees and the
    calibration comes out with the projector upside down.  A Gray code is absolute and needs no such check."""
    if any(b.kind == "gray" for b in ps.blocks):
        return
    if ps.order == "procam" and not ps.upside_down and all(b.fringe == Fringe() for b in ps.blocks):
        return  # procam's own sequence with its own conventions: what it projected is known, however it is mounted
    c = _rotation_cos(res, idx, lit, W)
    if c is None or (c >= TURNED_COS if not ps.upside_down else c <= -TURNED_COS):
        return
    blocks = [b for b in ps.blocks if b.kind == "phase"]
    shifts = {b.fringe.shift for b in blocks}
    signs = {b.fringe.sign for b in blocks}
    one = shifts.pop() if len(shifts) == 1 else None
    said = f'"shift": {one:+d}' if one is not None else "the blocks' shifts"
    fix = f'"shift": {-one:+d}' if one is not None else "each block's shift the other way round"
    sign = f'"sign": {signs.pop():+d}' if len(signs) == 1 else "the blocks' signs"
    angle = float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))
    if ps.upside_down:
        raise CaptureError(
            f"{name}: the description says \"upside_down\": true, but the projector's image decodes upright in the "
            f"camera (turned by {angle:.0f} degrees): drop \"upside_down\" from patterns.json (docs/patterns.md)")
    raise CaptureError(
        f"{name}: the description does not match the frames: the projector's image decodes upside down in the camera "
        f"(turned by {angle:.0f} degrees), which is what {said} of the wrong way round in every block does (the fringes "
        f"move the other way between frames than it says; {sign} flipped in every block does the same) — write {fix} "
        "in every block of patterns.json (docs/patterns.md); if the projector really shows its image upside down to "
        "the camera, say \"upside_down\": true")


def _frame_fit(values, psi, b, gamma, blur, ps, name, files) -> None:
    """Raise when frames of block ``b`` (samples ``values`` (N, n) at lit pixels) are off the block's sinusoid
    (through the projector's response): each frame's median residual over the median modulation."""
    c = _resp.waveform(b.fringe, gamma, b.period, blur)
    lut = _resp.phase_lut(c, b.shifts())
    phi = lut(psi, slope=False)[0] if lut is not None else psi
    G = _resp.samples(c, phi, b.shifts())
    dG, dY = G - G.mean(0), values - values.mean(0)
    beta = np.einsum("sn,sn->n", dG, dY) / np.maximum(np.einsum("sn,sn->n", dG, dG), 1e-12)
    fit = values.mean(0) + beta * dG
    r = np.median(np.abs(values - fit), axis=1) / max(float(np.median(np.abs(beta) * np.ptp(G, axis=0) / 2)), 1e-9)
    worst = float(r.max())
    if worst <= MAX_FRAME_RESIDUAL:
        return
    bad = [int(k) for k in np.flatnonzero(r > max(0.5 * worst, 4 * float(r.min())))]
    if 0 < len(bad) < b.steps:
        which = " and ".join(_describe(b.first + k, ps, files) for k in bad)
        good = np.delete(r, bad)
        raise CaptureError(
            f"{name}: frame{'s' if len(bad) > 1 else ''} {which} {'do' if len(bad) > 1 else 'does'} not follow the "
            f"sinusoid of {_block_name(b, ps)} (typical residual {r[bad].max():.2f} of the fringes' modulation, the "
            f"other frames' {float(np.median(good)):.2f}): a frame out of order, repeated or from another sequence — "
            "check the frames and patterns.json (docs/patterns.md)")
    raise CaptureError(
        f"{name}: {_block_name(b, ps)} do not make one sinusoid of {b.steps} steps (every frame's typical residual "
        f"is {float(np.median(r)):.2f} of the fringes' modulation): a frame out of order, repeated or from another "
        "sequence, or the steps or the shift are not the description's — check the frames and patterns.json "
        "(docs/patterns.md)")


def _describe(k: int, ps, files) -> str:
    from pathlib import Path

    text = f"#{k} ({ps.role(k)})"
    if files is not None and k < len(files):
        text += f" {Path(files[k]).name}"
    return text
