"""Figures of the experiment (:mod:`procam.paper.experiment`): focal errors against the pose angles, σ_T per set.

Functions return :class:`matplotlib.figure.Figure` objects (no pyplot, no backend switch).
"""

from __future__ import annotations

import numpy as np

from . import _figure, save_figure

__all__ = ["focal_error_figure", "sigma_t_figure", "experiment_figures", "save_figure"]


def _col(rows, key):
    return np.array([r.get(key, np.nan) for r in rows], float)


def _fit_limits(ax, x, y, rule):
    """Axis limits that hold every point and its label: x from 0 past the rule and the data, y from 0
    (log scale from below the smallest) with head room for the labels above the highest point."""
    xmax = max([rule] + [float(v) for v in x]) if len(x) else rule
    ax.set_xlim(0, 1.12 * xmax)
    y = np.asarray(y, float)
    if not y.size:
        return
    if np.nanmax(y) > 20 * max(np.nanmin(y), 1e-3):
        ax.set_yscale("log")
        lo = max(np.nanmin(y), 1e-3)
        ax.set_ylim(lo / 1.8, np.nanmax(y) * 2.2)
    else:
        ax.set_ylim(0, 1.15 * np.nanmax(y) if np.nanmax(y) > 0 else 1.0)


def focal_error_figure(result):
    """|Δf_c| against |ψ_c| + |ν_c| and |Δf_p| against |ν_p| for the single-pose calibrations,
    each point labelled with its pose number (the paper's degeneracy rules: > 10° and > 13°).

    The angles are the board's under the reference calibration (``*_ref`` columns), which stay
    meaningful when a single-pose solution is degenerate."""
    rows = result.single
    fig = _figure(figsize=(11, 4.2), constrained_layout=True)
    axes = fig.subplots(1, 2)
    cam_x = np.abs(_col(rows, "psi_c_ref")) + np.abs(_col(rows, "nu_c_ref"))
    specs = [(axes[0], cam_x, _col(rows, "abs_df_c"), "|ψ_c| + |ν_c| (deg, reference calibration)",
              "|Δf_c| (px)", 10.0, "camera"),
             (axes[1], np.abs(_col(rows, "nu_p_ref")), _col(rows, "abs_df_p"), "|ν_p| (deg, reference calibration)",
              "|Δf_p| (px)", 13.0, "projector")]
    for ax, x, y, xl, yl, rule, title in specs:
        ok = np.isfinite(x) & np.isfinite(y)
        ax.plot(x[ok], y[ok], "o", color="tab:blue", clip_on=False)
        for i in np.flatnonzero(ok):
            ax.annotate(str(rows[i]["set"]), (x[i], y[i]), textcoords="offset points", xytext=(4, 4),
                        annotation_clip=False)
        ax.axvline(rule, color="gray", ls="--", lw=1, label=f"paper's rule: {rule:g}°")
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
        ax.set_title(f"single-pose {title} against the multi-pose reference")
        _fit_limits(ax, x[ok], y[ok], rule)
        ax.grid(alpha=0.3)
        ax.legend(loc="best")
    return fig


