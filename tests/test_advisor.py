"""procam.advisor on the virtual procam: the simulator renders what the camera sees under the projector's white
light at the board's pose; an earlier capture's single-pose calibration gives the projector side.  Also the
preview window (off-screen and under Xvfb) and the CLI (procam advise, procam capture --advise)."""

import json

import numpy as np
import pytest
from conftest import run_cli
from test_acquire import xvfb  # noqa: F401  (the virtual X server fixture)

from procam import crlb, models, patterns, pipeline, simulate, single_pose
from procam.acquire.cameras import VirtualLiveCamera
from procam.acquire.live import advise
from procam.advisor import (Advisor, AdvisorOptions, apply_move, guessed_camera, move_between)
from procam.board import Board
from procam.board.corners import LIVE, detect_corners
from procam.errors import ProcamError

BOARD = Board(10, 6, 24.0)
NOW = AdvisorOptions(search_interval_s=0.0)  # the move search may run again on any frame (times are synthetic)


@pytest.fixture(scope="module")
def scene():
    """The 'ideal' rig (1280x800 camera, 1920x1080 projector, division distortion k1 = -1e-7) at the
    recommended pose."""
    return simulate.preset("ideal")


@pytest.fixture(scope="module")
def earlier(scene):
    """An earlier capture at the recommended pose (rendered, decoded) and its single-pose calibration."""
    s = scene.replace(supersample=1)
    stack, _ = simulate.render(s, seed=1)
    view, _ = pipeline.view_from_stack(stack, patterns.pattern_set(*s.proj_size), BOARD, name="pose01")
    return single_pose.calibrate(view)


def advisor(calib=None, options=NOW, size=(1280, 800)):
    a = Advisor(BOARD, size, options)
    if calib is not None:
        a.set_calibration(calib, "pose01")
    return a


def at_pose(scene, angles, frame="projector", seed=0):
    """A live camera with the board at ``angles`` (psi, nu, phi) in ``frame``, and the scene."""
    s = simulate.with_board_pose(scene, angles, frame=frame)
    return VirtualLiveCamera(s, seed=seed), s


def true_bounds(s, sigma_c=0.1, sigma_p=0.2):
    """Cramer-Rao std of f_c (the solver's rule for the principal-point prior) and f_p at the true pose, with the
    true intrinsics."""
    obj = BOARD.object_points()
    k1, k2 = s.cam_dist_coeffs
    b = crlb.camera_bound(s.K_cam, None, k1, k2, s.R_board, s.t_board, obj, sigma_c)
    prior = 0.025 * max(s.cam_size)
    if not max(b.std["u0c"], b.std["v0c"]) <= prior:
        b = crlb.camera_bound(s.K_cam, None, k1, k2, s.R_board, s.t_board, obj, sigma_c, pp_prior_std=prior)
    p = crlb.projector_bound(s.K_proj, s.R_board_proj, s.t_board_proj, obj, sigma_p)
    return b.std["f_c"], p.std["f_p"]


# --------------------------------------------------------------------------------------------
# pieces
# --------------------------------------------------------------------------------------------

def test_fast_detection_finds_the_corners_like_the_full_resolution_detector(scene):
    cam = VirtualLiveCamera(scene, seed=2)
    img = cam.grab().image
    truth = simulate.corner_truth(scene)["camera_distorted"]
    fast = detect_corners(img, BOARD.pattern_size, LIVE)  # the advisor's: downscaled to 640 px
    # the advisor refines with cornerSubPix (fast; its 0.05 px are far below the 0.1 px noise its bounds
    # assume); calibration uses the slower saddle fit (board.REFINERS "fit", ~0.01 px here)
    full = detect_corners(img, BOARD.pattern_size, refine="subpix")
    assert fast.shape == (60, 2)
    err_fast = np.sqrt(np.mean(np.sum((fast - truth) ** 2, axis=1)))
    err_full = np.sqrt(np.mean(np.sum((full - truth) ** 2, axis=1)))
    assert err_fast < 0.1 and err_fast < 1.5 * err_full  # px; the refinement at full resolution does the work
    # no board: nothing (and quickly rejected); uint16 frames work too
    assert detect_corners(np.full((800, 1280), 128, np.uint8), (10, 6), LIVE) is None
    assert detect_corners(np.random.default_rng(0).integers(0, 255, (800, 1280), dtype=np.uint8), (10, 6), LIVE) is None
    fast16 = detect_corners(img.astype(np.uint16) * 257, BOARD.pattern_size, LIVE)
    np.testing.assert_allclose(fast16, fast, atol=0.02)


