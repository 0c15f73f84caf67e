"""The metric verification in ``procam calibrate`` / ``procam evaluate`` output and JSON, ``procam report`` and
``--report`` (pose folders replaced by simulator correspondences, plus one real rendered capture)."""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

import pytest
from conftest import fake_pose_folders, run_cli, verdict_warnings

from procam import io, multi_pose, simulate, verify
from procam.view import View

ANGLES = [(15, -35, 0), (-15, 20, 5), (10, 25, -5), (-25, 15, 0)]
BOARD = ["--board", "10x6", "--square", "24"]


@pytest.fixture(scope="module")
def views():
    base = simulate.preset("paper")
    out = []
    for k, a in enumerate(ANGLES):
        sc = simulate.with_board_pose(base, a, distance=650.0)
        obj, cam, proj = simulate.correspondences(sc, 0.1, 0.2, k)
        out.append(View(obj, cam, proj, f"pose{k + 1}", sc.cam_size, sc.proj_size))
    return out


@pytest.fixture()
def folders(views, tmp_path, monkeypatch):
    """Pose folders whose decoding returns the simulator's correspondences."""
    add = fake_pose_folders(monkeypatch, tmp_path)
    return [add(v.name, v) for v in views]


def _sections(path):
    return re.findall(r'<section id="([^"]+)"', Path(path).read_text(encoding="utf-8"))


def test_calibrate_multi_pose_prints_in_sample_and_leave_one_out(folders, tmp_path):
    out, rep = tmp_path / "c.json", tmp_path / "c.html"
    code, stdout, err = run_cli(["calibrate", *folders, *BOARD, "-o", out, "--report", rep])
    assert code == 0, err
    assert "metric verification on the poses the calibration was fitted to" in stdout
    assert "in-sample vs leave-one-pose-out" in stdout
    calib = io.load_calibration(out)
    ver = verify.verify(calib, calib.views)
    assert f"{ver.overall.scale_error_pct:+.3f}" in stdout and f"{ver.overall.rigid_rms:.3f}" in stdout
    assert _sections(rep) == ["verdict", "parameters", "coverage", "residuals", "verification", "rig",
                              "leave-one-out"]
    assert f"wrote {rep}" in stdout


def test_calibrate_three_poses_says_why_there_is_no_leave_one_out(folders, tmp_path):
    code, stdout, err = run_cli(["calibrate", *folders[:3], *BOARD, "-o", tmp_path / "c.json"])
    assert code == 0, err
    assert "in-sample" in stdout and "leave-one-pose-out needs at least 4 poses" in stdout


def test_evaluate_json_has_the_verification(folders, views, tmp_path):
    calib = multi_pose.calibrate(views)
    cpath, jpath = tmp_path / "calib.json", tmp_path / "eval.json"
    io.save_calibration(calib, cpath)
    code, stdout, err = run_cli(["evaluate", cpath, *folders, *BOARD, "-o", jpath])
    assert code == 0, err
    d = json.loads(jpath.read_text())["verification"]
    assert set(d) == {"in_sample", "held_out", "leave_one_out", "notes"}
    # the given folders are the calibration's own poses (same corners), so all four are in-sample
    ref = verify.verify(io.load_calibration(cpath), views)
    assert d["held_out"] is None and len(d["in_sample"]["poses"]) == 4
    assert d["in_sample"]["overall"]["scale_error_pct"] == pytest.approx(ref.overall.scale_error_pct, abs=1e-9)
    assert d["leave_one_out"]["kind"] == "leave-one-out" and len(d["leave_one_out"]["held_out"]["poses"]) == 4
    assert "leave-one-pose-out" in stdout


def test_evaluate_single_pose_on_other_poses_is_held_out(folders, views, tmp_path):
    from procam import single_pose

    with verdict_warnings():            # the verdict is not this test's subject
        calib = single_pose.calibrate(views[0])
    cpath, jpath = tmp_path / "calib.json", tmp_path / "eval.json"
    io.save_calibration(calib, cpath)
    code, stdout, err = run_cli(["evaluate", cpath, *folders, *BOARD, "-o", jpath])
    assert code == 0, err
    d = json.loads(jpath.read_text())["verification"]
    # the poses are named by their folders relative to the JSON file, not by absolute paths
    assert [p["name"] for p in d["in_sample"]["poses"]] == [os.path.relpath(folders[0], tmp_path)]
    assert [p["name"] for p in d["held_out"]["poses"]] == [os.path.relpath(f, tmp_path) for f in folders[1:]]
    assert d["leave_one_out"] is None
    assert "metric verification on other poses (held out" in stdout


