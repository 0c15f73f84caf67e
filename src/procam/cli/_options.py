"""The options commands share, defined once with one help text and one set of bounds each, and their parsers.

Groups: the board and the capture-reading options (``--board``, ``--square``, ``--projector``, the decoder's,
the detector's and the correspondence's: :func:`with_pose_options`), the pattern sequence of the commands that
write one (``--family`` ...), the camera settings and live advice of the commands that open a camera
(``--exposure``, ``--gain``, ``--seed`` ...). Every number a user types is checked by :func:`number` (finite,
in range, one line naming the option) before any work. Choice lists come from :mod:`procam.choices`.
"""

from __future__ import annotations

import enum
import functools
import math
import re
from pathlib import Path
from typing import Annotated, Optional

import typer

from .. import choices
from ..errors import ProcamError
from ._app import fail, given, refuse


def choice(name: str, values) -> type[enum.Enum]:
    """A str Enum of ``values`` for a typer option: ``--help`` lists them and typer rejects anything else."""
    return enum.Enum(name, {v: v for v in values}, type=str)


def value(x):
    """The plain value of a choice option (None stays None)."""
    return getattr(x, "value", x)


Order = choice("Order", choices.PATTERN_ORDERS)
DecodeMethod = choice("DecodeMethod", choices.DECODE_METHODS)
Detector = choice("Detector", choices.DETECTORS)
Refiner = choice("Refiner", choices.REFINERS)
Estimator = choice("Estimator", choices.ESTIMATORS)
DistModel = choice("DistModel", choices.DIST_CHOICES)
SimPreset = choice("SimPreset", choices.SIM_PRESETS)
DeviceName = choice("DeviceName", choices.DEVICES)
BackgroundMode = choice("BackgroundMode", choices.BACKGROUND_MODES)

_SIZE = re.compile(r"^\s*(\d+)\s*[xX×,]\s*(\d+)\s*$")


def parse_size(text: str, what: str = "size", *, lo: int = 2, hi: int = 32768) -> tuple[int, int]:
    """Parse ``"1920x1080"`` into ``(1920, 1080)``; a clear error for anything else or a size outside
    ``lo`` .. ``hi`` pixels per side."""
    m = _SIZE.match(text or "")
    if not m:
        fail(f"{what} must look like WIDTHxHEIGHT (e.g. 1920x1080), got {text!r}")
    w, h = int(m.group(1)), int(m.group(2))
    if not (lo <= w <= hi and lo <= h <= hi):
        fail(f"{what} {text}: each side must be from {lo} to {hi}")
    return w, h


def optional_size(text: str | None, what: str = "--projector") -> tuple[int, int] | None:
    """:func:`parse_size` for an optional option (None stays None)."""
    return parse_size(text, what) if text else None


def parse_board(text: str, square: float):
    """``--board COLSxROWS`` and ``--square`` -> a :class:`procam.board.Board` (one-line errors)."""
    from .. import board as _board

    lo, hi = _board.CORNERS_PER_SIDE
    m = _SIZE.match(text or "")
    if not m:
        fail(f"--board must look like COLSxROWS of inner corners (e.g. 10x6), got {text!r}")
    cols, rows = int(m.group(1)), int(m.group(2))
    if not (lo <= cols <= hi and lo <= rows <= hi):
        fail(f"--board {text}: each side must be from {lo} to {hi} inner corners (a board of 11x7 squares has "
             "10x6 inner corners)")
    if not (math.isfinite(square) and square > 0):
        fail(f"--square must be a positive length (the board's square size, e.g. 24 for mm), got {square}")
    try:
        return _board.Board(cols, rows, square)
    except ProcamError as e:
        fail(f"--square: {e}")


