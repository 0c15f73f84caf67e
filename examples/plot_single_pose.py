"""Single-pose calibration from noisy synthetic correspondences, compared with the truth, and its residuals.

One pose of the board (the recommended one: turned about both axes of both devices) is enough for the
camera's intrinsics and lens distortion, the projector's intrinsics and the camera -> projector pose.

    python examples/plot_single_pose.py [out.png]    # default: a new temporary folder
"""

import sys
import tempfile
from pathlib import Path

import numpy as np

from procam import simulate, single_pose
from procam.plots import save_figure
from procam.plots.residuals import residual_figure
from procam.verdict import calibration_verdict
from procam.residuals import calibration_residuals
from procam.view import View

out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="procam-")) / "single_pose.png"
scene = simulate.with_board_pose(simulate.preset("ideal"), (20.0, 15.0, 0.0))  # board (psi, nu, phi), degrees
obj, cam, proj = simulate.correspondences(scene, sigma_cam=0.1, sigma_proj=0.2, seed=0)  # exact + noise, px
view = View(obj, cam, proj, "synthetic", scene.cam_size, scene.proj_size)
# the 'ideal' rig's projector has its principal point at the panel's centre, as the paper's model assumes; say so,
# or the rating adds what that assumption could cost a real projector (corners alone cannot measure u0p)
calib = single_pose.calibrate(view, rating_options=single_pose.RatingOptions(u0p_spread_fraction=0.0))
truth = simulate.truth(scene)
print(f"f_c = {calib.camera.K[0, 0]:.1f} ± {calib.std['f_c']:.1f} px (true {truth['camera']['f']})")
print(f"f_p = {calib.projector.K[0, 0]:.1f} ± {calib.std['f_p']:.1f} px (true {truth['projector']['f']})")
print(f"|T| = {np.linalg.norm(calib.T):.1f} mm (true {truth['extrinsics']['baseline']:.1f})")
print("advice:", calib.poses[0]["advice"]["camera"]["message"], "/", calib.poses[0]["advice"]["projector"]["message"])
fig = residual_figure(calibration_residuals(calib), scene.cam_size, scene.proj_size,
                      title="single-pose calibration of one simulated pose", verdict=calibration_verdict(calib).line())
save_figure(fig, out)
print(f"wrote {out}")
