"""The command line's side of a live advising session (``procam advise``, ``procam capture --advise``): Enter on
the terminal as the capture key, the advice as JSON lines on stdout, the session's messages printed.

A helper module of the commands (not a command): :func:`live_advice` builds the
:class:`procam.acquire.live.LiveAdvice` both commands run.
"""

from __future__ import annotations

import sys
import threading

from ._app import say, warn


class StdinKey:
    """A line on stdin (Enter) asks for the capture when there is no window (read by a daemon thread)."""

    def __init__(self):
        self.pressed = threading.Event()
        self._thread = None

    def start(self):
        if self._thread is None and sys.stdin is not None and sys.stdin.isatty():
            def read():
                for _ in sys.stdin:
                    self.pressed.set()
            self._thread = threading.Thread(target=read, daemon=True)
            self._thread.start()
        return self

    def poll(self):
        self.start()
        if self.pressed.is_set():
            self.pressed.clear()
            return "capture"
        return None


def print_json(image, advice) -> None:
    """One frame's advice as one JSON line on stdout."""
    sys.stdout.write(advice.to_json() + "\n")
    sys.stdout.flush()


def tell(level: str, text: str) -> None:
    """Print a message of the session: ``"warning"`` as a warning line, anything else as an information line."""
    (warn if level == "warning" else say)(text)


def live_advice(board, options, *, calibration=None, source: str = "", json_lines: bool = False, auto: bool = False,
                max_frames: int | None = None, known_camera=None, known_source: str = ""):
    """The advising session: the preview window, or with ``json_lines`` the advice as JSON lines on stdout and
    Enter on the terminal as the capture key; its messages printed."""
    from ..acquire.live import LiveAdvice

    return LiveAdvice(board, options, calibration=calibration, source=source, window=not json_lines,
                      on_advice=print_json if json_lines else None, poll=StdinKey().poll if json_lines else None,
                      auto=auto, max_frames=max_frames, notify=tell, known_camera=known_camera,
                      known_source=known_source)
