"""Evaluation metrics (METHOD §11) on simulator captures with known truth."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from procam import evaluate, simulate
from procam.calibration import Device, Distortion
from procam.errors import CalibrationError
from procam.view import View
from conftest import verdict_warnings

ANGLES = [(20, -15, 0), (-15, 20, 5), (10, 25, -5), (-25, -10, 0), (5, -20, 3)]
CAM_DIST = (-0.12, 0.15, 0.0008, -0.0005, 0.0)


def _views(scenes, sigma_c=0.0, sigma_p=0.0, seed=0):
    out = []
    for k, sc in enumerate(scenes):
        obj, cam, proj = simulate.correspondences(sc, sigma_c, sigma_p, seed * 100 + k)
        out.append(View(obj, cam, proj, f"pose{k + 1}", sc.cam_size, sc.proj_size))
    return out


@pytest.fixture(scope="module")
def opencv_rig():
    base = dataclasses.replace(simulate.preset("paper"), cam_distortion="opencv", cam_dist_coeffs=CAM_DIST)
    return base, [simulate.with_board_pose(base, a, distance=650.0) for a in ANGLES]


@pytest.fixture(scope="module")
def division_rig():
    base = simulate.preset("ideal")
    return base, [simulate.with_board_pose(base, a, distance=650.0) for a in ANGLES[:3]]



@pytest.mark.parametrize("rig_name", ["opencv_rig", "division_rig"])
def test_truth_on_noise_free_data_is_exact(rig_name, request):
    base, scenes = request.getfixturevalue(rig_name)
    ev = evaluate.evaluate(simulate.truth_calibration(base), _views(scenes))
    assert ev.cam_rms < 1e-5 and ev.proj_rms < 1e-5 and ev.stereo_rms < 1e-5
    assert ev.sigma_T < 1e-4 and ev.sigma_abs_T < 1e-4
    np.testing.assert_allclose(ev.T_mean, base.T, atol=1e-4)
    for p, sc in zip(ev.poses, scenes):
        np.testing.assert_allclose(p.T, base.T, atol=1e-4)
        np.testing.assert_allclose(p.cam_angles, simulate.matrix_euler(sc.R_board), atol=1e-6)
        np.testing.assert_allclose(p.proj_angles, simulate.matrix_euler(sc.R_board_proj), atol=1e-6)
        np.testing.assert_allclose(p.t_cam, sc.t_board, atol=1e-4)
    assert ev.R_angles == pytest.approx(tuple(simulate.matrix_euler(base.R)))


def test_sigma_T_grows_with_noise(opencv_rig):
    base, scenes = opencv_rig
    calib = simulate.truth_calibration(base)
    sig = {}
    for s in (0.0, 0.05, 0.1, 0.2, 0.4):
        ev = evaluate.evaluate(calib, _views(scenes, s, 2 * s, seed=1))
        sig[s] = ev
    vals = [sig[s].sigma_T for s in sorted(sig)]
    assert vals[0] < 1e-4
    assert all(a < b for a, b in zip(vals, vals[1:])), vals
    # small-noise regime: linear in sigma (same noise draw, scaled)
    assert 3.0 < sig[0.4].sigma_T / sig[0.1].sigma_T < 5.0
    # per-pose RMS near the injected noise (sqrt(2) sigma per point)
    assert sig[0.2].cam_rms == pytest.approx(0.2 * np.sqrt(2), rel=0.3)
    assert sig[0.2].proj_rms == pytest.approx(0.4 * np.sqrt(2), rel=0.3)
    # the stereo fit has fewer degrees of freedom per point than the two PnPs
    assert sig[0.2].stereo_rms > 0.9 * np.sqrt((sig[0.2].cam_rms_all ** 2 + sig[0.2].proj_rms_all ** 2) / 2)


def test_spread_definitions(opencv_rig):
    base, scenes = opencv_rig
    ev = evaluate.evaluate(simulate.truth_calibration(base), _views(scenes, 0.1, 0.2, seed=2))
    Ts = np.array([p.T for p in ev.poses])
    n = len(Ts)
    assert ev.sigma_T == pytest.approx(np.sqrt(np.sum(np.var(Ts, axis=0, ddof=1))))
    assert ev.sigma_abs_T == pytest.approx(np.std(np.linalg.norm(Ts, axis=1), ddof=1))
    assert ev.sigma_T_ddof0 == pytest.approx(ev.sigma_T * np.sqrt((n - 1) / n))
    assert ev.sigma_abs_T_ddof0 == pytest.approx(ev.sigma_abs_T * np.sqrt((n - 1) / n))
    assert ev.sigma_T == pytest.approx(np.linalg.norm(ev.sigma_xyz))
    # T_j = T_pj - R_j T_cj with R_j = R_pj R_cj^T
    p = ev.poses[0]
    np.testing.assert_allclose(p.R, p.R_proj @ p.R_cam.T)
    np.testing.assert_allclose(p.T, p.t_proj - p.R @ p.t_cam)
    d = json.loads(json.dumps(ev.to_dict()))
    assert d["sigma_T"] == pytest.approx(ev.sigma_T) and len(d["poses"]) == n
    assert d["poses"][0]["name"] == "pose1" and len(d["poses"][0]["cam_angles"]) == 3


def test_wrong_calibration_is_worse(opencv_rig):
    base, scenes = opencv_rig
    views = _views(scenes, 0.1, 0.2, seed=3)
    good = evaluate.evaluate(simulate.truth_calibration(base), views)
    bad = simulate.truth_calibration(base).replace(T=base.T + np.array([5.0, 0.0, 0.0]))
    ev_bad = evaluate.evaluate(bad, views)
    # PnP-based metrics do not depend on (R, T); the stereo RMS does
    assert ev_bad.cam_rms == pytest.approx(good.cam_rms) and ev_bad.sigma_T == pytest.approx(good.sigma_T)
    assert ev_bad.stereo_rms > 3 * good.stereo_rms
    Kbad = base.K_cam.copy()
    Kbad[0, 0] *= 1.03
    Kbad[1, 1] *= 1.03
    ev_k = evaluate.evaluate(simulate.truth_calibration(base).replace(
        camera=Device(Kbad, base.cam_size, Distortion("opencv", coeffs=CAM_DIST))), views)
    assert ev_k.sigma_T > 2 * good.sigma_T


def test_nan_corners_and_errors(opencv_rig):
    base, scenes = opencv_rig
    views = _views(scenes)
    proj = views[1].proj_pts.copy()
    proj[:7] = np.nan
    views[1] = View(views[1].obj_pts, views[1].cam_pts, proj, "holes", base.cam_size, base.proj_size)
    ev = evaluate.evaluate(simulate.truth_calibration(base), views)
    assert ev.poses[1].n_points == 53 and ev.stereo_rms < 1e-5
    with pytest.raises(CalibrationError, match="no projector"):
        evaluate.evaluate(simulate.truth_calibration(base).replace(projector=None), views)
    with pytest.raises(CalibrationError, match="at least one pose"):
        evaluate.evaluate(simulate.truth_calibration(base), [])
    tiny = views[0].subset(np.arange(60) < 4)
    with pytest.raises(CalibrationError, match="pose1"):
        evaluate.evaluate(simulate.truth_calibration(base), [tiny])


def test_multi_pose_calibration_evaluates_near_truth(opencv_rig):
    from procam import multi_pose

    base, scenes = opencv_rig
    views = _views(scenes, 0.1, 0.2, seed=4)
    calib = multi_pose.calibrate(views)
    ev = evaluate.evaluate(calib, views)
    ev_truth = evaluate.evaluate(simulate.truth_calibration(base), views)
    # the fitted model explains its own data at least as well as the truth does
    assert ev.stereo_rms <= ev_truth.stereo_rms * 1.01
    assert ev.sigma_T < 3.0 and abs(ev.stereo_rms - calib.stereo_rms) < 0.05


def test_multi_pose_noise_free_sigma_T_is_zero(opencv_rig):
    from procam import multi_pose

    base, scenes = opencv_rig
    views = _views(scenes)
    ev = evaluate.evaluate(multi_pose.calibrate(views), views)
    assert ev.sigma_T < 1e-4 and ev.stereo_rms < 1e-5


def test_single_pose_rms_and_angles_match_evaluate(division_rig):
    """Review 11/12/18: the solver's own cam/proj/stereo RMS and board angles are the evaluation's."""
    from procam import single_pose

    base, scenes = division_rig
    view = _views(scenes[1:2], 0.1, 0.2, seed=5)[0]  # scenes[0] has nu_p = -1.5 deg: degenerate for single-pose
    with verdict_warnings():            # the verdict is not this test's subject
        calib = single_pose.calibrate(view, base.proj_size)
    ev = evaluate.evaluate(calib, [view])
    p = ev.poses[0]
    assert p.cam_rms == pytest.approx(calib.cam_rms, rel=1e-6)
    assert p.proj_rms == pytest.approx(calib.proj_rms, rel=1e-6)
    assert p.stereo_rms == pytest.approx(calib.stereo_rms, rel=1e-6)
    # same frame convention; the poses differ slightly (PnP fits undistorted pixels, the solver distorted ones)
    assert p.cam_angles == pytest.approx(tuple(calib.poses[0]["camera_angles_deg"]), abs=0.01)
    assert p.proj_angles == pytest.approx(tuple(calib.poses[0]["projector_angles_deg"]), abs=0.01)


def test_multi_pose_angles_match_evaluate(opencv_rig):
    from procam import multi_pose

    base, scenes = opencv_rig
    views = _views(scenes)
    calib = multi_pose.calibrate(views)
    ev = evaluate.evaluate(calib, views)
    for p, q in zip(ev.poses, calib.poses):
        assert p.cam_angles == pytest.approx(tuple(q["camera_angles_deg"]), abs=1e-3)
        assert p.proj_angles == pytest.approx(tuple(q["projector_angles_deg"]), abs=1e-3)


def test_report_residuals_observed_minus_predicted(division_rig):
    from procam.residuals import pose_residuals

    base, scenes = division_rig
    views = _views(scenes[:1])
    moved = views[0].cam_pts.copy()
    moved[0, 0] += 3.0
    view = dataclasses.replace(views[0], cam_pts=moved)
    out = pose_residuals(simulate.truth_calibration(base), [view])[0]
    assert out["cam_res"][0, 0] > 2.0
    assert np.nanmax(np.abs(out["proj_res"])) < 1e-5
