"""The second real rig of issue 38 on the simulator: a structured-light scanner's camera and projector close to a
small board (shared by ``benchmarks/sigma_rigs.py`` and the tests).

Camera 1688x1352, f_c 2400 px; projector 1824x1140, f_p 2300 px, its principal point at the panel's last row
(lens shift), OpenCV k1 -0.05, k2 0.01; the projector ``baseline`` mm beside the camera, turned so its panel's
centre lights the point ``distance`` mm ahead of the camera; a 13x9 board (inner corners) of 10 mm squares with an
8 mm margin; the default wall 250 mm behind the board.
"""

from __future__ import annotations

import numpy as np


def _look_at(C, target, K, size):
    """Camera -> device rotation of a device at ``C`` (camera frame, mm) whose panel centre lights ``target``."""
    from scipy.spatial.transform import Rotation

    d = np.asarray(target, float) - C
    d /= np.linalg.norm(d)
    r = np.linalg.solve(K, [(size[0] - 1) / 2, (size[1] - 1) / 2, 1.0])
    r /= np.linalg.norm(r)
    down = np.array([0.0, 1.0, 0.0])          # the devices share the camera's down (image y)
    z = d
    x = np.cross(down, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    R0 = np.array([x, y, z])                  # camera frame -> a frame whose z is d
    ax = np.cross([0.0, 0.0, 1.0], r)
    ang = np.arcsin(np.linalg.norm(ax))
    Ra = Rotation.from_rotvec(ax / np.linalg.norm(ax) * ang).as_matrix() if ang > 0 else np.eye(3)
    return Ra @ R0


def scanner(baseline: float = 110.0, distance: float = 365.0, name: str = "scanner"):
    """The scanner rig (module docstring) as a :class:`procam.simulate.Scene`, the board not yet placed."""
    from procam import simulate

    Wp, Hp = 1824, 1140
    Kp = np.array([[2300.0, 0, Wp / 2 - 0.5 + 14], [0, 2300.0, float(Hp)], [0, 0, 1]])
    C = np.array([baseline, 0.0, 0.0])
    R = _look_at(C, [0.0, 0.0, distance], Kp, (Wp, Hp))
    Kc = np.array([[2400.0, 0, 1688 / 2 - 0.5 + 9], [0, 2400.0 * 1.0005, 1352 / 2 - 0.5 - 6], [0, 0, 1]])
    return simulate.Scene(cam_size=(1688, 1352), K_cam=Kc, cam_dist_coeffs=(-2e-8, 0.0), proj_size=(Wp, Hp),
                          K_proj=Kp, proj_distortion="opencv", proj_dist_coeffs=(-0.05, 0.01, 0.0, 0.0, 0.0),
                          R=R, T=-R @ C, board_cols=13, board_rows=9, square=10.0, margin=8.0,
                          wall_offset=250.0, name=name)


def far_rig(name: str = "far"):
    """The first real rig's kind (issue 38's study): narrow lenses 3 m from a large board. Camera 1920x1200, f_c
    4500 px; projector 1920x1080, f_p 4200 px, lens shift (v0p 1.1 H, u0p 25 px left of centre), OpenCV k1 -0.03;
    the projector 350 mm beside the camera converging at 3 m; a 9x6 board (inner corners) of 75 mm squares with a
    40 mm margin; the default wall 500 mm behind the board. The board not yet placed."""
    from procam import simulate

    Wp, Hp = 1920, 1080
    Kp = np.array([[4200.0, 0, Wp / 2 - 0.5 - 25], [0, 4200.0, 1.1 * Hp], [0, 0, 1]])
    C = np.array([350.0, 0.0, 0.0])
    R = _look_at(C, [0.0, 0.0, 3000.0], Kp, (Wp, Hp))
    Kc = np.array([[4500.0, 0, 959.5 + 12], [0, 4500.0, 599.5 - 7], [0, 0, 1]])
    return simulate.Scene(cam_size=(1920, 1200), K_cam=Kc, cam_dist_coeffs=(-5e-9, 0.0), proj_size=(Wp, Hp),
                          K_proj=Kp, proj_distortion="opencv", proj_dist_coeffs=(-0.03, 0.0, 0.0, 0.0, 0.0),
                          R=R, T=-R @ C, board_cols=9, board_rows=6, square=75.0, margin=40.0,
                          wall_offset=500.0, name=name)
