"""Picture of a decoded pose: colour-coded projector columns and rows plus the validity mask."""

from __future__ import annotations

import numpy as np

from ..decode import REASONS
from . import _figure
from . import save_figure  # noqa: F401  (re-exported: cli.calibrate/correspond/demo import it from here)


def decode_figure(result, white=None, title: str = ""):
    """Figure with four panels: columns, rows (colour = projector coordinate, black = invalid),
    validity reasons, and the white frame (if given). Returns the matplotlib Figure."""
    ps = result.pattern_set
    panels = 4 if white is not None else 3
    from matplotlib import colormaps
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    fig = _figure(figsize=(5 * panels, 4.2), constrained_layout=True)
    axes = fig.subplots(1, panels)
    cmap = colormaps["turbo"].with_extremes(bad="black")
    for ax, data, vmax, name in ((axes[0], result.col, ps.width - 1, "projector column"),
                                 (axes[1], result.row, ps.height - 1, "projector row")):
        im = ax.imshow(np.ma.masked_invalid(data), cmap=cmap, vmin=0, vmax=vmax, interpolation="nearest")
        ax.set_title(f"{name} (black = invalid)")
        fig.colorbar(im, ax=ax, shrink=0.8)
    reason = np.maximum(result.reason_col, result.reason_row)
    colors = ["#2ca02c", "#404040", "#ff7f0e", "#d62728", "#9467bd", "#e377c2", "#bcbd22", "#17becf"]
    rcmap = ListedColormap(colors)
    axes[2].imshow(reason, cmap=rcmap, vmin=-0.5, vmax=len(REASONS) - 0.5, interpolation="nearest")
    counts = np.bincount(reason.ravel(), minlength=len(REASONS)) / reason.size * 100
    handles = [Patch(color=colors[k], label=f"{REASONS[k].split(':')[0]} {counts[k]:.1f}%")
               for k in range(len(REASONS)) if k < 5 or counts[k] > 0]  # the phase decoder's reasons where they occur
    axes[2].legend(handles=handles, loc="lower right", fontsize=7, framealpha=0.8)
    axes[2].set_title(f"validity ({result.valid.mean() * 100:.1f}% decoded)")
    if white is not None:
        axes[3].imshow(white, cmap="gray", interpolation="nearest")
        axes[3].set_title("white frame")
    for ax in axes:
        ax.set_xticks([])
        ax.set_yticks([])
    if title:
        fig.suptitle(title)
    return fig
