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
