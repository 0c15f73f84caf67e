"""Figures of the experiment (:mod:`procam.paper.experiment`): focal errors against the pose angles, σ_T per set.

Functions return :class:`matplotlib.figure.Figure` objects (no pyplot, no backend switch).
"""

from __future__ import annotations

import numpy as np

from . import _figure, save_figure

__all__ = ["focal_error_figure", "sigma_t_figure", "experiment_figures", "save_figure"]


def _col(rows, key):
    return np.array([r.get(key, np.nan) for r in rows], float)


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
        ax.plot(x[ok], y[ok], "o", color="tab:blue")
        for i in np.flatnonzero(ok):
            ax.annotate(str(rows[i]["set"]), (x[i], y[i]), textcoords="offset points", xytext=(4, 4))
        ax.axvline(rule, color="gray", ls="--", lw=1, label=f"paper's rule: {rule:g}°")
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
        ax.set_title(f"single-pose {title} against the multi-pose reference")
        if ok.any() and np.nanmax(y[ok]) > 20 * max(np.nanmin(y[ok]), 1e-3):
            ax.set_yscale("log")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right")
    return fig


def sigma_t_figure(result):
    """σ_T (and σ_|T|) of every multi-pose set, by set number, Set A and the reference marked; the
    single-pose σ_T of each pose as horizontal ticks on the right for comparison."""
    rows = result.sets
    k = _col(rows, "set")
    sT = _col(rows, "sigma_T")
    sA = _col(rows, "sigma_abs_T")
    size = _col(rows, "size")
    fig = _figure(figsize=(11, 4.6), constrained_layout=True)
    ax = fig.subplots()
    sc = ax.scatter(k, sT, c=size, cmap="viridis", s=18, label="σ_T")
    ax.scatter(k, sA, c=size, cmap="viridis", s=12, marker="x", label="σ_|T|")
    ref = result.reference
    a = result.set_a
    ax.plot([ref["set"]], [ref["sigma_T"]], "o", mfc="none", mec="red", ms=12,
            label=f"reference {ref['poses']}")
    ax.plot([a["set"]], [a["sigma_T"]], "s", mfc="none", mec="black", ms=12, label=f"Set A {a['poses']}")
    single = _col(result.single_extrinsics, "sigma_T")
    if np.isfinite(single).any():
        x0 = np.nanmax(k) + 3
        for r, s in zip(result.single_extrinsics, single):
            if np.isfinite(s):
                ax.plot([x0, x0 + 2], [s, s], "-", color="tab:orange")
                ax.annotate(str(r["set"]), (x0 + 2, s), textcoords="offset points", xytext=(2, -3), fontsize=8)
        ax.plot([], [], "-", color="tab:orange", label="single-pose (per pose)")
    cb = fig.colorbar(sc, ax=ax)
    cb.set_label("poses in the set")
    sizes = np.unique(size[np.isfinite(size)])
    if len(sizes):
        cb.set_ticks(sizes)
    from matplotlib.ticker import MaxNLocator

    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel("multi-pose set number")
    ax.set_ylabel("σ over the per-pose PnP extrinsics (board units)")
    finite = np.concatenate([sT[np.isfinite(sT)], single[np.isfinite(single)]])
    if len(finite) and finite.max() > 20 * max(finite.min(), 1e-6):
        ax.set_yscale("log")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(0.0, -0.14), ncol=5, fontsize=8, frameon=False)
    ax.set_title("PnP precision per pose set")
    return fig


def experiment_figures(result) -> dict:
    """``name -> Figure`` for the report: ``focal_errors`` and ``sigma_T``."""
    return {"focal_errors": focal_error_figure(result), "sigma_T": sigma_t_figure(result)}