def test_turn_and_tilt_signs_and_their_inverse():
    R0, t0 = models.euler_to_matrix(*np.radians([10.0, -5.0, 3.0])), np.array([20.0, -10.0, 500.0])
    obj = BOARD.object_points()
    right, left = obj[BOARD.cols - 1], obj[0]                  # corner 0 is top-left in the image
    top, bottom = obj[0], obj[BOARD.n_corners - BOARD.cols]
    R, t = apply_move(R0, t0, turn_deg=10.0)
    depth = lambda R, X: (R @ X + t0)[2]  # noqa: E731
    assert depth(R, right) - depth(R, left) > depth(R0, right) - depth(R0, left) + 30   # right edge away
    R, t = apply_move(R0, t0, tilt_deg=10.0)
    assert depth(R, top) - depth(R, bottom) > depth(R0, top) - depth(R0, bottom) + 15    # top edge away
    np.testing.assert_array_equal(t, t0)                                                 # about the centre
    R, _ = apply_move(R0, t0, 12.0, -7.0)
    assert move_between(R0, R) == pytest.approx((12.0, -7.0), abs=0.3)


def test_principal_point_prior_is_the_bayesian_bound(scene):
    """camera_bound(pp_prior_std=s) = (Cov_data^-1 + diag(0, 0, 1/s^2, 1/s^2, 0...))^-1, and is finite without
    distortion, where the data alone determine nothing."""
    obj = BOARD.object_points()
    args = (scene.K_cam, None, -1e-7, 0.0, scene.R_board, scene.t_board, obj, 0.1)
    data = crlb.camera_bound(*args)
    post = crlb.camera_bound(*args, pp_prior_std=30.0)
    info = np.linalg.inv(data.cov)
    info[2, 2] += 1 / 30.0 ** 2
    info[3, 3] += 1 / 30.0 ** 2
    np.testing.assert_allclose(post.cov[:4, :4], np.linalg.inv(info)[:4, :4], rtol=1e-5)
    assert post.std["u0c"] < min(30.0, data.std["u0c"])
    flat = crlb.camera_bound(scene.K_cam, None, 0.0, 0.0, scene.R_board, scene.t_board, obj, 0.1)
    assert flat.degenerate
    assert 0 < crlb.camera_bound(scene.K_cam, None, 0.0, 0.0, scene.R_board, scene.t_board, obj, 0.1,
                                 pp_prior_std=32.0).std["f_c"] < 200


def test_options_are_checked_with_one_line():
    for kw, phrase in (({"target_pct": float("nan")}, "target_pct"), ({"target_pct": 0}, "target_pct"),
                       ({"still_s": -1}, "still_s"), ({"detect_width": 100}, "detect_width"),
                       ({"aim": 1.5}, "aim"), ({"sigma_camera": float("inf")}, "sigma_camera")):
        with pytest.raises(ProcamError, match=phrase) as info:
            AdvisorOptions(**kw)
        assert "\n" not in str(info.value)
    with pytest.raises(ProcamError, match="1280x800"):
        Advisor(BOARD, (640, 400), camera=guessed_camera((1280, 800)), camera_source="cam.json")
    with pytest.raises(ProcamError, match="expected a grey 1280x800"):
        advisor().update(np.zeros((400, 640), np.uint8))


# --------------------------------------------------------------------------------------------
# the advice against the simulator's truth
# --------------------------------------------------------------------------------------------

@pytest.mark.parametrize("psi_p", [-25.0, 0.0, 25.0])
def test_projector_angles_and_predicted_stds_across_poses(scene, earlier, psi_p):
    """nu_p from the earlier capture's R, T within 1 deg of the truth; the predicted stds are the Cramer-Rao
    bounds at the true pose with the true intrinsics (within 10 %)."""
    adv = advisor(earlier, AdvisorOptions(search_interval_s=60.0))  # one move search: not what this tests
    for nu_p in (-25.0, 0.0, 25.0):
        cam, s = at_pose(scene, (psi_p, nu_p, 0.0))
        a = adv.update(cam.grab().image, 0.0)
        assert a.found and a.phase == "target"
        true_p = models.board_angles_deg(s.R_board_proj, s.t_board_proj)
        true_c = models.board_angles_deg(s.R_board, s.t_board)
        assert abs(a.projector.angles_deg[1] - true_p[1]) < 1.0, (psi_p, nu_p)
        assert abs(a.projector.angles_deg[0] - true_p[0]) < 1.0
        assert np.max(np.abs(np.subtract(a.camera.angles_deg, true_c))) < 0.5
        bc, bp = true_bounds(s)
        # the bounds where they mean something (std < 5 % of f); near a degenerate angle (std ~ 1 / angle) both
        # only need to say "large"
        for got, want, f in ((a.camera.std_f, bc, s.K_cam[0, 0]), (a.projector.std_f, bp, s.K_proj[0, 0])):
            if want < 0.05 * f:
                assert got == pytest.approx(want, rel=0.1), (psi_p, nu_p)
            else:
                assert got > 0.03 * f, (psi_p, nu_p)
        if nu_p == 0.0:  # degenerate for the projector: no pose is good
            assert a.state == "adjust" and ("nu_p" in a.limiting or "f_p" in a.limiting)


