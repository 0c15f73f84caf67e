"""The typer application object, consoles, one-line errors (the options commands share are in
:mod:`procam.cli._options`, the checks of their inputs and outputs in :mod:`procam.cli._paths`).

Choice lists come from the library's one list of them (:mod:`procam.choices`), so the CLI cannot drift from
it. Nothing here or at the top of a command module imports numpy, OpenCV, scipy or matplotlib: commands import
everything heavy inside their function, so ``procam --help`` and ``--version`` start in a fraction of a second.
"""

from __future__ import annotations

import contextlib
import errno
import functools
import os
import sys
import warnings

import typer
from typer.core import TyperGroup

from ..errors import ProcamError, ProcamWarning
from ..style import shown


class _OneLineErrors(TyperGroup):
    """A command group whose usage errors (bad option values, missing arguments) are one line on stderr
    with exit code 2, like procam's own errors, instead of a framed usage panel."""

    def get_help_option(self, ctx):
        """The group's ``--help`` flag, off by default: typer 0.29 coerces a flag that is not given (None) through a
        pydantic adapter, importing pydantic (a tenth of a second) for ``procam CMD --help``, where nothing else
        needs it (procam requires typer < 0.29 for that reason; this keeps ``--help`` fast where 0.29 is installed
        all the same)."""
        opt = super().get_help_option(ctx)
        if opt is not None and opt.default is None:
            opt.default = False
        return opt

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
            err_console.print(f"[bold red]error:[/bold red] {escape(one_line(e.format_message()))} (see "
                              f"'{escape(cmd)} --help')",
                              highlight=False, soft_wrap=True)
            rv = 2
        except _click.exceptions.ClickException as e:
            err_console.print(f"[bold red]error:[/bold red] {escape(one_line(e.format_message()))}", highlight=False,
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
            self._console = Console(stderr=self._stderr, soft_wrap=True, emoji=False,  # ':abc:' is a name, not 🔤
                                    width=None if stream.isatty() else 160)
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


def one_line(text: str) -> str:
    """``text`` with its line breaks and runs of spaces as single spaces (click words some usage errors over
    several lines: ``Choose from:\n\tcamera,\n\tprojector``)."""
    return " ".join(text.split())


def fail(message: str, code: int = 2, label: str = "error"):
    """Print a one-line ``label: message`` to stderr and exit with ``code`` (plain text, not markup; a file name's
    undecodable bytes as escapes, :func:`procam.style.shown`, as in every line below). Exit codes:
    2 the user's input is wrong, 3 the result must not be trusted (a degenerate or failed calibration)."""
    err_console.print(f"[bold red]{escape(label)}:[/bold red] {escape(shown(str(message)))}", highlight=False,
                      soft_wrap=True)
    raise typer.Exit(code)


def given(*names: str) -> list[str]:
    """The options among ``names`` (parameter names) the user typed on the command line (or set by an environment
    variable), each as its flag (the one typed of ``--x/--no-x``), in the command's order; [] outside a command line
    (a command function called from Python)."""
    try:  # typer vendors click since 0.20-something; before, it used click itself
        from typer._click.globals import get_current_context
    except ImportError:  # pragma: no cover - older typer
        from click import get_current_context
    ctx = get_current_context(silent=True)
    if ctx is None:
        return []
    flags = []
    for p in ctx.command.params:
        source = ctx.get_parameter_source(p.name) if p.name in names else None
        if source is None or source.name not in ("COMMANDLINE", "ENVIRONMENT"):
            continue
        off = ctx.params.get(p.name) is False and getattr(p, "secondary_opts", None)
        flags.append(max(p.secondary_opts if off else p.opts, key=len))
    return flags


def refuse(names, why: str) -> None:
    """Refuse (one line, exit 2) the first of the options ``names`` (parameter names) the user typed, which the
    command would ignore: ``"{flag} {why}; leave it out"`` (``why``: what it applies to, and why not here)."""
    flags = given(*names)
    if flags:
        fail(f"{flags[0]} {why}; leave it out")


def warn(message: str):
    """Print a warning line (plain text, not markup)."""
    console.print(f"[yellow]warning:[/yellow] {escape(shown(str(message)))}", highlight=False)


def say(message: str):
    """Print an information line (plain text, not markup)."""
    console.print(escape(shown(str(message))), highlight=False)


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

    return Text(shown(str(text)))


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


def _print_version(flag: bool):
    if flag:
        from .. import __version__

        console.print(f"procam {__version__}")
        raise typer.Exit(0)


@app.callback()
def _root(version: bool = typer.Option(False, "--version", help="Print the version and exit.", is_eager=True,
                                       callback=_print_version)):
    """Projector-camera calibration from Gray-code captures of a chessboard."""


#: glibc's ``mallopt`` parameters (malloc.h) and the values :func:`keep_freed_memory` sets: blocks up to 32 MB (its
#: largest) from the heap, and up to 256 MB of freed heap kept.
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3
KEPT_HEAP, HEAP_BLOCKS = 256 << 20, 32 << 20


def keep_freed_memory() -> None:
    """Let this process's C allocator reuse the memory numpy and OpenCV free for their next arrays (glibc only; other
    C libraries are left alone).  By default glibc maps a block above an adaptive threshold anew each time and gives
    freed heap above another back to the kernel, which then zeroes and faults in fresh pages for the next frame's
    arrays: a 5-pose calibrate took 108 000 page faults (0.3 CPU-s of system time), 40 000 with these settings, for
    17 MB more peak memory.  Called first thing by the commands that read whole captures (calibrate, decode)."""
    if "CS_GNU_LIBC_VERSION" not in os.confstr_names:
        return
    try:
        if not os.confstr("CS_GNU_LIBC_VERSION"):
            return
        import ctypes

        libc = ctypes.CDLL(None)
        libc.mallopt(_M_MMAP_THRESHOLD, HEAP_BLOCKS)
        libc.mallopt(_M_TRIM_THRESHOLD, KEPT_HEAP)
    except (OSError, ValueError, AttributeError):  # no such C library or function: the defaults stay
        return


def is_tty() -> bool:
    """Is stderr a terminal (live progress bars) rather than a pipe or log?"""
    return sys.stderr.isatty()
