"""The sequence a pose folder holds: its ``patterns.json`` (:func:`read_patterns_json`) with the ``--projector``,
``--order`` and ``--step`` given (:func:`resolve_pattern_set`), and what a wrong count of frames points to."""

from __future__ import annotations

from pathlib import Path

from .. import patterns
from ..errors import CaptureError


def read_patterns_json(folder) -> dict | None:
    """The folder's ``patterns.json`` (bounded: :func:`procam.io.jsonfile.load_json`), or None without one.
    Raises :class:`CaptureError` naming the file for one that cannot be read or is no JSON object."""
    from ..io.jsonfile import JSONError, load_json

    path = Path(folder) / "patterns.json"
    if not path.is_file():
        return None
    try:
        meta = load_json(path)
    except OSError as e:
        raise CaptureError(f"{path}: cannot be read ({e.strerror or e}); check its permissions") from None
    except JSONError as e:
        raise CaptureError(f"{path}: {e}; fix it (docs/patterns.md)") from None
    if not isinstance(meta, dict):
        raise CaptureError(f"{path}: not a JSON object; a description is an object with width, height and, for a "
                           "phase family, family and sequence (docs/patterns.md)")
    return meta


def resolve_pattern_set(folder, projector=None, order=None, step=None):
    """The sequence of ``folder``: from ``projector`` (w, h), ``order`` and ``step``, else from its
    patterns.json, else the defaults (opencv order, step 1).  A patterns.json of a phase family
    (:func:`procam.patterns.from_dict`) gives a :class:`~procam.patterns.PhaseSet` (``order`` and ``step`` are the
    Gray family's).  A Gray-family patterns.json's ``bit_order`` is kept.  ``projector`` completes a description
    without a size; one that contradicts the size patterns.json states is a :class:`CaptureError` (the sequence
    shown was made for that projector: another size reads its codes as another projector's)."""
    from ..patterns.describe import gray_from_dict

    meta = read_patterns_json(folder)
    where = Path(folder) / "patterns.json"
    stated = (meta.get("width"), meta.get("height")) if meta is not None else (None, None)
    if projector is not None and all(type(v) is int for v in stated) and tuple(projector) != stated:
        raise CaptureError(f"--projector {projector[0]}x{projector[1]}: {where} says the sequence was made for a "
                           f"{stated[0]}x{stated[1]} projector; leave --projector out (or, if that is wrong, correct "
                           "its width and height)")
    if step is not None and meta is not None and type(meta.get("step")) is int and step != meta["step"]:
        raise CaptureError(f"--step {step}: {where} says the sequence was made with step {meta['step']}; leave --step "
                           "out (or, if that is wrong, correct its step)")
    family = patterns.family_of(meta)
    if family != "gray":
        if order is not None or step is not None:
            raise CaptureError(f"{where} describes a {family} sequence: --order and --step apply to Gray codes only; "
                               "drop them")
        try:
            return patterns.from_dict(meta, *(projector if projector is not None else (None, None)))
        except ValueError as e:
            raise CaptureError(f"{where}: {e} — see docs/patterns.md for how to describe a sequence") from None
    if meta is None:
        if projector is None:
            raise CaptureError(f"{folder}: the projector size is unknown; pass --projector WIDTHxHEIGHT "
                               "(no patterns.json in the folder)")
        try:
            return patterns.pattern_set(projector[0], projector[1], order or "opencv", 1 if step is None else step)
        except ValueError as e:
            raise CaptureError(f"{folder}: {e}") from None
    try:
        return gray_from_dict(meta, *(projector if projector is not None else (None, None)), order, step)
    except ValueError as e:
        text = str(e)
        if text.startswith(("width", "height", "no width", "no height")):
            raise CaptureError(f"{where}: no valid width/height: {text}; fix it or pass --projector WIDTHxHEIGHT") \
                from None
        fix = ("; fix it or pass --order" if text.startswith("unknown order")
               else "; fix it or pass --step" if text.startswith("step") else " — see docs/patterns.md")
        raise CaptureError(f"{where}: {text}{fix}") from None


def _count_with_step(w: int, h: int, order: str, step: int) -> int | None:
    """Frames of the Gray sequence of a ``w`` x ``h`` projector at ``step``, None when the step leaves it too few
    codes (a small projector)."""
    try:
        return patterns.pattern_set(w, h, order, step).count
    except ValueError:
        return None


def _count_hint(found: int, ps: patterns.PatternSet) -> str:
    w, h = ps.width, ps.height
    guesses = [f"{a}x{b}" for a, b in [(1920, 1080), (1280, 800), (1280, 720), (1024, 768), (800, 600),
                                        (1920, 1200), (3840, 2160), (1400, 1050), (1366, 768), (912, 1140)]
               if patterns.pattern_set(a, b).count == found and (a, b) != (w, h)]
    if found == ps.count - 2:
        other = f"that count fits a projector of {', '.join(guesses[:3])}: check --projector; or " if guesses else ""
        return (f" — two short: {other}the white and black frames seem to be missing (OpenCV's "
                "GrayCodePattern.generate() does not include them; capture them as the last two frames, or use "
                "'procam patterns')")
    n = min(ps.col_bits, ps.row_bits)
    if ps.col_bits != ps.row_bits and found == 2 + 4 * n:
        return (f" — this matches scan3d-capture's sequence with {n} bits on both axes, which drops column bits; "
                "re-capture with the sequence from 'procam patterns'")
    steps = [k for k in (2, 3, 4, 8) if ps.step == 1 and _count_with_step(w, h, ps.order, k) == found]
    hints = []
    if guesses:
        hints.append(f"that count fits a projector of {', '.join(guesses[:3])}: check --projector")
    if steps:
        hints.append(f"it fits this projector with --step {steps[0]} (one code per {steps[0]}x{steps[0]} pixels, "
                     "kamino410's graycode_step)")
    if hints:
        return " — " + "; or ".join(hints)
    return " — check --projector and that no frames are missing or extra"
