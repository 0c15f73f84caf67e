"""The renderer: physically plausible Gray-code captures of a :class:`~procam.simulate.Scene`.

Per camera pixel a ray (supersampled), board / wall albedo, projector illumination with defocus and
black level, the board's shadow on the wall, ambient light, gain, vignetting, optical blur, shot and
read noise, gamma, 8/16-bit output.  The geometry is computed once per scene (:class:`Renderer`);
each pattern image is then a cheap 1-D profile lookup, because Gray-code stripes depend on one
projector coordinate only.

* :func:`render` - the whole sequence at once, with its ground truth.
* :class:`Renderer` - one pattern image at a time (:meth:`Renderer.frame`), e.g. for a simulated
  camera that is triggered per projected pattern.
* :func:`true_projector_maps` - the exact projector coordinates seen at every camera pixel.
* :func:`write_capture` - a rendered capture in procam's capture-folder layout (thin over
  :func:`procam.capture.write_sequence`).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Callable

import cv2
import numpy as np

from .. import capture as _capture
from .. import patterns as _patterns
from ..io.files import to_jsonable
from .lens import undistort
from .scene import Scene, board_extent, truth

__all__ = ["Renderer", "render", "true_projector_maps", "write_capture"]


# --------------------------------------------------------------------------------------------
# rendering: geometry once per scene
# --------------------------------------------------------------------------------------------

#: Rows of the supersampled grid per band of the geometry pass. A band's float64 temporaries are then over 4 MB,
#: which NumPy asks the kernel to back with huge pages: bands of 16-64 rows page-faulted 4 times as often (up to
#: 2 s of system time for a 1280x800 camera at 3x3 supersamples, measured in a fresh process). Nothing else
#: depends on the band size.
GEOMETRY_BAND = 288

#: Samples per projector pixel of the 1-D stripe profiles looked up by ``cv2.remap``.
PROFILE_UPSAMPLE = 8


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


def _geometry_band(scene: Scene, ys, xs):
    """Per-sample geometry for the sample grid ``ys`` x ``xs`` (camera pixel coordinates).

    Returns dict of (len(ys), len(xs)) arrays: ``xp``, ``yp`` projector coords (NaN where no
    surface), ``coef`` = gain * albedo * irradiance factor where lit by the projector (0 elsewhere),
    ``amb`` = gain * albedo * ambient, ``board`` (bool, the ray hits the board), ``lit`` (bool).
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
        # wall plane
        nw = scene.wall_normal
        pw = tb + scene.wall_offset * np.array([0.0, 0.0, 1.0])
        sw = (nw @ pw) / (dx * nw[0] + dy * nw[1] + nw[2])
        on_wall = np.isfinite(sw) & (sw > 0)
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

        albedo = np.where(wall, scene.albedo_wall, 0.0)
        albedo[board] = _board_albedo(scene, bx[board], by[board], footprint(bx)[board], footprint(by)[board])
        del bx, by

        # projector coordinates
        R, T, Kp = scene.R, scene.T, scene.K_proj
        Xp = R[0, 0] * X + R[0, 1] * Y + R[0, 2] * Z + T[0]
        Yp = R[1, 0] * X + R[1, 1] * Y + R[1, 2] * Z + T[1]
        Zp = R[2, 0] * X + R[2, 1] * Y + R[2, 2] * Z + T[2]
        xp = Kp[0, 0] * Xp / Zp + Kp[0, 1] * Yp / Zp + Kp[0, 2]
        yp = Kp[1, 1] * Yp / Zp + Kp[1, 2]
        Wp, Hp = scene.proj_size
        front = Zp > 0
        in_panel = front & (xp >= -0.5) & (xp <= Wp - 0.5) & (yp >= -0.5) & (yp <= Hp - 0.5)

        # shading
        Cp = scene.proj_center_cam
        Lx, Ly, Lz = Cp[0] - X, Cp[1] - Y, Cp[2] - Z
        dist2 = Lx * Lx + Ly * Ly + Lz * Lz
        cos_p = Zp / np.sqrt(Xp * Xp + Yp * Yp + Zp * Zp)  # projector field angle
        nx = np.where(board, nb[0], nw[0])
        ny = np.where(board, nb[1], nw[1])
        nz = np.where(board, nb[2], nw[2])
        ndotl = nx * Lx + ny * Ly + nz * Lz
        ndotv = -(nx * X + ny * Y + nz * Z)
        facing = (ndotl * ndotv) > 0
        d_ref2 = float(np.sum((Cp - tb) ** 2))
        irr = np.abs(ndotl) / np.sqrt(dist2) * (d_ref2 / dist2) * np.abs(cos_p) ** scene.proj_vignetting
        del nx, ny, nz, ndotv, ndotl, dist2, Xp, Yp, Zp, cos_p

        # the board's shadow on the wall, as the projector sees it
        uu = (nb @ tb - (X * nb[0] + Y * nb[1] + Z * nb[2])) / (Lx * nb[0] + Ly * nb[1] + Lz * nb[2])
        qx, qy, qz = X + uu * Lx - tb[0], Y + uu * Ly - tb[1], Z + uu * Lz - tb[2]
        sx = qx * Rb[0, 0] + qy * Rb[1, 0] + qz * Rb[2, 0]
        sy = qx * Rb[0, 1] + qy * Rb[1, 1] + qz * Rb[2, 1]
        shadow = wall & (uu > 1e-9) & (uu < 1) & (sx >= x0) & (sx <= x1) & (sy >= y0) & (sy <= y1)
    finally:
        err.__exit__(None, None, None)

    # the panel's edges are left to the (defocused) panel masks of the renderer; `lit` is the truth mask
    illuminated = surf & front & facing & ~shadow
    lit = illuminated & in_panel
    coef = np.where(illuminated, scene.gain * albedo * irr * cam_vig, 0.0)
    amb = scene.gain * scene.ambient * albedo * cam_vig
    xp = np.where(surf, xp, np.nan)
    yp = np.where(surf, yp, np.nan)
    return {"xp": xp, "yp": yp, "coef": coef, "amb": amb, "board": board, "lit": lit}


