"""The report page: :func:`build_report` puts the sections (:mod:`.sections`) in one self-contained HTML
document, :func:`write_report` writes it."""

from __future__ import annotations

import warnings
from html import escape
from pathlib import Path

from ..errors import ProcamWarning
from ..io.formats import HTML_GENERATOR
from ..residuals import calibration_residuals
from ..verdict import calibration_verdict, flagged, with_evidence
from ..verify import CalibrationVerification, same_pose, verify_calibration
from .elements import CSP, CSS
from .sections import (coverage_section, loo_section, parameters_section, residuals_section, rig_section, section,
                       verdict_section, verification_section)

__all__ = ["build_report", "html_page", "write_report"]


def build_report(calib, views=None, *, decodes=None, check: CalibrationVerification | None = None, verify: bool = True,
                 name: str = "calibration", notes=()) -> str:
    """The HTML page of a calibration.

    Parameters
    ----------
    calib : :class:`procam.calibration.Calibration`.
    views : the poses to show and verify (default: the calibration's own ``views``).  Residuals are
        those of the calibration's own poses when it holds them (:func:`procam.residuals.calibration_residuals`),
        else of ``views``.
    decodes : optional :class:`procam.decode.DecodeResult` per view (coverage of the decoded pixels).
    check : the metric verification (:func:`procam.verify.verify_calibration`); computed here when None
        and ``verify`` (leave-one-pose-out refits included for a multi-pose calibration of >= 4 poses).
    name : the calibration's name in the title (e.g. its file name).
    notes : extra lines for the top of the page (e.g. what was decoded).

    Returns
    -------
    str : the whole page (UTF-8 text).
    """
    from .. import __version__

    views = list(calib.views) if views is None else list(views)
    if check is None and verify and calib.projector is not None:
        check = verify_calibration(calib, views)
    with warnings.catch_warnings():  # the page shows the evidence's reasons; it is not a new result
        warnings.simplefilter("ignore", ProcamWarning)
        calib = with_evidence(calib, check)
    verdict = calibration_verdict(calib)
    own = list(calib.views)
    per_pose = calibration_residuals(calib) if own else (calibration_residuals(calib, views) if views else [])
    shown = own or views
    # every pose in the coverage figure: the calibration's own and the given ones it was not fitted to
    given = list(views) if views else []
    cover = own + [v for v in given if not any(same_pose(v, w) for w in own)] if own else given
    cover_decodes = None
    if decodes:
        cover_decodes = [next((d for g, d in zip(given, decodes) if g is v or same_pose(g, v)), None) for v in cover]
    multi = calib.method == "multi-pose"
    sections = [verdict_section(calib, verdict, check, flagged(calib, check, views)),
                section("parameters", parameters_section(calib)),
                section("coverage", coverage_section(calib, cover, cover_decodes)),
                section("residuals", residuals_section(calib, per_pose, verdict))]
    if calib.projector is not None:
        sections.append(section("verification", verification_section(calib, check)))
    sections.append(section("rig", rig_section(calib, shown)))
    if multi:
        sections.append(section("leave-one-out", loo_section(check, calib)))
    head = (f'<p class="meta">{escape(calib.method)} calibration of a {calib.camera.image_size[0]}x'
            f'{calib.camera.image_size[1]} camera'
            + (f" and a {calib.projector.image_size[0]}x{calib.projector.image_size[1]} projector"
               if calib.projector is not None else "")
            + f", {len(calib.poses)} pose{'s' if len(calib.poses) != 1 else ''}; procam {escape(__version__)}.</p>")
    extra = "".join(f'<p class="note">{escape(n)}</p>' for n in notes)
    return html_page(f"procam report: {name}", f"procam calibration report: {name}", [head, extra, *sections])


def html_page(title: str, heading: str, parts) -> str:
    """The self-contained page around ``parts`` (HTML): the style sheet, the Content-Security-Policy, ``title``
    and the ``<h1>`` ``heading`` (both escaped here)."""
    return "\n".join([
        "<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">', HTML_GENERATOR,
        f'<meta http-equiv="Content-Security-Policy" content="{CSP}">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{escape(title)}</title>", f"<style>{CSS}</style>", "</head>", "<body>", "<main>",
        f"<h1>{escape(heading)}</h1>", *parts,
        '<p class="meta">Self-contained page: every figure is inline; it loads nothing from anywhere.</p>',
        "</main>", "</body>", "</html>", ""])


def write_report(text: str, path) -> Path:
    """Write the page ``text`` to ``path`` (UTF-8, atomically: temporary name, then rename; a file name's
    undecodable bytes shown as escapes, :func:`procam.style.shown`)."""
    from ..io.files import atomic_path
    from ..style import shown

    path = Path(path)
    with atomic_path(path) as tmp:
        Path(tmp).write_bytes(shown(text).encode("utf-8"))
    return path
