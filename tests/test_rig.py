"""Rigs (issue 27): the capture layout, the calibration of every device against the simulator's truth, the rig
file, the pairs' 3-D agreement and the blend masks.  Corner and dense fast paths here (no rendering); the rendered
end to end run is in test_rig_cli.py."""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import verdict_warnings
from rig_sim import fast_views

from procam import models


def _calibrate(poses, **kw):
    from procam.rig import calibrate_rig

    with verdict_warnings():
        return calibrate_rig(poses, **kw)


@pytest.fixture(scope="module")
def two_projectors():
    rig, poses = fast_views("two_projectors")
    return rig, poses, _calibrate(poses)


@pytest.fixture(scope="module")
def two_cameras():
    rig, poses = fast_views("two_cameras")
    return rig, poses, _calibrate(poses)


def _check_truth(rig, rc, k=3.0):
    """Every device's f, fy, u0, v0 and every relative pose's angles and T within k std of the truth."""
    worst = 0.0
    for d in rc.devices:
        K = rig.device(d.name).K
        for key, est, true in (("f", d.device.K[0, 0], K[0, 0]), ("fy", d.device.K[1, 1], K[1, 1]),
                               ("u0", d.device.K[0, 2], K[0, 2]), ("v0", d.device.K[1, 2], K[1, 2])):
            z = abs(est - true) / d.std[key]
            assert z < k, (d.name, key, est, true, d.std[key])
            worst = max(worst, z)
    for key, r in rc.relative.items():
        a, b = key.split("->")
        R, T = rig.relative_pose(a, b)
        za = np.abs(r.angles_deg - models.euler_deg(R)) / r.std_angles_deg
        zt = np.abs(r.T - T) / r.std_T
        assert np.all(za < k) and np.all(zt < k), (key, za, zt)
        worst = max(worst, za.max(), zt.max())
    return worst


def test_two_projectors_one_camera_three_poses_within_3_std(two_projectors):
    rig, _, rc = two_projectors
    assert rc.method == "multi-pose" and rc.verdict == "good" and rc.info["status"] == 1
    assert [d.name for d in rc.devices] == ["cam", "left", "right"] and rc.reference == "cam"
    _check_truth(rig, rc)
    # the projector-to-projector translation within 0.5 % of the baseline (500 mm)
    _, T = rig.relative_pose("left", "right")
    r = rc.relative["left->right"]
    assert np.linalg.norm(r.T - T) <= 0.005 * np.linalg.norm(T)
    assert 0 < r.std_baseline < 0.005 * r.baseline
    # each device's noise estimated from its own residuals (fast path: 0.02 px camera, 0.03 px projectors)
    s = rc.info["sigma_px"]
    assert s["cam"] == pytest.approx(0.02, rel=0.25) and s["left"] == pytest.approx(0.03, rel=0.25)


def test_one_projector_two_cameras_three_poses_within_3_std(two_cameras):
    rig, _, rc = two_cameras
    assert rc.verdict == "good" and [d.name for d in rc.cameras] == ["left", "right"]
    _check_truth(rig, rc)
    _, T = rig.relative_pose("left", "right")
    assert np.linalg.norm(rc.relative["left->right"].T - T) <= 0.005 * np.linalg.norm(T)


def test_pairs_are_ordinary_calibrations_in_their_camera_frame(two_cameras):
    rig, _, rc = two_cameras
    cal = rc.pairs["right/proj"]
    _, T = rig.relative_pose("right", "proj")
    assert cal.method == "multi-pose" and np.allclose(cal.R, rc.relative_pose("right", "proj").R)
    assert np.linalg.norm(cal.T - T) < 3 * np.linalg.norm(cal.std["T"]) + 1e-9
    assert cal.stereo_rms < 0.1 and len(cal.poses) == 3


def test_inverse_relative_pose_keeps_its_std(two_projectors):
    _, _, rc = two_projectors
    fwd, back = rc.relative["left->right"], rc.relative_pose("right", "left")
    assert np.allclose(back.R, fwd.R.T) and back.baseline == pytest.approx(fwd.baseline)
    assert back.std_baseline == pytest.approx(fwd.std_baseline, rel=1e-3)