def decode_options(*, decode_method=None, shadow: float = 10.0, contrast: float = 3.0, poses=()):
    """The :class:`procam.decode.DecodeOptions` of the decoder's options, validated; a decoder option typed that the
    pose folders ``poses`` leave unread is refused (:func:`refuse_unread_decoder`).  What ``procam decode`` reads
    (it finds no corners: none of :mod:`procam.pipeline`'s imports), and :func:`pose_options`' ``decode``."""
    from .. import decode as _decode

    refuse_unread_decoder(poses)
    for opt, v in (("--shadow-threshold", shadow), ("--contrast-threshold", contrast)):
        if not (math.isfinite(v) and 0 <= v <= 255):
            fail(f"{opt} must be a number of 8-bit grey levels from 0 to 255, got {v}")
    return _decode.DecodeOptions(value(decode_method) or "robust", float(shadow), float(contrast))


def pose_options(*, decode_method=None, shadow: float = 10.0, contrast: float = 3.0, detector=None,
                 refine_window: int | None = None, refine=None, window: int = 60, estimator=None,
                 min_corners: int = 10, background: bool = True, poses=()):
    """The :class:`procam.pipeline.PoseOptions` of the shared capture-reading options, validated; an option typed
    that these options or the pose folders ``poses`` leave unread is refused (:func:`refuse_unread_decoder`,
    ``--refine-window`` with ``--corner-refine none``)."""
    from .. import correspond as _corr
    from .. import pipeline

    if value(refine) == "none":
        refuse(("refine_window",), "is the corner refinement's half-window; --corner-refine none refines nothing")
    dec = decode_options(decode_method=decode_method, shadow=shadow, contrast=contrast, poses=poses)
    if refine_window is not None and not 0 <= refine_window <= 100:
        fail(f"--refine-window must be from 0 to 100 px, got {refine_window}")
    if not 6 <= window <= 1000:
        fail(f"--window must be from 6 to 1000 camera px, got {window}")
    corners = _corr.CornerOptions(window=int(window), estimator=value(estimator) or "trimmed")
    return pipeline.PoseOptions(decode=dec, detector=value(detector) or "auto", refine_window=refine_window,
                                refine=value(refine) or "fit", corners=corners, min_corners=min_corners,
                                background=background)


_PHASE = tuple(f for f in choices.PATTERN_FAMILIES if f != "gray")
#: The decoder options only some capture families' decoders read: parameter -> (families, what it is).
DECODER_SCOPE = {
    "decode_method": (("gray",), "the Gray-code bit classifier"),
    "contrast": (("gray", "gray-phase"), "the Gray-code bits' contrast threshold"),
    "gamma": (_PHASE, "the phase decoder's projector gamma"),
    "camera_noise": (_PHASE, "the phase decoder's camera noise"),
}


def refuse_unread_decoder(poses) -> None:
    """Refuse (one line naming the folder and its family, before any decoding) a decoder option typed that the
    family of a pose folder in ``poses`` does not read: ``--decode`` on a phase capture, ``--gamma`` on Gray codes
    (:data:`DECODER_SCOPE`).  A rig pose folder is checked pair by pair; a folder that cannot be read is left to
    its loader to name."""
    if not given(*DECODER_SCOPE):
        return
    from ..capture import is_rig_pose
    from ..capture.describe import read_patterns_json
    from ..patterns import family_of

    for p in map(Path, poses):
        if not p.is_dir():
            continue
        try:
            folders = sorted(q for q in p.iterdir() if q.is_dir()) if is_rig_pose(p) else [p]
            families = [family_of(read_patterns_json(f)) for f in folders]
        except (ProcamError, OSError):
            continue
        for folder, family in zip(folders, families):
            for name, (families_read, what) in DECODER_SCOPE.items():
                if family not in families_read:
                    refuse((name,), f"is {what}; {folder} holds a {family} capture, whose decoder does not read it")


# Options shared by the commands that read capture folders (one definition, one help text each).
BoardOpt = Annotated[str, typer.Option("--board", help="Inner corners COLSxROWS (OpenCV pattern_size), e.g. 10x6.")]
SquareOpt = Annotated[float, typer.Option("--square", help="Square size; the length unit of every output (e.g. mm).")]
ProjectorOpt = Annotated[Optional[str], typer.Option(
    "--projector", "-p", help="Projector size WIDTHxHEIGHT, for a folder whose patterns.json does not state it "
                             "(a size it states cannot be changed).")]
