"""Coverage of both image planes by a calibration's poses: where the board's corners were, per pose."""

from __future__ import annotations

import numpy as np

from ..board import board_outline
from . import _figure
from .residuals import short_name


def coverage_figure(views, cam_size, proj_size=None, decodes=None, coverage=None, title: str = ""):
    """The camera's and the projector's image planes with every pose's corners and their outline.

    Parameters
    ----------
    views : :class:`procam.view.View` sequence (corners in distorted pixels; NaN rows skipped).
    cam_size, proj_size : (width, height) of the device images (no projector panel without ``proj_size``).
    decodes : optional sequence of :class:`procam.decode.DecodeResult` (or None entries): the pixels
        decoded in any pose are shaded grey -- in the camera image where decoded, in the projector
        image where a camera pixel saw that projector pixel.
    coverage : optional ``{"camera": fraction, "projector": fraction}`` printed in the titles (the
        share of the image inside the union of the poses' corner outlines).
    title : the figure's title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import cv2
    from matplotlib import colormaps
    from matplotlib.patches import Polygon, Rectangle

    has_proj = proj_size is not None
    n = 2 if has_proj else 1
    fig = _figure(figsize=(6.2 * n, 4.6), constrained_layout=True)
    axes = fig.subplots(1, n, squeeze=False)[0]
    colors = colormaps["tab10"]
    panels = [("camera", "cam_pts", cam_size)] + ([("projector", "proj_pts", proj_size)] if has_proj else [])
    decodes = [d for d in (decodes or []) if d is not None]
    for ax, (label, key, size) in zip(axes, panels):
        W, H = int(size[0]), int(size[1])
        if decodes:
            if label == "camera":
                seen = np.zeros((H, W), bool)
                for d in decodes:
                    if d.valid.shape == (H, W):
                        seen |= d.valid
            else:
                seen = np.zeros((H, W), bool)
                for d in decodes:
                    m = d.valid
                    x = np.clip(np.rint(d.col[m]).astype(int), 0, W - 1)
                    y = np.clip(np.rint(d.row[m]).astype(int), 0, H - 1)
                    seen[y, x] = True
                # a camera coarser than the projector leaves gaps between the decoded projector pixels
                seen = cv2.dilate(seen.astype(np.uint8), np.ones((5, 5), np.uint8)).astype(bool)
            ax.imshow(np.where(seen, 0.82, 1.0), cmap="gray", vmin=0, vmax=1, extent=(-0.5, W - 0.5, H - 0.5, -0.5),
                      interpolation="nearest")
        for i, v in enumerate(views):
            pts = np.asarray(getattr(v, key), float).reshape(-1, 2)
            pts = pts[np.isfinite(pts).all(1)]
            if len(pts) < 3:
                continue
            c = colors(i % 10)
            ax.add_patch(Polygon(board_outline(pts), closed=True, facecolor=(*c[:3], 0.15), edgecolor=c, lw=1.2))
            ax.plot(pts[:, 0], pts[:, 1], ".", ms=2.5, color=c, label=short_name(v.name))
        ax.add_patch(Rectangle((-0.5, -0.5), W, H, fill=False, color="k"))
        ax.set_xlim(-0.04 * W, 1.04 * W)
        ax.set_ylim(1.04 * H, -0.04 * H)
        ax.set_aspect("equal")
        frac = (coverage or {}).get(label)
        head = f"{label} image ({W}x{H})"
        if frac is not None and np.isfinite(frac):
            head += f": {100 * frac:.0f} % inside the corners' outlines"
        ax.set_title(head, fontsize=10)
        if len(views) <= 10:
            ax.legend(fontsize=7, loc="lower right", markerscale=3)
    if title:
        fig.suptitle(title, fontsize=10)
    return fig