def sigma_t_figure(result):
    """σ_T (and σ_|T|) of every multi-pose set, by set number, Set A and the reference marked, next to
    the single-pose σ_T of each pose.

    With many sets the sets are a scatter by set number (colour = poses in the set, when sizes differ)
    and the single-pose values horizontal ticks on the right; with at most 3 sets every value gets its
    own labelled column (``set 1 {1,2,3}``, ``pose 1 alone``, ...), so that a single set reads."""
    rows = result.sets
    k = _col(rows, "set")
    sT = _col(rows, "sigma_T")
    sA = _col(rows, "sigma_abs_T")
    size = _col(rows, "size")
    single = _col(result.single_extrinsics, "sigma_T")
    single_abs = _col(result.single_extrinsics, "sigma_abs_T")
    ref, a = result.reference, result.set_a
    fig = _figure(figsize=(11, 4.6), constrained_layout=True)
    ax = fig.subplots()
    if len(rows) <= 3:
        labels, x = [], 0
        for r, t, ta in zip(rows, sT, sA):
            tag = " (reference, Set A)" if r["set"] == ref["set"] == a["set"] else (
                " (reference)" if r["set"] == ref["set"] else " (Set A)" if r["set"] == a["set"] else "")
            ax.plot([x], [t], "o", color="tab:blue", ms=8, label="multi-pose σ_T" if x == 0 else None)
            ax.plot([x], [ta], "x", color="tab:blue", ms=8, mew=2, label="multi-pose σ_|T|" if x == 0 else None)
            labels.append(f"set {r['set']} {r['poses']}{tag}")
            x += 1
        for j, (r, t, ta) in enumerate(zip(result.single_extrinsics, single, single_abs)):
            if np.isfinite(t):
                ax.plot([x], [t], "o", color="tab:orange", ms=8, label="single-pose σ_T" if j == 0 else None)
                ax.plot([x], [ta], "x", color="tab:orange", ms=8, mew=2,
                        label="single-pose σ_|T|" if j == 0 else None)
            labels.append(f"pose {r['set']} alone")
            x += 1
        ax.set_xticks(range(len(labels)), labels, rotation=20, ha="right", fontsize=8)
        ax.set_xlim(-0.6, len(labels) - 0.4)
        ax.set_xlabel("calibration (multi-pose set, or one pose single-pose)")
        legend = {"loc": "best", "fontsize": 8}
    else:
        many_sizes = len(np.unique(size[np.isfinite(size)])) > 1
        kw = {"c": size, "cmap": "viridis"} if many_sizes else {"color": "tab:blue"}
        sc = ax.scatter(k, sT, s=18, label="σ_T", **kw)
        ax.scatter(k, sA, s=12, marker="x", label="σ_|T|", **kw)
        ax.plot([ref["set"]], [ref["sigma_T"]], "o", mfc="none", mec="red", ms=12, label=f"reference {ref['poses']}")
        ax.plot([a["set"]], [a["sigma_T"]], "s", mfc="none", mec="black", ms=12, label=f"Set A {a['poses']}")
        if np.isfinite(single).any():
            x0 = np.nanmax(k) + 0.05 * max(np.nanmax(k), 10)
            w = 0.04 * max(np.nanmax(k), 10)
            for r, t in zip(result.single_extrinsics, single):
                if np.isfinite(t):
                    ax.plot([x0, x0 + w], [t, t], "-", color="tab:orange")
                    ax.annotate(f"pose {r['set']}", (x0 + w, t), textcoords="offset points", xytext=(2, -3),
                                fontsize=8, annotation_clip=False)
            ax.plot([], [], "-", color="tab:orange", label="single-pose σ_T (per pose)")
            ax.set_xlim(right=x0 + 3 * w)
        if many_sizes:
            cb = fig.colorbar(sc, ax=ax)
            cb.set_label("poses in the set")
            cb.set_ticks(np.unique(size[np.isfinite(size)]))
        from matplotlib.ticker import MaxNLocator

        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.set_xlabel("multi-pose set number")
        legend = {"loc": "upper left", "bbox_to_anchor": (0.0, -0.14), "ncol": 5, "fontsize": 8, "frameon": False}
    ax.set_ylabel("σ over the per-pose PnP extrinsics (board units)")
    finite = np.concatenate([v[np.isfinite(v)] for v in (sT, sA, single, single_abs)])
    finite = finite[finite > 0]
    if len(finite) and finite.max() > 20 * finite.min():
        ax.set_yscale("log")
        ax.set_ylim(finite.min() / 1.8, finite.max() * 1.8)
    elif len(finite):
        ax.set_ylim(0, 1.15 * finite.max())
    ax.grid(alpha=0.3)
    ax.legend(**legend)
    ax.set_title("PnP precision (σ_T, σ_|T|): multi-pose sets and single-pose calibrations")
    return fig


def experiment_figures(result) -> dict:
    """``name -> Figure`` for the report: ``focal_errors`` and ``sigma_T``."""
    return {"focal_errors": focal_error_figure(result), "sigma_T": sigma_t_figure(result)}
