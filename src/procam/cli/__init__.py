"""The ``procam`` command line: thin commands over the public API.

Each sub-command lives in its own module of this package and registers itself on
:data:`app` with ``@app.command()``.  User mistakes raise :class:`procam.errors.ProcamError`;
:func:`main` prints them as one line and exits with code 2 (no traceback).
"""

from __future__ import annotations

import sys

from ._app import app, console, err_console  # noqa: F401

# Sub-commands register themselves on import.  Keep the list explicit.
from . import patterns as _patterns  # noqa: F401,E402

for _name in ("decode", "simulate", "correspond", "calibrate", "evaluate", "experiment", "study", "demo"):
    try:
        __import__(f"{__name__}.{_name}")
    except ModuleNotFoundError as _e:  # a command whose module does not exist yet
        if _e.name != f"{__name__}.{_name}":
            raise


def main(argv: list[str] | None = None) -> None:
    """Console-script entry point."""
    from ..errors import ProcamError

    try:
        app(args=argv, standalone_mode=True)
    except ProcamError as e:  # pragma: no cover - raised inside typer normally
        err_console.print(f"[red]error:[/red] {e}", highlight=False)
        sys.exit(2)
