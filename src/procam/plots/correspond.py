"""Picture of a pose's correspondences: corners on the camera image and on a projector canvas."""

from __future__ import annotations

import numpy as np

from ..view import CORNER_REASONS
from . import _figure


def correspond_figure(view, white=None, title: str = ""):
    """Two panels: the camera image (white frame) with the detected corners, coloured by status, and
    the projector's image plane (the paper's "projector image") with the projector corners."""
    from matplotlib.patches import Rectangle

    fig = _figure(figsize=(13, 4.8), constrained_layout=True)
    axes = fig.subplots(1, 2)
    reason = view.diagnostics.get("reason", np.zeros(len(view.obj_pts), np.uint8))
    ok = reason == 0
    ax = axes[0]
    if white is not None:
        ax.imshow(white, cmap="gray", interpolation="nearest")
    elif view.cam_size:
        ax.set_xlim(-0.5, view.cam_size[0] - 0.5)
        ax.set_ylim(view.cam_size[1] - 0.5, -0.5)
    c = view.cam_pts
    ax.plot(c[ok, 0], c[ok, 1], "+", color="lime", ms=8, mew=1.5, label=f"{ok.sum()} corners with projector points")
    if (~ok).any():
        ax.plot(c[~ok, 0], c[~ok, 1], "x", color="red", ms=8, mew=1.5, label=f"{(~ok).sum()} failed")
    if np.isfinite(c[0]).all():
        ax.annotate("0", c[0], color="yellow", fontsize=9, xytext=(4, -4), textcoords="offset points")
    ax.set_title("camera: white frame and corners")
    ax.legend(loc="lower right", fontsize=8)
    ax = axes[1]
    W, H = view.proj_size or (int(np.nanmax(view.proj_pts[:, 0])) + 1, int(np.nanmax(view.proj_pts[:, 1])) + 1)
    ax.add_patch(Rectangle((-0.5, -0.5), W, H, fill=False, color="k"))
    p = view.proj_pts
    cols = int(round(len(p) / max(1, len(np.unique(view.obj_pts[:, 1])))))
    grid = p.reshape(-1, cols, 2) if len(p) % cols == 0 else None
    if grid is not None:
        for row in grid:
            ax.plot(row[:, 0], row[:, 1], "-", color="0.7", lw=0.8)
        for col in grid.transpose(1, 0, 2):
            ax.plot(col[:, 0], col[:, 1], "-", color="0.7", lw=0.8)
    ax.plot(p[ok, 0], p[ok, 1], "o", color="tab:blue", ms=4)
    ax.set_xlim(-0.05 * W, 1.05 * W)
    ax.set_ylim(1.05 * H, -0.05 * H)
    ax.set_aspect("equal")
    ax.set_title(f"projector image plane ({W}x{H})")
    failed = [f"{int(n)} {CORNER_REASONS[k]}" for k, n in enumerate(np.bincount(reason, minlength=6)) if k and n]
    if failed:
        ax.text(0.01, 0.01, "failed: " + "; ".join(failed), transform=ax.transAxes, fontsize=7, color="red")
    if title:
        fig.suptitle(title)
    return fig
