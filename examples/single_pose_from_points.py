"""Single-pose calibration from noisy synthetic correspondences, compared with the truth and the CRLB.

    python examples/single_pose_from_points.py
"""

import numpy as np

from procam import simulate, single_pose
from procam.view import View

scene = simulate.with_board_pose(simulate.preset("ideal"), (20.0, 15.0, 0.0))
obj, cam, proj = simulate.correspondences(scene, sigma_cam=0.1, sigma_proj=0.2, seed=0)
view = View(obj, cam, proj, "synthetic", scene.cam_size, scene.proj_size)
calib = single_pose.calibrate(view)
truth = simulate.truth(scene)
print(f"f_c = {calib.camera.K[0, 0]:.1f} ± {calib.std['f_c']:.1f} px (true {truth['camera']['f']})")
print(f"f_p = {calib.projector.K[0, 0]:.1f} ± {calib.std['f_p']:.1f} px (true {truth['projector']['f']})")
print(f"|T| = {np.linalg.norm(calib.T):.1f} mm (true {truth['extrinsics']['baseline']:.1f})")
print("advice:", calib.poses[0]["advice"]["camera"]["message"], "/", calib.poses[0]["advice"]["projector"]["message"])
