"""A multi-pose set in which one pose shows no board goes on without it, and says so in the output, the file and
the verdict; ``--strict`` fails instead; a single pose without a board still fails; a pose whose board only
OpenCV's SB detector finds (a speckled print) is calibrated with the others (issue: other tools' captures and the poses they drop)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import run_cli

BOARD = ["--board", "10x6", "--square", "24"]


@pytest.fixture(scope="module")
def poses_and_empty(tmp_path_factory):
    """Three small rendered poses and a fourth where the board is out of the camera's view (the camera sees the
    projector's patterns on the wall only: a pose the board had left when it was captured)."""
    from sim_small import small_scene
    from test_bad_inputs import render_poses

    from procam import simulate

    root = tmp_path_factory.mktemp("dropped")
    folders = render_poses(root)
    empty = root / "pose4"
    scene = simulate.with_board_pose(small_scene().replace(gain=0.3), (10.0, 10.0, 0.0), center=(2500.0, 0.0, 900.0))
    stack, truth = simulate.render(scene, seed=5)
    simulate.write_capture(empty, stack, truth)
    return folders, empty


def test_a_pose_without_a_board_is_left_out_and_named(poses_and_empty, tmp_path):
    folders, empty = poses_and_empty
    out = tmp_path / "multi.json"
    code, stdout, err = run_cli(["calibrate", *map(str, folders[:2]), str(empty), str(folders[2]), *BOARD,
                                 "-o", out])
    assert code == 0, err
    said = stdout + err
    assert f"pose {empty} left out" in said and "not found" in said and "--strict" in said
    data = json.loads(out.read_text())
    assert len(data["poses"]) == 3 and not any(str(empty) == p.get("name") for p in data["poses"])
    assert data["verdict"]["level"] in ("weak", "degenerate", "failed")
    assert any(f"pose {empty} left out" in r for r in data["verdict"]["reasons"])


def test_strict_fails_on_a_pose_without_a_board(poses_and_empty, tmp_path):
    folders, empty = poses_and_empty
    code, _, err = run_cli(["calibrate", *map(str, folders[:2]), str(empty), *BOARD, "--strict",
                            "-o", tmp_path / "multi.json"])
    assert code == 2 and str(empty) in err and "not found" in err
    assert not (tmp_path / "multi.json").exists()


def test_a_single_pose_without_a_board_still_fails(poses_and_empty, tmp_path):
    _, empty = poses_and_empty
    code, _, err = run_cli(["calibrate", str(empty), *BOARD, "-o", tmp_path / "one.json"])
    assert code == 2 and str(empty) in err and "not found" in err


def test_too_few_poses_with_a_board_is_an_error(poses_and_empty, tmp_path):
    folders, empty = poses_and_empty
    code, _, err = run_cli(["calibrate", str(folders[0]), str(empty), *BOARD, "-o", tmp_path / "multi.json"])
    assert code == 2 and "needs at least two" in err and str(empty) in err


#: A board printed with a speckled texture (the albedo's standard deviation 0.3, cells of 1 mm, fixed in every
#: frame: the capture's own checks pass).  The classic detector finds no board in any of the frames procam tries
#: (white, white - black, black); SB does.  Measured: full renders of this pose at 9 noise seeds (0-8), classic in
#: none of the three frames at any seed, SB in the black frame at 9, white - black at 8 (not seed 7, the fixture's),
#: white at 4.  Over the grain (white and black frames at 8 seeds): classic finds the board at 0.2, on 2 of 3 seeds
#: at 0.22 and on none from 0.26; SB in white - black on 8 of 8 at 0.26, 0.3 and 0.34, on 1 of 8 at 0.38.  At 0.3
#: the same holds at the small rig's other two poses.
GRAINY = {"board_grain": 0.3}
GRAINY_ANGLES = (-12.0, 15.0, 5.0)


@pytest.fixture(scope="module")
def grainy_pose(tmp_path_factory):
    """The grainy pose rendered (seed 7) into a folder: (folder, stack, pattern set, true camera corners)."""
    from sim_small import small_scene

    from procam import patterns, simulate

    scene = simulate.with_board_pose(small_scene().replace(**GRAINY), GRAINY_ANGLES)
    stack, truth = simulate.render(scene, seed=7)
    folder = tmp_path_factory.mktemp("grainy") / "grainy"
    simulate.write_capture(folder, stack, truth)
    ps = patterns.pattern_set(*scene.proj_size, "opencv")
    return folder, stack, ps, simulate.project_points(scene, simulate.board_corners(scene) @ scene.R_board.T
                                                      + scene.t_board)


def test_a_board_only_sb_finds_is_found_by_auto(grainy_pose):
    """The grainy pose: procam's pipeline with the classic detector finds no board in its white, white - black or
    black frame, SB finds it in one of them, and ``auto`` finds every corner, 0.3 px RMS of the truth at most."""
    from procam.board import corners as _corners
    from procam.errors import BoardNotFoundError
    from procam.pipeline import find_board

    _, stack, ps, true_corners = grainy_pose
    with pytest.raises(BoardNotFoundError, match="not found"):    # tries the white, white - black and black frames
        find_board(stack, ps, (10, 6), detector="classic")
    white, black = stack[ps.white], stack[ps.black]
    candidates = (white, np.clip(white.astype(np.float32) - black.astype(np.float32), 0, None), black)
    assert any(_corners.find_grid(image, (10, 6), detector="sb") is not None for image in candidates)
    c = find_board(stack, ps, (10, 6), detector="auto")
    err = np.hypot(*(c - true_corners).T)           # 0.23 px RMS, 0.54 max: the grain biases the corners a little
    assert np.sqrt(np.mean(err ** 2)) < 0.3 and err.max() < 1.0


def test_a_pose_only_sb_finds_is_calibrated_with_the_others(poses_and_empty, grainy_pose, tmp_path):
    """Two poses of the small rig and the grainy one: ``procam calibrate`` (detector auto) keeps all three and leaves
    none out; the calibration is the scene's within three of its own standard deviations (which the grainy pose's
    noisier corners widen about tenfold) and within 1 % in f, 15 px in the principal points.  Measured: f_c
    +0.31 % (std 0.36 %), f_p +0.10 %, projector principal point (-7.4, -5.2) px (std 10.4, 6.0)."""
    from sim_small import small_scene

    from procam import io, simulate

    folders, _ = poses_and_empty
    grainy = grainy_pose[0]
    out = tmp_path / "multi.json"
    code, stdout, err = run_cli(["calibrate", str(folders[0]), str(folders[2]), str(grainy), *BOARD, "-o", out])
    assert code in (0, 3), err
    assert "left out" not in stdout + err
    data = json.loads(out.read_text())
    assert len(data["poses"]) == 3 and data["poses"][2]["name"].endswith("grainy")
    got, truth = io.load_calibration(out), simulate.truth_calibration(small_scene())
    for dev, k in (("camera", "c"), ("projector", "p")):
        K, Kt = np.asarray(getattr(got, dev).K), np.asarray(getattr(truth, dev).K)
        assert abs(K[0, 0] - Kt[0, 0]) <= min(3 * got.std[f"f_{k}"], 0.01 * Kt[0, 0]), (dev, K, Kt, got.std)
        for i, name in ((0, f"u0{k}"), (1, f"v0{k}")):
            assert abs(K[i, 2] - Kt[i, 2]) <= min(3 * got.std[name], 15.0), (dev, name, K, Kt, got.std)
    dT = np.abs(np.asarray(got.T).ravel() - np.asarray(truth.T).ravel())
    assert (dT <= 3 * np.asarray(got.std["T"])).all(), (dT, got.std["T"])
