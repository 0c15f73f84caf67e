"""procam.acquire: the capture loop on the virtual procam (the simulator as the camera), its checks,
the folder-watch camera, the CLI, and the real projector window under a virtual X server (Xvfb)."""

import json
import os
import select
import shutil
import subprocess
import threading
import time

import numpy as np
import pytest
from conftest import run_cli

from procam import capture as capmod
from procam import decode, patterns, pipeline, simulate, single_pose
from procam.board import Board
from procam.acquire import (CaptureFailed, CaptureOptions, FolderWatchCamera, ProjectorWindow, VirtualCamera,
                            VirtualProjector, capture_pose, capture_poses, checks)
from procam.acquire.cameras import parse_camera_spec
from procam.errors import CaptureError, ProcamError

FAST = CaptureOptions(settle_s=0.0)


@pytest.fixture(scope="module")
def rig():
    """The 'ideal' rig at half the camera's and 512/1920 of the projector's resolution (same fields of view):
    a 640x400 camera and a 512x384 projector (38 patterns), board at the recommended pose, rendered once."""
    s = simulate.preset("ideal")
    c, p = 0.5, 512 / 1920
    s = s.replace(cam_size=(640, 400), K_cam=np.diag([c, c, 1.0]) @ s.K_cam, proj_size=(512, 384),
                  K_proj=np.diag([p, p, 1.0]) @ s.K_proj, cam_dist_coeffs=(s.cam_dist_coeffs[0] / c**2, 0.0),
                  name="small-ideal")
    s = simulate.with_board_pose(s, simulate.RECOMMENDED_POSE)
    stack, truth = simulate.render(s, seed=3)
    return s, stack, truth


def run_virtual(rig, out, options=FAST, progress=None, camera_cls=VirtualCamera, **camera_options):
    scene, stack, _ = rig
    with VirtualProjector(scene.proj_size) as proj, camera_cls(proj, scene, stack=stack, **camera_options) as cam:
        return capture_pose(out, proj, cam, options, progress=progress)


def captured(folder) -> np.ndarray:
    return capmod.load_capture(folder).stack


# --------------------------------------------------------------------------------------------
# the capture loop on the virtual procam
# --------------------------------------------------------------------------------------------

def test_capture_then_calibrate_recovers_the_simulated_rig(rig, tmp_path):
    scene, stack, truth = rig
    res = run_virtual(rig, tmp_path / "pose", CaptureOptions(settle_s=0.0, board=(10, 6)))
    assert res.folder == tmp_path / "pose" and res.retries == 0
    assert [p.name for p in tmp_path.iterdir()] == ["pose"]  # nothing else left behind
    # the folder is a valid capture (count, white/black, pattern/inverse pairs) holding exactly the rendered frames
    assert np.array_equal(captured(res.folder), stack)
    rec = json.loads((res.folder / "capture.json").read_text())
    assert rec["status"] == "complete" and rec["retries"] == 0 and len(rec["frames"]) == 38
    assert rec["camera"]["backend"] == "virtual" and rec["projector"]["size"] == [512, 384]
    assert rec["preflight"]["ok"] and rec["preflight"]["region"] == "board" and rec["preflight"]["white_saturated"] == 0
    assert rec["postflight"]["ok"]
    assert [f["camera"]["pattern"] for f in rec["frames"]] == list(range(38))
    assert all(f["check"]["ok"] for f in rec["frames"])
    assert json.loads((res.folder / "patterns.json").read_text())["files"][-1] == "37.png"

    view, _ = pipeline.view_from_folder(res.folder, Board(10, 6, 24.0))
    calib = single_pose.calibrate(view)
    assert abs(calib.camera.K[0, 0] - truth["camera"]["f"]) < 20       # 769.5 px
    assert abs(calib.projector.K[0, 0] - truth["projector"]["f"]) < 8  # 645.6 px
    assert np.linalg.norm(calib.T - np.array(truth["extrinsics"]["T"])) < 10  # mm, |T| = 186
    # and exactly what calibrate gives on the simulator's own folder of the same render
    ref = tmp_path / "rendered"
    simulate.write_capture(ref, stack, truth)
    calib_ref = single_pose.calibrate(pipeline.view_from_folder(ref, Board(10, 6, 24.0))[0])
    np.testing.assert_allclose(calib.camera.K, calib_ref.camera.K, rtol=1e-9)
    np.testing.assert_allclose(calib.projector.K, calib_ref.projector.K, rtol=1e-9)
    np.testing.assert_allclose(calib.T, calib_ref.T, rtol=1e-9, atol=1e-9)


