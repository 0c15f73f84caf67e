"""Render a synthetic capture, find the board's corners and their projector coordinates, draw them.

The correspondence stage: each camera corner gets projector coordinates from a homography fitted
to the decoded pixels around it (Moreno & Taubin's local homographies).

    python examples/plot_correspondences.py [out.png]    # default: a new temporary folder
"""

import sys
import tempfile
from pathlib import Path

import numpy as np

from procam import board, correspond, decode, patterns, simulate
from procam.board import corners
from procam.plots import save_figure
from procam.plots.correspond import correspond_figure
from procam.view import View

out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="procam-")) / "correspondences.png"
scene = simulate.preset("paper")                             # the paper's rig, board at the recommended pose
stack, truth = simulate.render(scene, seed=0)
ps = patterns.pattern_set(*scene.proj_size)
maps = decode.decode(stack, ps)
size = (scene.board_cols, scene.board_rows)                  # inner corners (10, 6)
cam = corners.detect_corners(stack[ps.white], size)          # (60, 2) camera corners
proj, diagnostics = correspond.projector_corners(cam, maps)  # (60, 2) projector corners, NaN where one failed
err = np.linalg.norm(proj - np.array(truth["corners"]["projector"]), axis=1)
print(f"{np.isfinite(err).sum()} of {len(err)} corners; projector corners vs truth: "
      f"{np.sqrt(np.nanmean(err ** 2)):.3f} px RMS")
view = View(board.object_points(*size, scene.square), cam, proj, "synthetic", scene.cam_size, scene.proj_size,
            diagnostics)
save_figure(correspond_figure(view, stack[ps.white], title="corners and their projector coordinates"), out)
print(f"wrote {out}")
