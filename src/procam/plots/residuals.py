"""Residual plots of a calibration: reprojection error vectors per device, all poses.

The figure draws what the tables print: give it :func:`procam.residuals.calibration_residuals` and the
RMS in each panel's title is the calibration's ``cam_rms`` / ``proj_rms``; corners the solver rejected
as outliers are marked with a red x and left out of that RMS.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .. import stats
from ..style import VERDICT_COLOURS
from . import _figure

#: Colour of the verdict line in the figure's title, by the verdict's first word.


def short_name(name) -> str:
    """A pose's name for legends and tables: the last part of its path (``/data/run3/pose1`` -> ``pose1``)."""
    s = str(name or "")
    return Path(s).name or s


def nice_length(x: float) -> float:
    """The 1-2-5 number nearest below ``x`` (> 0): the length of the scale key's arrow."""
    if not (np.isfinite(x) and x > 0):
        return 1.0
    e = np.floor(np.log10(x))
    m = x / 10 ** e
    return float((5 if m >= 5 else 2 if m >= 2 else 1) * 10 ** e)


def arrow_scale(lengths, width: float, fraction: float = 0.05) -> float:
    """Automatic magnification of residual arrows: the 95th-percentile arrow is drawn ``fraction`` of
    the image ``width`` long.

    Parameters
    ----------
    lengths : residual lengths (px) of the corners that count (rejected corners left out).
    width : image width (px).

    Returns
    -------
    Drawn length / residual length (1 when there is nothing to scale).
    """
    r = np.asarray(lengths, float)
    r = r[np.isfinite(r) & (r > 0)]
    if not r.size:
        return 1.0
    return float(fraction * width / np.percentile(r, 95))


def _split(p, key):
    """(pts, res, used, rejected) of one pose and device; ``used``/``rejected`` (N,) bool."""
    pts, res = p.get(f"{key}_pts"), p.get(f"{key}_res")
    if pts is None or res is None:
        return None
    pts = np.asarray(pts, float).reshape(-1, 2)
    res = np.asarray(res, float).reshape(-1, 2)
    fin = np.isfinite(pts).all(1) & np.isfinite(res).all(1)
    used = p.get(f"{key}_used")
    used = fin if used is None else (np.asarray(used, bool) & fin)
    return pts, res, used, fin & ~used


