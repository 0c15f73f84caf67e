"""The geometry oracle: what each camera ray sees, where it lies in the projector, how it is lit.

Per camera sample (a pixel centre or a supersample): the ray through the camera's lens, the nearest
surface it meets (the board, or the background: the default wall, or the planes and solids of a
:class:`~procam.simulate.Background`), that point's projector panel coordinates through the
projector's lens, whether the projector lights it (inside the panel, facing it, and no surface on the
segment to the projector's centre: a cast shadow otherwise), its albedo and irradiance.  The renderer
(:mod:`~procam.simulate.renderer`) turns this into images; :func:`true_projector_maps` is the dense
fast path for solvers' tests and benchmarks: the exact projector coordinates at camera pixels with
the masks of what is seen and lit, optionally rounded like a Gray-code decode and on a subsampled grid.

Shadows: the board shadows the background and the solids; each solid shadows everything else; planes
shadow nothing (the devices lie on one side of each, see :mod:`~procam.simulate.background`).  Light
that reaches a surface after another reflection (inter-reflection) is not modelled.

Pixels are ``(x, y)`` = (column, row) with the origin at the centre of the top-left pixel; pixel
``i`` covers ``[i - 0.5, i + 0.5]``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from .background import Plane
from .lens import undistort
from .scene import BOARD_GRAIN_MM, Scene, board_extent

__all__ = ["ProjectorMaps", "true_projector_maps"]

#: Rows of the supersampled grid per band of the geometry pass. A band's float64 temporaries are then over 4 MB,
#: which NumPy asks the kernel to back with huge pages: bands of 16-64 rows page-faulted 4 times as often (up to
#: 2 s of system time for a 1280x800 camera at 3x3 supersamples, measured in a fresh process). Nothing else
#: depends on the band size.
GEOMETRY_BAND = 288


def _box_filtered_step(u, w, n):
    """Box filter (width w) of the indicator of [0, n], evaluated at u (all in square units)."""
    return (np.clip(u + 0.5 * w, 0, n) - np.clip(u - 0.5 * w, 0, n)) / w


def _box_filtered_square_wave(u, w, n):
    """Box filter (width w) of sq(u) * [0 <= u <= n], sq = +1 on [2k, 2k+1), -1 on [2k+1, 2k+2)."""

    def F(x):  # integral of sq from 0 to x (a triangle wave), for x clipped to [0, n]
        fr = np.mod(np.clip(x, 0, n), 2.0)
        return np.where(fr < 1.0, fr, 2.0 - fr)

    return (F(u + 0.5 * w) - F(u - 0.5 * w)) / w


def _board_albedo(scene: Scene, bx, by, wx, wy):
    """Albedo of the printed board at board coords (bx, by) mm, box-filtered over (wx, wy) mm.

    The top-left square (smallest x, y) is black; squares alternate; a white margin surrounds them.
    """
    s = scene.square
    nx, ny = scene.board_cols + 1, scene.board_rows + 1  # printed squares
    u = (bx + 0.5 * nx * s) / s
    v = (by + 0.5 * ny * s) / s
    wu = np.maximum(wx / s, 1e-6)
    wv = np.maximum(wy / s, 1e-6)
    inside = _box_filtered_step(u, wu, nx) * _box_filtered_step(v, wv, ny)
    checker = _box_filtered_square_wave(u, wu, nx) * _box_filtered_square_wave(v, wv, ny)
    return scene.albedo_white + (scene.albedo_black - scene.albedo_white) * 0.5 * (inside + checker)


def _grain(scene: Scene, bx, by):
    """The board's print texture at board coords (bx, by) mm: a fixed field (seed 0) of unit-variance normal values
    on a grid of :data:`~procam.simulate.scene.BOARD_GRAIN_MM` cells over the printed board, bilinear (scaled by 3/2,
    so its mean variance stays 1)."""
    x0, x1, y0, y1 = board_extent(scene)
    c = BOARD_GRAIN_MM
    nx, ny = int(np.ceil((x1 - x0) / c)) + 2, int(np.ceil((y1 - y0) / c)) + 2
    field = np.random.default_rng(0).standard_normal((ny, nx))
    u = np.clip((np.asarray(bx, float) - x0) / c, 0, nx - 1.001)
    v = np.clip((np.asarray(by, float) - y0) / c, 0, ny - 1.001)
    i, j = u.astype(int), v.astype(int)
    fu, fv = u - i, v - j
    val = ((1 - fu) * (1 - fv) * field[j, i] + fu * (1 - fv) * field[j, i + 1] + (1 - fu) * fv * field[j + 1, i]
           + fu * fv * field[j + 1, i + 1])
    return 1.5 * val


def _background_normals(bg, on, idx, X, Y, Z):
    """Unit normals (nx, ny, nz) of the background surface ``idx`` at the points (X, Y, Z) (where ``on``)."""
    if len(bg.surfaces) == 1 and isinstance(bg.surfaces[0], Plane):
        n = bg.surfaces[0].normal
        return n[0], n[1], n[2]
    nx, ny, nz = (np.zeros_like(X) for _ in range(3))
    for i, k in enumerate(bg.surfaces):
        m = on & (idx == i)
        if not m.any():
            continue
        if isinstance(k, Plane):
            nx[m], ny[m], nz[m] = k.normal
        else:
            n = k.normal_at(np.stack([X[m], Y[m], Z[m]], axis=-1))
            nx[m], ny[m], nz[m] = n[:, 0], n[:, 1], n[:, 2]
    return nx, ny, nz


def _panel_coordinates(scene: Scene, Xp, Yp, Zp):
    """Projector panel pixels (xp, yp) lighting points (Xp, Yp, Zp) of the projector frame, through its lens."""
    Kp = scene.K_proj
    lens = scene.proj_lens
    if lens.model == "none":
        return Kp[0, 0] * Xp / Zp + Kp[0, 1] * Yp / Zp + Kp[0, 2], Kp[1, 1] * Yp / Zp + Kp[1, 2]
    if lens.model == "opencv":
        xd = lens.distort_normalized(Kp, np.stack([Xp / Zp, Yp / Zp], axis=-1))
        return Kp[0, 0] * xd[..., 0] + Kp[0, 1] * xd[..., 1] + Kp[0, 2], Kp[1, 1] * xd[..., 1] + Kp[1, 2]
    ideal = np.stack([Kp[0, 0] * Xp / Zp + Kp[0, 1] * Yp / Zp + Kp[0, 2], Kp[1, 1] * Yp / Zp + Kp[1, 2]], axis=-1)
    m = lens.distort(Kp, ideal)
    return m[..., 0], m[..., 1]


def _geometry_band(scene: Scene, ys, xs, detail: bool = False):
    """Per-sample geometry for the sample grid ``ys`` x ``xs`` (camera pixel coordinates).

    Returns dict of (len(ys), len(xs)) arrays: ``xp``, ``yp`` projector coords (NaN where no
    surface), ``coef`` = gain * albedo * irradiance factor where lit by the projector (0 elsewhere),
    ``amb`` = gain * albedo * ambient, ``board`` (bool, the ray hits the board), ``lit`` (bool); with
    ``detail`` also ``surface`` (int8: -1 none, 0 the board, k >= 1 background surface k - 1) and
    ``shadow`` (bool: a surface in a cast shadow).
    Irradiance factor: cosine of incidence times the inverse-square fall-off, relative to the
    projector's distance to the board centre (Lambertian surfaces, so no view dependence).
    """
    X_pix, Y_pix = np.meshgrid(np.asarray(xs, float), np.asarray(ys, float))
    und = undistort(scene, np.stack([X_pix, Y_pix], axis=-1))
    Kc = scene.K_cam
    # camera rays with z = 1 (zero skew)
    dx = (und[..., 0] - Kc[0, 2]) / Kc[0, 0]
    dy = (und[..., 1] - Kc[1, 2]) / Kc[1, 1]
    del und
    Rb, tb = scene.R_board, scene.t_board
    nb = Rb[:, 2]
    x0, x1, y0, y1 = board_extent(scene)
    bg = scene.surfaces()
    solids = [(i, k) for i, k in enumerate(bg.surfaces) if not isinstance(k, Plane)]
    err = np.errstate(divide="ignore", invalid="ignore")
    err.__enter__()
    try:
        # board plane
        sb = (nb @ tb) / (dx * nb[0] + dy * nb[1] + nb[2])
        rx, ry, rz = dx * sb - tb[0], dy * sb - tb[1], sb - tb[2]
        bx = rx * Rb[0, 0] + ry * Rb[1, 0] + rz * Rb[2, 0]
        by = rx * Rb[0, 1] + ry * Rb[1, 1] + rz * Rb[2, 1]
        del rx, ry, rz
        on_board = (sb > 0) & (bx >= x0) & (bx <= x1) & (by >= y0) & (by <= y1)
        # the background: nearest surface (the default wall: one plane)
        sw, idx = bg.camera_hits(dx, dy)
        on_wall = np.isfinite(sw)
        board = on_board & (~on_wall | (sb < sw))
        wall = on_wall & ~board
        surf = board | wall
        depth = np.where(board, sb, np.where(wall, sw, np.nan))
        del sb, sw
        X, Y, Z = dx * depth, dy * depth, depth
        cam_vig = (1.0 + dx * dx + dy * dy) ** (-0.5 * scene.cam_vignetting)  # cos(field angle) ** n
        del dx, dy

        # albedo; the board's is box-filtered over each sample's footprint (anti-aliasing)
        def footprint(a):
            g0 = np.abs(np.gradient(a, axis=0)) if a.shape[0] > 1 else 0.0
            g1 = np.abs(np.gradient(a, axis=1)) if a.shape[1] > 1 else 0.0
            return np.nan_to_num(g0 + g1, nan=1.0)

        if len(bg.surfaces) == 1:
            albedo = np.where(wall, bg.surfaces[0].albedo, 0.0)
        else:
            albedo = np.where(wall, np.array([k.albedo for k in bg.surfaces])[np.maximum(idx, 0)], 0.0)
        albedo[board] = _board_albedo(scene, bx[board], by[board], footprint(bx)[board], footprint(by)[board])
        if scene.board_grain:
            albedo[board] = np.clip(albedo[board] + scene.board_grain * _grain(scene, bx[board], by[board]), 0.0, 1.0)
        del bx, by

        # projector coordinates
        R, T = scene.R, scene.T
        Xp = R[0, 0] * X + R[0, 1] * Y + R[0, 2] * Z + T[0]
        Yp = R[1, 0] * X + R[1, 1] * Y + R[1, 2] * Z + T[1]
        Zp = R[2, 0] * X + R[2, 1] * Y + R[2, 2] * Z + T[2]
        xp, yp = _panel_coordinates(scene, Xp, Yp, Zp)
        Wp, Hp = scene.proj_size
        front = Zp > 0
        in_panel = front & (xp >= -0.5) & (xp <= Wp - 0.5) & (yp >= -0.5) & (yp <= Hp - 0.5)

        # shading
        Cp = scene.proj_center_cam
        Lx, Ly, Lz = Cp[0] - X, Cp[1] - Y, Cp[2] - Z
        dist2 = Lx * Lx + Ly * Ly + Lz * Lz
        cos_p = Zp / np.sqrt(Xp * Xp + Yp * Yp + Zp * Zp)  # projector field angle
        wx, wy, wz = _background_normals(bg, wall, idx, X, Y, Z)
        nx = np.where(board, nb[0], wx)
        ny = np.where(board, nb[1], wy)
        nz = np.where(board, nb[2], wz)
        del wx, wy, wz
        ndotl = nx * Lx + ny * Ly + nz * Lz
        ndotv = -(nx * X + ny * Y + nz * Z)
        facing = (ndotl * ndotv) > 0
        d_ref2 = float(np.sum((Cp - tb) ** 2))
        irr = np.abs(ndotl) / np.sqrt(dist2) * (d_ref2 / dist2) * np.abs(cos_p) ** scene.proj_vignetting
        del nx, ny, nz, ndotv, ndotl, dist2, Xp, Yp, Zp, cos_p

        # cast shadows: the board's (on everything else), then each solid's (on everything else)
        uu = (nb @ tb - (X * nb[0] + Y * nb[1] + Z * nb[2])) / (Lx * nb[0] + Ly * nb[1] + Lz * nb[2])
        qx, qy, qz = X + uu * Lx - tb[0], Y + uu * Ly - tb[1], Z + uu * Lz - tb[2]
        sx = qx * Rb[0, 0] + qy * Rb[1, 0] + qz * Rb[2, 0]
        sy = qx * Rb[0, 1] + qy * Rb[1, 1] + qz * Rb[2, 1]
        shadow = wall & (uu > 1e-9) & (uu < 1) & (sx >= x0) & (sx <= x1) & (sy >= y0) & (sy <= y1)
        del uu, qx, qy, qz, sx, sy
        if solids:
            P = np.stack([X, Y, Z], axis=-1)
            L = np.stack([Lx, Ly, Lz], axis=-1)
            for i, k in solids:
                shadow |= surf & ~(wall & (idx == i)) & k.blocks(P, L)
            del P, L
    finally:
        err.__exit__(None, None, None)

    # the panel's edges are left to the (defocused) panel masks of the renderer; `lit` is the truth mask
    illuminated = surf & front & facing & ~shadow
    lit = illuminated & in_panel
    coef = np.where(illuminated, scene.gain * albedo * irr * cam_vig, 0.0)
    amb = scene.gain * scene.ambient * albedo * cam_vig
    xp = np.where(surf, xp, np.nan)
    yp = np.where(surf, yp, np.nan)
    out = {"xp": xp, "yp": yp, "coef": coef, "amb": amb, "board": board, "lit": lit}
    if detail:
        out["surface"] = np.where(board, 0, np.where(wall, idx + 1, -1)).astype(np.int8)
        out["shadow"] = surf & shadow
    return out


def _sample_grid(n_pix: int, s: int) -> np.ndarray:
    """Sample positions (pixel coordinates) of ``s`` supersamples per pixel: pixel i covers [i-.5, i+.5]."""
    return (np.arange(n_pix * s) + 0.5) / s - 0.5


def _geometry_bands(scene: Scene, s: int, work: Callable, band_rows: int = GEOMETRY_BAND) -> None:
    """Call ``work(r0, r1, g)`` for each band ``r0:r1`` of rows of the supersampled grid (H*s, W*s), ``g`` the
    band's :func:`_geometry_band` (float64); ``band_rows`` see :data:`GEOMETRY_BAND`."""
    W, H = scene.cam_size
    xs, ys = _sample_grid(W, s), _sample_grid(H, s)

    def band(r0):
        r1 = min(len(ys), r0 + band_rows)
        # one extra row on each side so footprint gradients are central everywhere
        e0, e1 = max(0, r0 - 1), min(len(ys), r1 + 1)
        g = _geometry_band(scene, ys[e0:e1], xs)
        work(r0, r1, {k: v[r0 - e0: r0 - e0 + (r1 - r0)] for k, v in g.items()})

    for r0 in range(0, len(ys), band_rows):
        band(r0)


