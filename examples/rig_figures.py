"""The blend figure of docs/rigs.md: the two_projectors rig lighting a bare wall, each projector's alpha on its
own pixels, and the sum of the alphas seen by the camera.

    python examples/rig_figures.py docs/figures

Every number drawn comes from procam (the simulator's dense fast path and procam.rig.blend).
"""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import cv2  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from procam import simulate  # noqa: E402
from procam.rig.blend import blend_masks  # noqa: E402

META = {"Creator": "procam"}


def blend_figure(path):
    rig = simulate.rig_preset("two_projectors")
    t = np.asarray(rig.template.t_board, float)
    rig = dataclasses.replace(rig, template=rig.template.replace(t_board=(t[0] + 8000.0, t[1], t[2])))
    maps, sizes = {}, {}
    for p in ("left", "right"):
        sc = rig.scene("cam", p)
        m = simulate.true_projector_maps(sc, step=2, rounded=True)
        maps[p], sizes[p] = (m.col, m.row), sc.proj_size
    b = blend_masks(maps, sizes)
    total = np.zeros(maps["left"][0].shape, np.float32)
    lit = np.zeros(total.shape, bool)
    for p, (c, r) in maps.items():
        ok = np.isfinite(c)
        lit |= ok
        total += np.where(ok, cv2.remap(b.alpha[p], np.nan_to_num(c).astype(np.float32),
                                        np.nan_to_num(r).astype(np.float32), cv2.INTER_LINEAR), 0)
    fig, ax = plt.subplots(1, 3, figsize=(13, 3.4), constrained_layout=True)
    for k, p in enumerate(("left", "right")):
        im = ax[k].imshow(b.alpha[p], cmap="gray", vmin=0, vmax=1)
        ax[k].contour(b.overlap[p], levels=[0.5], colors="tab:orange", linewidths=1)
        ax[k].set_title(f"alpha of projector '{p}' (its pixels); orange: overlap", fontsize=9)
    fig.colorbar(im, ax=ax[1], fraction=0.03)
    im = ax[2].imshow(np.where(lit, total, np.nan), cmap="viridis", vmin=0.98, vmax=1.02)
    ax[2].set_title("sum of the alphas on the wall, seen by the camera", fontsize=9)
    fig.colorbar(im, ax=ax[2], fraction=0.03)
    fig.savefig(path, metadata=META)


if __name__ == "__main__":
    out = Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    out.mkdir(parents=True, exist_ok=True)
    blend_figure(out / "rig_blend.png")
