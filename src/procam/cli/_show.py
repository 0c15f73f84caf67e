"""What several commands print: a calibration's tables and verdict, its metric verification, a pose check, the
HTML report written and said.

A helper of the commands, not a command: the tables' cells come from :mod:`procam.summary` (the HTML report
shows the same ones); here they only become rich tables with their titles.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from .. import summary
from ._app import console, plain, say, warn

if TYPE_CHECKING:  # annotations only: rich is imported where a table is drawn
    from rich.table import Table


def rich_table(table: summary.TextTable, title=None) -> Table:
    """A :class:`procam.summary.TextTable` as a rich table: its word columns left-aligned, its numbers right, the
    pooled row bold; every cell printed as is (never read as markup)."""
    from rich.table import Table

    t = Table(title=title)
    for i, c in enumerate(table.header):
        t.add_column(c, justify="left" if i < table.left else "right")
    for r in table.rows:
        t.add_row(*map(plain, r))
    if table.pooled is not None:
        t.add_row(*map(plain, table.pooled), style="bold")
    return t


def verification_table(ver, title: str = "metric verification (board units)") -> Table:
    """A :class:`procam.verify.Verification` as a rich table (:func:`procam.summary.verification_table`)."""

    return rich_table(summary.verification_table(ver), title)


def cross_table(cross) -> Table:
    """In-sample next to held-out figures of a :class:`procam.verify.CrossVerification`
    (:func:`procam.summary.cross_table`)."""

    return rich_table(summary.cross_table(cross),
                      f"metric verification: in-sample vs {summary.CROSS_LABELS[cross.kind]} (board units)")


def print_calibration(calib, check=None) -> None:
    """Print a calibration's parameters and poses, its warnings and its verdict: the word, what it means and, for a
    usable one, how many things were flagged (:func:`procam.verdict.flagged`, the list the report shows)."""
    from ..verdict import MEANING, flagged

    console.print(rich_table(summary.parameter_table(calib),
                             plain(f"procam calibration ({calib.method}); {summary.plus_minus(calib)}")))
    for line in summary.projector_assumptions(calib):
        say(f"projector: {line}")
    console.print(rich_table(summary.datasheet_table(calib), "as a projector datasheet prints it (docs/datasheet.md)"))
    for line in summary.mounting_lines(calib):
        say(f"mounting: {line}")
    poses = summary.pose_table(calib)
    if poses.rows:
        console.print(rich_table(poses, "poses"))
    for w in calib.warnings:
        warn(w)
    n = len(flagged(calib, check))
    tail = "" if not calib.trusted else (f"; {n} thing{'s' if n != 1 else ''} flagged (above)" if n else
                                         "; nothing flagged")
    say(f"verdict: {calib.verdict} ({MEANING.get(calib.verdict, '')}{tail})")


def print_verification(check) -> None:
    """Print a :class:`procam.verify.CalibrationVerification` as rich tables, and its notes."""
    if check.in_sample is not None:
        console.print(verification_table(check.in_sample, "metric verification on the poses the calibration was "
                                                          "fitted to (in-sample, optimistic; board units)"))
    if check.held_out is not None:
        console.print(verification_table(check.held_out, "metric verification on other poses (held out; board "
                                                         "units)"))
    if check.leave_one_out is not None:
        console.print(cross_table(check.leave_one_out))
    for n in check.notes:
        say(f"note: {n}")


def print_spread(calib, refits) -> None:
    """Print each parameter's ± (Jacobian) next to the spread of the leave-one-pose-out ``refits``."""
    from ..verify import parameter_spread

    console.print(rich_table(summary.spread_table(parameter_spread(calib, refits)),
                             f"uncertainty: ± from the fit (model, i.i.d. noise) vs the spread of {len(refits)} "
                             "leave-one-pose-out refits (jackknife; no noise model)"))


def write_calibration_report(calib, path, *, views=None, decodes=None, check=None, name: str | None = None,
                             notes=()) -> Path:
    """Build and write the HTML report of ``calib`` (:func:`procam.report.build_report`) and say so."""
    from ..report import build_report, write_report

    text = build_report(calib, views, decodes=decodes, check=check, name=name or Path(path).stem, notes=notes)
    write_report(text, path)
    say(f"wrote {path} ({Path(path).stat().st_size / 1e6:.2f} MB)")
    return Path(path)


def print_pose_check(check, png=None) -> None:
    """Print a :class:`procam.check.PoseCheck` and write its overlay picture to ``png`` (optional)."""
    for line in check.lines:
        say(line)
    say(f"({check.seconds:.1f} s)")
    if png is not None:
        from ..check import overlay
        from ..io.files import write_image

        write_image(png, overlay(check))
        say(f"wrote {png}")
