"""Tests of the simulator (procam.simulate): geometry oracle, rendering, capture output."""

from __future__ import annotations

import ast
import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from procam import simulate as sim

SRC = Path(sim.__file__)


# ---------------------------------------------------------------------------------------------
# geometry
# ---------------------------------------------------------------------------------------------

def test_imports_no_solver_code():
    tree = ast.parse(SRC.read_text())
    mods = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            mods.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            mods.add(("." * node.level) + (node.module or "") + ":" + ",".join(a.name for a in node.names))
    allowed_prefix = ("numpy", "scipy", "cv2", "__future__", "dataclasses", "json", "os", "pathlib",
                      "typing", "time", "math")
    for m in mods:
        if m.startswith("."):
            assert m in (".:patterns", ".patterns:"), m  # only procam.patterns
        else:
            assert m.split(":")[0].startswith(allowed_prefix), m


@pytest.mark.parametrize("name", ["paper", "ideal"])
def test_presets(name):
    s = sim.preset(name)
    assert s.cam_size == (1280, 800) and s.proj_size == (1920, 1080)
    np.testing.assert_allclose(s.K_cam, [[1539, 0, 674], [0, 1539 * 1.004, 512], [0, 0, 1]])
    np.testing.assert_allclose(sim.matrix_euler(s.R), [0.87, 14.44, -0.25], atol=1e-9)
    np.testing.assert_allclose(s.T, [-170.05, -41.25, -65.35])
    assert (s.board_cols, s.board_rows, s.square) == (10, 6, 24.0)
    if name == "paper":
        np.testing.assert_allclose(s.K_proj, [[2421, 0, 1013], [0, 2421 * 1.002, 1065], [0, 0, 1]])
    else:
        np.testing.assert_allclose(s.K_proj, [[2421, 0, 960], [0, 2421, 1065], [0, 0, 1]])
        c = sim.corner_truth(s)
        d = np.linalg.norm(c["camera_distorted"] - c["camera_undistorted"], axis=1)
        assert 3 < d[[0, 9, 50, 59]].max() < 20  # distortion observable at the outer corners
    with pytest.raises(ValueError):
        sim.preset("nope")


@pytest.mark.parametrize("name", ["paper", "ideal"])
def test_recommended_pose_is_good_and_fully_visible(name):
    s = sim.preset(name)
    t = sim.truth(s)
    psi_c, nu_c, _ = t["pose"]["camera"]["angles_deg"]
    _, nu_p, _ = t["pose"]["projector"]["angles_deg"]
    np.testing.assert_allclose(t["pose"]["camera"]["angles_deg"], sim.RECOMMENDED_POSE, atol=1e-9)
    assert abs(psi_c) + abs(nu_c) > 10 and abs(nu_p) > 13
    assert t["fit_margin_px"] > 5
    cam = np.array(t["corners"]["camera_distorted"])
    proj = np.array(t["corners"]["projector"])
    # every corner with its 60x60 local-homography window inside the camera image
    assert cam.min() > 31 and cam[:, 0].max() < 1280 - 31 and cam[:, 1].max() < 800 - 31
    assert proj.min() > 0 and proj[:, 0].max() < 1919 and proj[:, 1].max() < 1079
    # canonical order: corner 0 top-left in the camera image, index runs right along the 10 cols
    assert cam[1, 0] > cam[0, 0] + 20 and abs(cam[1, 1] - cam[0, 1]) < 10
    assert cam[10, 1] > cam[0, 1] + 20
    assert np.argmin(cam.sum(axis=1)) == 0


def test_distortion_round_trips_and_opencv_agreement():
    s = sim.preset("ideal")
    p = np.random.default_rng(1).uniform([0, 0], [1280, 800], (500, 2))
    np.testing.assert_allclose(sim.undistort(s, sim.distort(s, p)), p, atol=1e-9)
    # barrel distortion (k1 < 0): distorted points lie closer to the centre
    c = s.cam_center
    assert np.all(np.linalg.norm(sim.distort(s, p) - c, axis=1) <= np.linalg.norm(p - c, axis=1) + 1e-9)
    coeffs = (-0.12, 0.05, 0.0015, -0.001, 0.01)
    s2 = s.replace(cam_distortion="opencv", cam_dist_coeffs=coeffs)
    np.testing.assert_allclose(sim.undistort(s2, sim.distort(s2, p)), p, atol=1e-8)
    K = s2.K_cam
    X = np.column_stack([(p[:, 0] - K[0, 2]) / K[0, 0], (p[:, 1] - K[1, 2]) / K[1, 1], np.ones(len(p))])
    q, _ = cv2.projectPoints(X, np.zeros(3), np.zeros(3), K, np.array(coeffs))
    np.testing.assert_allclose(q.reshape(-1, 2), sim.distort(s2, p), atol=1e-6)
    s3 = s.replace(cam_distortion="none", cam_dist_coeffs=())
    np.testing.assert_array_equal(sim.distort(s3, p), p)


