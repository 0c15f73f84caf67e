"""Rich tables of the metric verification (:mod:`procam.verify`) for ``evaluate`` / ``calibrate`` summaries."""

from __future__ import annotations

from pathlib import Path

from rich.table import Table

_COLUMNS = ("pose", "corners", "pairs", "scale error (%)", "spacing RMS", "planarity RMS", "planarity max",
            "rigid RMS", "reproj RMS (px)", "distance")


def _row(p, name=None):
    return (name if name is not None else (Path(p.name).name or p.name), str(p.n_corners), str(p.n_pairs),
            f"{p.scale_error_pct:+.3f}", f"{p.spacing_rms:.3f}", f"{p.planarity_rms:.3f}", f"{p.planarity_max:.3f}",
            f"{p.rigid_rms:.3f}", f"{p.reproj_rms:.3f}", f"{p.distance:.0f}")


def verification_table(ver, title: str = "metric verification (board units)") -> Table:
    """One row per pose and a pooled ``all`` row of a :class:`procam.verify.Verification`.

    Columns: corners and adjacent pairs triangulated; scale error of the mean adjacent-corner distance
    against the printed square (%); RMS of (distance - square); RMS / max distance of the corners to
    their best plane; RMS after the best rigid fit of the printed board; reprojection RMS of the
    triangulated corners; mean distance from the camera.
    """
    t = Table(title=title)
    for c in _COLUMNS:
        t.add_column(c, justify="left" if c == "pose" else "right")
    for p in ver.poses:
        t.add_row(*_row(p))
    if len(ver.poses) > 1:
        t.add_row(*_row(ver.overall, "all"), style="bold")
    return t


def cross_table(cross) -> Table:
    """In-sample next to held-out (leave-one-out or single-pose cross) overall figures of a
    :class:`procam.verify.CrossVerification`."""
    label = {"leave-one-out": "leave-one-pose-out", "single-pose-cross": "calibrated on another pose"}[cross.kind]
    t = Table(title=f"metric verification: in-sample vs {label} (board units)")
    for c in ("", "scale error (%)", "spacing RMS", "planarity RMS", "rigid RMS", "reproj RMS (px)", "poses"):
        t.add_column(c, justify="left" if c == "" else "right")
    rows = [("in-sample", cross.in_sample)]
    if cross.held_out is not None:
        rows.append((label, cross.held_out))
    for name, v in rows:
        o = v.overall
        t.add_row(name, f"{o.scale_error_pct:+.3f}", f"{o.spacing_rms:.3f}", f"{o.planarity_rms:.3f}",
                  f"{o.rigid_rms:.3f}", f"{o.reproj_rms:.3f}", str(len(v.poses)))
    return t
