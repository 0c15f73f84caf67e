"""Residual plots of a calibration: reprojection error vectors per device, all poses."""

from __future__ import annotations

import numpy as np

from . import _figure


def residual_figure(per_pose, cam_size, proj_size=None, scale: float = 100.0, title: str = ""):
    """Reprojection residuals, scaled up by ``scale``, at the observed points.

    per_pose : list of dicts with ``name``, ``cam_pts`` (N, 2), ``cam_res`` (N, 2) and optionally
        ``proj_pts``, ``proj_res`` (pixels; residual = observed - predicted).
    """
    has_proj = proj_size is not None and any(p.get("proj_res") is not None for p in per_pose)
    n = 2 if has_proj else 1
    from matplotlib import colormaps
    from matplotlib.patches import Rectangle

    fig = _figure(figsize=(6.5 * n, 8), constrained_layout=True)
    axes = fig.subplots(2, n, squeeze=False, gridspec_kw={"height_ratios": [3, 2]})
    colors = colormaps["tab10"]
    panels = [("camera", "cam", cam_size)] + ([("projector", "proj", proj_size)] if has_proj else [])
    for col, (label, key, size) in enumerate(panels):
        ax, hx = axes[0, col], axes[1, col]
        all_r = []
        for i, p in enumerate(per_pose):
            pts, res = p.get(f"{key}_pts"), p.get(f"{key}_res")
            if pts is None or res is None:
                continue
            ok = np.isfinite(pts).all(1) & np.isfinite(res).all(1)
            ax.quiver(pts[ok, 0], pts[ok, 1], res[ok, 0] * scale, res[ok, 1] * scale, angles="xy",
                      scale_units="xy", scale=1, color=colors(i % 10), width=0.003, label=p["name"])
            all_r.append(np.linalg.norm(res[ok], axis=1))
        ax.add_patch(Rectangle((-0.5, -0.5), size[0], size[1], fill=False, color="k"))
        ax.set_xlim(-0.05 * size[0], 1.05 * size[0])
        ax.set_ylim(1.05 * size[1], -0.05 * size[1])
        ax.set_aspect("equal")
        r = np.concatenate(all_r) if all_r else np.zeros(0)
        rms = float(np.sqrt(np.mean(r ** 2))) if r.size else float("nan")
        ax.set_title(f"{label}: residuals x{scale:g} (RMS {rms:.3f} px, max {r.max() if r.size else 0:.3f} px)")
        if len(per_pose) <= 10:
            ax.legend(fontsize=7, loc="lower right")
        if r.size:
            hx.hist(r, bins=30, color="0.4")
        hx.set_xlabel(f"{label} residual length (px)")
        hx.set_ylabel("corners")
    if title:
        fig.suptitle(title)
    return fig