OrderOpt = Annotated[Optional[Order], typer.Option(
    "--order", help="Sequence order (default: the folder's patterns.json, else opencv).")]
StepOpt = Annotated[Optional[int], typer.Option(
    "--step", min=1, max=64,
    help="Projector pixels per Gray code (kamino410's graycode_step; default: patterns.json's, else 1).")]
DecodeOpt = Annotated[DecodeMethod, typer.Option("--decode", help="Bit classifier.")]
ShadowOpt = Annotated[float, typer.Option(
    "--shadow-threshold", help="Minimum white - black for a lit pixel, 8-bit grey levels (scaled for 16-bit).")]
ContrastOpt = Annotated[float, typer.Option(
    "--contrast-threshold", help="Minimum |pattern - inverse| for a certain bit, 8-bit grey levels.")]
DetectorOpt = Annotated[Detector, typer.Option("--detector", help="Chessboard corner detector.")]
RefineOpt = Annotated[Optional[int], typer.Option(
    "--refine-window", help="Half-window of the corner refinement, camera px (default: 15 for fit, 11 for subpix).")]
RefinerOpt = Annotated[Refiner, typer.Option(
    "--corner-refine", help="Corner refinement: fit (a blurred X-corner model with uneven lighting; default), subpix "
                     "(OpenCV cornerSubPix, the paper's) or none.")]
WindowOpt = Annotated[int, typer.Option("--window", help="Local-homography window side, camera px.")]
EstimatorOpt = Annotated[Estimator, typer.Option("--estimator", help="Local-homography fit.")]
BackgroundOpt = Annotated[BackgroundMode, typer.Option(
    "--background", help="Single-pose: the decoded scene behind the board. off: the board alone calibrates the "
    "projector; free (default), auto, check: the background is the second plane of the projector's dense fit (with a "
    "view without dense samples: free lifts the paper's u0p = W/2 where the background determines it, auto only when "
    "it refutes it, check only says so).")]

# The camera settings and live advice of the commands that open a camera (capture, advise): one definition, one
# set of bounds each (checked by :func:`camera_settings` and :func:`live_limits` before any device is opened).
ExposureOpt = Annotated[Optional[float], typer.Option(
    "--exposure", help="Manual camera exposure in ms (default: leave the camera's setting; switch its auto exposure "
    "off yourself then).")]
GainOpt = Annotated[Optional[float], typer.Option("--gain", help="Camera gain in the camera's unit (GenICam: dB).")]
CameraSizeOpt = Annotated[Optional[str], typer.Option(
    "--camera-size", help="Camera resolution WIDTHxHEIGHT (OpenCV).")]
DisplayOpt = Annotated[Optional[int], typer.Option(
    "--display", help="The projector's display (default: the one that is not the primary; procam capture "
    "--list-devices lists them).")]
SeedOpt = Annotated[int, typer.Option("--seed", help="The simulator's noise seed (with --virtual; capture, advise: "
                                      "also --camera virtual): "
                                      "the same seed gives the same frames.")]
LiveJsonOpt = Annotated[bool, typer.Option(
    "--json", help="Live advice: one JSON line per frame on stdout instead of the preview window.")]
LiveAutoOpt = Annotated[bool, typer.Option(
    "--auto", help="Live advice: go on by itself as soon as the pose is good and the board still.")]
LiveCalibrationOpt = Annotated[Optional[Path], typer.Option(
    "--calibration", help="Live advice: a calibration of this camera (procam JSON or OpenCV YAML): its "
    "intrinsics, and with R, T the projector side.")]
LiveTargetOpt = Annotated[float, typer.Option(
    "--target", help="Live advice: a pose is good when the predicted std of f_c and f_p are at most this % of f.")]
