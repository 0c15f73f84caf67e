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


def dense_view(scene, *, seed: int = 0, sigma_cam: float = 0.02, sigma_proj: float = 0.05,
               sigma_sample: float = 0.03, step: int = 11, background: bool = True, name: str = "fast"):
    """A :class:`procam.view.View` of ``scene`` with board samples and (by ``background``) background samples."""
    from procam import simulate
    from procam.view import Samples, View

    obj, cam, proj = simulate.correspondences(scene, sigma_cam, sigma_proj, seed=seed)
    m = simulate.true_projector_maps(scene, step=step)
    rng = np.random.default_rng(seed + 1000)
    xx, yy = np.meshgrid(m.x, m.y)
    lit = np.isfinite(m.col) & np.isfinite(m.row)
    on_board = _eroded(m.lit_board & lit)
    off = lit & (m.surface >= 1)
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
    back = samples(off_board) if background else None
    return View(obj, cam, proj, name, scene.cam_size, scene.proj_size, background=back, board_samples=board)
