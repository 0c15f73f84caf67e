"""Text of a number in a report or console table (shared by :mod:`procam.paper.report` and the CLI)."""

from __future__ import annotations

import math
import numbers

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