def test_a_phase_sequence_is_captured_and_decodes_to_the_simulators_truth(rig, tmp_path):
    """``capture --family phase``: the frames the projector shows, the folder's patterns.json and capture.json come
    from the phase family's generator (8 steps at 16 and 128 px under the cue, white, black), and the decoded
    projector coordinates are the simulator's truth (within 0.1 px RMS on the white squares, every pixel within
    1 px: none in a wrong period)."""
    scene = rig[0]
    opts = CaptureOptions(settle_s=0.0, family="phase", board=(10, 6))
    ps = opts.sequence(*scene.proj_size)
    stack, _ = simulate.render(scene, order=ps, seed=3)
    with VirtualProjector(scene.proj_size) as proj, VirtualCamera(proj, scene, stack=stack, sequence=ps) as cam:
        res = capture_pose(tmp_path / "pose", proj, cam, opts)
    rec = json.loads((res.folder / "capture.json").read_text())
    assert rec["pattern_set"]["family"] == "phase" and rec["pattern_set"]["count"] == ps.count == 50
    assert [f["camera"]["pattern"] for f in rec["frames"]] == list(range(50))  # shown in the sequence's order
    assert rec["frames"][0]["pattern"] == "#0 (column phase 1 of 8, period 16 px)"
    cap = capmod.load_capture(res.folder)
    assert cap.pattern_set == ps and np.array_equal(cap.stack, stack)
    maps = decode.decode_with(cap.stack, cap.pattern_set)  # no warning (the suite's warnings are errors)
    tm = simulate.true_projector_maps(scene)
    from scipy.ndimage import binary_erosion, maximum_filter, minimum_filter

    # inside the board's white squares: a pixel within 2 px of a square's edge mixes two albedos' fringes (a real
    # camera's too) and has no single true coordinate; the black squares' fringes are ten times fainter
    white = cap.stack[ps.white].astype(float)
    board = binary_erosion(tm.lit_board, iterations=3) & (maximum_filter(white, 5) < 1.5 * minimum_filter(white, 5))
    board &= white > np.median(white[board])
    for got, true in ((maps.col, tm.col), (maps.row, tm.row)):
        ok = board & np.isfinite(got)
        err = (got - true)[ok]
        assert ok.sum() > 0.95 * board.sum()
        assert np.sqrt(np.mean(err ** 2)) < 0.1 and np.abs(err).max() < 1.0


@pytest.mark.parametrize("camera", [dict(latency=1, flush_works=False), dict(stale_grabs=(9, 16, 30, 41))],
                         ids=["one-frame-late-no-flush", "four-stale-grabs"])
def test_stale_frames_are_detected_and_regrabbed(rig, tmp_path, camera):
    _, stack, _ = rig
    events = []
    res = run_virtual(rig, tmp_path / "pose", progress=events.append, **camera)
    regrabs = [e for e in events if e.kind == "retry"]
    rec = res.record
    if "latency" in camera:
        assert res.retries == len(regrabs) == 38  # every first grab after a new pattern is the old one
        assert all(f["attempts"] == 2 for f in rec["frames"])
    else:
        assert res.retries == len(regrabs) == 4
    assert all(e.data["status"] in ("stale", "same") and "looks like" in e.message for e in regrabs)
    assert not any(f["camera"]["stale"] for f in rec["frames"])  # no stale frame was kept
    assert np.array_equal(captured(res.folder), stack)