def follow(advice_json: dict) -> tuple[float, float, np.ndarray]:
    """What the scripted user does with one JSON advice: every turn and tilt as told, a 20 mm step per move."""
    turn = sum(a["degrees"] for a in advice_json["actions"] if a["kind"] == "turn")
    tilt = sum(a["degrees"] for a in advice_json["actions"] if a["kind"] == "tilt")
    shift = np.zeros(3)
    for a in advice_json["actions"]:
        if a["kind"] == "move":
            shift += {"left": (-20, 0, 0), "right": (20, 0, 0), "up": (0, -20, 0), "down": (0, 20, 0)}[a["direction"]]
        elif a["kind"] == "closer":
            shift[2] -= 50
    return turn, tilt, shift


def test_scripted_session_from_a_degenerate_pose_reaches_a_good_one(scene, earlier):
    """Start with the board square to the projector's vertical axis (nu_p = 0.5 deg), turn and tilt it as the
    JSON advice says, hold still: the pose it calls ready calibrates within the predicted std of the truth."""
    cam, _ = at_pose(scene, (12.0, 0.5, 0.0), seed=7)
    adv = advisor(earlier)
    t, steps, log = 0.0, 0, []
    for steps in range(1, 6):
        d = json.loads(adv.update(cam.grab().image, t).to_json())
        t += 0.1
        log.append((d["state"], d["projector"]["nu"], d["message"]))
        if d["state"] in ("good", "ready"):
            break
        assert d["state"] == "adjust" and any(a["kind"] in ("turn", "tilt") for a in d["actions"])
        cam.move(*follow(d))
    else:
        pytest.fail(f"no good pose in 5 steps: {log}")
    assert log[0][0] == "adjust" and abs(log[0][1]) < 1.5 and "nu_p" in log[0][2] or "turn" in log[0][2]
    assert steps <= 3, log
    for _ in range(10):  # hold still: ready once the corners have not moved for still_s
        a = adv.update(cam.grab().image, t)
        t += 0.1
        if a.ready:
            break
    assert a.ready and a.message.startswith("good — hold still") and a.motion_px < 0.5
    # the capture of that pose: a full render, decoded, single-pose calibration
    s = cam.scene
    stack, _ = simulate.render(s, seed=11)
    calib = single_pose.calibrate(pipeline.view_from_stack(stack, patterns.pattern_set(*s.proj_size), BOARD)[0])
    assert calib.poses[0]["advice"]["ok"] and not calib.warnings
    assert abs(calib.camera.K[0, 0] - s.K_cam[0, 0]) <= a.camera.std_f
    assert abs(calib.projector.K[0, 0] - s.K_proj[0, 0]) <= a.projector.std_f
    assert a.camera.rel_std_f <= 0.01 and a.projector.rel_std_f <= 0.01


def test_first_capture_with_guessed_intrinsics(scene):
    """No calibration: guessed f, the projector side unknown, the camera rule; a board square to the camera's
    horizontal axis (psi_c = 1 deg) is turned into a pose good for the first capture."""
    cam, _ = at_pose(scene, (1.0, 14.0, 0.0), frame="camera", seed=4)
    adv = advisor()
    d = json.loads(adv.update(cam.grab().image, 0.0).to_json())
    assert d["phase"] == "first" and d["projector"] is None and d["state"] == "adjust"
    assert d["intrinsics"].startswith("guessed f = image diagonal (1509 px)")
    assert any("projector side unknown" in n for n in d["notes"]) and "psi_c" in d["limiting"]
    assert d["actions"][0]["kind"] == "tilt" and abs(d["actions"][0]["degrees"]) >= 3
    cam.move(*follow(d))
    a = adv.update(cam.grab().image, 0.1)
    assert a.good and a.actions[-1].kind == "capture" and "first capture" in a.message


