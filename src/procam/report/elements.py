"""The HTML elements of the report page: its style sheet and Content-Security-Policy, tables (of a
:class:`procam.summary.TextTable` or of plain rows), inline PNG figures and numbers as text.

Every string these put into a cell or an attribute is HTML-escaped here.
"""

from __future__ import annotations

import base64
import io as _stdio
from html import escape

import numpy as np

from ..style import DEVICE_COLOURS, VERDICT_BACKGROUNDS, VERDICT_COLOURS

CSS = """
body{font:15px/1.45 system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;color:#1b1b1b;margin:0;background:#f6f6f4}
main{max-width:1120px;margin:0 auto;padding:18px 28px 40px;background:#fff}
h1{font-size:1.6em;margin:.2em 0}h2{font-size:1.25em;margin:1.6em 0 .4em;border-bottom:1px solid #ddd;padding-bottom:.2em}
h3{font-size:1.05em;margin:1.1em 0 .3em}
.meta{color:#555;font-size:.92em}
table{border-collapse:collapse;margin:.5em 0 1em;font-size:.9em}
th,td{border:1px solid #d4d4d4;padding:3px 8px;text-align:right;vertical-align:top}
th{background:#f0f0ee}th[colspan]{text-align:center}td.l,th.l{text-align:left}tr.all td{font-weight:600;background:#fafaf7}
.verdict{border-left:10px solid #777;padding:10px 16px;background:#f7f7f7;margin:10px 0}
.verdict h2{border:0;margin:0 0 .3em;font-size:1.5em}
@VERDICTS@
.word{text-transform:uppercase;letter-spacing:.04em}
.note{color:#555;font-size:.9em}.warn{color:#8a4b00}
figure{margin:.6em 0}figure img{max-width:100%;height:auto;border:1px solid #eee}
figcaption{color:#555;font-size:.88em}
#rig-svg{border:1px solid #ddd;background:#fcfcfc;cursor:grab;max-width:100%;height:auto;touch-action:none;
user-select:none;-webkit-user-select:none}
.rig-camera{stroke:@camera@;stroke-width:1.6;fill:none}.rig-projector{stroke:@projector@;stroke-width:1.6;fill:none}
.rig-board{stroke:#555;stroke-width:1.2;fill:rgba(120,120,120,.12)}.rig-board0{stroke:#c62828;stroke-width:2;fill:none}
.rig-axis{stroke:#999;stroke-width:1;fill:none}
.rig-label{font-size:12px;stroke:none}text.rig-camera{fill:@camera@}text.rig-projector{fill:@projector@}
text.rig-camera{text-anchor:end}text.rig-board{fill:#333;font-size:11px}text.rig-axis{fill:#888;font-size:11px}
code{font-size:.92em}
"""
# the palette's colours (procam.style): one colour per verdict and per device in every picture and page
CSS = CSS.replace("@VERDICTS@", "".join(
    f".verdict.{v}{{border-color:{VERDICT_COLOURS[v]};background:{VERDICT_BACKGROUNDS[v]}}}" for v in VERDICT_COLOURS))
for _device, _colour in DEVICE_COLOURS.items():
    CSS = CSS.replace(f"@{_device}@", _colour)

CSP = ("default-src 'none'; img-src data:; style-src 'unsafe-inline'; script-src 'unsafe-inline'; "
        "base-uri 'none'; form-action 'none'")


def table(headers, rows, *, left=1, row_classes=None) -> str:
    """An HTML table; the first ``left`` columns left-aligned; every cell escaped."""
    h = "".join(f'<th class="l">{escape(str(c))}</th>' if i < left else f"<th>{escape(str(c))}</th>"
                for i, c in enumerate(headers))
    body = []
    for k, r in enumerate(rows):
        cls = f' class="{row_classes[k]}"' if row_classes and row_classes[k] else ""
        cells = "".join(f'<td class="l">{escape(str(c))}</td>' if i < left else f"<td>{escape(str(c))}</td>"
                        for i, c in enumerate(r))
        body.append(f"<tr{cls}>{cells}</tr>")
    return f"<table><thead><tr>{h}</tr></thead><tbody>{''.join(body)}</tbody></table>"


def text_table(t) -> str:
    """A :class:`procam.summary.TextTable` as an HTML table, its pooled row highlighted."""
    rows = list(t.rows) + ([t.pooled] if t.pooled is not None else [])
    classes = [""] * len(t.rows) + (["all"] if t.pooled is not None else [])
    return table(t.header, rows, left=t.left, row_classes=classes)


def png(fig, alt: str, dpi: int = 80) -> str:
    """A matplotlib figure as an inline ``<img>`` (base64 PNG)."""
    from ..plots import printable

    buf = _stdio.BytesIO()
    printable(fig).savefig(buf, format="png", dpi=dpi)
    data = base64.b64encode(buf.getvalue()).decode("ascii")
    return f'<img src="data:image/png;base64,{data}" alt="{escape(alt)}">'


def fmt(x, spec=".3f") -> str:
    """A number as text; empty when it is None or not finite."""
    return "" if x is None or not np.isfinite(x) else f"{x:{spec}}"