def _geometry(scene: Scene, s: int | None = None, band_rows: int = GEOMETRY_BAND):
    """Geometry on the supersampled grid (H*s, W*s): :func:`_geometry_band` in row bands, stored as float32
    (``xp``, ``yp``, ``coef``, ``amb``) and bool (``board``, ``lit``)."""
    s = scene.supersample if s is None else int(s)
    W, H = scene.cam_size
    shape = (H * s, W * s)
    out = {k: np.empty(shape, dtype=np.float32) for k in ("xp", "yp", "coef", "amb")}
    out.update({k: np.empty(shape, dtype=bool) for k in ("board", "lit")})

    def work(r0, r1, g):
        for k, v in g.items():
            out[k][r0:r1] = v

    _geometry_bands(scene, s, work, band_rows)
    return out


# ------------------------------------------------------------------------------------------------
# the dense fast path
# ------------------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class ProjectorMaps:
    """The exact projector coordinates seen at camera pixels, with what is seen and lit there.

    Unpacks as ``col, row, lit_board = true_projector_maps(scene)`` (its first three fields).

    Attributes (arrays (h, w) on the camera grid ``y`` x ``x``)
    ----------
    col, row : float64, the projector panel x / y (pixels, through the projector's lens) of the surface
        seen at the pixel centre where the projector lights it, NaN elsewhere (no surface, outside the
        panel, turned away from the projector, or in a cast shadow).  Whole projector pixels
        (``floor(c + 0.5)``, the pixel whose area holds the point, as a Gray-code decode gives) when
        ``rounded``.
    lit_board : bool, the whole pixel (every supersample of it) lies on the board and is lit.
    board : bool, the pixel centre sees the board (nothing in front of it).
    surface : int8, what the pixel centre sees: -1 nothing, 0 the board, k >= 1 the background's
        surface k - 1 (``scene.surfaces().surfaces[k - 1]``; the default wall is 1).
    lit : bool, the pixel centre's surface is lit (``col``, ``row`` finite).
    shadow : bool, the pixel centre's surface is in a cast shadow (the board or a solid lies between it
        and the projector's centre).
    x, y : (w,), (h,) float64, camera pixel coordinates of the grid's columns and rows.
    step : the grid's spacing in camera pixels (1: every pixel).
    rounded : whether ``col``, ``row`` are whole projector pixels.
    """

    col: np.ndarray
    row: np.ndarray
    lit_board: np.ndarray
    board: np.ndarray
    surface: np.ndarray
    lit: np.ndarray
    shadow: np.ndarray
    x: np.ndarray
    y: np.ndarray
    step: int = 1
    rounded: bool = False

    def __iter__(self):
        return iter((self.col, self.row, self.lit_board))