def test_truth_geometry_is_consistent():
    s = sim.preset("paper")
    t = json.loads(json.dumps(sim.truth(s)))  # JSON-able
    B = np.array(t["corners"]["board"])
    assert B.shape == (60, 3)
    np.testing.assert_allclose(B[:, :2].mean(axis=0), 0, atol=1e-12)
    np.testing.assert_allclose(B[1] - B[0], [24, 0, 0])
    np.testing.assert_allclose(B[10] - B[0], [0, 24, 0])
    for dev, K in (("camera", s.K_cam), ("projector", s.K_proj)):
        R = np.array(t["pose"][dev]["R"])
        tv = np.array(t["pose"][dev]["t"])
        np.testing.assert_allclose(R, sim.euler_matrix(t["pose"][dev]["angles_deg"]), atol=1e-12)
        m = sim.project(K, B @ R.T + tv)
        key = "camera_undistorted" if dev == "camera" else "projector"
        np.testing.assert_allclose(m, t["corners"][key], atol=1e-9)
    # the division model maps the distorted corners back to the undistorted ones
    k1, k2 = t["camera"]["distortion"]["k1"], t["camera"]["distortion"]["k2"]
    c = np.array(t["camera"]["distortion"]["center"])
    d = np.array(t["corners"]["camera_distorted"]) - c
    r2 = (d ** 2).sum(axis=1, keepdims=True)
    np.testing.assert_allclose(c + d / (1 + k1 * r2 + k2 * r2 ** 2), t["corners"]["camera_undistorted"],
                               atol=1e-9)
    # extrinsics: the board pose in the projector frame is R (camera pose) + T
    Rc, tc = np.array(t["pose"]["camera"]["R"]), np.array(t["pose"]["camera"]["t"])
    Rp, tp = np.array(t["pose"]["projector"]["R"]), np.array(t["pose"]["projector"]["t"])
    np.testing.assert_allclose(Rp @ Rc.T, s.R, atol=1e-12)
    np.testing.assert_allclose(tp - s.R @ tc, s.T, atol=1e-9)


def test_with_board_pose_frames_and_center():
    s = sim.preset("paper")
    a = (5.0, -20.0, 3.0)
    sp = sim.with_board_pose(s, a, frame="projector")
    np.testing.assert_allclose(sim.matrix_euler(sp.R_board_proj), a, atol=1e-9)
    assert sim.fit_margin(sp) > 0
    sc = sim.with_board_pose(s, (10, 10, 0), center=(0, 0, 500))
    np.testing.assert_allclose(sc.t_board, [0, 0, 500])
    np.testing.assert_allclose(sim.matrix_euler(sc.R_board), (10, 10, 0), atol=1e-9)
    s7 = sim.with_board_pose(s, (10, 20, 0), distance=700.0)
    assert s7.t_board[2] == pytest.approx(700.0) and sim.fit_margin(s7) > 0
    with pytest.raises(ValueError):
        sim.with_board_pose(s, (0, 0, 0), frame="wall")


def test_correspondences_fast_path():
    s = sim.preset("paper")
    c = sim.corner_truth(s)
    obj, cam, proj = sim.correspondences(s, sigma_cam=0.0, sigma_proj=0.0)
    np.testing.assert_allclose(cam, c["camera_distorted"])
    np.testing.assert_allclose(proj, c["projector"])
    o1, c1, p1 = sim.correspondences(s, 0.1, 0.2, seed=3)
    o2, c2, p2 = sim.correspondences(s, 0.1, 0.2, seed=3)
    np.testing.assert_array_equal(c1, c2)
    np.testing.assert_array_equal(p1, p2)
    # noise level over many draws
    ec = np.concatenate([sim.correspondences(s, 0.1, 0.2, seed=k)[1] - c["camera_distorted"] for k in range(50)])
    ep = np.concatenate([sim.correspondences(s, 0.1, 0.2, seed=k)[2] - c["projector"] for k in range(50)])
    assert ec.std() == pytest.approx(0.1, rel=0.1) and ep.std() == pytest.approx(0.2, rel=0.1)