def _sample_grid(n_pix: int, s: int) -> np.ndarray:
    """Sample positions (pixel coordinates) of ``s`` supersamples per pixel: pixel i covers [i-.5, i+.5]."""
    return (np.arange(n_pix * s) + 0.5) / s - 0.5


def _geometry_bands(scene: Scene, s: int, work: Callable, band_rows: int = 288) -> None:
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


def true_projector_maps(scene: Scene):
    """Exact projector coordinates seen at every camera pixel centre.

    Returns
    -------
    col, row : (H, W) float64, projector x / y (pixels) of the surface (board or wall) seen at the
        pixel centre where it is lit by the projector, NaN elsewhere (outside the projector image,
        in the board's shadow, or no surface).
    lit_board : (H, W) bool, pixels lying entirely on the board (every supersample of the pixel)
        and entirely lit by the projector.
    """
    s = scene.supersample
    W, H = scene.cam_size
    g = _geometry(scene, s=s)
    ok = (g["board"] & g["lit"]).reshape(H, s, W, s).all(axis=(1, 3))
    del g
    exact = _geometry_band(scene, np.arange(H, dtype=float), np.arange(W, dtype=float))
    col = np.where(exact["lit"], exact["xp"], np.nan)
    row = np.where(exact["lit"], exact["yp"], np.nan)
    return col, row, ok


# --------------------------------------------------------------------------------------------
# rendering: the image sequence
# --------------------------------------------------------------------------------------------