@pytest.mark.parametrize("camera, board, phrase", [
    (dict(dead_projector=True), None, "the projector's light is not visible to the camera"),
    (dict(gain=1.5), (10, 6), "saturated on the board"),
    (dict(exposure_change_at=20), None, "changed mid-sequence"),
    (dict(exposure_change_at=20, exposure_factor=2.0), None, "the exposure or gain went up"),
    (dict(exposure_change_at=44, exposure_factor=0.7), None, "drifted during the capture"),
], ids=["dead-projector", "saturated-white", "exposure-halved", "exposure-doubled", "exposure-drift-at-end"])
def test_a_bad_capture_stops_with_one_line_and_leaves_nothing(rig, tmp_path, camera, board, phrase):
    with pytest.raises(CaptureFailed) as info:
        run_virtual(rig, tmp_path / "pose", CaptureOptions(settle_s=0.0, board=board), **camera)
    msg = str(info.value)
    assert phrase in msg and "\n" not in msg
    assert list(tmp_path.iterdir()) == []


def test_saturation_refusal_gives_exposure_advice(rig, tmp_path):
    with pytest.raises(CaptureFailed, match=r"white frame is \d+% saturated on the board .*lower the exposure to about "
                                            r"25% of the current exposure"):
        run_virtual(rig, tmp_path / "pose", CaptureOptions(settle_s=0.0, board=(10, 6)), gain=1.5)


class _CtrlC(VirtualCamera):
    """Ctrl-C arrives during the 25th grab."""

    def grab(self):
        if self.grabs == 25:
            raise KeyboardInterrupt
        return super().grab()


def test_ctrl_c_leaves_no_complete_looking_folder(rig, tmp_path):
    with pytest.raises(KeyboardInterrupt):
        run_virtual(rig, tmp_path / "pose", camera_cls=_CtrlC)
    assert list(tmp_path.iterdir()) == []
    # kept for inspection: hidden, partial, no JSON, and the pose folder itself does not exist
    with pytest.raises(KeyboardInterrupt):
        run_virtual(rig, tmp_path / "pose", CaptureOptions(settle_s=0.0, keep_failed=True), camera_cls=_CtrlC)
    (left,) = tmp_path.iterdir()
    assert left.name.startswith(".pose.partial")
    names = sorted(p.name for p in left.iterdir())
    assert names and all(n.endswith(".png") and not n.startswith(".") for n in names) and len(names) < 38
    with pytest.raises(CaptureError, match="no such folder"):
        capmod.load_capture(tmp_path / "pose")


def test_output_folder_is_never_written_into(rig, tmp_path):
    busy = tmp_path / "busy"
    busy.mkdir()
    (busy / "notes.txt").write_text("mine")
    with pytest.raises(ProcamError, match="exists and is not empty"):
        run_virtual(rig, busy)
    assert [p.name for p in busy.iterdir()] == ["notes.txt"] and (busy / "notes.txt").read_text() == "mine"
    empty = tmp_path / "empty"
    empty.mkdir()
    res = run_virtual(rig, empty)
    assert res.folder == empty and (empty / "capture.json").is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["busy", "empty"]


def test_moreno_order_and_a_session_of_poses(rig, tmp_path):
    scene, _, _ = rig
    stack, _ = simulate.render(scene, order="moreno", seed=4)
    seen = []
    with VirtualProjector(scene.proj_size) as proj, VirtualCamera(proj, scene, order="moreno", stack=stack) as cam:
        results = capture_poses(tmp_path / "session", 2, proj, lambda i: cam, CaptureOptions(settle_s=0.0, order="moreno"),
                                before_pose=seen.append)
    assert seen == [0, 1] and [r.folder.name for r in results] == ["pose01", "pose02"]
    for r in results:
        assert np.array_equal(captured(r.folder), stack)
        assert json.loads((r.folder / "patterns.json").read_text())["order"] == "moreno"
        assert r.record["extra"]["poses"] == 2


class _Recorder:
    """Hooks of a capture session that write down what they are told instead of printing it."""

    def __init__(self):
        self.calls = []

    def __getattr__(self, name):
        if name == "busy":
            import contextlib

            return lambda text: (self.calls.append(("busy", text)), contextlib.nullcontext())[1]
        return lambda *args: self.calls.append((name, *args))


@pytest.mark.parametrize("board", [None, pytest.param(Board(10, 6, 1.0), marks=pytest.mark.slow)],
                         ids=["no-board", "instant-verdict"])
