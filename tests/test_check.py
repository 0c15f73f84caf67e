"""procam check / procam capture's instant verdict on one pose folder."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from conftest import run_cli
from sim_small import small_scene

from procam import simulate
from procam.board import Board
from procam.check import check_pose, overlay


@pytest.fixture(scope="module")
def degenerate_folder(tmp_path_factory):
    """The small rig with the board at nu_p = 0 (no turn about the projector's vertical axis)."""
    scene = simulate.with_board_pose(small_scene(), (18.0, 0.0, 0.0), frame="projector")
    stack, truth = simulate.render(scene, seed=4)
    folder = tmp_path_factory.mktemp("flat") / "pose"
    simulate.write_capture(folder, stack, truth)
    return folder


def test_check_of_a_good_pose(paper_capture, tmp_path):
    folder = paper_capture[0]
    chk = check_pose(folder, Board(10, 6, 24.0))
    assert chk.verdict in ("good", "weak") and chk.calibration is not None
    assert chk.lines[-1].startswith(f"verdict: {chk.verdict}")
    # the paper rig's u0p is 1013, not W/2: the dense fit estimates it, and the line says so, not the assumption
    assert chk.calibration.info["dense"] is not None
    assert any("u0p = " in ln and "ESTIMATED from the pose's decoded board and background" in ln for ln in chk.lines)
    assert not any("u0p = W/2" in ln for ln in chk.lines)
    assert abs(chk.calibration.projector.K[0, 2] - paper_capture[2]["projector"]["u0"]) < 4 * chk.calibration.std["u0p"]
    f_true = paper_capture[2]["camera"]["f"]
    assert abs(chk.calibration.camera.K[0, 0] - f_true) < 0.03 * f_true
    img = overlay(chk)
    assert img.shape[2] == 3 and img.dtype == np.uint8
    code, out, err = run_cli(["check", folder, "--board", "10x6", "--square", "24", "--png", tmp_path / "c.png"])
    assert code == 0, err
    assert f"verdict: {chk.verdict}" in out and cv2.imread(str(tmp_path / "c.png")) is not None


def test_check_of_a_degenerate_pose_exits_3(degenerate_folder, tmp_path):
    # nu_p = 0: the board alone does not determine the projector (the wall behind it would, roughly: weak)
    chk = check_pose(degenerate_folder, Board(10, 6, 24.0), background="off")
    assert chk.verdict == "degenerate" and any("projector" in r for r in chk.reasons)
    # with the wall the dense fit may determine it; whatever the rating, "good" must keep its promise (f_p within
    # 1 %, the principal point within 15 px of the truth) -- the pose sits near the threshold, whose side depends
    # on the BLAS kernel
    chk = check_pose(degenerate_folder, Board(10, 6, 24.0))
    assert chk.verdict in ("good", "weak", "degenerate")
    if chk.verdict == "good":
        truth = np.asarray(small_scene().K_proj, float)
        K = chk.calibration.projector.K
        assert abs(K[0, 0] / truth[0, 0] - 1) < 0.01
        assert max(abs(K[0, 2] - truth[0, 2]), abs(K[1, 2] - truth[1, 2])) < 15
    code, out, err = run_cli(["check", degenerate_folder, "--board", "10x6", "--background", "off"])
    assert code == 3 and "verdict: degenerate" in out
    assert len(err.strip().splitlines()) == 1 and "not good" in err and "turn the board" in err


def test_check_of_an_unusable_folder_is_a_user_error(tmp_path):
    code, out, err = run_cli(["check", tmp_path, "--board", "10x6"])
    assert code == 2 and "no images found" in err and "Traceback" not in err
