"""The typer application object, consoles, one-line errors and the options every command shares.

Choice lists come from the library's one list of them (:mod:`procam.choices`), so the CLI cannot drift from
it. Nothing here or at the top of a command module imports numpy, OpenCV, scipy or matplotlib: commands import
everything heavy inside their function, so ``procam --help`` and ``--version`` start in a fraction of a second.
"""

from __future__ import annotations

import contextlib
import enum
import errno
import functools
import math
import os
import re
import sys
import warnings
from pathlib import Path
from typing import Annotated, Optional

import typer
from typer.core import TyperGroup

from .. import choices
from ..errors import OutputError, ProcamError, ProcamWarning


class _OneLineErrors(TyperGroup):
    """A command group whose usage errors (bad option values, missing arguments) are one line on stderr
    with exit code 2, like procam's own errors, instead of a framed usage panel."""

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        try:  # typer vendors click since 0.20-something; before, it used click itself
            from typer import _click
        except ImportError:  # pragma: no cover - older typer
            import click as _click
        Abort = getattr(_click.exceptions, "Abort", None)
        if Abort is None:  # typer's vendored click raises typer's own
            from typer.exceptions import Abort

        try:
            rv = super().main(args=args, prog_name=prog_name, complete_var=complete_var, standalone_mode=False,
                              **extra)
        except _click.exceptions.UsageError as e:
            cmd = e.ctx.command_path if e.ctx is not None else "procam"
            err_console.print(f"[bold red]error:[/bold red] {escape(e.format_message())} (see '{escape(cmd)} --help')",
                              highlight=False, soft_wrap=True)
            rv = 2
        except _click.exceptions.ClickException as e:
            err_console.print(f"[bold red]error:[/bold red] {escape(e.format_message())}", highlight=False,
                              soft_wrap=True)
            rv = e.exit_code
        except (Abort, KeyboardInterrupt):
            err_console.print("interrupted", highlight=False)
            rv = 130
        if not standalone_mode:
            return rv
        sys.exit(rv if isinstance(rv, int) else 0)


app = typer.Typer(cls=_OneLineErrors, add_completion=False, no_args_is_help=True, pretty_exceptions_enable=False,
                  rich_markup_mode=None,
                  help="Projector-camera calibration from Gray-code captures of a chessboard.")
class _LazyConsole:
    """A rich Console made on first use: importing rich's console is a tenth of the start-up, and ``procam
    --version`` or ``--help`` prints nothing through it. Not a terminal (pipes, CI, logs): wide enough that
    tables don't wrap."""

    def __init__(self, stderr: bool = False):
        self._stderr = stderr
        self._console = None

    @property
    def real(self):
        """The rich Console itself (made now if not yet)."""
        if self._console is None:
            from rich.console import Console

            stream = sys.stderr if self._stderr else sys.stdout
            self._console = Console(stderr=self._stderr, soft_wrap=True, width=None if stream.isatty() else 160)
        return self._console

    def __getattr__(self, name):
        return getattr(self.real, name)

    def __enter__(self):
        return self.real.__enter__()

    def __exit__(self, *exc):
        return self.real.__exit__(*exc)


console = _LazyConsole()
err_console = _LazyConsole(stderr=True)


@contextlib.contextmanager
def text_on_stderr(on: bool = True):
    """While stdout carries data (``--json`` lines), print the command's text lines (:func:`say`, :func:`warn`,
    tables) on stderr; ``on=False`` changes nothing."""
    if not on:
        yield
        return
    old = console._console
    console._console = err_console.real
    try:
        yield
    finally:
        console._console = old


def escape(text: str) -> str:
    """``text`` with rich markup escaped (:func:`rich.markup.escape`)."""
    from rich.markup import escape as _escape

    return _escape(text)


def fail(message: str, code: int = 2, label: str = "error"):
    """Print a one-line ``label: message`` to stderr and exit with ``code`` (plain text, not markup). Exit codes:
    2 the user's input is wrong, 3 the result must not be trusted (a degenerate or failed calibration)."""
    err_console.print(f"[bold red]{escape(label)}:[/bold red] {escape(str(message))}", highlight=False, soft_wrap=True)
    raise typer.Exit(code)


def warn(message: str):
    """Print a warning line (plain text, not markup)."""
    console.print(f"[yellow]warning:[/yellow] {escape(str(message))}", highlight=False)


def say(message: str):
    """Print an information line (plain text, not markup)."""
    console.print(escape(str(message)), highlight=False)


