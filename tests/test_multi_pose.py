"""Multi-pose calibration: ground truth from the simulator, lens-shifted projectors, joint refinement."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import cv2
import numpy as np
import pytest

from procam import models, multi_pose, simulate
from procam.multi_pose import bundle
from conftest import expect_warning

from procam.errors import CalibrationError, FailedEstimateWarning
from procam.view import View

CAM_DIST = (-0.12, 0.15, 0.0008, -0.0005, 0.0)
ANGLES = [(20, -15, 0), (-15, 20, 5), (10, 25, -5), (-25, -10, 0), (5, -20, 3), (-10, 10, 0), (25, 5, -3)]
SHARED = Path(__file__).resolve().parents[2] / "shared"


def _scenes(base, angles, distance=650.0):
    # an explicit depth skips the simulator's depth search (slow); every board fits both images
    return [simulate.with_board_pose(base, a, distance=distance) for a in angles]


def _views(scenes, sigma_c=0.0, sigma_p=0.0, seed=0):
    out = []
    for k, sc in enumerate(scenes):
        obj, cam, proj = simulate.correspondences(sc, sigma_c, sigma_p, seed * 100 + k)
        out.append(View(obj, cam, proj, f"pose{k + 1}", sc.cam_size, sc.proj_size))
    return out


@pytest.fixture(scope="module")
def rig():
    base = dataclasses.replace(simulate.preset("paper"), cam_distortion="opencv", cam_dist_coeffs=CAM_DIST)
    return base, _scenes(base, ANGLES)


@pytest.fixture(scope="module")
def shifted_rig():
    """A lens-shifted projector: principal point 330 px below the image (v0 = 1410 > H = 1080)."""
    base = dataclasses.replace(simulate.preset("paper"), cam_distortion="opencv", cam_dist_coeffs=CAM_DIST,
                               K_proj=models.intrinsic_matrix(2421.0, 960.0, 1410.0, 1.0))
    return base, _scenes(base, ANGLES[:5], distance=1000.0)


def _rot_err_deg(Ra, Rb):
    return float(np.degrees(np.linalg.norm(models.matrix_to_rvec(Ra @ Rb.T))))


def test_noise_free_recovers_truth(rig):
    base, scenes = rig
    calib = multi_pose.calibrate(_views(scenes))
    assert calib.method == "multi-pose"
    np.testing.assert_allclose(calib.camera.K, base.K_cam, atol=1e-4)
    np.testing.assert_allclose(calib.projector.K, base.K_proj, atol=1e-4)
    np.testing.assert_allclose(calib.camera.distortion.coeffs, CAM_DIST, atol=1e-8)
    np.testing.assert_allclose(calib.projector.distortion.coeffs, 0.0, atol=1e-8)
    assert _rot_err_deg(calib.R, base.R) < 1e-7
    np.testing.assert_allclose(calib.T, base.T, atol=1e-6)
    assert calib.stereo_rms < 1e-6 and calib.cam_rms < 1e-6 and calib.proj_rms < 1e-6
    assert calib.camera.distortion.model == "opencv" and calib.camera.image_size == (1280, 800)
    # the frozen (stereoCalibrate, CALIB_FIX_INTRINSIC) stage is kept for comparison
    np.testing.assert_allclose(calib.info["frozen"]["T"], base.T, atol=1e-3)
    assert len(calib.poses) == 7 and abs(calib.poses[0]["camera_angles_deg"][0] - 20) < 1e-6


def test_noisy_recovery_and_std(rig):
    base, scenes = rig
    calib = multi_pose.calibrate(_views(scenes, 0.1, 0.2, seed=3))
    truth = {"f_c": base.K_cam[0, 0], "fy_c": base.K_cam[1, 1], "u0c": base.K_cam[0, 2], "v0c": base.K_cam[1, 2],
             "f_p": base.K_proj[0, 0], "fy_p": base.K_proj[1, 1], "u0p": base.K_proj[0, 2], "v0p": base.K_proj[1, 2]}
    est = {"f_c": calib.camera.K[0, 0], "fy_c": calib.camera.K[1, 1], "u0c": calib.camera.K[0, 2],
           "v0c": calib.camera.K[1, 2], "f_p": calib.projector.K[0, 0], "fy_p": calib.projector.K[1, 1],
           "u0p": calib.projector.K[0, 2], "v0p": calib.projector.K[1, 2]}
    for i in range(3):
        truth[f"T{i}"], est[f"T{i}"] = base.T[i], calib.T[i]
        truth[f"R{i}"] = simulate.matrix_euler(base.R)[i]
        est[f"R{i}"] = np.degrees(models.matrix_to_euler(calib.R))[i]
    std = dict(calib.std)
    for i in range(3):
        std[f"T{i}"], std[f"R{i}"] = calib.std["T"][i], calib.std["R_euler_deg"][i]
    for key, value in truth.items():
        # within 4 predicted standard deviations, and the deviations themselves are small
        assert abs(est[key] - value) < 4 * std[key], (key, est[key], value, std[key])
        assert std[key] < 4.0, key
    assert _rot_err_deg(calib.R, base.R) < 0.2
    # RMS near the injected noise: camera 0.1*sqrt(2), projector 0.2*sqrt(2) per point
    assert 0.10 < calib.cam_rms < 0.16 and 0.22 < calib.proj_rms < 0.31


def test_joint_refinement_at_least_as_close_as_frozen_stereo(rig):
    """Monte Carlo, 5 poses, sigma 0.1 / 0.2 px: RMS error over 12 trials, joint <= frozen.

    Measured over 30 trials (f_c, u0c, v0c, f_p, u0p, v0p in px; |dT| mm; R in deg):
    frozen [2.00 2.27 1.78 3.62 3.96 3.30 1.41 0.146], joint [1.55 2.31 1.70 2.32 3.52 2.65 0.71 0.124]
    (u0c is the one parameter not improved).
    """
    base, scenes = rig
    frozen, joint = [], []
    for seed in range(12):
        c = multi_pose.calibrate(_views(scenes[:5], 0.1, 0.2, seed=seed))
        fr = c.info["frozen"]
        for out, Kc, Kp, R, T in ((frozen, fr["cam_K"], fr["proj_K"], fr["R"], fr["T"]),
                                  (joint, c.camera.K, c.projector.K, c.R, c.T)):
            Kc, Kp = np.asarray(Kc), np.asarray(Kp)
            out.append([Kc[0, 0] - base.K_cam[0, 0], Kp[0, 0] - base.K_proj[0, 0],
                        np.linalg.norm(np.asarray(T) - base.T), _rot_err_deg(np.asarray(R), base.R)])
    rms_f = np.sqrt(np.mean(np.square(frozen), axis=0))
    rms_j = np.sqrt(np.mean(np.square(joint), axis=0))
    assert np.all(rms_j <= rms_f), (rms_f, rms_j)
    assert rms_j[1] < 0.8 * rms_f[1] and rms_j[2] < 0.7 * rms_f[2], (rms_f, rms_j)


def test_refinement_jacobian_matches_finite_differences(rig):
    base, scenes = rig
    views = _views(scenes[:3], 0.1, 0.2)
    objs = [v.obj_pts for v in views]
    cams = [v.cam_pts for v in views]
    projs = [v.proj_pts for v in views]
    lay = bundle.Layout(["k1k2p1p2k3", "k1k2"], 3)
    rv = [models.matrix_to_rvec(sc.R_board) + 0.01 for sc in scenes[:3]]
    tv = [sc.t_board + 1.0 for sc in scenes[:3]]
    devices = [bundle.JointDevice("camera", base.K_cam, np.array(CAM_DIST) + 0.01, "k1k2p1p2k3", np.eye(3), np.zeros(3)),
               bundle.JointDevice("projector", base.K_proj, [0.02, -0.01, 0, 0, 0], "k1k2",
                                  models.rvec_to_matrix(models.matrix_to_rvec(base.R) + 0.01), base.T)]
    x0 = lay.pack(devices, rv, tv)
    obs = [bundle.Observation(i, j, objs[j], (cams, projs)[i][j]) for j in range(3) for i in (0, 1)]
    args = (lay, obs, [np.zeros(5), np.zeros(5)], (1.0, 0.5))
    _, J = bundle.model(x0, *args, True, sparse=False)
    Jn = np.empty_like(J)
    for i in range(len(x0)):
        h = 1e-6 * max(1.0, abs(x0[i]))
        xp, xm = x0.copy(), x0.copy()
        xp[i] += h
        xm[i] -= h
        Jn[:, i] = (bundle.model(xp, *args, False) - bundle.model(xm, *args, False)) / (2 * h)
    _, Js = bundle.model(x0, *args, True, sparse=True)
    np.testing.assert_array_equal(Js.toarray(), J)  # the rig's sparse Jacobian is the pair's dense one
    assert np.abs(J - Jn).max() < 1e-6 * np.abs(Jn).max()


def test_lens_shifted_projector_principal_point_outside_image(shifted_rig):
    base, scenes = shifted_rig
    views = _views(scenes, 0.1, 0.2, seed=1)
    objs = [v.obj_pts for v in views]
    projs = [v.proj_pts for v in views]
    K0 = multi_pose.zhang_intrinsics(objs, projs, (1920, 1080))
    assert K0[1, 2] > 1080  # the closed-form start lies outside the image ...
    with pytest.raises(cv2.error):  # ... which OpenCV refuses as a guess
        cv2.calibrateCamera([o.astype(np.float32) for o in objs], [p.astype(np.float32) for p in projs],
                            (1920, 1080), K0, np.zeros(5), flags=cv2.CALIB_USE_INTRINSIC_GUESS)
    dc = multi_pose.calibrate_device(objs, projs, (1920, 1080), init="zhang")
    K, rms = dc.K, dc.rms
    assert abs(K[1, 2] - 1410) < 10 and abs(K[0, 0] - 2421) < 25 and rms < 0.35
    calib = multi_pose.calibrate(views)
    assert abs(calib.projector.K[1, 2] - 1410) < 10 and abs(calib.projector.K[0, 0] - 2421) < 25
    sd_T = np.array(calib.std["T"])
    assert np.all(np.abs(calib.T - base.T) < 4 * sd_T), (calib.T - base.T, sd_T)
    exact = _views(scenes)
    K = multi_pose.calibrate_device([v.obj_pts for v in exact], [v.proj_pts for v in exact], (1920, 1080),
                                    init="zhang").K
    np.testing.assert_allclose(K, base.K_proj, atol=1e-2)  # float32 points in OpenCV


def test_distortion_models_and_options(rig):
    base, scenes = rig
    views = _views(scenes[:4], 0.05, 0.1)
    # the frozen stereo step with an 8-term camera model puts T 420 mm off (stereo RMS ~100 px): failed, not silent
    with expect_warning(FailedEstimateWarning, match="stereo RMS"):
        c = multi_pose.calibrate(views, cam_dist="rational", proj_dist="none", refine=False)
    assert c.verdict == "failed" and "R, T do not describe the rig" in c.verdict_reasons[0]
    assert len(c.camera.distortion.coeffs) == 8
    assert np.all(np.asarray(c.projector.distortion.coeffs) == 0.0)
    assert c.std == {} and c.info["refined"] is False
    c2 = multi_pose.calibrate(views, cam_dist="k1k2p1p2k3", proj_dist="k1", loss="linear")
    assert c2.projector.distortion.coeffs[1:] == (0.0, 0.0, 0.0, 0.0)
    with pytest.raises(CalibrationError, match="unknown distortion model"):
        multi_pose.calibrate(views, cam_dist="fisheye")


def test_nan_corners_and_errors(rig):
    base, scenes = rig
    views = _views(scenes[:4])
    cam = views[0].cam_pts.copy()
    cam[[3, 17, 40]] = np.nan
    views[0] = View(views[0].obj_pts, cam, views[0].proj_pts, "holes", (1280, 800), (1920, 1080))
    c = multi_pose.calibrate(views)
    np.testing.assert_allclose(c.camera.K, base.K_cam, atol=1e-3)
    assert c.poses[0]["n_corners"] == 57
    with pytest.raises(CalibrationError, match="at least 2 poses"):
        multi_pose.calibrate(views[:1])
    nosize = [View(v.obj_pts, v.cam_pts, v.proj_pts, v.name) for v in views]
    with pytest.raises(CalibrationError, match="image sizes"):
        multi_pose.calibrate(nosize)
    few = View(views[1].obj_pts[:4], views[1].cam_pts[:4], views[1].proj_pts[:4], "tiny", (1280, 800), (1920, 1080))
    with pytest.raises(CalibrationError, match="tiny"):
        multi_pose.calibrate([views[0], few, views[2]])


def _left_corners():
    folder = SHARED / "data" / "opencv-left-right"
    if not folder.is_dir():
        pytest.skip("../shared/data/opencv-left-right not available")
    obj = np.zeros((54, 3))
    obj[:, :2] = np.mgrid[0:9, 0:6].T.reshape(-1, 2) * 25.0
    objs, imgs = [], []
    for p in sorted(folder.glob("left*.jpg")):
        img = cv2.imread(str(p), cv2.IMREAD_GRAYSCALE)
        ok, c = cv2.findChessboardCorners(img, (9, 6))
        assert ok, p.name
        c = cv2.cornerSubPix(img, c, (11, 11), (-1, -1),
                             (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.01))
        objs.append(obj)
        imgs.append(c.reshape(-1, 2).astype(float))
    return objs, imgs


def test_real_left_camera_against_published_reference():
    """OpenCV's left*.jpg (13 photos): fx = fy 536.11, cx 342.37, cy 235.60, rms 0.409 px (README)."""
    objs, imgs = _left_corners()
    assert len(objs) == 13
    dev = multi_pose.calibrate_device(objs, imgs, (640, 480), fix_aspect_ratio=True)
    K, rms = dev.K, dev.rms
    assert abs(K[0, 0] - 536.11) < 1.0 and abs(K[1, 1] - 536.11) < 1.0
    assert abs(K[0, 2] - 342.37) < 1.0 and abs(K[1, 2] - 235.60) < 1.0
    assert abs(rms - 0.409) < 0.02
    # the default (free aspect) is close to the same camera too
    K2 = multi_pose.calibrate_device(objs, imgs, (640, 480)).K
    assert abs(K2[0, 0] - 536.11) < 4.0 and abs(K2[0, 2] - 342.37) < 3.0
