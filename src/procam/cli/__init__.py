"""The ``procam`` command line: thin commands over the public API.

Each sub-command lives in its own module of this package and registers itself on
:data:`app` with ``@app.command()``.  User mistakes raise :class:`procam.errors.ProcamError`;
:func:`main` prints them as one line and exits with code 2 (no traceback).
"""

from __future__ import annotations

from ._app import app, console, err_console  # noqa: F401

# Sub-commands register themselves on import, in the order `procam --help` lists them.
from . import (advise, capture, check, patterns, decode, simulate, correspond, calibrate, evaluate, report, reconstruct,  # noqa: F401,E402
               export, blend, experiment, study, demo)


def main(argv: list[str] | None = None) -> None:
    """Console-script entry point (errors are handled per command by ``_app.user_errors``)."""
    app(args=argv, standalone_mode=True)
