"""A multi-pose set in which one pose shows no board goes on without it, and says so in the output, the file and
the verdict; ``--strict`` fails instead; a single pose without a board still fails (issue: other tools' captures
and the poses they drop)."""

from __future__ import annotations

import json
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
