"""The CLI end to end on a rendered capture, including its error messages."""

import json

import cv2
import numpy as np
from conftest import run_cli

from procam import io


def test_calibrate_single_pose_end_to_end(ideal_capture, tmp_path):
    folder, _, truth, _ = ideal_capture
    out, yml, png = tmp_path / "calib.json", tmp_path / "calib.yml", tmp_path / "res.png"
    code, stdout, err = run_cli(["calibrate", folder, "--board", "10x6", "--square", "24", "-o", out,
                                 "--yaml", yml, "--png", png])
    assert code == 0, err
    assert "single-pose" in stdout and "±" in stdout
    c = io.load_calibration(out)
    assert abs(c.camera.K[0, 0] - truth["camera"]["f"]) < 40
    assert abs(c.projector.K[0, 0] - truth["projector"]["f"]) < 15
    assert np.linalg.norm(c.T - truth["extrinsics"]["T"]) < 10
    y = io.load_calibration(yml)
    assert np.allclose(y.projector.K, c.projector.K) and np.allclose(y.R, c.R)
    assert cv2.imread(str(png)) is not None
    doc = json.loads(out.read_text())
    assert doc["poses"][0]["advice"]["camera"]["paper_rule_ok"]


def test_calibrate_errors(ideal_capture, tmp_path):
    folder, _, _, _ = ideal_capture
    out = tmp_path / "c.json"
    code, _, err = run_cli(["calibrate", folder, "--board", "10x6", "--square", "-3", "-o", out])
    assert code != 0 and "--square" in err
    code, _, err = run_cli(["calibrate", folder, "--board", "ten", "--square", "24", "-o", out])
    assert code == 2 and "--board" in err
    code, _, err = run_cli(["calibrate", folder, "--board", "9x6", "--square", "24", "-o", out])
    assert code == 2 and "not found" in err and "inner corners" in err
    assert not out.exists()


def test_camera_only_on_a_real_photo(shared_data, tmp_path):
    out = tmp_path / "cam.json"
    img = shared_data / "opencv-left-right" / "left12.jpg"
    code, stdout, err = run_cli(["calibrate", "--camera-only", img, "--board", "9x6", "--square", "25", "-o", out])
    assert code == 0, err
    c = io.load_calibration(out)
    assert c.projector is None and c.camera.image_size == (640, 480)
    assert 400 < c.camera.K[0, 0] < 700  # reference 536; one photo is coarse
    code, _, err = run_cli(["calibrate", "--camera-only", img, "--board", "10x6", "--square", "25", "-o", out])
    assert code == 2 and "not found" in err


def test_demo_runs(tmp_path):
    code, stdout, err = run_cli(["demo", tmp_path / "demo"])
    assert code == 0, err
    assert "estimate vs truth" in stdout
    s = json.loads((tmp_path / "demo" / "demo_summary.json").read_text())
    assert abs(s["projector_f"][1] - s["projector_f"][0]) < 20
    assert (tmp_path / "demo" / "calib.yml").is_file() and (tmp_path / "demo" / "capture" / "truth.json").is_file()


def test_examples_run(tmp_path):
    """The examples are documentation: they must run."""
    import runpy
    import sys
    from pathlib import Path

    ex = Path(__file__).resolve().parents[1] / "examples"
    runpy.run_path(str(ex / "single_pose_from_points.py"), run_name="__main__")
    old = sys.argv
    sys.argv = ["plot_decode.py", str(tmp_path / "d.png")]
    try:
        runpy.run_path(str(ex / "plot_decode.py"), run_name="__main__")
    finally:
        sys.argv = old
    assert (tmp_path / "d.png").is_file()
