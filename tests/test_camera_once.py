"""The camera calibrated once (issue: the camera once, each projector from one pose): ``procam calibrate
--camera-only`` takes pose folders -- a Gray capture's white frame, a phase capture's board image (the mean of its
fringes, no white frame) -- and photos, mixed, and recovers the simulator's camera."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest
from conftest import run_cli

from procam import capture, patterns, simulate

BOARD = ["--board", "10x6", "--square", "24"]
#: Three board poses in the camera frame (deg): tilted about both image axes, as a camera calibration needs.
POSES = ((22.0, 16.0, 5.0), (-20.0, 14.0, -6.0), (12.0, -22.0, 8.0))


@pytest.fixture(scope="module")
def mixed(tmp_path_factory):
    """A Gray pose folder, a phase pose folder without white and black frames, and a photo, of the small rig."""
    from sim_small import small_scene

    root = tmp_path_factory.mktemp("camera_once")
    base = small_scene()
    w, h = base.proj_size
    gray = patterns.pattern_set(w, h)
    sequences = (gray, patterns.pattern_set(w, h, family="phase", white_black=False), None)
    paths = []
    for k, (pose, ps) in enumerate(zip(POSES, sequences)):
        scene = simulate.with_board_pose(base, pose)
        stack, truth = simulate.render(scene, ps if ps is not None else "opencv", seed=10 + k)
        if ps is None:  # a photo: the board under the projector's white light, as a camera's own software saves it
            path = root / "photo.png"
            assert cv2.imwrite(str(path), stack[gray.white])
        else:
            path = root / f"pose{k}"
            simulate.write_capture(path, stack, truth, ps)
            assert (capture.load_capture(path).pattern_set.white is None) == (k == 1)
        paths.append(path)
    return paths, base


def test_camera_only_takes_pose_folders_and_photos_mixed(mixed, tmp_path):
    paths, scene = mixed
    code, out, err = run_cli(["calibrate", *map(str, paths), "--camera-only", *BOARD, "-o", tmp_path / "cam.json"])
    assert code in (0, 3), err
    cam = json.loads((tmp_path / "cam.json").read_text())["camera"]
    K = np.array(cam["K"], float)
    K_true = np.array(scene.K_cam, float)
    std = json.loads((tmp_path / "cam.json").read_text())["std"]
    # within 0.2 % and 3 px of the truth, and within 4 of its own +- (the corners' noise alone)
    for got, true, s in ((K[0, 0], K_true[0, 0], std["f_c"]), (K[1, 1], K_true[1, 1], std["fy_c"])):
        assert abs(got / true - 1) < 0.002 and abs(got - true) < 4 * s + 0.5, (got, true, s)
    assert np.hypot(K[0, 2] - K_true[0, 2], K[1, 2] - K_true[1, 2]) < 3.0, (K, K_true)
    for p in paths:  # every input is one of the calibration's views, named by its folder or file
        assert p.name in out


def test_a_pose_folder_without_a_board_is_named(mixed, tmp_path):
    paths, _ = mixed
    code, _, err = run_cli(["calibrate", str(paths[0]), str(paths[2]), "--camera-only", "--board", "9x4",
                            "--square", "24", "-o", tmp_path / "cam.json"])
    assert code == 2 and str(paths[0]) in err and "not found" in err
    assert not (tmp_path / "cam.json").exists()


def test_the_camera_file_says_what_it_was_calibrated_from_and_carries_its_covariance(mixed, tmp_path):
    """The camera file names its inputs (relative to the file), their count and the date, and holds the intrinsics'
    covariance with its rows named, whose diagonal is OpenCV's own std (stdDeviationsIntrinsics) of the same fit;
    it reads back exactly through procam.io, and a file without the two blocks (written before) still loads."""
    from datetime import datetime, timedelta, timezone

    from procam import io
    from procam.errors import CalibrationFileError

    paths, _ = mixed
    out = tmp_path / "cam.json"
    code, _, err = run_cli(["calibrate", *map(str, paths), "--camera-only", *BOARD, "-o", out])
    assert code in (0, 3), err
    doc = json.loads(out.read_text())
    src = doc["calibrated_from"]
    assert src["count"] == 3 and [i["name"] for i in src["inputs"]] == [
        io.files.portable_path(str(p), tmp_path) for p in paths]
    when = datetime.fromisoformat(src["date"])
    assert abs(datetime.now(timezone.utc) - when) < timedelta(minutes=10)
    cov = doc["covariance"]
    assert cov["params"][:4] == ["f_c", "fy_c", "u0c", "v0c"] and len(cov["matrix"]) == len(cov["params"])
    m = np.array(cov["matrix"], float)
    for k, name in enumerate(cov["params"][:4]):  # the diagonal is OpenCV's std of the same fit, squared
        assert np.sqrt(m[k, k]) == pytest.approx(doc["std"][name], rel=1e-4), name
    assert np.all(np.linalg.eigvalsh(m) > 0)
    calib = io.load_calibration(out)
    back = calib.info["covariance"]
    assert back["params"] == tuple(cov["params"]) and np.array_equal(back["matrix"], m)
    assert calib.info["calibrated_from"]["count"] == 3
    again = tmp_path / "again.json"  # written back through io: the same blocks
    io.save_calibration(calib, again)
    doc2 = json.loads(again.read_text())
    assert doc2["covariance"]["matrix"] == cov["matrix"] and doc2["calibrated_from"]["date"] == src["date"]
    old = {k: v for k, v in doc.items() if k not in ("covariance", "calibrated_from")}
    (tmp_path / "old.json").write_text(json.dumps(old))
    assert "covariance" not in io.load_calibration(tmp_path / "old.json").info
    m[0, 1] += 1.0  # not symmetric: refused, naming the field
    (tmp_path / "bad.json").write_text(json.dumps({**doc, "covariance": {**cov, "matrix": m.tolist()}}))
    with pytest.raises(CalibrationFileError, match="covariance.matrix"):
        io.load_calibration(tmp_path / "bad.json")


def test_the_camera_files_covariance_travels_with_its_camera(tmp_path):
    """The camera from photos carries its covariance in memory, in its file and back, and as --camera reads it."""
    import warnings as _w

    from procam import io, multi_pose, simulate
    from procam.errors import ProcamWarning
    from procam.io import load_camera_intrinsics

    scene = simulate.preset("lensshift")
    views = []
    for k, (psi, nu) in enumerate(((20, 10), (-15, 20), (10, -25), (-20, -15))):
        sc = simulate.with_board_pose(scene, (psi, nu, 5 * k))
        o, c, p = simulate.correspondences(sc, 0.1, 0.2, seed=k)
        from procam.view import View
        views.append(View(o, c, np.full_like(p, np.nan), f"photo{k}", sc.cam_size, None))
    with _w.catch_warnings():
        _w.simplefilter("ignore", ProcamWarning)
        cal = multi_pose.calibrate_camera(views)
    names, C = cal.camera.covariance
    assert names[:4] == ("f_c", "fy_c", "u0c", "v0c") and C.shape == (len(names), len(names))
    assert np.sqrt(C[0, 0]) == pytest.approx(cal.std["f_c"], rel=1e-6)
    io.save_calibration(cal, tmp_path / "cam.json")
    for dev in (io.load_calibration(tmp_path / "cam.json").camera, load_camera_intrinsics(tmp_path / "cam.json")):
        assert dev.covariance[0] == names
        np.testing.assert_allclose(dev.covariance[1], C, rtol=1e-9)
