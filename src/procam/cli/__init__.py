"""The ``procam`` command line: thin commands over the public API.

Each sub-command lives in its own module of this package and registers itself on
:data:`app` with ``@app.command()``.  User mistakes raise :class:`procam.errors.ProcamError`;
:func:`main` prints them as one line and exits with code 2 (no traceback).

A command line is built only as far as it is used: ``procam --version`` answers before the command line (typer,
and through it pydantic) is imported, and ``procam CMD ...`` registers only ``CMD``'s module, so its start-up
does not pay for building the other fifteen commands' parameters.  ``procam --help``, an unknown command and
:data:`app` itself (``from procam.cli import app``: the tests' in-process runner) have every command.
"""

from __future__ import annotations

import gc
import importlib
import io
import sys

#: Sub-command -> the module of this package that registers it, in the order ``procam --help`` lists them.
COMMANDS = {name: name for name in ("advise", "capture", "check", "patterns", "decode", "simulate", "correspond",
                                    "calibrate", "evaluate", "report", "reconstruct", "export", "blend",
                                    "experiment", "study", "demo")}
COMMANDS["world-check"] = "world_check"
COMMANDS["app"] = "webapp"  # not cli/app.py: that module would shadow the package's ``app`` (the typer app)


def register(names=None) -> None:
    """Import the modules of the commands ``names`` (all when None), which registers them on :data:`app`."""
    for name in COMMANDS if names is None else names:
        importlib.import_module(f"{__name__}.{COMMANDS[name]}")


def __getattr__(name: str):
    if name in ("app", "console", "err_console"):
        register()
        from . import _app

        return getattr(_app, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def main(argv: list[str] | None = None) -> None:
    """Console-script entry point (errors are handled per command by ``_app.user_errors``)."""
    args = list(sys.argv[1:] if argv is None else argv)
    if argv is None:  # the console script: this process ends when main returns
        import atexit

        # Python's last act is a collection over every object still alive, scipy's, numpy's and typer's module
        # objects among them: 0.1-0.25 s after a calibrate's or a decode's files are written (a help's less). Moved
        # to the permanent generation by an exit handler (one registered now runs after those registered later),
        # they are left to the process's end, as Python leaves every object its final collection does not reach;
        # objects still freed by their reference counts are freed as before
        atexit.register(gc.freeze)
    if args == ["--version"]:
        from .. import __version__

        sys.stdout.write(f"procam {__version__}\n")
        return
    first = next((a for a in args if not a.startswith("-")), None)
    thresholds = gc.get_threshold()
    # a terminal or file in a legacy encoding (cp1252, ascii: Windows output redirected to a file) cannot encode
    # every character the tables print (sigma, box lines): written as backslash escapes, as Python's own stderr
    # does, rather than an error that would end the command before its files are written
    strict = [f for f in (sys.stdout, sys.stderr) if isinstance(f, io.TextIOWrapper) and f.errors == "strict"]
    for f in strict:
        f.reconfigure(errors="backslashreplace")
    try:
        if first in ("calibrate", "decode"):
            # Python's cyclic collector, at its default thresholds, runs hundreds of times over the start-up's
            # new module objects (scipy's, typer's), holding the interpreter lock while the reader threads wait;
            # these batch commands leave almost no cycles behind, so they collect far less often (as mypy's command
            # line does); the thresholds are restored after
            gc.set_threshold(*COLLECT_AFTER)
            _start_reading(first, args[args.index(first) + 1:])
        register([first] if first in COMMANDS else None)
        from ._app import app

        app(args=argv, standalone_mode=True)
    finally:
        for f in strict:
            f.reconfigure(errors="strict")
        gc.set_threshold(*thresholds)
        reader = _EARLY.pop("reader", None)
        if reader is not None:  # not taken: the command line was not what it looked like
            reader.close()


#: ``gc.set_threshold`` while ``procam calibrate`` or ``decode`` runs: allocations before a young collection, then
#: young and middle collections before an older one (Python's defaults: 700, 10, 10)
COLLECT_AFTER = (200_000, 30, 30)


#: The pose folders' reader :func:`main` started before parsing a ``procam calibrate`` or ``decode`` command line.
_EARLY: dict = {}


def _start_reading(command: str, args: list[str]) -> None:
    """Start reading the pose folders among the arguments ``args`` of ``procam calibrate`` (every folder) or
    ``procam decode`` (the first) now, before the command line is parsed: typer, and through it pydantic, take a
    tenth of a second to start, while the second core would wait. The folders are taken in their order (a
    :class:`procam.stream.Prefetcher`: the first pose at once); the command adopts the reader when they are its pose
    folders exactly (:func:`take_reader`), else :func:`main` closes it unused, as after a usage error: reading has
    no effect but the time it takes. Not for help or a camera-only calibration (photos, not pose folders)."""
    import os

    if any(a in ("--help", "-h", "--camera-only") for a in args):
        return
    folders = [a for a in args if not a.startswith("-") and os.path.isdir(a)]
    if folders:
        child = None
        if command == "calibrate" and len(folders) > 1:
            # several poses: a child process reads them (procam.io.child_reader), forked now, while this process
            # runs one thread, before numpy and OpenCV start theirs
            from ..io.child_reader import ChildReader

            child = ChildReader.start()
        from ..stream import Prefetcher

        _EARLY["reader"] = Prefetcher(folders if command == "calibrate" else folders[:1], child=child)


def take_reader(poses):
    """The reader :func:`main` started for the folders ``poses`` (the same, in their order), else None; the caller
    closes it."""
    from pathlib import Path

    reader = _EARLY.pop("reader", None)
    if reader is not None and reader.folders != [Path(p) for p in poses]:
        reader.close()
        reader = None
    return reader