#: What to do about an OS error, by errno.
_OS_HINTS = {errno.ENOSPC: "the disk is full; free some space or write elsewhere",
             errno.EDQUOT: "the disk quota is exhausted; free some space or write elsewhere",
             errno.EROFS: "the file system is read-only; write elsewhere",
             errno.EACCES: "permission denied; check the path and its permissions",
             errno.EPERM: "not permitted; check the path and its permissions",
             errno.ENOENT: "no such file or folder; check the path",
             errno.ENOTDIR: "a part of the path is not a folder; check the path",
             errno.EISDIR: "is a folder; give a file name",
             errno.ELOOP: "too many levels of symbolic links (a link loop); check the path",
             errno.ENAMETOOLONG: "the name is too long; use a shorter path",
             errno.EMFILE: "too many open files; close other programs and retry"}


def os_error_message(e: OSError) -> str:
    """One line for an OS error: the user's path, what happened and what to do."""
    hint = _OS_HINTS.get(e.errno, f"{e.strerror or e}; check the path and its permissions")
    return f"{e.filename}: {hint}" if e.filename else hint


def plain(text):
    """``text`` as rich Text: printed as is, never read as markup (file names like ``cap[red]``, table cells)."""
    from rich.text import Text

    return Text(str(text))


def user_errors(fn):
    """Decorator for commands: turn :class:`ProcamError` (and OS errors, memory exhaustion) into one-line errors,
    exit code 2; anything else into one line that asks for a report, exit code 1 (``PROCAM_DEBUG=1`` shows the
    traceback)."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            with warnings.catch_warnings():  # results carry their warnings; commands print them themselves
                warnings.simplefilter("ignore", ProcamWarning)
                return fn(*args, **kwargs)
        except typer.Exit:
            raise
        except ProcamError as e:
            fail(str(e))
        except OSError as e:  # unwritable output folder, disk full, permission denied ...
            fail(os_error_message(e))
        except MemoryError:
            fail("not enough memory for this job; use smaller images, sizes or grids, or free memory")
        except KeyboardInterrupt:
            err_console.print("interrupted")
            raise typer.Exit(130)
        except Exception as e:  # a bug: still one line, but say so
            if os.environ.get("PROCAM_DEBUG"):
                raise
            first = (str(e).strip().splitlines() or [""])[-1][:300]
            fail(f"internal error ({type(e).__name__}: {first}); please report it with the command line "
                 "(PROCAM_DEBUG=1 shows the traceback)", code=1)

    return wrapper


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


def pose_options(*, decode_method=None, shadow: float = 10.0, contrast: float = 3.0, detector=None,
                 refine_window: int | None = None, refine=None, window: int = 60, estimator=None,
                 min_corners: int = 10, background: bool = True):
    """The :class:`procam.pipeline.PoseOptions` of the shared capture-reading options, validated."""
    from .. import correspond as _corr
    from .. import decode as _decode
    from .. import pipeline

    for opt, v in (("--shadow-threshold", shadow), ("--contrast-threshold", contrast)):
        if not (math.isfinite(v) and 0 <= v <= 255):
            fail(f"{opt} must be a number of 8-bit grey levels from 0 to 255, got {v}")
    if refine_window is not None and not 0 <= refine_window <= 100:
        fail(f"--refine-window must be from 0 to 100 px, got {refine_window}")
    if not 6 <= window <= 1000:
        fail(f"--window must be from 6 to 1000 camera px, got {window}")
    dec = _decode.DecodeOptions(value(decode_method) or "robust", float(shadow), float(contrast))
    corners = _corr.CornerOptions(window=int(window), estimator=value(estimator) or "trimmed")
    return pipeline.PoseOptions(decode=dec, detector=value(detector) or "auto", refine_window=refine_window,
                                refine=value(refine) or "fit", corners=corners, min_corners=min_corners,
                                background=background)


# Options shared by the commands that read capture folders (one definition, one help text each).
BoardOpt = Annotated[str, typer.Option("--board", help="Inner corners COLSxROWS (OpenCV pattern_size), e.g. 10x6.")]
SquareOpt = Annotated[float, typer.Option("--square", help="Square size; the length unit of every output (e.g. mm).")]
ProjectorOpt = Annotated[Optional[str], typer.Option(
    "--projector", "-p", help="Projector size WIDTHxHEIGHT (default: the folder's patterns.json).")]
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
SeedOpt = Annotated[int, typer.Option("--seed", help="The simulator's noise seed (--virtual, --camera virtual): "
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


def camera_settings(exposure, gain, camera_size, seed) -> tuple[int, int] | None:
    """Check the camera options of ``capture``/``advise`` (one line naming the option when one is out of range);
    returns the camera size ``(width, height)`` or None."""
    number(exposure, "--exposure", lo=EXPOSURE_MS[0], hi=EXPOSURE_MS[1], lo_open=True, unit=" ms",
           what="a finite number")
    number(gain, "--gain", lo=GAIN[0], hi=GAIN[1], what="a finite number")
    number(seed, "--seed", lo=0, hi=MAX_SEED, what="a seed")
    return parse_size(camera_size, "--camera-size") if camera_size else None


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
InverseOpt = Annotated[bool, typer.Option("--inverse/--no-inverse", help="gray-phase: every Gray bit followed by its "
                                          "inverse.")]
ComplementaryOpt = Annotated[bool, typer.Option(
    "--complementary/--no-complementary", help="gray-phase: a complementary Gray bit (removes stripe-edge errors).")]
WhiteBlackOpt = Annotated[bool, typer.Option("--white-black/--no-white-black",
                                             help="Phase families: end with a white and a black frame.")]


def pattern_sequence(size, *, family, order="opencv", step: int = 1, steps=None, period=None, counts=None,
                     inverse: bool = True, complementary: bool = True, white_black: bool = True):
    """The sequence (:func:`procam.patterns.pattern_set`) of the pattern options, validated (one-line errors)."""
    from .. import patterns

    family = value(family)
    if family == "gray":
        given = [o for o, v in (("--steps", steps), ("--period", period), ("--counts", counts)) if v]
        if given:
            fail(f"{', '.join(given)} appl{'y' if len(given) > 1 else 'ies'} to the phase families; add --family "
                 "phase, heterodyne or gray-phase")
        try:
            return patterns.pattern_set(*size, value(order), step)
        except ValueError as e:
            fail(f"--step {step}: {e}; use a smaller --step")
    if step != 1:
        fail("--step applies to the Gray family only")
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
    if period and family == "heterodyne":
        fail("--period: the heterodyne's periods are given as --counts (periods across the panel)")
    if counts is not None and family != "heterodyne":
        fail("--counts applies to --family heterodyne")
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


def with_pose_options(fn):
    """Give a command that reads pose folders the shared capture-processing options (:data:`POSE_OPTIONS`:
    ``--decode``, ``--shadow-threshold``, ..., ``--estimator``): one definition, the same defaults everywhere.

    The command declares ``**pose_args`` and receives them there, ready for
    ``pose_options(**pose_args, min_corners=...)``.
    """
    import inspect

    sig = inspect.signature(fn, eval_str=True)  # typer reads a given __signature__ as it is
    params = [p for p in sig.parameters.values() if p.kind is not inspect.Parameter.VAR_KEYWORD]
    params += [inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=default, annotation=annotation)
               for name, annotation, default in POSE_OPTIONS]

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        return fn(*args, **kwargs)

    wrapper.__signature__ = sig.replace(parameters=params)
    return wrapper


FIGURE_SUFFIXES = (".png", ".pdf", ".svg", ".jpg", ".jpeg")


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


def _capture_folder(folder: Path, inputs) -> bool:
    """Does ``folder`` hold a capture sequence (a pose folder given to this command, or a sequence folder)?"""
    from ..io import files as _files

    try:
        folder = folder.resolve()
    except OSError:
        return False
    for p in inputs:
        try:
            if Path(p).resolve() == folder:
                return True
        except OSError:
            continue
    man = _files.read_manifest(folder)
    if man is not None:
        return any(r in ("frame", "captured") for r in man["files"].values())
    return (folder / "patterns.json").is_file() or (folder / "capture.json").is_file()


def distinct_poses(poses) -> None:
    """Refuse a pose folder given twice: the same folder once links are resolved, or the same frames (it would
    count as two poses of the board; :func:`procam.capture.distinct.refuse_repeats`)."""
    from ..capture.distinct import refuse_repeats
    from ..errors import CaptureError

    try:
        refuse_repeats(poses, "pose folder", "give each pose once")
    except CaptureError as e:
        fail(str(e))


def load_pose(pose_dir, projector, calib, order=None, step=None):
    """The capture of one pose folder for a command that has a calibration: the projector size from
    ``--projector``, else the folder's ``patterns.json``, else the calibration's; its warnings printed."""
    from .. import capture

    size = optional_size(projector)
    if size is None and not (Path(pose_dir) / "patterns.json").exists():
        size = tuple(calib.projector.image_size)
    cap = capture.load_capture(pose_dir, size, value(order), step=step)
    for w in cap.warnings:
        warn(w)
    return cap


def pose_sizes(calib, path, cam_size, proj_size):
    """``calib`` with the image sizes its file did not store (``info["image_size_assumed"]``) taken from the pose
    (:func:`procam.io.complete_sizes`), each said in a warning (never a silent choice): other tools' result files
    store no size, or only the camera's."""
    from .. import io

    before = set((calib.info or {}).get("image_size_assumed", ()))
    calib = io.complete_sizes(calib, cam_size, proj_size)
    taken = before - set((calib.info or {}).get("image_size_assumed", ()))
    for key, name, size in (("cam_size", "camera", cam_size), ("proj_size", "projector", proj_size)):
        if key in taken:
            warn(f"{Path(path).name} does not store the {name} size; the pose's {size[0]}x{size[1]} is used")
    return calib


