"""An option the command would not read is refused, never silently ignored (attack round 3): one line naming
the option and what it applies to, exit 2, before any work and with nothing written; where it does apply, the
same option is taken.  And a command that writes several files checks every one of them before its work, so a
user's file of the same name stops it at once, not after the rendering or the calibrations."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import camera_view_of_patterns, run_cli, write_stack

from procam import patterns


def _refused(args, flag, *words):
    code, out, err = run_cli(args)
    assert code == 2, (code, out, err)
    assert err.startswith(f"error: {flag} ") and err.rstrip().endswith("leave it out"), err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    for w in words:
        assert w in err, err
    return err


def _phase_folder(folder, family):
    """A pose folder whose patterns.json describes ``family`` (the refusal reads nothing else)."""
    folder.mkdir()
    (folder / "patterns.json").write_text(json.dumps(patterns.pattern_set(256, 160, family=family).to_dict()))
    return folder


@pytest.mark.parametrize("args, flag, why", [
    (["--virtual", "--camera-size", "640x480"], "--camera-size", "real camera"),
    (["--virtual", "--exposure", "5"], "--exposure", "real camera"),
    (["--camera", "virtual", "--gain", "2", "--exposure", "5"], "--exposure", "real camera"),
    (["--virtual", "--display", "1"], "--display", "virtual one"),
    (["--virtual", "--timeout", "3"], "--timeout", "folder camera"),
    (["--camera", "opencv:1", "--seed", "3"], "--seed", "--virtual"),
    (["--virtual", "--target", "2"], "--target", None),
    (["--virtual", "--square", "5"], "--square", "--board"),
])
def test_capture_refuses_what_its_devices_would_ignore(tmp_path, args, flag, why):
    """The simulator has no exposure or resolution setting, a virtual projector no display, a real camera no seed;
    --target is live advice's, --square the board's: each was accepted and ignored."""
    out = tmp_path / "pose"
    code, _, err = run_cli(["capture", out, *args])
    if flag == "--target":
        assert code == 2 and err.strip() == "error: --target belongs to --advise; add --advise", err
    else:
        _refused(["capture", out, *args], flag, why)
    assert not out.exists()


def test_capture_checks_the_square_size_it_takes():
    code, _, err = run_cli(["capture", "x", "--virtual", "--board", "10x6", "--square", "nan"])
    assert code == 2 and "--square must be a square size > 0" in err, err


@pytest.mark.parametrize("args, flag", [
    (["--seed", "5"], "--seed"), (["--virtual", "--display", "1"], "--display"),
    (["--virtual", "--camera", "opencv:0"], "--camera"),
])
def test_app_refuses_device_options_of_the_other_rig(tmp_path, args, flag):
    _refused(["app", tmp_path / "project", "--no-browser", *args], flag)
    assert not (tmp_path / "project").exists()


_REAL_CAMERA_SETTINGS = [
    ("folder:shots", ["--exposure", "10"], "--exposure", "a folder camera"),
    ("folder:shots", ["--gain", "2"], "--gain", "a folder camera"),
    ("folder:shots", ["--camera-size", "640x480"], "--camera-size", "a folder camera"),
    ("genicam:/opt/x/producer.cti", ["--camera-size", "640x480"], "--camera-size", "GenICam"),
]


@pytest.mark.parametrize("command, extra, camera, args, flag, why", [
    (command, extra, *case) for command, extra in (("capture", []), ("advise", ["--board", "10x6"]),
                                                   ("world-check", ["CALIB", "--board", "10x6"]))
    for case in _REAL_CAMERA_SETTINGS
    if not (command == "advise" and case[0].startswith("folder:"))])  # advise refuses a folder camera itself
def test_a_real_camera_refuses_the_settings_it_does_not_read(tmp_path, command, extra, camera, args, flag, why):
    """A folder camera reads files (no exposure, gain or size of its own), a GenICam camera has its own size: each was
    accepted and ignored by capture, advise and world-check."""
    extra = [tmp_path / "c.json" if a == "CALIB" else a for a in extra]
    out = [tmp_path / "pose"] if command == "capture" else []
    _refused([command, *out, *extra, "--camera", camera, *args], flag, why)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("command, camera, words", [
    (command, *case) for command in (["capture", "POSE"], ["world-check", "c.json", "--board", "10x6"],
                                     ["advise", "--board", "10x6"], ["app", "p", "--no-browser"])
    for case in (("folder:NOPE", "no such folder; give the folder your camera software"),
                 ("genicam:NOPE/producer.cti", "no such GenTL producer (.cti) file"))
    if not (command[0] == "advise" and case[0].startswith("folder:"))])  # advise refuses a folder camera itself
def test_a_camera_that_names_a_missing_folder_or_producer_is_refused_at_once(tmp_path, command, camera, words):
    """The app started on a folder camera whose folder does not exist, and said so only when a capture began."""
    camera = camera.replace("NOPE", str(tmp_path / "nope"))
    args = [tmp_path / "pose" if a == "POSE" else tmp_path / a if a in ("c.json", "p") else a for a in command]
    code, _, err = run_cli([*args, "--camera", camera])
    assert code == 2 and err.startswith(f"error: --camera {camera}: {words}") and err.count("\n") == 1, err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("command, extra", [("world-check", ["c.json", "--board", "10x6"]), ("app", ["p", "--no-browser"])])
def test_the_simulators_camera_comes_with_virtual(tmp_path, command, extra):
    """--camera virtual without --virtual: the simulated camera without its simulated projector."""
    code, _, err = run_cli([command, *[tmp_path / a if a in ("c.json", "p") else a for a in extra],
                            "--camera", "virtual"])
    assert code == 2 and err.strip().endswith("use --virtual instead") and err.count("\n") == 1, err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("args, option", [(["--virtual", "--seed", "-5"], "--seed"),
                                          (["--display", "-1"], "--display"),
                                          (["--virtual", "--seed", "99999999999"], "--seed")])
def test_app_checks_its_numbers_before_creating_the_project(tmp_path, args, option):
    """--seed -5 was an internal error after the project folder was created."""
    code, _, err = run_cli(["app", tmp_path / "project", "--no-browser", *args])
    assert code == 2 and err.startswith(f"error: {option} must be"), err
    assert not (tmp_path / "project").exists()


@pytest.mark.parametrize("args, flag", [
    (["--method", "multi"], "--method"), (["--decode", "simple"], "--decode"), (["-p", "800x600"], "--projector"),
    (["--order", "opencv"], "--order"), (["--step", "2"], "--step"), (["--shadow-threshold", "5"],
                                                                     "--shadow-threshold"),
    (["--contrast-threshold", "5"], "--contrast-threshold"), (["--window", "30"], "--window"),
    (["--estimator", "lsq"], "--estimator"), (["--strict"], "--strict"),
])
def test_a_camera_only_calibration_refuses_the_pattern_options(tmp_path, args, flag):
    """A camera-only calibration reads photos of the board: the options of pattern captures were ignored."""
    photo = tmp_path / "photo.png"
    write_stack(tmp_path, np.full((1, 48, 64), 255, np.uint8), names=["photo.png"])
    _refused(["calibrate", photo, "--camera-only", "--board", "10x6", "--square", "24", "-o", tmp_path / "c.json",
              *args], flag, "camera-only (one photo) calibration")


def test_strict_is_refused_on_one_pose(tmp_path):
    pose = tmp_path / "pose"
    write_stack(pose, camera_view_of_patterns())
    _refused(["calibrate", pose, "--strict", "--board", "10x6", "--square", "24", "-o", tmp_path / "c.json"],
             "--strict", "single-pose calibration")


@pytest.mark.parametrize("family, args, flag", [
    ("phase", ["--decode", "simple"], "--decode"), ("phase", ["--contrast-threshold", "5"], "--contrast-threshold"),
    ("heterodyne", ["--decode", "simple"], "--decode"), ("gray-phase", ["--decode", "simple"], "--decode"),
])
@pytest.mark.parametrize("command", ["decode", "check", "calibrate"])
def test_a_gray_code_decoder_option_is_refused_on_a_phase_capture(tmp_path, family, args, flag, command):
    pose = _phase_folder(tmp_path / "pose", family)
    extra = {"decode": [], "check": ["--board", "10x6", "--square", "24"],
             "calibrate": ["--board", "10x6", "--square", "24", "-o", tmp_path / "c.json"]}[command]
    _refused([command, pose, *args, *extra], flag, f"{pose} holds a {family} capture")
    assert not (tmp_path / "c.json").exists()


def test_the_phase_decoder_options_are_refused_on_gray_codes_and_taken_where_they_apply(tmp_path):
    """--gamma and --camera-noise were a no-op on a Gray capture; --contrast-threshold applies to gray-phase's Gray
    bits, --decode to Gray codes."""
    gray = tmp_path / "gray"
    write_stack(gray, camera_view_of_patterns())
    _refused(["decode", gray, "--gamma", "2.2"], "--gamma", f"{gray} holds a gray capture")
    _refused(["decode", gray, "--camera-noise", "1"], "--camera-noise", "phase decoder")
    code, out, err = run_cli(["decode", gray, "-p", "64x48", "--decode", "simple", "--contrast-threshold", "5"])
    assert code == 0 and "simple classifier" in out, err
    gp = tmp_path / "gp"
    ps = patterns.pattern_set(256, 160, family="gray-phase")
    write_stack(gp, [(20 + 0.7 * f).astype(np.uint8) for f in patterns.frames(ps)])
    (gp / "patterns.json").write_text(json.dumps(ps.to_dict()))
    code, out, err = run_cli(["decode", gp, "--contrast-threshold", "5", "--camera-noise", "1"])
    assert code == 0 and "both 100.0 %" in out, err


def test_refine_window_is_refused_without_a_refinement(tmp_path):
    pose = tmp_path / "pose"
    write_stack(pose, camera_view_of_patterns())
    _refused(["check", pose, "--board", "10x6", "--square", "24", "--corner-refine", "none", "--refine-window",
              "7"], "--refine-window", "refines nothing")


@pytest.mark.parametrize("args, flag", [(["--square", "nan"], "--square"), (["--board", "10x6"], "--board"),
                                        (["--decode", "simple"], "--decode"), (["--window", "30"], "--window")])
def test_a_report_without_pose_folders_refuses_the_pose_options(tmp_path, args, flag):
    from procam import io, simulate

    io.save_calibration(simulate.truth_calibration(simulate.preset("paper")), tmp_path / "c.json")
    _refused(["report", tmp_path / "c.json", "-o", tmp_path / "r.html", *args], flag, "this report has none")
    assert not (tmp_path / "r.html").exists()


def test_demo_force_finds_a_users_file_before_rendering(tmp_path):
    """--force lets the demo write into a folder that holds other files; a user's demo_summary.json was found only
    after the rendering and the calibration, with the other files already written."""
    out = tmp_path / "demo"
    out.mkdir()
    (out / "demo_summary.json").write_text('{"mine": 1}')
    code, _, err = run_cli(["demo", out, "--force"])
    assert code == 2 and "demo_summary.json" in err, err
    assert sorted(p.name for p in out.iterdir()) == ["demo_summary.json"]
    assert (out / "demo_summary.json").read_text() == '{"mine": 1}'


def test_experiment_force_finds_a_users_file_before_decoding(tmp_path):
    from procam.paper.report import REPORT_FILES

    poses = []
    for i in range(3):
        poses.append(tmp_path / f"pose{i}")
        write_stack(poses[-1], camera_view_of_patterns(seed=i))
    out = tmp_path / "exp"
    out.mkdir()
    (out / "report.md").write_text("my notes")
    code, _, err = run_cli(["experiment", *poses, "--board", "10x6", "--square", "24", "-o", out, "--force"])
    assert code == 2 and "report.md" in err and "decoding" not in err, err
    assert sorted(p.name for p in out.iterdir()) == ["report.md"] and "report.md" in REPORT_FILES


def _truth_calibration(tmp_path):
    from procam import io, simulate

    path = tmp_path / "calib.json"
    io.save_calibration(simulate.truth_calibration(simulate.preset("ideal")), path)
    return path


def test_reconstruct_refuses_max_residual_with_one_coordinate(tmp_path):
    pytest.importorskip("plyfile", reason="reconstruct writes PLY through plyfile (pip install \".[ply]\")")
    pose = tmp_path / "pose"
    write_stack(pose, camera_view_of_patterns())
    _refused(["reconstruct", _truth_calibration(tmp_path), pose, "-o", tmp_path / "x.ply", "--use", "col",
              "--max-residual", "1"], "--max-residual", "--use col")


def test_simulate_refuses_a_preset_for_a_rig(tmp_path):
    _refused(["simulate", tmp_path / "rig", "--rig", "two_projectors", "--preset", "ideal"], "--preset",
             "--rig two_projectors")
    assert not (tmp_path / "rig").exists()


@pytest.mark.parametrize("args, flag", [
    (["--mode", "camera", "-o", "{tmp}/cam.json", "--target", "2"], "--target"),
    (["--mode", "camera", "-o", "{tmp}/cam.json", "--still", "1"], "--still"),
    (["--f-target", "1"], "--f-target"), (["--pp-target", "1"], "--pp-target"),
    (["--camera", "virtual", "--gain", "2"], "--gain"), (["--camera", "virtual", "--camera-size", "640x480"],
                                                         "--camera-size"),
    (["--camera", "opencv:3", "--seed", "2"], "--seed"),
])
def test_advise_refuses_the_other_modes_and_devices_options(tmp_path, args, flag):
    _refused(["advise", "--board", "10x6", *(a.format(tmp=tmp_path) for a in args)], flag)
    assert not (tmp_path / "cam.json").exists()


def test_advise_on_the_virtual_camera_without_a_square_sees_the_simulators_board():
    """Without --square the simulated board was drawn with squares of one unit (a millimetre), too small to find;
    the advice's lengths are in squares, the board the simulator's."""
    code, out, err = run_cli(["advise", "--board", "9x6", "--camera", "virtual", "--json", "--max-frames", "2"])
    assert code == 0, err
    states = [json.loads(line)["state"] for line in out.splitlines() if line.startswith("{")]
    assert len(states) == 2 and "no-board" not in states, out


@pytest.mark.parametrize("args, flag, why", [
    (["--virtual", "--settle-ms", "10"], "--settle-ms", "--virtual uses the simulator"),
    (["--virtual", "--exposure", "3"], "--exposure", "--virtual uses the simulator"),
])
def test_world_check_refuses_device_settings_under_virtual(tmp_path, args, flag, why):
    _refused(["world-check", _truth_calibration(tmp_path), *args], flag, why)


def test_world_check_refuses_a_seed_without_the_simulator_and_names_a_bad_square(tmp_path):
    cal = _truth_calibration(tmp_path)
    code, _, err = run_cli(["world-check", cal, "--board", "9x6", "--square", "30", "--seed", "3"])
    assert code == 2 and err.strip() == "error: --seed belongs to --virtual; add --virtual or leave it out", err
    code, _, err = run_cli(["world-check", cal, "--virtual", "--square", "nan"])
    assert code == 2 and err.startswith("error: --square must be"), err
    code, _, err = run_cli(["world-check", tmp_path, "--virtual"])
    assert code == 2 and "a folder, not a calibration file" in err, err


@pytest.mark.parametrize("args, flag", [(["--no-slices", "--slice-grid", "0"], "--slice-grid"),
                                        (["--psi", "0", "--nu", "0", "--grid", "0"], "--grid")])
def test_study_refuses_angles_it_would_not_use(tmp_path, args, flag):
    _refused(["study", "camera", "-o", tmp_path / "st", "--trials", "0", *args], flag)
    assert not (tmp_path / "st").exists()


@pytest.mark.parametrize("args, option", [(["--psi", "abc"], "--psi: grid must be"), (["--nu", "1:2"], "--nu: grid"),
                                          (["--slice-grid", "x"], "--slice-grid: grid"),
                                          (["--model-error", "foo"], "--model-error must be paper or none")])
def test_study_errors_name_the_option(tmp_path, args, option):
    code, _, err = run_cli(["study", "camera", "-o", tmp_path / "st", "--trials", "0", "--grid", "0", *args])
    assert code == 2 and err.startswith(f"error: {option}"), err


def test_a_study_of_one_trial_per_cell_summarises_without_a_warning(tmp_path):
    """One trial has no spread (std/sqrt(CRLB) NaN in every cell): the summary said so through numpy's All-NaN
    RuntimeWarning (an error under this suite's filterwarnings)."""
    code, out, err = run_cli(["study", "camera", "-o", tmp_path / "st", "--trials", "1", "--grid", "0,10",
                              "--no-slices", "--no-figures"])
    assert code == 0, err
    summary = json.loads((tmp_path / "st" / "study_camera_paper.json").read_text())["summary"]
    assert summary["cells"] == 4 and summary["median_ratio_std"] is None, summary
    assert np.isfinite(summary["median_ratio_median"]), summary


def test_export_refuses_force_for_a_single_file(tmp_path):
    _refused(["export", _truth_calibration(tmp_path), "--format", "opengl", "--near",
              "100", "--far", "5000", "-o", tmp_path / "gl.json", "--force"], "--force", "--format maps")


def test_a_folder_given_as_the_calibration_is_called_a_folder(tmp_path):
    pose = tmp_path / "pose"
    write_stack(pose, camera_view_of_patterns())
    code, _, err = run_cli(["report", tmp_path, "-o", tmp_path / "r.html"])
    assert code == 2 and f"{tmp_path}: a folder, not a calibration file" in err, err


# attack round 4: a board of 3 corners a side, and a failed board step after the cloud was written


def test_a_board_with_a_side_of_three_is_not_found_and_named_not_an_internal_error(paper_capture):
    """The search for the board actually in view handed OpenCV a pattern of 2 corners a side (an internal error,
    exit 1); now the usual one line naming the board in view."""
    folder = paper_capture[0]
    code, _, err = run_cli(["check", folder, "--board", "4x3", "--square", "24"])
    assert code == 2 and "4x3 inner corners not found" in err and "internal error" not in err, err


def test_reconstruct_writes_no_cloud_when_the_board_is_not_found(tmp_path, paper_capture):
    pytest.importorskip("plyfile", reason="reconstruct writes PLY through plyfile (pip install \".[ply]\")")
    from procam import io, simulate

    folder, _, _, scene = paper_capture
    cal = tmp_path / "calib.json"
    io.save_calibration(simulate.truth_calibration(scene), cal)
    code, _, err = run_cli(["reconstruct", cal, folder, "-o", tmp_path / "r.ply", "--board", "9x5"])
    assert code == 2 and "9x5 inner corners not found" in err, err
    assert not (tmp_path / "r.ply").exists()
    code, out, err = run_cli(["reconstruct", cal, folder, "-o", tmp_path / "r.ply", "--board", "10x6"])
    assert code == 0 and "board plane RMS" in out and (tmp_path / "r.ply").is_file(), err


@pytest.mark.parametrize("command", [["capture", "POSE", "--virtual"], ["world-check", "c.json", "--virtual"]])
def test_the_simulators_gain_is_a_factor_above_zero(tmp_path, command):
    """--gain 0 on the simulator rendered black frames and failed at the pre-flight without naming the option."""
    args = [tmp_path / "pose" if a == "POSE" else tmp_path / a if a == "c.json" else a for a in command]
    code, _, err = run_cli([*args, "--gain", "0"])
    assert code == 2 and err.startswith("error: --gain must be a gain factor > 0") and err.count("\n") == 1, err
    assert list(tmp_path.iterdir()) == []


def test_study_refuses_a_noise_with_no_noisy_trials(tmp_path):
    _refused(["study", "camera", "--trials", "0", "--noise", "0.5", "-o", tmp_path / "st"], "--noise", "--trials 0")
    assert not (tmp_path / "st").exists()


@pytest.mark.parametrize("command", [["decode", "RIG"], ["export", "c.json", "--format", "projector-view", "--pose",
                                                         "RIG", "-o", "v.png"]])
def test_a_rig_pose_given_for_one_pose_names_its_pose_folders(tmp_path, command):
    """A rig pose folder (rig.json, one pose folder per projector) where one pose is read: "no images found" did
    not say what to give."""
    from procam import io, simulate
    from sim_small import small_capture

    scene, stack, truth, _ = small_capture()
    rig = tmp_path / "rig1"
    for name in ("left", "right"):
        simulate.write_capture(rig / name, stack, truth)
    (rig / "rig.json").write_text('{"format": "procam-rig-pose"}')
    io.save_calibration(simulate.truth_calibration(scene), tmp_path / "c.json")
    args = [rig if a == "RIG" else tmp_path / a if a in ("c.json", "v.png") else a for a in command]
    code, _, err = run_cli(args)
    assert code == 2 and "rig1: a rig pose folder (one pose folder per projector: left, right)" in err, err
    assert f"give one of them, e.g. {rig / 'left'}" in err and not (tmp_path / "v.png").exists()