LiveMaxFramesOpt = Annotated[Optional[int], typer.Option(
    "--max-frames", help="Live advice: go on after N frames at the latest (scripts).")]
#: Bounds of the options above (exposure in ms, gain in the camera's unit, frames, seed).
EXPOSURE_MS = (0.0, 60_000.0)
GAIN = (0.0, 1000.0)
MAX_FRAMES = 10_000_000
MAX_SEED = 2**32 - 1 - 99  # a session of up to 99 poses seeds pose k with seed + k
MAX_DISPLAY = 64


def parse_pose(text: str) -> tuple[float, float, float]:
    """``--pose PSI,NU[,PHI]``: the board's angles in degrees (phi 0 when left out), checked (one-line errors)."""
    parts = [p for p in text.replace(";", ",").split(",") if p.strip()] if text else []
    try:
        vals = [float(p) for p in parts]
    except ValueError:
        vals = []
    if len(vals) not in (2, 3):
        fail(f"--pose must be PSI,NU[,PHI] in degrees (e.g. 15,12,0), got {text!r}")
    if not all(math.isfinite(v) for v in vals):
        fail(f"--pose angles must be finite numbers of degrees, got {text!r}")
    if len(vals) == 2:
        vals.append(0.0)
    if any(abs(v) >= 80 for v in vals[:2]):
        fail(f"--pose angles psi and nu must be within +-80 degrees, got {text!r}")
    if abs(vals[2]) > 360:
        fail(f"--pose angle phi must be within +-360 degrees, got {text!r}")
    return vals[0], vals[1], vals[2]


def camera_settings(exposure, gain, camera_size, seed, display=None) -> tuple[int, int] | None:
    """Check the device options of ``capture``/``advise``/``world-check`` (one line naming the option when one is out
    of range); returns the camera size ``(width, height)`` or None."""
    number(display, "--display", lo=0, hi=MAX_DISPLAY, what="a display index",
           unit=" (procam capture --list-devices lists them)")
    number(exposure, "--exposure", lo=EXPOSURE_MS[0], hi=EXPOSURE_MS[1], lo_open=True, unit=" ms",
           what="a finite number")
    number(gain, "--gain", lo=GAIN[0], hi=GAIN[1], what="a finite number")
    number(seed, "--seed", lo=0, hi=MAX_SEED, what="a seed")
    return parse_size(camera_size, "--camera-size") if camera_size else None


#: Why a device option is refused with the simulator's devices (or the seed with a real camera): :func:`refuse` texts.
SIMULATED_CAMERA = "is a setting of a real camera; the simulator renders at its scene's size and exposure"
SIMULATED_PROJECTOR = "chooses the real projector's display; --virtual projects on a virtual one"


#: The options a real camera of a kind does not read (a folder camera reads files; GenICam has its own size).
_CAMERA_IGNORES = {
    "folder": (("camera_size", "exposure", "gain"), "is a setting of a streaming camera; a folder camera "
               "(--camera folder:) reads the files the camera's own software saves: set it there"),
    "genicam": (("camera_size",), "is an OpenCV camera's resolution; a GenICam camera delivers the size set in its "
                "own settings (the vendor's tool)"),
}


def real_camera(camera: str, *, virtual_flag: str = "--virtual") -> str:
    """The kind (:func:`procam.acquire.cameras.parse_camera_spec`) of a real ``--camera``, the spec checked and the
    device options that kind would not read refused; ``--camera virtual`` names ``virtual_flag`` (the simulator's
    camera comes with the simulated rig)."""
    kind = refuse_unread_camera(camera)
    if kind == "virtual":
        fail(f"--camera {camera}: the simulator's camera comes with its projector; use {virtual_flag} instead")
    return kind


def virtual_gain(gain) -> None:
    """Check ``--gain`` for the simulator's camera: a factor on the light (0 would render black frames)."""
    number(gain, "--gain", lo=0, lo_open=True, hi=GAIN[1], what="a gain factor",
           unit=" (the simulator's camera multiplies the light by it)")