def residual_figure(per_pose, cam_size, proj_size=None, scale: float | None = None, title: str = "",
                    verdict: str | None = None, key_fraction: float = 0.05):
    """Reprojection residuals as arrows at the observed points, one panel per device, with a histogram.

    Parameters
    ----------
    per_pose : list of dicts with ``name``, ``cam_pts`` (N, 2), ``cam_res`` (N, 2) and optionally
        ``proj_pts``, ``proj_res`` (pixels; residual = observed - predicted) and ``cam_used`` /
        ``proj_used`` ((N,) bool: False marks a rejected corner) -- the output of
        :func:`procam.residuals.calibration_residuals` or :func:`procam.residuals.pose_residuals`.
    cam_size, proj_size : (width, height) of the device images (no projector panel without
        ``proj_size``).
    scale : arrow magnification; default (None): automatic per device (:func:`arrow_scale`: the
        95th-percentile arrow is ``key_fraction`` of the image width). A key arrow of a round length
        says what the arrows mean.
    title : first line of the figure's title.
    verdict : the calibration's verdict in words (e.g. ``"degenerate: camera: ..."``), printed under
        the title, coloured by its first word (:data:`procam.style.VERDICT_COLOURS`).

    Returns
    -------
    matplotlib.figure.Figure
        Each panel's title holds the RMS and the largest residual over the corners that count (rejected
        corners, drawn as red x, are left out: the RMS is the calibration's) and how many were rejected.
    """
    has_proj = proj_size is not None and any(p.get("proj_res") is not None for p in per_pose)
    n = 2 if has_proj else 1
    from matplotlib import colormaps
    from matplotlib.patches import Rectangle

    fig = _figure(figsize=(6.5 * n, 8.4), constrained_layout=True)
    axes = fig.subplots(2, n, squeeze=False, gridspec_kw={"height_ratios": [3, 2]})
    colors = colormaps["tab10"]
    panels = [("camera", "cam", cam_size)] + ([("projector", "proj", proj_size)] if has_proj else [])
    for col, (label, key, size) in enumerate(panels):
        ax, hx = axes[0, col], axes[1, col]
        parts = [(i, p, _split(p, key)) for i, p in enumerate(per_pose)]
        parts = [(i, p, s) for i, p, s in parts if s is not None]
        used_len = np.concatenate([np.linalg.norm(s[1][s[2]], axis=1) for _, _, s in parts]) if parts else np.zeros(0)
        rej_len = np.concatenate([np.linalg.norm(s[1][s[3]], axis=1) for _, _, s in parts]) if parts else np.zeros(0)
        k = float(scale) if scale is not None else arrow_scale(used_len, size[0], key_fraction)
        quiver = None
        for i, p, (pts, res, used, rej) in parts:
            c = colors(i % 10)
            if used.any():
                quiver = ax.quiver(pts[used, 0], pts[used, 1], res[used, 0] * k, res[used, 1] * k, angles="xy",
                                   scale_units="xy", scale=1, color=c, width=0.003, label=short_name(p.get("name")))
            else:
                ax.plot([], [], color=c, label=short_name(p.get("name")))
        rx = [s[0][s[3]] for _, _, s in parts if s[3].any()]
        if rx:
            rx = np.concatenate(rx)
            ax.plot(rx[:, 0], rx[:, 1], "x", color="red", ms=9, mew=2, zorder=5,
                    label=f"rejected ({len(rx)}, up to {rej_len.max():.2f} px; not in the RMS)")
        ax.add_patch(Rectangle((-0.5, -0.5), size[0], size[1], fill=False, color="k"))
        ax.set_xlim(-0.05 * size[0], 1.05 * size[0])
        ax.set_ylim(1.05 * size[1], -0.13 * size[1])  # room above the image for the key
        ax.set_aspect("equal")
        if quiver is not None:
            L = nice_length(np.percentile(used_len, 95))
            ax.quiverkey(quiver, 0.03, 0.955, L * k, f"{L:g} px (arrows x{k:.3g})", labelpos="E", coordinates="axes",
                         color="k", fontproperties={"size": 8})
        rms = stats.rms(used_len, dim=1)
        mx = float(used_len.max()) if used_len.size else float("nan")
        head = f"{label}: RMS {rms:.3f} px over {used_len.size} corners, max {mx:.3f} px"
        if rej_len.size:
            head += f"\n{rej_len.size} rejected as outliers (red x), not in the RMS"
        ax.set_title(head, fontsize=10)
        if len(per_pose) <= 10 or rej_len.size:
            ax.legend(fontsize=7, loc="upper right", ncol=min(3, len(per_pose) + (1 if rej_len.size else 0)))
        if used_len.size:
            hx.hist(used_len, bins=30, color="0.4")
        hx.set_xlabel(f"{label} residual length (px), corners in the RMS")
        hx.set_ylabel("corners")
    _suptitle(fig, title, verdict, width=70 * n)
    return fig


def _suptitle(fig, title: str, verdict: str | None, width: int = 100) -> None:
    """The figure's title: ``title`` and, on the next line(s), the verdict in its colour."""
    import textwrap

    lines = [title] if title else []
    if verdict:
        lines += textwrap.wrap(f"verdict: {verdict}", width)
    if not lines:
        return
    word = verdict.replace(":", " ").split()[0].lower() if verdict and verdict.strip() else ""
    fig.suptitle("\n".join(lines), fontsize=10, color=VERDICT_COLOURS.get(word, "k"),
                 weight="normal" if word in ("", "good") else "bold")