def assumed_size(calib, key: str) -> str:
    """A note for a size mismatch when the calibration file had no ``key`` (``cam_size``/``proj_size``) and
    its size was assumed from the principal point; '' otherwise."""
    if key in (calib.info or {}).get("image_size_assumed", ()):
        return f" (the file has no {key}, so 2 (u0, v0) was assumed; add {key}: [width, height] to it)"
    return ""


def output_path(path, option: str, suffixes: tuple[str, ...], inputs=()):
    """Check an output file before any work is done (one-line errors): a known suffix; a folder that can be
    created and written; not a file that is an input of the command (``inputs``: files and pose folders),
    not a file procam did not write in a capture folder, not an image added to a capture folder that
    has no manifest (it would be read as a frame of the sequence)."""
    if path is None:
        return None
    from ..io import files as _files
    from ..io import folders

    path = Path(path)
    if path.suffix.lower() not in suffixes:
        fail(f"{option} {path}: the file name must end in {' or '.join(suffixes)}")
    if path.is_dir():
        fail(f"{option} {path}: is a folder; give a file name")
    # the folder is created when the file is written (an early failure leaves no empty folder behind)
    parent = path.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir():
        fail(f"{option} {path}: cannot create the folder {path.parent} ({parent} is not a folder)")
    why = folders.why_not_writable(parent)
    if why is not None:
        where = f"write into {parent}" if parent == path.parent else f"create the folder {path.parent}"
        fail(f"{option} {path}: cannot {where} ({why}); choose another place")
    if path.is_symlink() and not path.exists():
        fail(f"{option} {path}: is a broken or looping symbolic link; give another name")
    if path.exists():
        if not path.is_file():
            fail(f"{option} {path}: exists and is not a regular file; give another name")
        if not os.access(path, os.W_OK):
            fail(f"{option} {path}: the file is read-only; give another name or make it writable")
        if not _files.procam_wrote(path):
            fail(f"{option} {path}: the file exists and procam did not write it; give another name, or move it "
                 "away first (procam never overwrites a file it did not write)")
        for p in inputs:
            try:
                same = Path(p).exists() and path.samefile(p)
            except OSError:
                same = False
            if same:
                fail(f"{option} {path}: is also an input of this command; give another name")
    folder = path.parent
    if _capture_folder(folder, inputs):
        own = folders.replaceable(folder)
        man = _files.read_manifest(folder)
        roles = man["files"] if man is not None else {}
        if path.exists() and (path.name not in own or roles.get(path.name) not in (None, "output")):
            fail(f"{option} {path}: would overwrite a file of the capture in {folder}; write it elsewhere")
        if path.suffix.lower() in _files.IMAGE_EXTS and man is None:
            fail(f"{option} {path}: {folder} holds a capture, and an image written there would be read as a frame "
                 "of its sequence; write it elsewhere")
    return path