def refuse_unread_camera(camera: str) -> str:
    """The kind of the ``--camera`` spec, the device options it would not read refused (a folder camera's exposure,
    gain and size; a GenICam camera's ``--camera-size``) and the folder or producer file it names checked, before
    any work; returns the kind (:func:`procam.acquire.cameras.parse_camera_spec`)."""
    from ..acquire.cameras import parse_camera_spec

    kind, arg = parse_camera_spec(camera)
    if kind in _CAMERA_IGNORES:
        refuse(*_CAMERA_IGNORES[kind])
    if kind == "folder" and not Path(arg).expanduser().is_dir():
        fail(f"--camera {camera}: no such folder; give the folder your camera software saves into (make it first)")
    if kind == "genicam" and not Path(arg.partition("#")[0]).expanduser().is_file():
        fail(f"--camera {camera}: no such GenTL producer (.cti) file; give the path of the camera vendor's producer")
    return kind


def seed_applies(where: str) -> str:
    """Why ``--seed`` is refused with a real camera: it applies with ``where`` (the simulator's option)."""
    return f"is the simulator's noise seed: it applies with {where}"


def live_limits(max_frames) -> None:
    """Check ``--max-frames`` (the other live-advice numbers: :func:`procam.acquire.live.advisor_options`)."""
    number(max_frames, "--max-frames", lo=1, hi=MAX_FRAMES, what="a frame count")


# The pattern sequence of the commands that write one (patterns, simulate): docs/patterns.md
Family = choice("Family", choices.PATTERN_FAMILIES)
FamilyOpt = Annotated[Family, typer.Option(
    "--family", help="Pattern family: gray (Gray codes), phase (N-step fringes + a unit-frequency cue), "
                     "heterodyne (three frequencies) or gray-phase (Gray code + fringes); docs/patterns.md.")]
StepsOpt = Annotated[Optional[int], typer.Option(
    "--steps", help="Phase families: phase shifts per block, N >= 3 (default 8 for phase and heterodyne, 4 for "
                "gray-phase).")]
PeriodOpt = Annotated[Optional[list[float]], typer.Option(
    "--period", help="phase, gray-phase: fringe period in projector px (default: phase 16 and 128 under the "
                     "cue, gray-phase 16); phase: repeat it for more levels below the cue.")]
CountsOpt = Annotated[Optional[str], typer.Option(
    "--counts", help="heterodyne: the three counts of periods across the panel, e.g. 70,64,59 (the default).")]
InverseOpt = Annotated[Optional[bool], typer.Option(
    "--inverse/--no-inverse", help="gray-phase: every Gray bit followed by its inverse (default: on).")]
ComplementaryOpt = Annotated[Optional[bool], typer.Option(
    "--complementary/--no-complementary", help="gray-phase: a complementary Gray bit (removes stripe-edge errors; "
                                               "default: on).")]
WhiteBlackOpt = Annotated[Optional[bool], typer.Option(
    "--white-black/--no-white-black", help="Phase families: end with a white and a black frame (default: on).")]


GrayOrderOpt = Annotated[Optional[Order], typer.Option("--order", help="Gray family: sequence order (default: opencv).")]
GrayStepOpt = Annotated[Optional[int], typer.Option(
    "--step", help="Gray family: projector pixels per code, 1-64 (>1 against moire, as kamino410's graycode_step; "
                   "default 1).")]
#: The pattern options of the commands that write or show a sequence: (parameter, option, default). A family's own
#: options default to None (not given) and are refused with another family (:data:`PATTERN_SCOPE`).
PATTERN_OPTIONS = (("order", GrayOrderOpt, None), ("step", GrayStepOpt, None), ("family", FamilyOpt, Family.gray),
                   ("steps", StepsOpt, None), ("period", PeriodOpt, None), ("counts", CountsOpt, None),
                   ("inverse", InverseOpt, None), ("complementary", ComplementaryOpt, None),
                   ("white_black", WhiteBlackOpt, None))
