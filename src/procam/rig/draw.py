"""The drawing of a calibrated rig: every device seen from above (x right, z forward, reference camera frame),
its field of view, its name and verdict, and the pairs' 3-D agreement (:func:`procam.rig.verify.verify_rig`).

matplotlib is imported here only (a cold path)."""

from __future__ import annotations

import numpy as np

from ..style import NEUTRAL, VERDICT_COLOURS

__all__ = ["rig_figure"]



def rig_figure(rc, agreement=(), *, title: str = "", depth: float | None = None):
    """A matplotlib figure of ``rc`` (:class:`~procam.calibration.RigCalibration`): top view with each device's
    horizontal field of view drawn to ``depth`` (default: 1.2 x the board poses' mean depth, else 1000 board
    units), coloured by its verdict; a text panel with the agreement figures."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(9, 5), constrained_layout=True)
    ax, tx = fig.subplots(1, 2, gridspec_kw={"width_ratios": [3, 2]})
    if depth is None:
        bp = rc.info.get("board_poses") or []
        depth = 1.2 * float(np.mean([p["t"][2] for p in bp])) if bp else 1000.0
    for d in rc.devices:
        R = np.asarray(d.R)
        c = d.center
        K, W = np.asarray(d.device.K), d.device.image_size[0]
        ends = []
        for u in (-0.5, W - 0.5):
            ray = R.T @ np.array([(u - K[0, 2]) / K[0, 0], 0.0, 1.0])
            ends.append(c + ray * depth / max(ray[2], 1e-9))
        col = VERDICT_COLOURS.get(d.verdict, NEUTRAL)
        ax.fill([c[0], ends[0][0], ends[1][0]], [c[2], ends[0][2], ends[1][2]], color=col, alpha=0.15)
        ax.plot([ends[0][0], c[0], ends[1][0]], [ends[0][2], c[2], ends[1][2]], color=col, lw=1)
        ax.plot(c[0], c[2], "s" if d.kind == "camera" else "^", color=col, ms=9)
        ax.annotate(f"{d.name}\n{d.kind}, {d.verdict}", (c[0], c[2]), textcoords="offset points", xytext=(0, -28),
                    ha="center", fontsize=8)
    for p in rc.info.get("board_poses") or []:
        t = np.asarray(p["t"])
        ax.plot(t[0], t[2], "k+", ms=8)
    ax.set_aspect("equal")
    ax.set_xlabel("x (reference camera frame)")
    ax.set_ylabel("z (depth)")
    ax.set_title(f"{title}: rig seen from above" if title else "rig seen from above", fontsize=10)
    ax.invert_yaxis()
    tx.axis("off")
    lines = [f"method: {rc.method}", f"verdict: {rc.verdict}", ""]
    for k, r in rc.relative.items():
        lines.append(f"{k}: baseline {r.baseline:.1f} ± {r.std_baseline:.2f}")
    if agreement:
        lines += ["", "two pairs, same corners (3-D):"]
        for a in agreement:
            lines.append(f"{a.a} vs {a.b}: {a.rms_mm:.2f} mm rms ({a.rms_pct:.3f} % depth), n={a.n}")
    tx.text(0, 1, "\n".join(lines), va="top", ha="left", fontsize=8, family="monospace", transform=tx.transAxes,
            wrap=True)
    return fig