def test_capture_session_runs_a_virtual_rig_through_its_hooks(tmp_path, capsys, monkeypatch, board):
    """The whole ``capture --virtual [--board]`` session as a library call: it prints nothing, tells its hooks
    every step in order, writes the pose with the simulator's truth, and with a board judges it."""
    from procam.acquire import cameras
    from procam.acquire.orchestrate import Devices, capture_session

    if board is None:  # a quarter of the camera's resolution (same field of view): the render is 16 times cheaper
        demo = cameras.demo_scene

        def small(*args, **kw):
            s = demo(*args, **kw)
            return s.replace(cam_size=(320, 200), K_cam=np.diag([0.25, 0.25, 1.0]) @ s.K_cam,
                             cam_dist_coeffs=(s.cam_dist_coeffs[0] / 0.25**2, 0.0))
        monkeypatch.setattr(cameras, "demo_scene", small)
    hooks = _Recorder()
    results = capture_session(tmp_path / "pose", 1, Devices(virtual=True, proj_size=(320, 200)), FAST,
                              board=board, hooks=hooks)
    assert capsys.readouterr() == ("", "")
    (res,) = results
    assert res.folder == tmp_path / "pose" and (res.folder / "truth.json").is_file()
    steps = [c[0] for c in hooks.calls]
    end = ["captured"] if board is None else ["captured", "verdict"]
    assert steps[:3] == ["projector", "pose", "busy"] and steps[-len(end):] == end
    assert hooks.calls[1] == ("pose", 0, 1, "virtual")
    assert hooks.calls[2] == ("busy", "rendering the simulator's view of pose 1")
    assert {"progress"} == set(steps[3:-len(end)])
    assert hooks.calls[len(steps) - len(end)] == ("captured", res)
    if board is not None:
        _, result, check, png = hooks.calls[-1]
        assert result is res and check.verdict == "good" and png == tmp_path / "pose.check.png"
        assert not png.exists()  # the picture is the hooks' to draw
    with pytest.raises(ProcamError, match="exists and is not empty"):  # before any device opens
        capture_session(tmp_path / "pose", 1, Devices(virtual=True), FAST, hooks=(later := _Recorder()))
    assert later.calls == []


# --------------------------------------------------------------------------------------------
# checks on synthetic arrays
# --------------------------------------------------------------------------------------------

def _synthetic(white=200, black=20, lit=(slice(20, 80), slice(30, 130))):
    W = np.full((100, 160), black, np.uint8)
    W[lit] = white
    return W, np.full((100, 160), black, np.uint8)


def test_preflight_levels_and_advice():
    W, B = _synthetic()
    pre = checks.preflight(W, B, W.copy())
    assert pre.ok and pre.region == "lit area" and pre.white_saturated == 0
    assert pre.region_fraction == pytest.approx(60 * 100 / 16000)
    assert pre.white_level == pytest.approx(200 / 255) and pre.contrast == pytest.approx(180 / 255)
    assert pre.repeat == 0 and pre.suggestions == ()
    assert np.allclose(pre.reference.normalise(W), 1) and np.allclose(pre.reference.normalise(B), 0)

    sat = W.copy()
    sat[20:26, 30:130] = 255  # 10 % of the lit area
    pre = checks.preflight(sat, B, exposure_ms=16.7)
    assert not pre.ok and pre.white_saturated == pytest.approx(0.1)
    assert "10% saturated on the lit area" in pre.reason and "about 8.35 ms (now 16.7 ms)" in pre.reason

    dim, _ = _synthetic(white=60)
    pre = checks.preflight(dim, B)
    assert pre.ok and pre.exposure_factor == pytest.approx(0.8 / (60 / 255))
    assert "raise the exposure to about 340% of the current exposure" in pre.suggestions[0]

    assert "not visible" in checks.preflight(B, B).reason
    assert "stale frame" in checks.preflight(W, B, B).reason  # the second white is not white


def test_preflight_measures_on_the_board():
    W, B = _synthetic()
    W[40:50, 60:70] = 255  # saturated, and the board is exactly there
    corners = np.array([[60, 40], [69, 40], [69, 49], [60, 49]], float)
    assert checks.preflight(W, B).ok  # 1.7 % of the lit area
    pre = checks.preflight(W, B, board_corners=corners)
    assert not pre.ok and pre.region == "board" and pre.white_saturated == 1.0