def test_stillness_size_edges_and_the_projector_light(scene, earlier):
    adv = advisor(earlier, AdvisorOptions(search_interval_s=0.0, still_s=0.3, still_px=0.5))
    cam = VirtualLiveCamera(scene, seed=1)
    img = cam.grab().image
    states = [adv.update(img, t).state for t in (0.0, 0.1, 0.2, 0.3)]
    assert states == ["good", "good", "good", "ready"]
    moved = np.roll(img, 2, axis=1)  # the board moved 2 px
    a = adv.update(moved, 0.4)
    assert a.state == "good" and not a.still and a.motion_px == pytest.approx(2.0, abs=0.3)
    assert adv.update(moved, 0.75).ready
    # below the projector's light (its axis is near its image's bottom edge): move up
    cam.set_board(scene.R_board, scene.t_board + [0.0, 30.0, 0.0])
    a = adv.update(cam.grab().image, 1.0)
    assert a.outside_light == ("bottom",) and a.state == "adjust"
    assert a.actions[0].kind == "move" and a.actions[0].direction == "up" and "projector's light" in a.message
    # far away: too small
    cam.set_board(scene.R_board, scene.t_board * 2.0)
    a = adv.update(cam.grab().image, 1.1)
    assert a.board_fraction < 0.05 and a.actions[0].kind == "closer"
    # the outer squares at the image's top edge (the guess will do: no projector side)
    cam.set_board(scene.R_board, scene.t_board + [0.0, -66.0, 0.0])
    a = advisor().update(cam.grab().image, 1.2)
    assert a.edge_px < 8 and a.actions[0].kind == "move" and a.actions[0].direction == "down"
    assert "from the image's top edge" in a.message
    # no board at all
    a = adv.update(np.full((800, 1280), 40, np.uint8), 1.3)
    assert a.state == "no-board" and not a.found and a.camera is None
    d = json.loads(a.to_json())
    assert d["state"] == "no-board" and d["actions"][0]["kind"] == "find"


def test_the_loop_captures_by_itself_when_ready(scene, earlier):
    cam = VirtualLiveCamera(scene, seed=5)
    adv = advisor(earlier, AdvisorOptions(still_s=0.2))
    seen = []
    res = advise(cam, adv, on_advice=lambda img, a: seen.append(a.state), auto=True, max_frames=200)
    assert res.reason == "auto" and res.advice.ready and seen[-1] == "ready" and seen[0] == "good"
    res = advise(cam, adv, poll=lambda: "capture")
    assert res.reason == "key" and res.frames == 1
    assert advise(cam, adv, max_frames=2).reason == "max-frames"


# --------------------------------------------------------------------------------------------
# Monte Carlo (slow): the predicted stds against the spread of actual single-pose calibrations
# --------------------------------------------------------------------------------------------

@pytest.mark.slow
def test_predicted_stds_match_monte_carlo_single_pose_calibrations(scene, earlier):
    """At poses across the grid (away from degenerate angles), the advisor's std of f_c and f_p (from one rendered
    frame and the earlier capture's calibration) is within 20 % of the spread of 150 single-pose calibrations of
    that pose from corners with the assumed noise (0.1 px camera, 0.2 px projector)."""
    adv = advisor(earlier)
    for i, angles in enumerate(((15.0, 25.0), (-15.0, 30.0), (20.0, -20.0), (-20.0, -25.0), (10.0, 30.0))):
        cam, s = at_pose(scene, (*angles, 0.0))
        a = adv.update(cam.grab().image, 0.0)
        # poses where the bound means something (near a degenerate angle the estimate is not Gaussian)
        assert a.camera.rel_std_f < 0.03 and a.projector.rel_std_f < 0.03, angles
        fc, fp = [], []
        for k in range(150):
            obj, c, p = simulate.correspondences(s, 0.1, 0.2, seed=1000 * (i + 1) + k)  # new draws per pose
            fc.append(single_pose.calibrate_camera(obj, c, s.cam_size).K[0, 0])
            fp.append(single_pose.calibrate_projector(obj, p, s.proj_size).K[0, 0])
        assert a.camera.std_f == pytest.approx(np.std(fc, ddof=1), rel=0.2), angles
        assert a.projector.std_f == pytest.approx(np.std(fp, ddof=1), rel=0.2), angles


# --------------------------------------------------------------------------------------------
# the preview
# --------------------------------------------------------------------------------------------

