"""The typer application object, consoles and shared option parsing."""

from __future__ import annotations

import functools
import re
import sys
from typing import Annotated, Optional

import typer
from rich.console import Console

from ..errors import ProcamError

app = typer.Typer(add_completion=False, no_args_is_help=True, pretty_exceptions_enable=False,
                  help="Projector-camera calibration from Gray-code captures of a chessboard.")
# Not a terminal (pipes, CI, logs): wide enough that tables don't wrap.
console = Console(soft_wrap=True, width=None if sys.stdout.isatty() else 160)
err_console = Console(stderr=True, soft_wrap=True, width=None if sys.stderr.isatty() else 160)


def fail(message: str, code: int = 2):
    """Print a one-line error to stderr and exit with ``code``."""
    err_console.print(f"[bold red]error:[/bold red] {message}", highlight=False, soft_wrap=True)
    raise typer.Exit(code)


def user_errors(fn):
    """Decorator for commands: turn :class:`ProcamError` (and bad values) into one-line errors."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except ProcamError as e:
            fail(str(e))
        except OSError as e:  # unwritable output folder, disk full, permission denied ...
            where = e.filename or "file"
            fail(f"{where}: {e.strerror or e}; check the path and its permissions")
        except KeyboardInterrupt:
            err_console.print("interrupted")
            raise typer.Exit(130)

    return wrapper


_SIZE = re.compile(r"^\s*(\d+)\s*[xX×,]\s*(\d+)\s*$")


def parse_size(text: str, what: str = "size") -> tuple[int, int]:
    """Parse ``"1920x1080"`` into ``(1920, 1080)``; a clear error otherwise."""
    m = _SIZE.match(text or "")
    if not m:
        fail(f"{what} must look like WIDTHxHEIGHT (e.g. 1920x1080), got {text!r}")
    w, h = int(m.group(1)), int(m.group(2))
    if w < 2 or h < 2:
        fail(f"{what} must be at least 2x2, got {text!r}")
    return w, h


# Options shared by the commands that read capture folders (one definition, one help text).
BoardOpt = Annotated[str, typer.Option("--board", help="Inner corners COLSxROWS (OpenCV pattern_size), e.g. 10x6.")]
SquareOpt = Annotated[float, typer.Option("--square", help="Square size; the length unit of every output (e.g. mm).")]
ProjectorOpt = Annotated[Optional[str], typer.Option(
    "--projector", "-p", help="Projector size WIDTHxHEIGHT (default: the folder's patterns.json).")]
OrderOpt = Annotated[Optional[str], typer.Option("--order", help="Sequence order: opencv (default) or moreno.")]
StepOpt = Annotated[Optional[int], typer.Option(
    "--step", help="Projector pixels per Gray code (kamino410's graycode_step; default: patterns.json's, else 1).")]
WindowOpt = Annotated[int, typer.Option("--window", help="Local-homography window side, camera px.")]
EstimatorOpt = Annotated[str, typer.Option("--estimator", help="Homography fit: lsq, ransac or lmeds.")]


def optional_size(text: str | None, what: str = "--projector") -> tuple[int, int] | None:
    """:func:`parse_size` for an optional option (None stays None)."""
    return parse_size(text, what) if text else None


def parse_square(value: float) -> float:
    """``--square``: a positive, finite length."""
    import math

    if not (math.isfinite(value) and value > 0):
        fail(f"--square must be a positive length (the board's square size, e.g. 24 for mm), got {value}")
    return float(value)


FIGURE_SUFFIXES = (".png", ".pdf", ".svg", ".jpg", ".jpeg")


def output_path(path, option: str, suffixes: tuple[str, ...]):
    """Check an output path before any work is done: a known suffix and a folder that can be created."""
    from pathlib import Path

    if path is None:
        return None
    path = Path(path)
    if path.suffix.lower() not in suffixes:
        fail(f"{option} {path}: the file name must end in {' or '.join(suffixes)}")
    if path.is_dir():
        fail(f"{option} {path}: is a folder; give a file name")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        fail(f"{option} {path}: cannot create the folder {path.parent} ({e.strerror or e})")
    return path


@app.callback()
def _root(version: bool = typer.Option(False, "--version", help="Print the version and exit.")):
    """Projector-camera calibration from Gray-code captures of a chessboard."""
    if version:
        from .. import __version__

        console.print(f"procam {__version__}")
        raise typer.Exit(0)


def is_tty() -> bool:
    """Is stderr a terminal (live progress bars) rather than a pipe or log?"""
    return sys.stderr.isatty()