def test_pair_and_frame_checks():
    ps = patterns.pattern_set(64, 32)
    rng = np.random.default_rng(5)
    bits = rng.random(4000) < 0.5
    p_a = np.where(bits, 1.0, 0.0) + rng.normal(0, 0.02, 4000)
    p_b = 1.0 - p_a + rng.normal(0, 0.02, 4000)
    a, b = (int(v) for v in ps.pair_indices("col")[2])  # #4, #5: column bit 3 and its inverse
    assert checks.check_pair(p_a, p_b, a, b, ps).status == "ok"
    assert checks.check_frame(p_b, b, ps, (a, p_a), p_a).status == "ok"
    # a stale inverse (a copy of the pattern) is caught frame by frame
    fc = checks.check_frame(p_a.copy(), b, ps, (a, p_a), p_a)
    assert fc.status == "stale" and "#5 (column bit 3 inverse) looks like #4 (column bit 3)" in fc.reason
    # a pattern/inverse pair whose sum is off: the exposure changed
    pc = checks.check_pair(p_a, 0.5 * p_b, a, b, ps)
    assert pc.status == "level" and "changed mid-sequence" in pc.reason
    # unrelated frames are not a pair
    assert checks.check_pair(p_a, np.where(rng.random(4000) < 0.5, 1.0, 0.0), a, b, ps).status == "not-inverse"
    # white/black levels, and a black frame that is the white one again
    ones = np.ones(4000)
    assert checks.check_frame(ones, ps.white, ps, (ps.white - 1, p_b)).ok
    assert checks.check_frame(0.6 * ones, ps.white, ps, (ps.white - 1, p_b)).status == "level"
    assert checks.check_frame(ones, ps.black, ps, (ps.white, ones)).status == "stale"
    assert checks.check_frame(1.6 * p_a, a, ps).status == "level"
    # unresolved stripes (grey) cannot be judged: kept as unverified
    assert checks.check_frame(np.full(4000, 0.5), a, ps, (a - 1, np.full(4000, 0.5))).status == "unverified"
    assert capmod.describe_frame(ps.row_start + 1, ps) == "#13 (row bit 4 inverse)"


# --------------------------------------------------------------------------------------------
# folder-watch camera: a "vendor app" saves a shot of each pattern shown
# --------------------------------------------------------------------------------------------

