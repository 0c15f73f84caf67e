"""Figures of the simulation study (:mod:`procam.paper.study`): heat maps and the paper's slices.

Every function returns a :class:`matplotlib.figure.Figure` (no pyplot, no backend switch), and
:func:`save_study_figures` writes PNGs.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import _figure, save_figure

__all__ = ["heatmap", "slices", "save_study_figures"]

_LABEL = {"median_abs_df": "median |Δf| (px)", "abs_df_noise_free": "noise-free |Δf| (px)",
          "bound_f": "√CRLB(f) (px)", "ratio_std": "std(f) / √CRLB(f)", "ratio_median": "median |Δf| / √CRLB(f)"}
_SYM = {"camera": "c", "projector": "p"}


def _title(result, what):
    c = result.config
    return (f"{c.device}: {what}\nmodel error: {c.model_error}, σ = {c.sigma:g} px, "
            f"{c.trials} trials, D = {c.distance:g} mm")


def heatmap(result, metric: str = "median_abs_df", *, log: bool = True, vmin=None, vmax=None,
            annotate: bool | None = None):
    """Heat map of ``metric`` over the study grid; ψ down the rows, ν across.

    Parameters
    ----------
    result : procam.paper.study.StudyResult
    metric : a column of the result (``median_abs_df``, ``abs_df_noise_free``, ``bound_f``, ...).
    log : logarithmic colour scale (|Δf| spans 1–1000 px).
    vmin, vmax : colour limits (default: the finite data's range, clipped to >= 0.1 on a log scale,
        and at most the 95th percentile, so that the few huge cells on the degenerate lines
        ψ = 0 / ν = 0 do not wash out the rest; they saturate and the colour bar says so).
    annotate : write the values in the cells (default: grids of at most 11 × 11).

    Returns
    -------
    matplotlib.figure.Figure
        Non-finite cells (failed or degenerate) are grey.
    """
    from matplotlib.colors import LogNorm, TwoSlopeNorm

    psi, nu, val = result.grid(metric)
    finite = val[np.isfinite(val)]
    fig = _figure(figsize=(7.2, 6.0), constrained_layout=True)
    ax = fig.subplots()
    ax.set_facecolor("0.8")
    if finite.size:
        lo = vmin if vmin is not None else (max(0.1, float(finite[finite > 0].min())) if log and np.any(finite > 0)
                                            else float(finite.min()))
        hi = vmax if vmax is not None else float(np.percentile(finite, 95))
        hi = max(hi, lo * 1.0001)
        extend = ("min" if finite.min() < lo else "neither")
        if finite.max() > hi:
            extend = "both" if extend == "min" else "max"
        ratio = metric.startswith("ratio")
        if log:
            norm = LogNorm(vmin=lo, vmax=hi)
        elif ratio and lo < 1 < hi:  # ratios to the bound: diverging about 1
            norm = TwoSlopeNorm(vcenter=1.0, vmin=lo, vmax=hi)
        else:
            norm = None
        data = np.ma.masked_invalid(np.where(val <= 0, lo, val) if log else val)
        dpsi = np.diff(psi).min() if psi.size > 1 else 1.0
        dnu = np.diff(nu).min() if nu.size > 1 else 1.0
        im = ax.imshow(data, origin="lower", aspect="auto", cmap="RdBu_r" if ratio else "viridis", norm=norm,
                       vmin=None if norm is not None else lo, vmax=None if norm is not None else hi,
                       extent=(nu[0] - dnu / 2, nu[-1] + dnu / 2, psi[0] - dpsi / 2, psi[-1] + dpsi / 2),
                       interpolation="nearest")
        fig.colorbar(im, ax=ax, label=_LABEL.get(metric, metric), extend=extend)
        if annotate is None:
            annotate = psi.size <= 11 and nu.size <= 11
        if annotate:
            for i, p in enumerate(psi):
                for j, n in enumerate(nu):
                    if np.isfinite(val[i, j]):
                        ax.text(n, p, f"{val[i, j]:.3g}", ha="center", va="center", fontsize=7, color="w")
    s = _SYM[result.config.device]
    ax.set_xlabel(f"ν_{s} (deg, rotation about the board's y axis)")
    ax.set_ylabel(f"ψ_{s} (deg, rotation about the board's x axis)")
    ax.set_title(_title(result, _LABEL.get(metric, metric)), fontsize=10)
    return fig


def slices(result):
    """The paper's slices (its Figs 5 and 7) with the Cramér–Rao bound drawn in.

    One panel per slice: median |Δf| over the trials (markers), the noise-free |Δf| (the
    deterministic bias of the model error; dashed), √CRLB(f) at the study's σ (solid grey) and
    0.674·√CRLB, the median |Δf| an efficient unbiased estimator would reach (dotted).
    Log scale; cells where the method failed or the bound is infinite are left out.

    Returns
    -------
    matplotlib.figure.Figure
    """
    specs = result.slice_specs()
    fig = _figure(figsize=(5.2 * len(specs), 4.3), constrained_layout=True)
    axes = fig.subplots(1, len(specs), squeeze=False)
    s = _SYM[result.config.device]
    for ax, (label, axis, fixed, val) in zip(axes[0], specs):
        rows = result.slice(label)
        x = np.array([r[axis] for r in rows])

        def col(name):
            return np.array([r[name] for r in rows], float)

        med, nf, bd = col("median_abs_df"), col("abs_df_noise_free"), col("bound_f")
        if result.config.trials > 0:
            ax.plot(x, med, "o-", ms=4, color="C0", label="median |Δf| (noisy)")
        ax.plot(x, nf, "s--", ms=3, color="C1", label="|Δf| noise-free (bias)")
        if result.config.sigma > 0:
            ax.plot(x, bd, "-", color="0.35", lw=2, label="√CRLB(f)")
            ax.plot(x, 0.674 * bd, ":", color="0.35", label="0.674·√CRLB (efficient median)")
        ax.set_yscale("log")
        # without a model error the noise-free |Δf| is ~1e-11 px (solver precision): keep the axis on
        # the noisy scale and pin such points to the bottom edge
        ref = np.concatenate([med, 0.674 * bd]) if result.config.trials > 0 else np.array([])
        ref = ref[np.isfinite(ref) & (ref > 0)]
        if ref.size:
            lo = ref.min() / 3
            top = np.nanmax(np.concatenate([ref, nf[np.isfinite(nf)]])) * 2
            ax.set_ylim(lo, top)
            below = np.isfinite(nf) & (nf < lo)
            if below.any():
                ax.plot(x[below], np.full(below.sum(), lo * 1.15), "v", ms=4, color="C1",
                        label="noise-free |Δf| below axis")
        ax.set_xlabel(f"{'ψ' if axis == 'psi' else 'ν'}_{s} (deg)")
        ax.set_ylabel("|Δf| (px)")
        ax.set_title(f"{'ν' if fixed == 'nu' else 'ψ'}_{s} = {val:g}°", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].legend(fontsize=8)
    fig.suptitle(_title(result, "slices"), fontsize=10)
    return fig


def save_study_figures(result, outdir, prefix: str | None = None) -> list[Path]:
    """Write the heat maps (median |Δf|, noise-free |Δf|, √CRLB, std/√CRLB) and the slices as PNGs.

    Returns the paths written.
    """
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    c = result.config
    prefix = prefix or f"study_{c.device}_{c.model_error}"
    out = []
    metrics = ["abs_df_noise_free"]
    if c.trials > 0:
        metrics.insert(0, "median_abs_df")
    if c.sigma > 0:
        metrics.append("bound_f")
        if c.trials > 1:
            metrics.append("ratio_std")
    for m in metrics:
        fig = heatmap(result, m, log=not m.startswith("ratio"),
                      vmin=0.5 if m.startswith("ratio") else None, vmax=2.0 if m.startswith("ratio") else None)
        out.append(save_figure(fig, outdir / f"{prefix}_heatmap_{m}.png"))
    if any(r["slices"] for r in result.rows) or result.rows:
        fig = slices(result)
        out.append(save_figure(fig, outdir / f"{prefix}_slices.png"))
    return out