def test_report_command(folders, views, tmp_path):
    calib = multi_pose.calibrate(views)
    cpath = tmp_path / "calib.json"
    io.save_calibration(calib, cpath)
    rep = tmp_path / "out" / "r.html"
    code, stdout, err = run_cli(["report", cpath, "-o", rep])  # the poses stored in the calibration
    assert code == 0, err
    assert _sections(rep)[0] == "verdict" and "leave-one-out" in _sections(rep)
    # procam knows its own page: a second run writes over it (a page of the user's it refuses, below)
    code, _, err = run_cli(["report", cpath, "-o", rep])
    assert code == 0, err
    (tmp_path / "theirs.html").write_text("<html><head><title>my notes</title></head><body></body></html>")
    code, _, err = run_cli(["report", cpath, "-o", tmp_path / "theirs.html"])
    assert code == 2 and "procam did not write" in err
    assert "my notes" in (tmp_path / "theirs.html").read_text()
    code, stdout, err = run_cli(["report", cpath, *folders[:2], *BOARD, "-o", tmp_path / "r2.html"])
    assert code == 0, err
    assert "pose1: 60 of 60 corners" in stdout
    # mistakes: one line, exit code 2, nothing written
    for args, msg in ((["report", cpath, *folders[:1], "-o", tmp_path / "x.html"], "give --board"),
                      (["report", cpath, "-o", tmp_path / "x.pdf"], "must end in .html"),
                      (["report", tmp_path / "nope.json", "-o", tmp_path / "x.html"], "no such file")):
        code, _, err = run_cli(args)
        assert code == 2 and msg in err and len(err.strip().splitlines()) == 1, (args, err)
    assert not (tmp_path / "x.html").exists()


def test_report_of_a_file_without_poses_says_so(views, tmp_path):
    calib = multi_pose.calibrate(views)
    yml = tmp_path / "c.yml"
    io.save_opencv_yaml(calib, yml)
    code, stdout, err = run_cli(["report", yml, "-o", tmp_path / "r.html"])
    assert code == 0, err
    assert "holds no poses" in stdout
    page = (tmp_path / "r.html").read_text(encoding="utf-8")
    assert f"Verdict: <span class=\"word\">{calib.verdict}</span>" in page  # the YAML records the verdict
    # an OpenCV YAML from another tool records none
    other = tmp_path / "other.yml"
    other.write_text("".join(line for line in yml.read_text().splitlines(keepends=True) if "verdict" not in line))
    code, stdout, err = run_cli(["report", other, "-o", tmp_path / "o.html"])
    assert code == 0, err
    assert "Verdict: <span class=\"word\">unknown</span>" in (tmp_path / "o.html").read_text(encoding="utf-8")


@pytest.mark.slow    # fast sibling: test_experiment's report test
def test_experiment_report(folders, tmp_path):
    rep = tmp_path / "exp.html"
    code, stdout, err = run_cli(["experiment", *folders, "-o", tmp_path / "exp", *BOARD, "--projector", "1920x1080",
                                 "--report", rep])
    assert code == 0, err
    assert _sections(rep)[-1] == "leave-one-out"


def test_calibrate_and_report_a_rendered_capture(ideal_capture, tmp_path):
    """The whole chain on real (rendered) images: decode, calibrate, --png/--report, then procam report with the
    pose folder (its decoded pixels shade the coverage)."""
    folder = ideal_capture[0]
    out, png, rep = tmp_path / "c.json", tmp_path / "res.png", tmp_path / "c.html"
    code, stdout, err = run_cli(["calibrate", folder, *BOARD, "-o", out, "--png", png, "--report", rep])
    assert code == 0, err
    assert "metric verification on the poses the calibration was fitted to" in stdout
    assert "own pose only" in stdout
    assert png.read_bytes().startswith(b"\x89PNG") and _sections(rep)[0] == "verdict"
    rep2 = tmp_path / "c2.html"
    code, stdout, err = run_cli(["report", out, folder, *BOARD, "-o", rep2])
    assert code == 0, err
    page = rep2.read_text(encoding="utf-8")
    assert "over the pixels decoded in any pose (grey)" in page
    assert len(page.encode("utf-8")) < 5e6