#: The families each family-specific pattern option applies to, its option names (given, not given) and its value
#: when not given: an option of another family is refused, never silently ignored.
PATTERN_SCOPE = {
    "order": (("gray",), ("--order",), "opencv"),
    "step": (("gray",), ("--step",), 1),
    "steps": (_PHASE, ("--steps",), None),
    "period": (("phase", "gray-phase"), ("--period",), None),
    "counts": (("heterodyne",), ("--counts",), None),
    "inverse": (("gray-phase",), ("--inverse", "--no-inverse"), True),
    "complementary": (("gray-phase",), ("--complementary", "--no-complementary"), True),
    "white_black": (_PHASE, ("--white-black", "--no-white-black"), True),
}


def pattern_defaults(args: dict) -> dict:
    """The pattern options ``args`` (as typer gives them: None where not given) checked against the family and
    with every option not given at its default: an option of another family (``--no-inverse`` with Gray codes,
    ``--order`` with a phase family) is a one-line error naming the family it belongs to."""
    family = value(args.get("family", "gray"))
    out = dict(args)
    for name, (families, flags, default) in PATTERN_SCOPE.items():
        if name not in args:
            continue
        given = args[name]
        if given is None or (isinstance(given, (list, tuple)) and not given):
            out[name] = default
            continue
        if family not in families:
            flag = flags[0] if len(flags) == 1 or given else flags[1]
            where = ("the Gray family (--family gray, the default)" if families == ("gray",) else
                     "the phase families" if families == _PHASE else
                     f"--family {' or '.join(families)}")
            hint = " (the heterodyne's periods are given as --counts)" if name == "period" else ""
            fail(f"{flag} applies to {where}, not to --family {family}{hint}; leave it out or choose that family")
    return out
#: Most projector pixels per Gray code (``--step``).
MAX_STEP = 64


def pattern_sequence(size, *, family, order="opencv", step: int = 1, steps=None, period=None, counts=None,
                     inverse: bool = True, complementary: bool = True, white_black: bool = True):
    """The sequence (:func:`procam.patterns.pattern_set`) of the pattern options (as :func:`pattern_defaults` leaves
    them: each option of the family's own), validated (one-line errors)."""
    from .. import patterns

    number(step, "--step", lo=1, hi=MAX_STEP, what="a whole number of projector pixels")
    family = value(family)
    if family == "gray":
        try:
            return patterns.pattern_set(*size, value(order), step)
        except ValueError as e:
            fail(f"--step {step}: {e}; use a smaller --step")
    kw = phase_keywords(family, steps=steps, period=period, counts=counts, inverse=inverse,
                        complementary=complementary, white_black=white_black)
    try:
        return patterns.pattern_set(*size, family=family, **kw)
    except ValueError as e:
        fail(f"the {family} sequence for a {size[0]}x{size[1]} projector: {e}")


def phase_keywords(family, *, steps=None, period=None, counts=None, inverse: bool = True, complementary: bool = True,
                   white_black: bool = True) -> dict:
    """The keywords of :func:`procam.patterns.phase_set` for a phase ``family`` from the pattern options, each
    validated (one-line errors)."""
    family = value(family)
    kw = {"inverse": inverse, "complementary": complementary, "white_black": white_black}
    if steps is not None:
        kw["steps"] = int(number(steps, "--steps", lo=3, hi=64, what="a number of phase shifts"))
    for p in period or ():
        number(p, "--period", lo=2, hi=1e6, unit=" projector px", what="a fringe period")
    if family == "heterodyne" and counts is not None:
        try:
            kw["periods"] = tuple(float(v) for v in counts.replace(";", ",").split(","))
        except ValueError:
            fail(f"--counts must be three numbers like 70,64,59, got {counts!r}")
        if len(kw["periods"]) != 3 or not all(math.isfinite(v) and v > 1 for v in kw["periods"]):
            fail(f"--counts must be three numbers above 1 like 70,64,59, got {counts!r}")
    elif period:
        if family == "gray-phase" and len(period) > 1:
            fail("--period: gray-phase has one fringe period")
        kw["period" if len(period) == 1 else "periods"] = period[0] if len(period) == 1 else tuple(period)
    return kw