def _profile(values: np.ndarray, sigma: float, pad: int):
    """Upsampled, defocused 1-D light profile of a projector line ``values`` (n,) in [0, 1].

    Sample ``q`` of the result is at projector coordinate ``(q - pad + 0.5) / U - 0.5`` with
    ``U = PROFILE_UPSAMPLE`` (projector pixel i covers [i - .5, i + .5]); zero outside the panel.
    """
    U = PROFILE_UPSAMPLE
    line = np.zeros(len(values) * U + 2 * pad, dtype=np.float32)
    line[pad:pad + len(values) * U] = np.repeat(values.astype(np.float32), U)
    if sigma > 0:
        line = cv2.GaussianBlur(line[None, :], (0, 0), sigmaX=sigma * U, sigmaY=1e-6,
                                borderType=cv2.BORDER_CONSTANT)[0]
    return line[None, :]


def _to_profile_map(p: np.ndarray, pad: int) -> np.ndarray:
    """Projector coordinates -> sample index of :func:`_profile` (float32; far outside where NaN)."""
    q = (p.astype(np.float64) + 0.5) * PROFILE_UPSAMPLE - 0.5 + pad
    return np.where(np.isfinite(q), q, -1e6).astype(np.float32)


class Renderer:
    """One scene's Gray-code capture, one pattern image at a time.

    The geometry (camera rays, surfaces, shading, projector coordinates per supersample) is computed
    here, once: it is most of the cost of a capture.  Each :meth:`frame` is then a 1-D profile
    lookup, the camera's blur and noise, gamma and quantisation.

    Parameters
    ----------
    scene : the set-up (board pose, photometry, bit depth, supersampling).
    order : pattern sequence order, ``"opencv"`` or ``"moreno"`` (see :mod:`procam.patterns`).

    Attributes
    ----------
    scene : Scene
    pattern_set : procam.patterns.PatternSet
        The sequence: ``pattern_set.count`` images (46 for a 1920x1080 projector), the white and
        black frames at ``pattern_set.white`` / ``pattern_set.black``.

    Examples
    --------
    Frames ``0, 1, ...`` drawn in order with one generator are :func:`render`'s images, bit for bit::

        r = Renderer(scene, "opencv")
        rng = np.random.default_rng(seed)
        images = [r.frame(k, rng) for k in range(r.pattern_set.count)]  # == render(scene, seed=seed)[0]
    """

    def __init__(self, scene: Scene, order: str = "opencv"):
        self.scene = scene
        self.pattern_set = _patterns.pattern_set(*scene.proj_size, order)
        Wp, Hp = scene.proj_size
        self.pad = int(np.ceil(4 * max(scene.proj_defocus, 0.25) * PROFILE_UPSAMPLE)) + PROFILE_UPSAMPLE
        s = scene.supersample
        W, H = scene.cam_size
        shape = (H * s, W * s)
        self.sigma = scene.proj_defocus
        # float32 maps (faster than fixed-point ones for a one-row source image); the y map of the one-row profile
        # is all zeros: one band of it serves every band
        self.mapx, self.mapy, self.coef_cols, self.coef_rows, self.full, self.amb = (
            np.empty(shape, np.float32) for _ in range(6))
        self._zeros = np.zeros((max(self.BAND * s, GEOMETRY_BAND), W * s), np.float32)
        ones_x = _profile(np.ones(Wp), self.sigma, self.pad)
        ones_y = _profile(np.ones(Hp), self.sigma, self.pad)

        def work(r0, r1, g):  # the geometry of rows r0:r1, as stored by _geometry, into the lookup tables
            b = slice(r0, r1)
            self.mapx[b] = _to_profile_map(g["xp"].astype(np.float32), self.pad)
            self.mapy[b] = _to_profile_map(g["yp"].astype(np.float32), self.pad)
            mask_x = self._lookup(ones_x, "x", b)
            mask_y = self._lookup(ones_y, "y", b)
            coef = g["coef"].astype(np.float32)
            self.coef_cols[b] = coef * mask_y          # column patterns vary with x only
            self.coef_rows[b] = coef * mask_x          # row patterns vary with y only
            self.full[b] = coef * mask_x * mask_y      # a white panel
            self.amb[b] = g["amb"]

        # band by band: no full-size intermediates (the float64 maps, the masks, the products)
        _geometry_bands(scene, s, work, GEOMETRY_BAND)
        self.col_planes = _patterns.bit_planes(Wp, self.pattern_set.col_bits, self.pattern_set.col_offset)
        self.row_planes = _patterns.bit_planes(Hp, self.pattern_set.row_bits, self.pattern_set.row_offset)
        self.index = {}
        for j, (a, b) in enumerate(self.pattern_set.pair_indices("col")):
            self.index[int(a)], self.index[int(b)] = ("col", j, False), ("col", j, True)
        for j, (a, b) in enumerate(self.pattern_set.pair_indices("row")):
            self.index[int(a)], self.index[int(b)] = ("row", j, False), ("row", j, True)

    #: camera rows per band of :meth:`linear` (its buffer is then over 4 MB: huge pages, few page faults)
    BAND = 96

    def _lookup(self, profile, axis, rows: slice, out=None):
        m = (self.mapx if axis == "x" else self.mapy)[rows]
        return cv2.remap(profile, m, self._zeros[:m.shape[0]], cv2.INTER_LINEAR, dst=out,
                         borderMode=cv2.BORDER_CONSTANT, borderValue=0)

    def frame(self, k: int, rng: np.random.Generator) -> np.ndarray:
        """Image ``k`` of the sequence as the camera records it.

        Parameters
        ----------
        k : index in the sequence, ``0 <= k < pattern_set.count``.
        rng : the noise source; one generator used for frames ``0, 1, ...`` in order gives
            :func:`render`'s images.

        Returns
        -------
        (H, W) uint8 (``scene.bits == 8``) or uint16 (full scale 65535).
        """
        return self.finish(self.linear(k), rng)

    def linear(self, k: int) -> np.ndarray:
        """Noise-free linear camera image k (H, W) float32 (fraction of full scale), before blur."""
        if not 0 <= k < self.pattern_set.count:
            raise IndexError(f"frame {k} is outside the sequence of {self.pattern_set.count} images")
        sc = self.scene
        black = sc.proj_black
        prof = axis = None
        if k not in (self.pattern_set.white, self.pattern_set.black):
            axis, j, inv = self.index[k]
            plane = self.col_planes[j] if axis == "col" else self.row_planes[j]
            if inv:
                plane = ~plane
            prof = _profile(black + (1.0 - black) * plane, self.sigma, self.pad)
        W, H = sc.cam_size
        s = self.mapx.shape[0] // H  # supersamples per pixel and axis
        out = np.empty((H, W), np.float32)
        buf = np.empty((self.BAND * s, W * s), np.float32)
        # in bands of camera rows, in one buffer: no supersampled temporaries of the whole image (37 MB each for a
        # 1280x800 camera at 3x3); every step is per pixel (the area average per block of s x s samples), so the
        # bands and the in-place operations give the same numbers as whole-image ones
        for y0 in range(0, H, self.BAND):
            y1 = min(H, y0 + self.BAND)
            b = slice(y0 * s, y1 * s)
            hi = buf[:(y1 - y0) * s]
            if k == self.pattern_set.white:
                np.add(self.full[b], self.amb[b], out=hi)
            elif k == self.pattern_set.black:
                np.multiply(self.full[b], black, out=hi)
                hi += self.amb[b]
            else:
                self._lookup(prof, "x" if axis == "col" else "y", b, out=hi)
                hi *= self.coef_cols[b] if axis == "col" else self.coef_rows[b]
                hi += self.amb[b]
            cv2.resize(hi, (W, y1 - y0), dst=out[y0:y1], interpolation=cv2.INTER_AREA)
        return out

    def finish(self, lin: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Optics, noise, gamma and quantisation of a linear image."""
        sc = self.scene
        if sc.cam_blur > 0:
            lin = cv2.GaussianBlur(lin, (0, 0), sigmaX=sc.cam_blur, sigmaY=sc.cam_blur,
                                   borderType=cv2.BORDER_REFLECT)
        var = np.full_like(lin, (sc.read_noise / 255.0) ** 2)
        if sc.full_well > 0:
            var += np.maximum(lin, 0) / sc.full_well
        noisy = lin + np.sqrt(var) * rng.standard_normal(lin.shape, dtype=np.float32)
        np.clip(noisy, 0.0, 1.0, out=noisy)
        if sc.gamma != 1.0:
            noisy = noisy ** (1.0 / sc.gamma)
        top = 255 if sc.bits == 8 else 65535
        return np.rint(noisy * top).astype(np.uint8 if sc.bits == 8 else np.uint16)


def render(scene: Scene, order: str = "opencv", seed: int = 0,
           progress: Callable[[int, int], None] | None = None):
    """Render the full Gray-code capture of ``scene``.

    Parameters
    ----------
    scene : the set-up (board pose, photometry, bit depth, supersampling).
    order : pattern sequence order, ``"opencv"`` (default) or ``"moreno"`` (see :mod:`procam.patterns`).
    seed : noise seed; the same seed gives bit-identical images.
    progress : optional ``callable(done, total)`` called after the geometry and after each image.

    Returns
    -------
    stack : (K, H, W) uint8 (``bits=8``) or uint16 (``bits=16``, full scale 65535), K = 46 for a
        1920x1080 projector, in the sequence order.
    truth : dict, :func:`truth` plus ``"render"`` (order, seed, pattern set).
    """
    r = Renderer(scene, order)
    ps = r.pattern_set
    total = ps.count + 1
    if progress is not None:
        progress(1, total)
    rng = np.random.default_rng(seed)
    W, H = scene.cam_size
    stack = np.empty((ps.count, H, W), dtype=np.uint8 if scene.bits == 8 else np.uint16)
    for k in range(ps.count):
        stack[k] = r.frame(k, rng)
        if progress is not None:
            progress(k + 2, total)
    t = truth(scene)
    t["render"] = {"order": order, "seed": int(seed), "count": int(ps.count),
                   "white": int(ps.white), "black": int(ps.black),
                   "pattern_set": ps.to_dict()}
    return stack, to_jsonable(t)


# --------------------------------------------------------------------------------------------
# output
# --------------------------------------------------------------------------------------------

def write_capture(out_dir, stack: np.ndarray, truth: dict, order: str = "opencv", *, force: bool = False) -> list[Path]:
    """Write a rendered capture in procam's default capture-folder layout.

    Files: ``00.png`` ... ``45.png`` (zero-padded index, sequence order), ``truth.json`` (``truth``),
    ``patterns.json`` (:meth:`procam.patterns.PatternSet.to_dict` plus ``"files"``) and the manifest
    ``.procam-manifest.json``.  Every file is written under a hidden temporary name and renamed
    (:func:`procam.capture.write_sequence`), so an interrupted run leaves no half-written image that a
    loader would pick up.  ``out_dir`` must be new, empty or an earlier simulator output; ``force`` writes
    into another folder, but never over (or deletes) a file procam did not write.  Numbered PNGs of an
    earlier, longer simulated sequence are deleted, so they are not read as part of this one.

    Parameters
    ----------
    out_dir : folder (created if missing).
    stack : (K, H, W) uint8 or uint16 images from :func:`render`.
    truth : the truth dict from :func:`render` (its projector size names the pattern set).
    order : the sequence order the stack was rendered in.
    force : write into a folder that holds other files.

    Returns
    -------
    list of the image paths, in sequence order.  Raises :class:`procam.errors.OutputError` when the
    folder is refused.
    """
    wp, hp = truth["projector"]["size"]
    ps = _patterns.pattern_set(int(wp), int(hp), order)
    stack = np.asarray(stack)
    if stack.ndim != 3 or stack.shape[0] != ps.count:
        raise ValueError(f"stack must be ({ps.count}, H, W) for a {wp}x{hp} projector, got {stack.shape}")
    if stack.dtype not in (np.uint8, np.uint16):
        raise ValueError(f"stack must be uint8 or uint16, got {stack.dtype}")
    return _capture.write_sequence(out_dir, stack, ps, writer="simulate", force=force,
                                   extra_files={"truth.json": json.dumps(to_jsonable(truth), indent=1)})