def _vendor_app(proj, cam, folder, stop):
    """Saves what ``cam`` sees after each new pattern, slowly (half the bytes, a pause, the rest), plus junk."""
    import cv2

    shown, n = proj.shown, 0
    while not stop.is_set():
        if proj.shown == shown:
            time.sleep(0.002)
            continue
        shown = proj.shown
        time.sleep(0.01)  # the photographer reacts
        data = cv2.imencode(".png", cam.grab().image)[1].tobytes()
        n += 1
        (folder / f".IMG_{n:04d}.png").write_bytes(data[:100])  # a hidden temporary file
        (folder / f"IMG_{n:04d}.png.part").write_bytes(data[:100])
        path = folder / f"IMG_{n:04d}.png"
        with open(path, "wb") as f:
            f.write(data[: len(data) // 2])
            f.flush()
            time.sleep(0.03)
            f.write(data[len(data) // 2:])


def test_folder_watch_camera_through_a_whole_capture(rig, tmp_path):
    scene, stack, _ = rig
    shots = tmp_path / "shots"
    shots.mkdir()
    import cv2

    cv2.imwrite(str(shots / "old.png"), stack[0])  # there before: never taken
    stop = threading.Event()
    with VirtualProjector(scene.proj_size) as proj, VirtualCamera(proj, scene, stack=stack) as seen:
        cam = FolderWatchCamera(shots, timeout_s=20, poll_s=0.01, stable_s=0.06)
        app = threading.Thread(target=_vendor_app, args=(proj, seen, shots, stop), daemon=True)
        app.start()
        try:
            with cam:
                res = capture_pose(tmp_path / "pose", proj, cam, FAST)
        finally:
            stop.set()
            app.join()
    assert np.array_equal(captured(res.folder), stack)
    files = res.record["camera"]["files"]  # three pre-flight shots, the sequence, one post-flight shot
    assert files == [f"IMG_{n:04d}.png" for n in range(1, 3 + 38 + 2)]
    assert res.record["frames"][0]["camera"]["file"].endswith("IMG_0004.png")
    assert (shots / "old.png").exists()


def test_folder_watch_times_out_with_one_line(tmp_path):
    with FolderWatchCamera(tmp_path, timeout_s=0.1, poll_s=0.01) as cam:
        with pytest.raises(ProcamError, match=r"no new image within 0.1 s") as info:
            cam.grab()
    assert "\n" not in str(info.value)
    with pytest.raises(ProcamError, match="no such folder"):
        FolderWatchCamera(tmp_path / "missing").open()


def test_opencv_camera_reports_settings_the_source_ignores(tmp_path):
    """OpenCVCamera on a video file (FFmpeg): frames come grey, flush drops frames, and the exposure and gain
    the source cannot take are reported as not taking effect."""
    import cv2

    from procam.acquire import OpenCVCamera

    path = str(tmp_path / "clip.avi")
    writer = cv2.VideoWriter(path, cv2.VideoWriter_fourcc(*"MJPG"), 30, (160, 120))
    if not writer.isOpened():
        pytest.skip("this OpenCV build cannot write MJPG video")
    for i in range(8):
        writer.write(np.full((120, 160, 3), 30 * i, np.uint8))
    writer.release()
    with OpenCVCamera(path, exposure_ms=10.0, gain=2.0, flush_frames=2) as cam:
        first = cam.grab()  # frame 1 (opening read frame 0)
        cam.flush()
        later = cam.grab()  # frame 4
        d = cam.describe()
    assert first.image.shape == (120, 160) and first.image.dtype == np.uint8
    assert abs(first.image.mean() - 30) < 3 and abs(later.image.mean() - 120) < 3
    assert d["size"] == [160, 120] and cam.exposure_ms is None
    assert d["settings"]["exposure_ms"]["took_effect"] is False and d["settings"]["gain"]["took_effect"] is False
    assert any("exposure" in n for n in d["notes"]) and any("gain 2 not accepted" in n for n in d["notes"])
    with pytest.raises(ProcamError, match="cannot be opened"):
        OpenCVCamera(str(tmp_path / "missing.avi")).open()


def test_camera_specs():
    assert parse_camera_spec("opencv:2") == ("opencv", "2")
    assert parse_camera_spec("opencv") == ("opencv", "0")
    assert parse_camera_spec("genicam:/opt/x/producer.cti#SN123") == ("genicam", "/opt/x/producer.cti#SN123")
    assert parse_camera_spec("folder:shots") == ("folder", "shots")
    assert parse_camera_spec("virtual") == ("virtual", "")
    for bad in ("webcam:0", "opencv:cam", "genicam:producer.so", "folder:", ""):
        with pytest.raises(ProcamError, match="--camera"):
            parse_camera_spec(bad)


# --------------------------------------------------------------------------------------------
# the CLI (importing the module registers the command)
# --------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def cli():
    import procam.cli.capture  # noqa: F401

    return run_cli


@pytest.mark.parametrize("args, phrase", [
    (["--settle-ms", "nan"], "--settle-ms must be a finite number"),
    (["--settle-ms", "-1"], "--settle-ms must be a finite number >= 0"),
    (["--exposure", "0"], "--exposure must be a finite number > 0"),
    (["--exposure", "inf"], "--exposure must be a finite number"),
    (["--gain", "nan"], "--gain must be a finite number"),
    (["--timeout", "-3"], "--timeout must be a finite number > 0"),
    (["--retries", "100"], "--retries must be between 0 and 20"),
    (["--poses", "0"], "--poses must be between 1 and 99"),
    (["--display", "-1"], "--display must be a display index"),
    (["--projector", "1x1"], "--projector 1x1: each side must be from 2"),
    (["--projector", "99999x2"], "--projector 99999x2: each side must be"),
    (["--camera", "webcam:0"], "unknown camera"),
    (["--order", "zigzag"], "'zigzag' is not one of 'opencv', 'moreno'"),
    (["--virtual", "--camera", "folder:x"], "--virtual uses the simulator"),
    (["--virtual", "--step", "2"], "renders step-1 sequences only"),
    (["--family", "phase", "--step", "2"], "--step applies to the Gray family (--family gray, the default), not to --family phase"),
    (["--steps", "4"], "--steps applies to the phase families"),
    (["--family", "phase", "--counts", "7,6,5"], "--counts applies to --family heterodyne"),
    (["--family", "gray-phase", "--steps", "2"], "--steps must be"),
])
def test_cli_checks_every_option_before_opening_a_device(cli, tmp_path, args, phrase):
    code, _, err = cli(["capture", tmp_path / "pose", *args])
    assert code == 2 and phrase in err and len(err.strip().splitlines()) == 1, err
    assert list(tmp_path.iterdir()) == []


def test_cli_refuses_a_non_empty_folder_and_a_missing_one(cli, tmp_path):
    (tmp_path / "x.txt").write_text("x")
    code, _, err = cli(["capture", tmp_path, "--virtual"])
    assert code == 2 and "exists and is not empty" in err
    code, _, err = cli(["capture"])
    assert code == 2 and "OUT_DIR" in err


def test_cli_list_devices_without_a_desktop(cli, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    code, out, _ = cli(["capture", "--list-devices"])
    assert code == 0 and "displays" in out and "none:" in out and "cameras" in out


@pytest.mark.slow
def test_cli_virtual_demo_writes_a_capture_that_calibrates(cli, tmp_path):
    """``procam capture --virtual`` (the ideal rig, its projector resized to 640x400), then ``procam calibrate``."""
    code, out, err = cli(["capture", tmp_path / "pose", "--virtual", "--projector", "640x400", "--board", "10x6"])
    assert code == 0, err
    assert "wrote 40 frames, patterns.json and capture.json" in out
    # the instant verdict, before the next pose: printed, and its picture next to the folder
    assert "verdict: good" in out and (tmp_path / "pose.check.png").is_file()
    truth = json.loads((tmp_path / "pose" / "truth.json").read_text())
    code, out, err = cli(["calibrate", tmp_path / "pose", "--board", "10x6", "--square", "24", "-o", tmp_path / "c.json"])
    assert code == 0, err
    c = json.loads((tmp_path / "c.json").read_text())
    assert abs(c["camera"]["K"][0][0] - truth["camera"]["f"]) < 40
    assert abs(c["projector"]["K"][0][0] - truth["projector"]["f"]) < 8


# --------------------------------------------------------------------------------------------
# the real projector window under Xvfb
# --------------------------------------------------------------------------------------------

def _screen_grabber():
    try:
        import mss
    except ImportError:
        mss = None
    if mss is not None:
        def grab(display):
            cls = getattr(mss, "MSS", None) or mss.mss
            with cls(display=display) as sct:
                shot = np.array(sct.grab(sct.monitors[0]))  # BGRA
            return shot[:, :, 2::-1]
        return grab
    if shutil.which("xwd"):
        return lambda display: _xwd(display)
    return None


def _xwd(display) -> np.ndarray:
    """The X screen as (H, W, 3) RGB through ``xwd -root`` (ZPixmap, 24/32 bits per pixel)."""
    data = subprocess.run(["xwd", "-root", "-silent", "-display", display], check=True, capture_output=True).stdout
    hdr = np.frombuffer(data[:100], ">u4")
    header_size, width, height, byte_order, bpp, bpl, ncolors = (int(hdr[i]) for i in (0, 4, 5, 7, 11, 12, 19))
    rmask, gmask, bmask = (int(hdr[i]) for i in (14, 15, 16))
    start = header_size + 12 * ncolors
    assert bpp == 32, f"xwd: {bpp} bits per pixel"
    rows = np.frombuffer(data[start:start + bpl * height], np.uint8).reshape(height, bpl)[:, :4 * width]
    px = rows.copy().view("<u4" if byte_order == 0 else ">u4").reshape(height, width)

    def channel(mask):
        shift = (mask & -mask).bit_length() - 1
        return ((px & mask) >> shift).astype(np.uint8)

    return np.stack([channel(rmask), channel(gmask), channel(bmask)], axis=2)


@pytest.fixture
def xvfb(monkeypatch):
    """Start Xvfb on a free display number with one screen of the given size; DISPLAY points at it."""
    if shutil.which("Xvfb") is None:
        pytest.skip("Xvfb is not installed (Debian: apt-get install xvfb)")
    pytest.importorskip("pygame", reason="pygame-ce is not installed (pip install 'procam[capture]')")
    pytest.importorskip("screeninfo", reason="screeninfo is not installed (pip install 'procam[capture]')")
    grab = _screen_grabber()
    if grab is None:
        pytest.skip("no X screen grabber: pip install mss, or apt-get install x11-apps (xwd)")
    procs = []

    def start(size):
        r, w = os.pipe()
        proc = subprocess.Popen(["Xvfb", "-displayfd", str(w), "-screen", "0", f"{size[0]}x{size[1]}x24",
                                 "-nolisten", "tcp", "-noreset"], pass_fds=(w,), stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)
        os.close(w)
        procs.append(proc)
        text, deadline = b"", time.monotonic() + 20
        while not text.endswith(b"\n") and time.monotonic() < deadline:  # Xvfb writes "N\n" once it is ready
            ready, _, _ = select.select([r], [], [], max(0.0, deadline - time.monotonic()))
            chunk = os.read(r, 64) if ready else b""
            if not chunk:
                break
            text += chunk
        os.close(r)
        number = text.decode().strip()
        if not text.endswith(b"\n") or not number.isdigit():
            pytest.skip("Xvfb did not start")
        display = f":{number}"
        monkeypatch.setenv("DISPLAY", display)
        monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
        monkeypatch.setenv("SDL_VIDEODRIVER", "x11")
        return display, grab

    yield start
    for proc in procs:
        proc.terminate()
        proc.wait(10)


def test_projector_window_is_full_screen_and_pixel_exact(xvfb):
    display, grab = xvfb((512, 384))
    seq = patterns.generate(512, 384)
    noise = np.random.default_rng(0).integers(0, 256, (384, 512), dtype=np.uint8)
    with ProjectorWindow((512, 384), display=0) as win:
        d = win.describe()
        assert d["display"]["width"] == 512 and d["display"]["height"] == 384 and d["sdl_driver"] == "x11"
        for k, img in enumerate(list(seq) + [noise]):
            win.show(img)
            shot = grab(display)
            assert shot.shape == (384, 512, 3)
            for c in range(3):
                assert np.array_equal(shot[:, :, c], img), f"pattern {k}, channel {c}"


def test_projector_window_refuses_a_display_of_another_size(xvfb):
    xvfb((640, 480))
    with pytest.raises(ProcamError, match=r"display 0 is 640x480 but the patterns are 512x384.*--projector 640x480") as info:
        ProjectorWindow((512, 384), display=0).open()
    assert "\n" not in str(info.value)
    with pytest.raises(ProcamError, match="only one display is connected"):
        ProjectorWindow((640, 480)).open()


def test_capture_through_the_real_window(rig, xvfb, tmp_path):
    scene, stack, _ = rig
    display, grab = xvfb(scene.proj_size)
    with ProjectorWindow(scene.proj_size, display=0) as win, VirtualCamera(win, scene, stack=stack) as cam:
        res = capture_pose(tmp_path / "pose", win, cam, FAST)
        assert np.array_equal(grab(display)[:, :, 0], np.zeros((384, 512), np.uint8))  # dark after the capture
    assert np.array_equal(captured(res.folder), stack)
    assert res.record["projector"]["backend"] == "pygame-window"


def test_the_capture_command_prints_the_preflights_suggestions(capsys):
    """procam capture printed the pre-flight's advice from a key its dict does not have: a dim white frame's
    'raise the exposure' never reached the user."""
    from types import SimpleNamespace

    from procam.cli import capture as cli_capture

    dim, B = _synthetic(white=60)
    pre = checks.preflight(dim, B)
    assert pre.ok and pre.suggestions
    with cli_capture._Printer() as printer:
        printer.progress(0, SimpleNamespace(kind="preflight", data=pre.to_dict(), total=3))
    out = capsys.readouterr()
    assert "raise the exposure to about 340%" in out.out + out.err
