"""Issue 38 on renders, not the fast path: the close scanner rig (tests/sim_scanner.py) rendered as its captures are
(3-step phase under one unit-frequency cue, 16 fringes, no white frame), the projector's gamma left for the decoder
to measure, the board lit on part of its 117 corners, through the whole pipeline (decode, corners, single pose).
Every written parameter within 3 of its ±, on both paths a user of that rig runs (slow: ~15 s a case)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from sim_scanner import scanner

from procam import models, patterns, pipeline, simulate
from procam import single_pose as sp
from procam.board import Board
from procam.calibration import Device, Distortion


def _zs(pose, gamma, known, seed):
    sc = simulate.with_board_pose(scanner(), pose)
    ps = patterns.pattern_set(1824, 1140, family="phase", steps=3, period=114, white_black=False)
    r = simulate.Renderer(sc).photometry(proj_gamma=gamma).with_patterns(ps)
    rng = np.random.default_rng(seed)
    stack = np.stack([r.frame(k, rng) for k in range(ps.count)])
    view, _ = pipeline.view_from_stack(stack, ps, Board(13, 9, 10.0), name="scan")
    cam = Device(np.array(sc.K_cam), sc.cam_size, Distortion("division", tuple(sc.cam_center), *sc.cam_dist_coeffs))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cal = sp.calibrate(view, known_camera=cam if known else None)
    Kc, Kp = np.asarray(sc.K_cam), np.asarray(sc.K_proj)
    z = {"f_p": (cal.projector.K[0, 0] - Kp[0, 0]) / cal.std["f_p"],
         "u0p": (cal.projector.K[0, 2] - Kp[0, 2]) / cal.std["u0p"],
         "v0p": (cal.projector.K[1, 2] - Kp[1, 2]) / cal.std["v0p"]}
    if not known:
        z["f_c"] = (cal.camera.K[0, 0] - Kc[0, 0]) / cal.std["f_c"]
    dR = (models.euler_deg(cal.R) - models.euler_deg(np.asarray(sc.R)) + 180.0) % 360.0 - 180.0
    z["R"] = float(np.max(np.abs(dR) / np.asarray(cal.std["R_euler_deg"])))
    z["T"] = float(np.max(np.abs(cal.T - np.asarray(sc.T)) / np.asarray(cal.std["T"])))
    return cal, int(view.valid.sum()), z


@pytest.mark.slow
@pytest.mark.parametrize("pose, gamma, known, seed", [
    ((20.0, 25.0, 3.0), 2.2, False, 5),        # 60 of 117 corners lit
    ((20.0, 25.0, 3.0), 2.8, False, 6),        # the harmonic a stronger gamma leaves after correction
    ((20.0, 25.0, 3.0), 2.2, True, 7),         # the camera given
    ((-15.0, 30.0, -4.0), 2.2, False, 8),
    ((25.0, -20.0, 2.0), 2.5, True, 9),        # k2 wanted by the likelihood ratio, not by the held-out test
])
def test_a_rendered_scanner_pose_is_within_its_pm(pose, gamma, known, seed):
    cal, lit, z = _zs(pose, gamma, known, seed)
    assert lit < 117 and cal.verdict in ("good", "weak")
    assert max(abs(v) for v in z.values()) <= 3.0, z
