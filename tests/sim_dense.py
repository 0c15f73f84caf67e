"""The fast path of a decoded pose with dense samples: the simulator's exact geometry plus Gaussian noise, no render.

The corners are :func:`procam.simulate.correspondences` (exact plus noise of the size procam's fitted corners
have); the samples are the exact projector coordinates (through the projector's lens, occlusions and shadows
included) at the centres of a grid of ``step``-pixel windows on the board and on the scene behind it, plus
Gaussian noise of the size a window mean of a Gray-code decode has (``sigma_sample``, measured on renders by
``benchmarks/real_projector.py``). A window is kept when its grid neighbours see the same surface, lit, as a
decode's windows must be wholly on one surface. Rendered captures (slow tests) check the whole pipeline.
"""

from __future__ import annotations

import numpy as np


def _eroded(mask):
    m = mask.copy()
    m[1:, :] &= mask[:-1, :]
    m[:-1, :] &= mask[1:, :]
    m[:, 1:] &= mask[:, :-1]
    m[:, :-1] &= mask[:, 1:]
    return m


def harmonic(pp, proj_size, amp_px: float, periods: int = 16, order: int = 3):
    """The systematic error (M, 2) px a phase-shift decode leaves at projector points ``pp`` (M, 2): an ``order``-th
    harmonic of the fringe (3 for 3-step phase shift under a residual projector gamma) of amplitude ``amp_px``, each
    axis on its own fringes of ``periods`` across the panel."""
    out = np.zeros_like(pp)
    for a in range(2):
        P = proj_size[a] / periods
        out[:, a] = amp_px * np.sin(order * 2 * np.pi * pp[:, a] / P + 0.7)
    return out


def dense_view(scene, *, seed: int = 0, sigma_cam: float = 0.02, sigma_proj: float = 0.05,
               sigma_sample: float = 0.03, step: int = 11, background: bool = True, name: str = "fast",
               lit=None, harmonic_px: float = 0.0, edge_bias_px: float = 0.0, edge_rings: int = 2):
    """A :class:`procam.view.View` of ``scene`` with board samples and (by ``background``) background samples.

    What a second real rig adds (issue 38; the defaults add nothing and draw no random numbers):

    lit : ``(axis, limit)``: the projector lights only panel points with coordinate ``axis`` (0 = x, 1 = y) below
        ``limit`` (px): the board partly lit; corners and samples beyond it are not decoded.
    harmonic_px : amplitude (projector px) of a 3-step phase decode's third harmonic (:func:`harmonic`, 16 fringes),
        on the projector corners and every sample.
    edge_bias_px : the samples within ``edge_rings`` windows of the lit board's edge (the board's rim and the lit
        region's edge) are off by this many projector px, pointing out of the lit board (a window partly dark).
    """
    from procam import simulate
    from procam.view import Samples, View

    obj, cam, proj = simulate.correspondences(scene, sigma_cam, sigma_proj, seed=seed)
    m = simulate.true_projector_maps(scene, step=step)
    rng = np.random.default_rng(seed + 1000)
    xx, yy = np.meshgrid(m.x, m.y)
    lit_px = np.isfinite(m.col) & np.isfinite(m.row)
    if lit is not None:
        axis, limit = lit
        with np.errstate(invalid="ignore"):
            lit_px &= (m.col if axis == 0 else m.row) < limit
        proj[~(proj[:, axis] < limit)] = np.nan
    on_board = _eroded(m.lit_board & lit_px)
    off = lit_px & (m.surface >= 1)
    same = np.zeros_like(off)
    for k in np.unique(m.surface[off]):
        same |= _eroded(off & (m.surface == k))
    # the board with its margin is not background: leave two windows' margin around it
    near_board = _eroded(_eroded(~(m.board | m.lit_board)))
    off_board = same & near_board

    def samples(mask):
        pts = np.column_stack([xx[mask], yy[mask]])
        pp = np.column_stack([m.col[mask], m.row[mask]]) + sigma_sample * rng.standard_normal((int(mask.sum()), 2))
        return Samples(pts, pp, np.full(len(pts), sigma_sample), window=step)

    board = samples(on_board)
    if harmonic_px:
        proj = proj + harmonic(np.nan_to_num(proj), scene.proj_size, harmonic_px)
        board = Samples(board.cam_pts, board.proj_pts + harmonic(board.proj_pts, scene.proj_size, harmonic_px),
                        board.sigma, window=step)
    if edge_bias_px:
        inner = on_board
        for _ in range(edge_rings):
            inner = _eroded(inner)
        rim = (on_board & ~inner)[on_board]
        c = np.mean(board.proj_pts, axis=0)
        d = board.proj_pts - c
        d /= np.linalg.norm(d, axis=1, keepdims=True).clip(1e-9)
        pp = board.proj_pts + np.where(rim[:, None], edge_bias_px * d, 0.0)
        board = Samples(board.cam_pts, pp, board.sigma, window=step)
    back = samples(off_board) if background else None
    return View(obj, cam, proj, name, scene.cam_size, scene.proj_size, background=back, board_samples=board)