def test_single_pose_rig_gives_each_projector_its_verdict():
    from procam.rig import calibrate_rig

    rig, poses = fast_views("two_projectors", n_poses=1, angles=((22.0, 24.0, 0.0),))
    with verdict_warnings():
        rc = calibrate_rig(poses)
    assert rc.method == "single-pose" and set(rc.pairs) == {"cam/left", "cam/right"}
    for p in rc.projectors:
        assert p.verdict in ("good", "weak", "degenerate", "failed")
        assert p.verdict == rc.pairs[f"cam/{p.name}"].verdict
        # one pose of 60 corners (no background points on this fast path): within 10 %, and said to be weak
        assert p.device.K[0, 0] == pytest.approx(rig.device(p.name).K[0, 0], rel=0.10)
    # the right projector's lens distorts, which the single-pose model does not describe: its verdict says so
    assert any("model error" in r for r in rc.device("right").verdict_reasons)
    # every pair estimates the camera with its projector (its error is in each projector's ±): the same board's
    # corners, so nearly the same camera; the rig reports the first pair's
    assert "camera given" not in rc.pairs["cam/right"].method
    a, b = rc.pairs["cam/left"], rc.pairs["cam/right"]
    assert abs(a.camera.K[0, 0] - b.camera.K[0, 0]) <= 3 * np.hypot(a.std["f_c"], b.std["f_c"])
    assert np.array_equal(rc.device("cam").device.K, rc.pairs["cam/left"].camera.K)
    assert np.all(np.isfinite(rc.relative["left->right"].std_T))


def test_rig_file_json_yaml_and_pairs(two_projectors, tmp_path):
    import cv2

    from procam.errors import CalibrationFileError
    from procam.io import load_calibration, save_calibration
    from procam.io.rig import load_rig_document, save_rig_calibration

    _, _, rc = two_projectors
    path = save_rig_calibration(rc, tmp_path / "rig.json")
    doc = load_rig_document(path)
    assert doc["reference"] == "cam" and set(doc["projectors"]) == {"left", "right"}
    assert doc["relative"]["left->right"]["std"]["T"] == pytest.approx(list(rc.relative["left->right"].std_T))
    assert "independent and Gaussian" in doc["uncertainty"]
    left = load_calibration(path, pair="left")
    assert np.allclose(left.R, rc.pairs["cam/left"].R) and np.allclose(left.projector.K, rc.device("left").device.K)
    assert np.allclose(load_calibration(path, pair="cam/right").T, rc.pairs["cam/right"].T)
    with pytest.raises(CalibrationFileError, match="name one pair"):
        load_calibration(path)
    with pytest.raises(CalibrationFileError, match="names no pair"):
        load_calibration(path, pair="nope")
    # a single-pair file is unchanged and has no pairs
    single = save_calibration(rc.pairs["cam/left"], tmp_path / "one.json")
    assert json.loads(single.read_text())["format"] == "procam-calibration"
    with pytest.raises(CalibrationFileError, match="not a rig"):
        load_calibration(single, pair="left")
    y = save_rig_calibration(rc, tmp_path / "rig.yml")
    fs = cv2.FileStorage(str(y), cv2.FILE_STORAGE_READ)
    assert np.allclose(fs.getNode("right_T").mat().ravel(), rc.device("right").T)
    assert np.allclose(fs.getNode("proj_K").mat(), rc.device("left").device.K)  # the reference pair's keys
    assert fs.getNode("rig_projectors").string() == "left,right"
    fs.release()
    # the reference pair of the YAML reads as an ordinary OpenCV calibration
    assert np.allclose(load_calibration(y).T, rc.pairs["cam/left"].T, atol=1e-6)


def test_projector_pairs_agree_in_3d_and_a_wrong_pose_shows(two_projectors):
    from procam.rig.verify import verify_rig

    _, poses, rc = two_projectors
    agree = verify_rig(rc, poses)
    assert len(agree) == 3 and all(a.n == 60 for a in agree)
    assert max(a.rms_mm for a in agree) < 0.2 and max(a.rms_pct for a in agree) < 0.02
    shifted = rc.pairs["cam/right"].replace(T=rc.pairs["cam/right"].T + np.array([3.0, 0.0, 0.0]))
    bad = verify_rig(rc.__class__(**{**rc.__dict__, "pairs": {**rc.pairs, "cam/right": shifted}}), poses)
    assert min(a.rms_mm for a in bad) > 1.0


