"""Calibrate from three simulated poses and draw the reprojection residuals of every corner.

The residual stage: the residuals of the calibration's own model at its own board poses (whose RMS is
the RMS it reports), observed - predicted, drawn where they were observed at an automatic scale.

    python examples/plot_residuals.py [out.png]    # default: a new temporary folder
"""

import sys
import tempfile
from pathlib import Path

from procam import multi_pose, simulate
from procam.plots import save_figure
from procam.plots.residuals import residual_figure
from procam.verdict import calibration_verdict
from procam.residuals import calibration_residuals
from procam.view import View

out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="procam-")) / "residuals.png"
base = simulate.preset("paper")
views = []
for k, angles in enumerate([(15, -35, 0), (-15, 20, 5), (10, 25, -5)]):  # board (psi, nu, phi), degrees
    scene = simulate.with_board_pose(base, angles, distance=650.0)
    obj, cam, proj = simulate.correspondences(scene, sigma_cam=0.1, sigma_proj=0.2, seed=k)  # exact + noise
    views.append(View(obj, cam, proj, f"pose {k + 1}", scene.cam_size, scene.proj_size))
calib = multi_pose.calibrate(views)
print(f"RMS camera {calib.cam_rms:.3f} px, projector {calib.proj_rms:.3f} px "
      f"(corner noise 0.1 and 0.2 px per coordinate)")
fig = residual_figure(calibration_residuals(calib), base.cam_size, base.proj_size,
                      title="multi-pose calibration from 3 simulated poses", verdict=calibration_verdict(calib).line())
save_figure(fig, out)
print(f"wrote {out}")