def _overlay_checks(shot: np.ndarray, a, size):
    """The outline's colour along the board's outline, and white text in the panel."""
    from procam.acquire.preview import COLOURS

    sx, sy = size[0] / 1280, size[1] / 800
    o = (a.outline + 0.5) * [sx, sy] - 0.5
    colour = np.array(COLOURS[a.state])
    hits = 0
    for p, q in zip(o, np.roll(o, -1, axis=0)):
        for u in np.linspace(0.1, 0.9, 9):
            x, y = (p + u * (q - p)).round().astype(int)
            patch = shot[y - 2:y + 3, x - 2:x + 3].reshape(-1, 3).astype(int)
            hits += bool(np.any(np.all(np.abs(patch - colour) <= 2, axis=1)))
    assert hits >= 34  # of 36 points along the four edges
    panel = shot[5:60, 5:300].reshape(-1, 3)
    assert np.sum(np.all(panel >= 240, axis=1)) > 200            # white text
    assert np.sum(np.all(np.abs(panel.astype(int) - colour) <= 2, axis=1)) > 50  # the headline in the state's colour


def test_preview_draws_the_overlay_off_screen(scene, earlier):
    pg = pytest.importorskip("pygame", reason="pygame-ce is not installed (pip install 'procam[capture]')")
    from procam.acquire.preview import PreviewWindow, advice_lines

    cam, _ = at_pose(scene, (12.0, 0.5, 0.0))
    img = cam.grab().image
    a = advisor(earlier).update(img, 0.0)
    win = PreviewWindow((1280, 800), max_size=(1280, 800))
    shot = np.transpose(pg.surfarray.array3d(win.render_offscreen(img, a)), (1, 0, 2))
    _overlay_checks(shot, a, (1280, 800))
    lines = [t for _, t in advice_lines(a)]
    assert lines[0] == a.message and any(t.startswith("projector: psi_p") for t in lines)
    assert any("intrinsics from pose01" in t for t in lines)
    # scaled down: a 1920x1080 camera in a window of at most 1280x800
    assert PreviewWindow((1920, 1080)).size == (1280, 720)


def test_preview_window_under_xvfb(scene, earlier, xvfb):  # noqa: F811 (the imported fixture)
    """The real window: a screen grab shows the frame with the overlay exactly as the off-screen drawing."""
    from procam.acquire.preview import PreviewWindow

    display, grab = xvfb((1280, 800))
    cam, _ = at_pose(scene, (12.0, 0.5, 0.0))
    img = cam.grab().image
    a = advisor(earlier).update(img, 0.0)
    assert a.state == "adjust" and a.actions[0].kind == "turn"
    with PreviewWindow((1280, 800), position=(0, 0)) as win:
        win.show(img, a)
        assert win.poll() is None
        shot = grab(display)
        ref = np.transpose(__import__("pygame").surfarray.array3d(win.render_offscreen(img, a)), (1, 0, 2))
    assert shot.shape == (800, 1280, 3)
    _overlay_checks(shot, a, (1280, 800))
    assert np.mean(np.all(shot == ref, axis=2)) > 0.999


# --------------------------------------------------------------------------------------------
# the CLI
# --------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def cli():
    import procam.cli.advise  # noqa: F401
    import procam.cli.capture  # noqa: F401

    return run_cli


def test_cli_advise_prints_json_lines(cli, earlier, tmp_path):
    from procam.io import save_calibration

    path = save_calibration(earlier, tmp_path / "c.json")  # its view says the board (24 mm squares)
    code, out, err = cli(["advise", "--board", "10x6", "--square", "24", "--camera", "virtual", "--json",
                          "--max-frames", "2", "--calibration", path, "--virtual-pose", "15,12"])
    assert code == 0, err
    lines = [json.loads(x) for x in out.splitlines()]
    assert [d["frame"] for d in lines] == [0, 1]
    d = lines[-1]
    assert d["phase"] == "target" and d["intrinsics"] == f"intrinsics from {path}"
    assert d["camera"]["psi"] == pytest.approx(15.0, abs=0.5) and d["camera"]["nu"] == pytest.approx(12.0, abs=0.5)
    assert d["projector"]["nu"] == pytest.approx(26.1, abs=1.0) and d["state"] in ("good", "ready")
    code, _, err = cli(["advise", "--board", "10x6", "--square", "30", "--camera", "virtual", "--json",
                        "--max-frames", "1", "--calibration", path])
    assert code == 2 and "squares of 24 but --square is 30" in err


