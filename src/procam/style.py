"""How procam presents what it found: the text of a number in a table, of a file name, and the one palette.

Every picture, figure and page colours a verdict and a device the same way: the report's verdict box, the
residual figure's title, the check overlay, the rig drawing, the live preview's advice (its states are verdicts
of the pose in view: ``ready``/``good`` good, ``adjust`` weak, ``no-board`` failed). Colours are hex strings
here; :func:`rgb` and :func:`bgr` give the tuples pygame and OpenCV draw with.  Imports nothing heavy.
"""

from __future__ import annotations

import math
import numbers
import re

#: Text of a missing value (None or NaN) in tables.
MISSING = "—"


def fmt_number(v, nd: int = 2, spec: str | None = None) -> str:
    """Table text of ``v``.

    Real numbers get ``nd`` decimals (or the format ``spec``, e.g. ``".3g"``); None and NaN
    give ``"—"``, ±inf ``"∞"``/``"-∞"``; integers and anything else (labels, pose tuples) ``str(v)``.
    """
    if v is None:
        return MISSING
    if isinstance(v, numbers.Integral) or not isinstance(v, numbers.Real):
        return str(v)
    x = float(v)
    if math.isnan(x):
        return MISSING
    if math.isinf(x):
        return "∞" if x > 0 else "-∞"
    return format(x, spec or f".{nd}f")


#: One colour per verdict word (:data:`procam.verdict.VERDICTS`), hex.
VERDICT_COLOURS = {"good": "#2e8b3c", "weak": "#e0901a", "degenerate": "#c62828", "failed": "#c62828"}
#: A verdict's pale background (the report's verdict box).
VERDICT_BACKGROUNDS = {"good": "#eef8ef", "weak": "#fdf5e7", "degenerate": "#fdecec", "failed": "#fdecec"}
#: One colour per device (camera, projector) and for the board, hex.
DEVICE_COLOURS = {"camera": "#1f77b4", "projector": "#e07b00", "board": "#555555"}
#: Anything without a verdict.
NEUTRAL = "#777777"


def rgb(colour: str) -> tuple[int, int, int]:
    """``"#rrggbb"`` -> ``(r, g, b)`` 0-255 (pygame's order)."""
    c = colour.lstrip("#")
    return int(c[0:2], 16), int(c[2:4], 16), int(c[4:6], 16)


def bgr(colour: str) -> tuple[int, int, int]:
    """``"#rrggbb"`` -> ``(b, g, r)`` 0-255 (OpenCV's order)."""
    r, g, b = rgb(colour)
    return b, g, r


def on_dark(colour: str, amount: float = 0.4) -> str:
    """``colour`` mixed ``amount`` of the way to white: the same hue, readable on a dark panel (the live preview)."""
    return "#" + "".join(f"{round(c + (255 - c) * amount):02x}" for c in rgb(colour))


def shown(text: str) -> str:
    """``text`` as a person reads it (a figure's title, a page, a line in a terminal): the bytes of a file name that
    no encoding decodes, which Python keeps as lone surrogates (``pose\\udcff1``: fonts and UTF-8 files refuse
    them), as escapes of the bytes (``pose\\xff1``), and control characters but tab and line break (a name holding
    a terminal's escape sequence, which would recolour or rewrite the terminal) as escapes (``\\x1b``); any other
    text unchanged."""
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        try:
            text = text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")
        except UnicodeEncodeError:  # a surrogate that is not a byte's (a broken UTF-16 pair)
            text = text.encode("utf-8", "backslashreplace").decode("utf-8")
    return _CONTROL.sub(lambda m: m.group().encode("unicode_escape").decode("ascii"), text)


_CONTROL = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f]")
