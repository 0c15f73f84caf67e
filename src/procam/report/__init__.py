"""A calibration as one self-contained HTML page (``procam report``, ``procam calibrate --report``).

:func:`build_report` returns the page as a string; :func:`write_report` writes it atomically.  The page
reads top to bottom: the verdict in words and why, the parameters with their uncertainty and the model's
assumptions, the coverage of both image planes, the residual vectors (the same residuals and RMS as the
tables, rejected corners marked), the metric verification, the rig in 3-D and, for a multi-pose
calibration, the leave-one-pose-out verification.

Self-contained: the figures are inline PNG (``data:`` URLs), the style sheet and the rig's small script
are inline, and a Content-Security-Policy forbids every other source, so the page makes no request.
Every user string (file and pose names, messages) is HTML-escaped.

The rooms: :mod:`.page` (the page), :mod:`.sections` (its sections), :mod:`.elements` (style sheet, tables,
inline figures), :mod:`.rig` (the rig in 3-D and its SVG view), :mod:`.rig_page` (the page of a calibration of
several projectors and cameras, :mod:`procam.rig`), :mod:`.coverage` (of the image planes). The
verdict the page opens with is :mod:`procam.verdict`'s.
"""

from ..verdict import Verdict, calibration_verdict  # noqa: F401 -- here before procam.verdict existed
from .coverage import coverage_fractions
from .page import build_report, write_report
from .scene3d import rig_geometry, rig_svg
from .rig_page import build_rig_report
from .sections import SECTIONS

__all__ = ["SECTIONS", "build_report", "build_rig_report", "coverage_fractions", "rig_geometry", "rig_svg", "write_report"]