@pytest.mark.parametrize("args, phrase", [
    (["--target", "nan"], "--target must be a finite number > 0"),
    (["--target", "0"], "--target must be a finite number > 0"),
    (["--still", "-1"], "--still must be a finite number >= 0"),
    (["--max-frames", "0"], "--max-frames must be a frame count >= 1"),
    (["--exposure", "0"], "--exposure must be a finite number > 0 and <= 60000 ms"),
    (["--gain", "1e9"], "--gain must be a finite number >= 0 and <= 1000"),
    (["--camera", "folder:x"], "a folder camera delivers no live frames"),
    (["--camera", "webcam"], "unknown camera"),
    (["--virtual-pose", "1"], "--virtual-pose must be PSI,NU"),
    (["--virtual-pose", "1,2", "--camera", "opencv:0"], "applies to --camera virtual only"),
    (["--calibration", "missing.json", "--camera", "virtual"], "missing.json: no such file"),
])
def test_cli_advise_checks_its_options(cli, args, phrase):
    code, _, err = cli(["advise", "--board", "10x6", "--square", "24", *args])
    assert code == 2 and phrase in err and len(err.strip().splitlines()) == 1, err


def test_cli_advise_without_a_desktop_says_use_json(cli, monkeypatch):
    pytest.importorskip("pygame", reason="pygame-ce is not installed (pip install 'procam[capture]')")
    for var in ("DISPLAY", "WAYLAND_DISPLAY", "SDL_VIDEODRIVER"):
        monkeypatch.delenv(var, raising=False)
    code, out, err = cli(["advise", "--board", "10x6", "--square", "24", "--camera", "virtual", "--max-frames", "1"])
    assert code == 2 and "cannot open the preview window" in err and "use --json" in err and out == ""


def test_cli_capture_advise_options(cli, tmp_path):
    code, _, err = cli(["capture", tmp_path / "p", "--virtual", "--auto"])
    assert code == 2 and "--auto belongs to --advise" in err
    code, _, err = cli(["capture", tmp_path / "p", "--virtual", "--advise"])
    assert code == 2 and "--advise needs --board" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_cli_capture_with_advice_learns_the_projector_side(cli, tmp_path):
    """``procam capture --virtual --poses 2 --advise --auto --json``: the first pose's advice knows no projector;
    after its capture and quick calibration, the second pose's advice has nu_p and std(f_p)."""
    code, out, err = cli(["capture", tmp_path / "s", "--virtual", "--projector", "640x400", "--board", "10x6",
                          "--poses", "2", "--advise", "--auto", "--json", "--max-frames", "5"])
    assert code == 0, err
    advice = [json.loads(x) for x in out.splitlines()]     # stdout carries the JSON lines only
    assert len(advice) == 10
    assert all(d["phase"] == "first" and d["projector"] is None for d in advice[:5])
    assert all(d["phase"] == "target" and d["projector"]["std_f"] > 0 for d in advice[5:])
    assert "quick calibration of pose01" in err and (tmp_path / "s" / "pose02" / "capture.json").is_file()


def test_quick_calibration_after_a_capture_teaches_the_advisor(ideal_capture, capsys):
    """``capture --advise`` calibrates each captured pose at once (LiveAdvice.learn): the result's K, R, T
    become the advisor's projector side. (The whole CLI session is the slow test above.)"""
    from procam.cli._live import live_advice as LiveAdvice

    folder, _, truth, _ = ideal_capture
    session = LiveAdvice(Board(10, 6, 24.0), AdvisorOptions())
    calib = session.learn(folder, "pose01")
    assert calib is not None and session.best is not None and session.best[1] is calib
    assert abs(calib.projector.K[0, 0] - truth["projector"]["f"]) < 4 * calib.std["f_p"] + 2
    assert session.best[2] == "pose01 (captured)"
    assert f"quick calibration of {folder.name}: f_c = " in capsys.readouterr().out
    # capture --advise hands over the instant verdict's calibration: the pose is not calibrated a second time
    from procam.check import check_pose

    checked = check_pose(folder, session.board)
    again = LiveAdvice(Board(10, 6, 24.0), AdvisorOptions())
    assert again.learn(folder, "pose01", checked=checked) is checked.calibration
    np.testing.assert_array_equal(checked.calibration.projector.K, calib.projector.K)
    failed = again.learn(folder, "pose02", checked=ProcamError("no corners"))
    said = capsys.readouterr()
    assert failed is None and "no corners; the advice keeps what it knew" in said.out + said.err
