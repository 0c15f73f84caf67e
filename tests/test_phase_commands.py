"""Every command on a capture of each phase family (phase, heterodyne, gray-phase: procam's default sequences),
rendered by the simulator and written as procam writes a capture folder, and checked against the simulator's
truth: ``check`` (verdict and overlay), ``calibrate`` (single pose: f_p), ``reconstruct`` (points on the board),
``report`` (the verdict in the page), ``export`` (remap tables, the projector's view) and ``advise`` (its JSON
lines with the projector side from the phase capture's calibration).

The capture is the paper's rig at its 1280x800 camera (``advise --camera virtual`` is a 1280x800 camera, and a
calibration of another resolution is refused), one ray per pixel; each family is rendered and calibrated once
per module. Rendering and calibrating take 4-12 s per family there, so those tests are marked slow; the fast
sibling runs ``check`` on the small 640x400 render of each family (a few seconds each).
"""

import functools
import json

import cv2
import numpy as np
import pytest
from conftest import run_cli
from sim_small import small_scene

from procam import patterns, simulate

FAMILIES = ("phase", "heterodyne", "gray-phase")
BOARD = ["--board", "10x6", "--square", "24"]


def _write(scene, family, folder, seed):
    ps = patterns.pattern_set(*scene.proj_size, family=family)  # the family's default sequence
    stack, truth = simulate.render(scene, order=ps, seed=seed)
    simulate.write_capture(folder, stack, truth, order=ps)
    return folder


def _f_p(scene) -> float:
    return float(np.asarray(scene.K_proj, float)[0, 0])


@functools.cache
def paper_scene():
    """The paper's rig at the recommended pose, one ray per pixel (a render of the sequence in a few seconds)."""
    return simulate.preset("paper").replace(supersample=1)


@pytest.fixture(scope="module", params=FAMILIES)
def calibrated(request, tmp_path_factory):
    """(family, pose folder, calibration file, calibrate's stdout): rendered at the paper's rig, seed 5, and
    calibrated by ``procam calibrate`` from this one pose."""
    family = request.param
    root = tmp_path_factory.mktemp(f"phase_commands_{family}")
    pose = _write(paper_scene(), family, root / "pose", seed=5)
    code, out, err = run_cli(["calibrate", pose, *BOARD, "-o", root / "calib.json"])
    assert code == 0, err
    return family, pose, root / "calib.json", out


@pytest.mark.slow
def test_calibrate_a_phase_capture_finds_the_projector(calibrated):
    family, _, calib, out = calibrated
    saved = json.loads(calib.read_text())
    assert saved["method"] == "single-pose" and saved["verdict"]["level"] == "good"
    f_p, std = saved["projector"]["K"][0][0], saved["std"]["f_p"]
    # the pose's f_p within 3 of its stated std (about 18 px) and within 1 % of the truth
    assert abs(f_p - _f_p(paper_scene())) < min(3 * std, 0.01 * _f_p(paper_scene())), (family, f_p, std)
    assert f"wrote {calib}" in out.replace("\n", "")


@pytest.mark.slow
def test_check_of_a_phase_capture_gives_a_verdict_and_an_overlay(calibrated, tmp_path):
    _, pose, _, _ = calibrated
    code, out, err = run_cli(["check", pose, *BOARD, "--png", tmp_path / "check.png"])
    assert code == 0, err
    _assert_verdict_and_f_p(out, _f_p(paper_scene()), calibrated[0])
    img = cv2.imread(str(tmp_path / "check.png"))
    assert img is not None and img.shape == (800, 1280, 3)


@pytest.mark.slow
def test_reconstruct_of_a_phase_capture_lies_on_the_board(calibrated, tmp_path):
    pytest.importorskip("plyfile", reason="reading the cloud needs the plyfile package")
    from procam.io import read_ply

    family, pose, calib, _ = calibrated
    code, _, err = run_cli(["reconstruct", calib, pose, "-o", tmp_path / "cloud.ply"])
    assert code == 0, err
    pts, _, _ = read_ply(tmp_path / "cloud.ply")
    sc = paper_scene()
    Xb = (pts - sc.t_board) @ sc.R_board  # in the board's frame: z is the height over the board's plane (mm)
    half_w, half_h = 0.4 * (sc.board_cols - 1) * sc.square, 0.4 * (sc.board_rows - 1) * sc.square
    on = (np.abs(Xb[:, 0]) < half_w) & (np.abs(Xb[:, 1]) < half_h) & (np.abs(Xb[:, 2]) < 20.0)
    z = Xb[on, 2]
    assert on.sum() > 30000, on.sum()
    # through the pose's own calibration (f_p within 1 %), the board 640 mm away: within a millimetre
    # (measured: the mean 0.4 mm or less, the median deviation from it 0.05 mm or less; a dark square's pixels
    # scatter most)
    dev = np.abs(z - np.mean(z))
    assert abs(np.mean(z)) < 1.0 and np.median(dev) < 0.15 and np.percentile(dev, 90) < 1.0, (family, np.mean(z))


