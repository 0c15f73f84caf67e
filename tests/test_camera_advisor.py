"""The advisor's camera mode (issue 33: the camera once, each projector from one pose) on the virtual camera: the
simulated user follows the advice (turn, tilt and move the board), the advisor takes the photos it calls for, says
"enough" at the stated target and writes the camera file -- whose camera is the simulator's within its own ±; and
the prediction machinery it uses (procam.crlb.views_bound) against the scatter of real fits."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from conftest import run_cli

from procam import crlb, io, models, multi_pose, simulate
from procam.acquire.cameras import VirtualLiveCamera
from procam.acquire.live import advise_camera, camera_calibration
from procam.advisor import CameraAdvisor
from procam.board import Board
from procam.errors import WeakPoseWarning
from procam.view import View

BOARD = ["--board", "10x6", "--square", "24"]


def room_lit(pose=(5.0, 3.0, 0.0)):
    """The small rig's camera (640x400, division distortion k1 = -4e-7) looking at the board in room light."""
    from sim_small import small_scene

    return simulate.with_board_pose(small_scene(), pose).replace(ambient=0.8, gain=0.5)


def test_the_camera_mode_guides_the_photos_to_enough_and_writes_the_camera(tmp_path):
    scene = room_lit()
    board = Board(scene.board_cols, scene.board_rows, scene.square)
    cam = VirtualLiveCamera(scene, seed=4)
    adv = CameraAdvisor(board, scene.cam_size)
    seen = []
    res = advise_camera(cam, adv, auto=True, max_frames=40, on_advice=lambda img, a: seen.append(a))
    assert res.reason == "enough" and adv.enough, [a.message for a in seen]
    taken = [a for a in seen if a.state == "take"]
    assert 4 <= len(adv.views) == len(taken) <= 8
    # after each photo the predicted ± of f_c falls (once determined) and the corners reach more of the image
    pct = [a.with_this["f_c_pct"] for a in taken if a.with_this is not None]
    assert len(pct) >= 3 and all(b < a for a, b in zip(pct, pct[1:])), pct
    assert seen[-1].coverage >= 7 / 9 and seen[-1].now["f_c_pct"] <= 0.2 and max(
        seen[-1].now["u0c"], seen[-1].now["v0c"]) <= 2.0
    assert any(act.kind in ("turn", "tilt") for a in seen if a.state == "adjust" for act in a.actions)
    calib = camera_calibration(adv, tmp_path / "cam.json")
    back = io.load_calibration(tmp_path / "cam.json")
    cov = back.info["covariance"]
    std = dict(zip(cov["params"], np.sqrt(np.diag(cov["matrix"]))))
    K, K_true = np.asarray(back.camera.K), np.asarray(scene.K_cam)
    assert calib.verdict == "good" and back.info["calibrated_from"]["count"] == len(adv.views)
    for (i, j), name in (((0, 0), "f_c"), ((1, 1), "fy_c"), ((0, 2), "u0c"), ((1, 2), "v0c")):
        # the truth within 4 of the file's own ± (the corners' noise; the lens is the division model, fitted by
        # OpenCV's polynomial) and within the targets
        assert abs(K[i, j] - K_true[i, j]) <= 4 * std[name] + 0.05, (name, K[i, j], K_true[i, j], std[name])
    assert abs(K[0, 0] / K_true[0, 0] - 1) < 0.002 and np.hypot(*(K[:2, 2] - K_true[:2, 2])) < 2.0


def test_the_camera_mode_on_the_command_line(tmp_path):
    """(The whole way to "enough" is the test above, on the library.)"""
    # stopped early: the photos so far are written, and the exit code says the camera is not determined
    code, out, err = run_cli(["advise", "--mode", "camera", "--camera", "virtual", *BOARD, "--auto",
                              "--max-frames", "3", "-o", tmp_path / "early.json", "--json"])
    assert code == 3 and "not enough" in err and (tmp_path / "early.json").exists()
    lines = [json.loads(s) for s in out.splitlines()]
    assert len(lines) == 3 and lines[0]["mode"] == "camera" and lines[0]["state"] == "take"
    code, _, err = run_cli(["advise", "--mode", "camera", "--camera", "virtual", *BOARD])
    assert code == 2 and "-o" in err