def test_layout_manifest_and_fallback(tmp_path):
    from procam import capture
    from procam.errors import CaptureError

    rig = tmp_path / "pose1"
    for sub in ("left", "right"):
        (rig / sub).mkdir(parents=True)
        (rig / sub / "patterns.json").write_text("{}")
    assert capture.is_rig_pose(rig) and not capture.is_rig_pose(rig / "left")
    r = capture.read_rig_pose(rig)  # no manifest: one camera "camera", projectors named after the folders
    assert r.cameras == ("camera",) and r.projectors == ("left", "right") and r.pairs[1].key == "camera/right"
    (rig / "rig.json").write_text(json.dumps(capture.rig_manifest(["cam"], ["left", "right"])))
    r = capture.read_rig_pose(rig)
    assert r.reference == "cam" and [p.folder.name for p in r.pairs] == ["left", "right"]
    assert capture.pair_folder_name("c1", "p1", 2, 2) == "c1_p1"
    (rig / "rig.json").write_text(json.dumps(capture.rig_manifest(["cam"], ["left", "right", "top"])))
    with pytest.raises(CaptureError, match="no folder"):
        capture.read_rig_pose(rig)
    with pytest.raises(ValueError, match="device name"):
        capture.rig_manifest(["cam 1"], ["left"])
    with pytest.raises(ValueError, match="unique"):
        capture.rig_manifest(["cam"], ["cam"])


def test_blend_sums_to_one_in_the_overlap_and_falls_off_smoothly(tmp_path):
    import cv2
    from scipy import ndimage

    from procam import simulate as sim
    from procam.io.images import read_image
    from procam.rig.blend import blend_masks, write_blend
    from rig_sim import bare_wall

    rig = bare_wall()
    maps, sizes = {}, {}
    for p in ("left", "right"):
        sc = rig.scene("cam", p)
        m = sim.true_projector_maps(sc, step=4, rounded=True)
        maps[p], sizes[p] = (m.col, m.row), sc.proj_size
    b = blend_masks(maps, sizes)
    both = np.isfinite(maps["left"][0]) & np.isfinite(maps["right"][0])
    total = np.zeros(both.shape, np.float32)
    inner = both.copy()
    for p, (c, r) in maps.items():
        W, H = sizes[p]
        total += cv2.remap(b.alpha[p], np.nan_to_num(c).astype(np.float32), np.nan_to_num(r).astype(np.float32),
                           cv2.INTER_LINEAR)
        # away from the projectors' own borders (where two borders meet, the ratio of two vanishing weights)
        inner &= (np.minimum(c, W - 1 - c) > 40) & (np.minimum(r, H - 1 - r) > 40)
    # and away from the camera image's edge (beyond it the alpha is continued, not measured)
    inner[:3], inner[-3:], inner[:, :3], inner[:, -3:] = False, False, False, False
    assert inner.sum() > 5000
    assert np.abs(total[inner] - 1).max() <= 0.01
    for p in ("left", "right"):
        a, seen = b.alpha[p], b.seen[p]
        assert a.min() >= 0 and a.max() <= 1 and b.overlap[p].any() and not b.overlap[p].all()
        core = seen[40:-40, 40:-40]
        dx = np.abs(np.diff(a[40:-40, 40:-40], axis=1))[:, :-1][core[:, 1:-1]]
        assert dx.max() < 0.01  # no step: the overlap is ~900 px wide
        alone = ndimage.binary_erosion(~b.overlap[p], iterations=16)[40:-40, 40:-40] & core
        # alone: full light (the mask is interpolated separately from alpha: they agree on 99 % of those pixels)
        assert alone.sum() > 10000 and np.mean(a[40:-40, 40:-40][alone] > 0.99) > 0.99
    paths = write_blend(b, tmp_path)
    png = read_image(tmp_path / "alpha_left.png")
    assert png.dtype == np.uint16 and np.abs(png / 65535.0 - b.alpha["left"]).max() <= 0.5 / 65535 + 1e-7
    z = np.load(tmp_path / "blend.npz")
    assert "multiply the linear-light" in str(z["conventions"]) and z["overlap_right"].dtype == bool
    assert len(paths) == 5