def output_dir(path, option: str, writer: str, force: bool = False, create: bool = False) -> Path:
    """Check an output folder before any work is done: new, empty, or ``writer``'s own earlier output; with
    ``force`` any folder, where nothing procam did not write is overwritten or deleted
    (:func:`procam.io.folders.prepare_output_dir`).  A new folder is created only with ``create`` (otherwise by
    the writer, so an interrupted run leaves none)."""
    from ..io import folders

    try:
        return folders.prepare_output_dir(path, writer, force=force, option=option, create=create)
    except OutputError as e:
        fail(str(e))


ForceOpt = Annotated[bool, typer.Option(
    "--force", help="Write into a folder that holds other files (procam still never overwrites or deletes a file "
                    "it did not write).")]


def _print_version(flag: bool):
    if flag:
        from .. import __version__

        console.print(f"procam {__version__}")
        raise typer.Exit(0)


@app.callback()
def _root(version: bool = typer.Option(False, "--version", help="Print the version and exit.", is_eager=True,
                                       callback=_print_version)):
    """Projector-camera calibration from Gray-code captures of a chessboard."""


def preload(modules) -> None:
    """Import ``modules`` (dotted names) in a daemon thread: a command that will need a heavy module later (scipy's
    optimizer for a calibration) starts its import while it reads and decodes its captures. A later import of the
    same module waits for that one (Python's per-module import lock), so nothing is imported twice or half."""
    import importlib
    import threading

    def run():
        for name in modules:
            try:
                importlib.import_module(name)
            except ImportError:  # the command's own import will raise it where it is needed
                return

    threading.Thread(target=run, name="procam-preload", daemon=True).start()


def is_tty() -> bool:
    """Is stderr a terminal (live progress bars) rather than a pipe or log?"""
    return sys.stderr.isatty()