#: The capture-processing options of :func:`pose_options`: (parameter name, annotation, default).
POSE_OPTIONS = (("decode_method", DecodeOpt, DecodeMethod.robust), ("shadow", ShadowOpt, 10.0),
                ("contrast", ContrastOpt, 3.0), ("detector", DetectorOpt, Detector.auto),
                ("refine_window", RefineOpt, None), ("refine", RefinerOpt, Refiner.fit), ("window", WindowOpt, 60),
                ("estimator", EstimatorOpt, Estimator.trimmed))


def _with_group(fn, group, prepare=None):
    """``fn`` with the keyword-only options of ``group`` (``(name, annotation, default)``) added to its signature;
    it receives them in its ``**kwargs`` (passed through ``prepare(kwargs) -> kwargs`` first, when given)."""
    import inspect

    sig = inspect.signature(fn, eval_str=True)  # typer reads a given __signature__ as it is
    params = [p for p in sig.parameters.values() if p.kind is not inspect.Parameter.VAR_KEYWORD]
    params += [inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=default, annotation=annotation)
               for name, annotation, default in group]

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        return fn(*args, **(kwargs if prepare is None else prepare(kwargs)))

    wrapper.__signature__ = sig.replace(parameters=params)
    return wrapper


def with_pose_options(fn):
    """Give a command that reads pose folders the shared capture-processing options (:data:`POSE_OPTIONS`:
    ``--decode``, ``--shadow-threshold``, ..., ``--estimator``): one definition, the same defaults everywhere.

    The command declares ``**pose_args`` and receives them there, ready for
    ``pose_options(**pose_args, min_corners=...)``.
    """
    return _with_group(fn, POSE_OPTIONS)


def with_pattern_options(*, leave_out: tuple = ()):
    """Give a command that writes or shows a pattern sequence (patterns, simulate, capture) the pattern options
    (:data:`PATTERN_OPTIONS`: ``--order``, ``--step``, ``--family`` ... ``--white-black``) but those it leaves out:
    one definition, one help text, one set of bounds (checked by :func:`pattern_sequence`), an option of another
    family refused (:func:`pattern_defaults`).

    The command declares ``**pattern_args`` and receives them there, ready for ``pattern_sequence(size,
    **pattern_args)``.
    """
    group = tuple(o for o in PATTERN_OPTIONS if o[0] not in leave_out)
    return lambda fn: _with_group(fn, group, pattern_defaults)


def number(value, option: str, *, lo: float | None = None, hi: float | None = None, lo_open: bool = False,
           unit: str = "", what: str = "a number"):
    """``value`` of ``option`` if it is finite and within ``[lo, hi]`` (``(lo, hi]`` with ``lo_open``), else a
    one-line error that says the range.  None (an option not given) stays None."""
    if value is None:
        return None
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if ok and lo is not None:
        ok = value > lo if lo_open else value >= lo
    if ok and hi is not None:
        ok = value <= hi
    if not ok:
        def g(x):
            return str(int(x)) if float(x).is_integer() and abs(x) < 1e15 else f"{x:g}"

        rng = []
        if lo is not None:
            rng.append(f"{'>' if lo_open else '>='} {g(lo)}")
        if hi is not None:
            rng.append(f"<= {g(hi)}")
        fail(f"{option} must be {what}{' ' + ' and '.join(rng) if rng else ''}{unit}, got {value}")
    return value


ForceOpt = Annotated[bool, typer.Option(
    "--force", help="Write into a folder that holds other files (procam still never overwrites or deletes a file "
                    "it did not write).")]
