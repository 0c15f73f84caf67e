"""Blend masks of overlapping projectors: per projector, alpha per projector pixel, summing to 1 where they overlap.

Method (feathering by distance to the image border, measured on the surface the camera sees): one camera sees
what every projector lights (a rig pose's decoded maps: camera pixel -> projector pixel, per projector).  At a
camera pixel lit by projectors ``k`` the weight of projector ``k`` is its pixel's distance to its own image
border, ``e_k = dx dy`` with ``dx = min(x, W-1-x) / ((W-1)/2)`` and ``dy`` alike (1 at the image centre,
0 on its border: no ridges along the diagonals as with the nearest border's distance), and ``alpha_k = e_k / sum_i e_i`` over the
projectors that light the pixel.  The alphas sum to 1 exactly there, each falls off linearly to 0 at its own
image border (where another projector takes over), so the ramp is continuous and as wide as the overlap.  Each
projector's alpha is carried to its own pixels by linear interpolation over its decoded camera samples
(Delaunay, on a grid of every ``grid`` projector pixels, then bilinear upsampling).

Conventions: ``alpha[y, x]`` for projector pixel column x, row y (the pixel centre), float in [0, 1]; the
fraction of the light of a surface point this projector gives; multiply the projector's **linear-light** image
by alpha (a gamma-encoded image: by ``alpha ** (1 / gamma)``).  Projector pixels whose light the camera does not
see get the value of the nearest grid node the camera sees (``seen`` says where alpha is measured); ``overlap`` is True where another projector lights the same
surface point.  Files: ``alpha_<name>.png`` 16-bit grey ``round(65535 alpha)``, ``overlap_<name>.png`` 8-bit
(255 = overlap), ``blend.npz`` (``alpha_<name>`` float32, ``overlap_<name>`` bool, ``conventions``).

Failure modes: a surface point the camera sees lit by one projector only gives alpha 1 there even if another
projector lights it out of the camera's view; decode errors at isolated pixels are smoothed by the grid.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Blend", "blend_masks", "write_blend", "BLEND_CONVENTIONS"]

BLEND_CONVENTIONS = ("alpha[y, x] per projector pixel (column x, row y), in [0, 1]: the fraction of a surface point's "
                     "light this projector gives; weights = product of the normalised distances to the projector's own image borders, "
                     "normalised over the projectors lighting the point the camera sees; multiply the linear-light "
                     "image by alpha (gamma-encoded: alpha ** (1/gamma)); beyond the camera's view the nearest seen value; "
                     "PNG: 16-bit grey round(65535 alpha); overlap PNG: 8-bit, 255 = overlap")


@dataclass(frozen=True)
class Blend:
    """Per projector name: ``alpha`` (H, W) float32, ``overlap`` (H, W) bool and ``seen`` (H, W) bool (the
    camera saw this pixel's light: alpha there is measured, elsewhere continued) on its own pixels."""

    alpha: dict
    overlap: dict
    seen: dict


def _edge(col, row, size):
    W, H = size
    dx = np.clip(np.minimum(col, W - 1 - col) / (0.5 * (W - 1)), 0.0, 1.0)
    dy = np.clip(np.minimum(row, H - 1 - row) / (0.5 * (H - 1)), 0.0, 1.0)
    return dx * dy


def blend_masks(maps: dict, sizes: dict, *, grid: int = 8, max_samples: int = 60000) -> Blend:
    """Blend masks from the decoded maps of one camera (module docstring).

    Parameters
    ----------
    maps : ``{projector name: (col, row)}`` camera-pixel maps (h, w) of projector coordinates, NaN where not
        decoded (a :class:`~procam.decode.DecodeResult`'s ``col``/``row``, or the simulator's
        :func:`~procam.simulate.true_projector_maps`).
    sizes : ``{projector name: (W, H)}``.
    grid : projector pixels between the interpolation grid's nodes (bilinear in between).
    max_samples : camera samples per projector for the interpolation (evenly subsampled beyond).

    Returns
    -------
    :class:`Blend`
    """
    import cv2
    from scipy.interpolate import LinearNDInterpolator

    names = list(maps)
    cols = {n: np.asarray(maps[n][0], float) for n in names}
    rows = {n: np.asarray(maps[n][1], float) for n in names}
    lit = {n: np.isfinite(cols[n]) & np.isfinite(rows[n]) for n in names}
    e = {n: np.where(lit[n], _edge(np.nan_to_num(cols[n]), np.nan_to_num(rows[n]), sizes[n]), 0.0) for n in names}
    total = sum(e.values())
    alpha, overlap, seen_all = {}, {}, {}
    for n in names:
        others = np.zeros_like(lit[n])
        for m in names:
            if m != n:
                others |= lit[m] & (e[m] > 0)
        m = lit[n]
        a = np.where(total > 0, e[n] / np.where(total > 0, total, 1.0), 1.0)
        pts = np.column_stack([cols[n][m], rows[n][m]])
        vals = np.column_stack([a[m], others[m].astype(float)])
        if len(pts) > max_samples:
            idx = np.linspace(0, len(pts) - 1, max_samples).astype(int)
            pts, vals = pts[idx], vals[idx]
        W, H = sizes[n]
        gx = np.arange(0, W + grid, grid, dtype=float)
        gy = np.arange(0, H + grid, grid, dtype=float)
        X, Y = np.meshgrid(np.minimum(gx, W - 1), np.minimum(gy, H - 1))
        if len(pts) >= 3:
            f = LinearNDInterpolator(pts, vals, fill_value=np.nan)
            g = f(X, Y)
        else:
            g = np.full(X.shape + (2,), np.nan)
        seen = np.isfinite(g[..., 0])
        if seen.any() and not seen.all():  # beyond the camera's view: the nearest seen node's values
            from scipy.interpolate import NearestNDInterpolator

            g[~seen] = NearestNDInterpolator(np.column_stack([X[seen], Y[seen]]), g[seen])(X[~seen], Y[~seen])
        ga = np.where(np.isfinite(g[..., 0]), g[..., 0], 1.0).astype(np.float32)
        go = np.where(np.isfinite(g[..., 1]), g[..., 1], 0.0).astype(np.float32)
        seen_px = cv2.remap(seen.astype(np.float32), *_grid_maps(W, H, grid), cv2.INTER_LINEAR,
                            borderMode=cv2.BORDER_REPLICATE) >= 1.0
        # bilinear from the grid to every pixel: pixel x sits at grid coordinate x / grid
        mx, my = _grid_maps(W, H, grid)
        full_a = cv2.remap(ga, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        full_o = cv2.remap(go, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        alpha[n] = np.clip(full_a, 0.0, 1.0)
        overlap[n] = full_o >= 0.5
        seen_all[n] = seen_px
    return Blend(alpha, overlap, seen_all)


def _grid_maps(W, H, grid):
    return np.meshgrid(np.arange(W, dtype=np.float32) / grid, np.arange(H, dtype=np.float32) / grid)


def write_blend(blend: Blend, out_dir) -> list:
    """Write ``alpha_<name>.png`` (16-bit), ``overlap_<name>.png`` (8-bit) and ``blend.npz`` into ``out_dir``
    (module docstring), atomically; returns the paths."""
    from pathlib import Path

    from ..io.files import write_image, write_npz

    out = Path(out_dir)
    paths = []
    for n, a in blend.alpha.items():
        paths.append(write_image(out / f"alpha_{n}.png", np.round(a.astype(np.float64) * 65535).astype(np.uint16)))
        paths.append(write_image(out / f"overlap_{n}.png", np.where(blend.overlap[n], 255, 0).astype(np.uint8)))
    arrays = {f"alpha_{n}": a.astype(np.float32) for n, a in blend.alpha.items()}
    arrays.update({f"overlap_{n}": o for n, o in blend.overlap.items()})
    paths.append(write_npz(out / "blend.npz", conventions=np.array(BLEND_CONVENTIONS), **arrays))
    return paths