def _lit_board(scene: Scene, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """(len(ys), len(xs)) bool: every supersample of the camera pixels (whole coordinates ``ys`` x ``xs``) lies on
    the board and is lit; computed in bands of pixel rows (no supersampled image of the whole camera)."""
    s = scene.supersample
    sub = np.arange(s)
    sx = ((xs[:, None] * s + sub).ravel() + 0.5) / s - 0.5   # the positions of _sample_grid
    out = np.empty((len(ys), len(xs)), bool)
    rows = max(1, GEOMETRY_BAND // s)
    for r0 in range(0, len(ys), rows):
        yb = ys[r0:r0 + rows]
        sy = ((yb[:, None] * s + sub).ravel() + 0.5) / s - 0.5
        g = _geometry_band(scene, sy, sx)
        out[r0:r0 + len(yb)] = (g["board"] & g["lit"]).reshape(len(yb), s, len(xs), s).all(axis=(1, 3))
    return out


def true_projector_maps(scene: Scene, step: int = 1, rounded: bool = False) -> ProjectorMaps:
    """Exact projector coordinates seen at camera pixel centres, on the board and on the background.

    The dense fast path for solvers' tests and benchmarks: what a perfect Gray-code decode would give,
    without rendering (the same geometry as the renderer's, at the pixel centres).

    Parameters
    ----------
    scene : the set-up.
    step : camera grid spacing (pixels ``0, step, 2 step, ...`` along each axis); 1 = every pixel.
    rounded : round the projector coordinates to whole projector pixels, as a Gray-code decode does.

    Returns
    -------
    :class:`ProjectorMaps`; ``col, row, lit_board = true_projector_maps(scene)`` unpacks its first three.
    """
    step = int(step)
    if step < 1:
        raise ValueError(f"step must be a whole number >= 1, got {step}")
    W, H = scene.cam_size
    xs, ys = np.arange(0, W, step, dtype=float), np.arange(0, H, step, dtype=float)
    ok = _lit_board(scene, xs, ys)
    exact = _geometry_band(scene, ys, xs, detail=True)
    col = np.where(exact["lit"], exact["xp"], np.nan)
    row = np.where(exact["lit"], exact["yp"], np.nan)
    if rounded:
        Wp, Hp = scene.proj_size
        with np.errstate(invalid="ignore"):
            col = np.clip(np.floor(col + 0.5), 0, Wp - 1)
            row = np.clip(np.floor(row + 0.5), 0, Hp - 1)
    return ProjectorMaps(col, row, ok, exact["board"], exact["surface"], exact["lit"], exact["shadow"], xs, ys,
                         step, bool(rounded))