@pytest.mark.slow
def test_report_of_a_phase_calibration_shows_its_verdict(calibrated, tmp_path):
    calib = calibrated[2]
    code, _, err = run_cli(["report", calib, "-o", tmp_path / "r.html"])
    assert code == 0, err
    html = (tmp_path / "r.html").read_text()
    assert 'class="verdict good"' in html


@pytest.mark.slow
def test_export_of_a_phase_calibration_writes_maps_and_the_projector_view(calibrated, tmp_path):
    _, pose, calib, _ = calibrated
    code, _, err = run_cli(["export", calib, "--format", "maps", "-o", tmp_path / "maps"])
    assert code == 0, err
    cam = np.load(tmp_path / "maps" / "camera_undistort.npz")
    proj = np.load(tmp_path / "maps" / "projector_predistort.npz")
    assert cam["map_x"].shape == (800, 1280) and proj["map_x"].shape == (1080, 1920)
    code, _, err = run_cli(["export", calib, "--format", "projector-view", "--pose", pose, "-o",
                              tmp_path / "view.png"])
    assert code == 0, err
    view = cv2.imread(str(tmp_path / "view.png"), cv2.IMREAD_UNCHANGED).astype(np.float64)
    mask = cv2.imread(str(tmp_path / "view_mask.png"), cv2.IMREAD_UNCHANGED) > 0
    assert view.shape[:2] == (1080, 1920) and mask.mean() > 0.2
    # at the true projector pixel of each corner the view shows the camera's white frame at that corner
    truth = simulate.corner_truth(paper_scene())
    from procam.capture import load_capture

    white = load_capture(pose).white.astype(np.float32)
    seen = cv2.remap(white, *[np.float32(truth["camera_distorted"][:, i])[None] for i in (0, 1)],
                     cv2.INTER_LINEAR)[0]
    px = np.rint(truth["projector"]).astype(int)
    inside = mask[px[:, 1], px[:, 0]]
    assert inside.sum() >= 50
    assert np.median(np.abs(view[px[:, 1], px[:, 0]][inside] - seen[inside])) < 4.0 and np.ptp(seen) > 20


@pytest.mark.slow
def test_advise_with_a_phase_calibration_gives_advice_lines(calibrated):
    import procam.cli.advise  # noqa: F401

    calib = calibrated[2]
    code, out, err = run_cli(["advise", *BOARD, "--camera", "virtual", "--json", "--max-frames", "2",
                              "--calibration", calib])
    assert code == 0, err
    lines = [json.loads(x) for x in out.splitlines()]
    assert [d["frame"] for d in lines] == [0, 1]
    d = lines[-1]
    saved = json.loads(calib.read_text())
    # the projector side is the phase capture's calibration: its f_p, and the board's angles in the projector
    assert d["projector"]["f"] == pytest.approx(saved["projector"]["K"][0][0], abs=0.1)
    assert f"projector side from {calib}" in d["notes"] and d["actions"] is not None
    # the virtual camera's board (the ideal rig at the recommended pose) in the projector: its turn about the
    # projector's vertical axis as the simulator has it (25.8 deg)
    true_nu = simulate.truth(simulate.preset("ideal"))["pose"]["projector"]["angles_deg"][1]
    assert d["projector"]["nu"] == pytest.approx(true_nu, abs=1.0) and d["image_size"] == [1280, 800]


@pytest.fixture(scope="module", params=FAMILIES)
def small_pose(request, tmp_path_factory):
    family = request.param
    return family, _write(small_scene(), family, tmp_path_factory.mktemp(f"phase_small_{family}") / "pose", seed=5)


def test_check_of_a_small_phase_capture_gives_a_verdict_and_an_overlay(small_pose, tmp_path):
    """The fast sibling of the slow tests: ``check`` on each family's small (640x400) render."""
    family, pose = small_pose
    code, out, err = run_cli(["check", pose, *BOARD, "--png", tmp_path / "check.png"])
    assert code == 0, err
    _assert_verdict_and_f_p(out, _f_p(small_scene()), family)
    img = cv2.imread(str(tmp_path / "check.png"))
    assert img is not None and img.shape == (400, 640, 3)


def _assert_verdict_and_f_p(out: str, true_fp: float, family: str):
    """``check``'s verdict is good and its f_p line within 1 % and 3 stated std of the truth (measured: within
    3 px, std 18-33 px)."""
    assert "verdict: good" in out, out
    line = next(ln for ln in out.splitlines() if ln.startswith("f_c = "))
    f_p, std = (float(x) for x in line.split("f_p = ")[1].split(" px")[0].split(" ± "))
    assert abs(f_p - true_fp) < min(3 * std, 0.01 * true_fp), (family, line)