def test_the_predicted_covariance_is_the_scatter_of_real_fits():
    """views_bound at the truth (5 photos, 0.1 px corner noise) against the std of f_c, u0c over 40 seeded
    calibrate_camera fits of noisy corners (the same OpenCV model, k1 k2 p1 p2 k3): within 30 % (40 samples
    estimate a std to ~11 %)."""
    K = models.intrinsic_matrix(1200.0, 640.0, 400.0, alpha=1.0)
    coeffs = np.array([-0.12, 0.08, 0.0005, -0.0003, 0.0])
    board = Board(10, 6, 24.0)
    obj = board.object_points()
    poses = []
    for k, ang in enumerate([(25, 10, 0), (-20, 15, 5), (10, -25, -5), (-15, -20, 10), (30, -5, 0)]):
        R = models.euler_to_matrix(*np.radians(ang))
        poses.append((models.matrix_to_rvec(R), np.array([20.0 * (k - 2), 10.0 * (k % 2), 550.0])))
    import cv2

    clean = [cv2.projectPoints(obj, r, t, K, coeffs)[0].reshape(-1, 2) for r, t in poses]
    b = crlb.views_bound(K, coeffs, poses, obj, 0.1)
    rng = np.random.default_rng(7)
    fits = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", WeakPoseWarning)
        for _ in range(40):
            views = [View(obj, m + rng.normal(0, 0.1, m.shape), np.full_like(m, np.nan), f"p{k}", (1280, 800), None,
                          board=board) for k, m in enumerate(clean)]
            c = multi_pose.calibrate_camera(views, dist="k1k2p1p2k3")
            fits.append(np.asarray(c.camera.K)[[0, 0, 1], [0, 2, 2]])
    fits = np.array(fits)
    for k, name in enumerate(("f_c", "u0c", "v0c")):
        assert fits[:, k].std(ddof=1) == pytest.approx(b.std[name], rel=0.3), name


def test_the_projector_mode_predicts_the_pm_of_the_one_pose_calibration_with_the_camera_known():
    """The pose mode with the camera known (its file; the projector side from an earlier calibration, here the
    simulator's) predicts, before the capture, the ± of f_p and v0p the single-pose calibration with that camera
    then reports -- within a factor of 3: the bound frees f_p, v0p and the pose on the board samples' grid with a
    nominal noise (0.05 px), the fit also frees u0p under its 3 % prior and the lens terms its evidence picks, and
    widens by its block jackknife where the residuals are correlated (reported / predicted 0.3-2.5 over six poses
    of this rig).  The corners-only bound of a free camera's pose overstates it many times."""
    from sim_small import small_scene

    from procam import patterns, pipeline, single_pose
    from procam.advisor import Advisor, AdvisorOptions, ProjectorSide
    from procam.calibration import Device, Distortion

    s = simulate.with_board_pose(small_scene(), (20.0, 15.0, 0.0), frame="projector")
    board = Board(s.board_cols, s.board_rows, s.square)
    cam = Device(np.array(s.K_cam), s.cam_size, Distortion("division", tuple(s.cam_center), *s.cam_dist_coeffs))
    ps = patterns.pattern_set(*s.proj_size)
    stack, _ = simulate.render(s, ps, seed=2)
    side = ProjectorSide(np.array(s.K_proj), tuple(s.proj_size), np.array(s.R), np.array(s.T), "earlier")
    adv = Advisor(board, s.cam_size, AdvisorOptions(), projector=side)
    before = adv.update(stack[ps.white], 0.0).projector          # the camera's intrinsics guessed, estimated
    adv.set_camera(cam, "cam.json", known=True)
    a = adv.update(stack[ps.white], 0.1)
    assert a.camera.std_f == 0.0 and "known" in a.intrinsics
    view, _ = pipeline.view_from_stack(stack, ps, board, name="pose")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        calib = single_pose.calibrate(view, known_camera=cam)
    assert calib.method == "single-pose, camera given" and calib.trusted
    for pred, name in ((a.projector.std_f, "f_p"), (a.projector.std_v0, "v0p")):
        assert 1 / 3 <= calib.std[name] / pred <= 3, (name, calib.std[name], pred)
    assert before.std_f > 3 * calib.std["f_p"]


def test_the_pose_mode_with_a_known_camera_on_the_command_line(tmp_path):
    """procam advise --known-camera cam.json --calibration earlier.json: the camera is held (its std 0, no camera
    term limits the pose), the projector's ± is the known-camera prediction; a camera file of another size is
    refused with exit 2."""
    from procam.calibration import Calibration

    scene = simulate.preset("ideal")
    truth = simulate.truth_calibration(scene)
    io.save_calibration(truth, tmp_path / "earlier.json")
    io.save_calibration(Calibration(truth.camera, None, None, None, "camera-only"), tmp_path / "cam.json")
    args = ["advise", "--camera", "virtual", *BOARD, "--json", "--max-frames", "1", "--calibration",
            tmp_path / "earlier.json"]
    code, out, err = run_cli(args + ["--known-camera", tmp_path / "cam.json"])
    assert code == 0, err
    a = json.loads(out.splitlines()[-1])
    assert a["camera"]["std_f"] == 0.0 and "known" in a["intrinsics"] and not a["limiting"].startswith("f_c")
    assert "board samples" in a["projector"]["assumes"] and a["projector"]["std_f"] > 0
    code, out, err = run_cli(args)  # the camera re-estimated from the pose: the corners' bound, larger
    assert code == 0, err
    assert json.loads(out.splitlines()[-1])["projector"]["std_f"] > 2 * a["projector"]["std_f"]
    small = Calibration(truth.camera.__class__(truth.camera.K, (640, 400), truth.camera.distortion), None, None,
                        None, "camera-only")
    io.save_calibration(small, tmp_path / "small.json")
    code, _, err = run_cli(args + ["--known-camera", tmp_path / "small.json"])
    assert code == 2 and "640x400" in err
