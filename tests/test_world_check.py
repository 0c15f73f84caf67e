"""The check in the world (procam.world_check, ``procam world-check``): spots projected where the calibration
puts the board's white squares land there when the calibration is right, and miss by what the geometry predicts
when it is not (issue 33, item 4).  The simulator is the oracle: the small scene of tests/sim_small.py."""

from __future__ import annotations

import functools
import json

import numpy as np
import pytest
from conftest import run_cli
from sim_small import small_scene

from procam import simulate
from procam.board import Board
from procam.calibration import Device
from procam.errors import BoardNotFoundError, CalibrationError, ProcamError
from procam.world_check import WorldCheckOptions, draw, white_square_centres, world_check


@functools.lru_cache(maxsize=None)
def _renderer():
    return simulate.Renderer(small_scene())


def _device(seed=1):
    """The small scene as ``show_and_grab`` (the geometry shared, the noise seeded)."""
    r = _renderer()
    rng = np.random.default_rng(seed)
    return lambda image: r.finish(r.linear_image(image), rng)


def _board(scene):
    return Board(scene.board_cols, scene.board_rows, scene.square)


def _perturbed(kind: str):
    """The truth calibration of the small scene with the projector's focal length +1 % or R turned 0.2 deg."""
    truth = simulate.truth_calibration(small_scene())
    if kind == "f_p +1%":
        K = np.array(truth.projector.K, float)
        K[0, 0] *= 1.01
        K[1, 1] *= 1.01
        return truth.replace(projector=Device(K, truth.projector.image_size, truth.projector.distortion))
    return truth.replace(R=simulate.euler_matrix((0.0, 0.2, 0.0)) @ np.asarray(truth.R))


def _expected_miss(calib, targets_xy):
    """Where the spots land by the scene's true geometry, independently of procam.world_check: each target
    (board frame) is drawn at the projector pixel ``calib`` gives it (the board at its TRUE pose); the true
    projector's ray of that pixel meets the board at X_lit; the camera sees X_lit.  Returns the misses (N, 2) in
    camera px and on the board (mm)."""
    sc = small_scene()
    assert sc.proj_distortion == "none"  # the true projector ray below is a pinhole's
    X = np.column_stack([targets_xy, np.zeros(len(targets_xy))])
    Rb, tb = np.asarray(sc.R_board), np.asarray(sc.t_board)
    Xc = X @ Rb.T + tb
    R, T = np.asarray(calib.R), np.asarray(calib.T)
    q = calib.projector.project(R @ Rb, R @ tb + T, X)             # the calibration's projector pixel
    d_p = np.column_stack([q, np.ones(len(q))]) @ np.linalg.inv(np.asarray(sc.K_proj)).T
    Rt, Tt = np.asarray(sc.R), np.asarray(sc.T)
    origin, d = -Rt.T @ Tt, d_p @ Rt                                 # the true projector ray, camera frame
    n = Rb[:, 2]
    s = ((tb - origin) @ n) / (d @ n)
    X_lit = origin + d * s[:, None]
    miss_px = simulate.project_points(sc, X_lit) - simulate.project_points(sc, Xc)
    miss = ((X_lit - tb) @ Rb)[:, :2] - targets_xy
    return miss_px, miss


def test_linear_image_renders_any_projector_image_as_the_1d_paths_do():
    """Renderer.linear_image of a white panel and of a fringe repeated down the panel is what the white frame and
    linear_stripes render (the 1-D paths' 8x finer profiles differ only within a pixel of the panel's edges)."""
    r = _renderer()
    Wp, Hp = r.scene.proj_size
    white = r.linear_image(np.full((Hp, Wp), 255, np.uint8))
    ref = r._linear("white")
    assert ref.max() > 0.5 and np.abs(white - ref).max() < 0.01 and np.abs(white - ref).mean() < 2e-5
    line = np.clip(128 + 100 * np.sin(np.arange(Wp) / 20.0), 0, 255).astype(np.uint8)
    fringe = r.linear_image(np.tile(line, (Hp, 1)))
    assert np.abs(fringe - r.linear_stripes(line, "col")).mean() < 2e-5
    black = r.linear_image(np.zeros((Hp, Wp), np.uint8))
    assert np.abs(black - r._linear("black")).max() < 1e-3
    with pytest.raises(ValueError, match=r"\(1080, 1920\)"):
        r.linear_image(np.zeros((Wp, Hp), np.uint8))


def test_the_truth_holds_in_the_world():
    """The scene's exact calibration: every spot found, within 0.3 px of where it should be, verdict 'holds'."""
    sc = small_scene()
    wc = world_check(simulate.truth_calibration(sc), _board(sc), _device())
    assert wc.verdict == "holds", wc.reasons
    assert set(wc.status) == {"found"} and len(wc.status) == 22     # of the 45 squares inside the corners
    # the targets are the white squares': the white frame is brighter at each of them than at any other square
    centres, _ = white_square_centres(_board(sc))
    others = [c for c in centres[:, :2] if np.min(np.hypot(*(wc.targets - c).T)) > 1e-9]
    assert len(others) == 23
    level = [wc.white[round(y), round(x)] for x, y in simulate.project_points(
        sc, np.column_stack([others, np.zeros(23)]) @ np.asarray(sc.R_board).T + sc.t_board)]
    assert wc.white[tuple(np.rint(wc.predicted[:, ::-1]).astype(int).T)].min() > 2 * max(level)
    assert wc.rms_px <= 0.3 and wc.max_px <= 0.3 and wc.rms <= 0.3 and wc.diagnosis == ""
    # the pose from the white frame is the scene's
    np.testing.assert_allclose(wc.t_board, sc.t_board, atol=1.0)
    img = draw(wc)
    assert img.shape == (*wc.white.shape, 3) and img.dtype == np.uint8


@pytest.mark.parametrize("kind, words", [("f_p +1%", "focal length looks too long"),
                                         ("R 0.2 deg", "the rotation R or translation T")])
def test_a_wrong_calibration_misses_by_what_the_geometry_predicts(kind, words):
    """f_p 1 % too long or R turned 0.2 deg: each spot misses by what the true geometry predicts (within 0.3 px,
    0.3 mm), the verdict is 'off', and the diagnosis names the parameter the pattern points to."""
    sc = small_scene()
    calib = _perturbed(kind)
    wc = world_check(calib, _board(sc), _device())
    exp_px, exp = _expected_miss(calib, wc.targets)
    assert set(wc.status) == {"found"}
    assert np.sqrt(np.mean(np.sum(exp_px ** 2, 1))) > 1.5       # a miss the check must see
    assert np.abs(wc.miss_px - exp_px).max() <= 0.3
    assert np.abs(wc.miss - exp).max() <= 0.3
    assert wc.verdict == "off" and wc.rms_px > 1.5, wc.reasons
    assert words in wc.diagnosis, wc.diagnosis
    if kind == "f_p +1%":
        assert wc.pattern["scale"] == pytest.approx(0.01, abs=5e-4)


def _wall_truth(calib, q):
    """Independently of procam.world_check: where each wall spot shown at projector pixel ``q`` (M, 2) lands in the
    camera by the scene's TRUE geometry (the true projector ray meets the scene's wall), and how far that is from
    the epipolar curve ``calib`` gives ``q`` (its projector ray, sampled every 0.5 mm of depth from 200 to 3000 mm,
    seen by the true camera, which ``calib`` shares).  Returns (true pixels (M, 2), distances (M,) camera px)."""
    sc = small_scene()
    assert sc.proj_distortion == "none" and calib.projector.distortion.model == "none"
    (wall,) = sc.surfaces().surfaces
    hom = np.column_stack([q, np.ones(len(q))])
    Rt, Tt = np.asarray(sc.R), np.asarray(sc.T)
    o, d = -Rt.T @ Tt, (hom @ np.linalg.inv(np.asarray(sc.K_proj)).T) @ Rt
    s = ((np.asarray(wall.point) - o) @ wall.normal) / (d @ wall.normal)
    lands = simulate.project_points(sc, o + d * s[:, None])
    R, T = np.asarray(calib.R), np.asarray(calib.T)
    oc, dc = -R.T @ T, (hom @ np.linalg.inv(np.asarray(calib.projector.K)).T) @ R
    z = np.arange(200.0, 3000.0, 0.5)
    dist = np.empty(len(q))
    for k in range(len(q)):
        curve = simulate.project_points(sc, oc + np.outer(z, dc[k]))
        dist[k] = np.min(np.hypot(*(curve - lands[k]).T))
    return lands, dist


@pytest.mark.parametrize("kind", ["truth", "f_p +1%", "R 0.2 deg"])
def test_the_walls_spots_land_on_their_epipolar_lines_only_when_the_calibration_is_right(kind):
    """Spots on the wall behind the board (``wall=(8, 5)``): each is found where the true geometry puts it (within
    0.3 px) and its miss is its distance from the calibration's epipolar curve as the true geometry predicts
    (within three times the centroid's own sd, + 0.05 px): 0.03 px RMS for the truth (the wall 'holds'), 1-2 px with f_p +1 % or R turned 0.2 deg (the
    wall's part says 'off', as the board's does)."""
    sc = small_scene()
    calib = simulate.truth_calibration(sc) if kind == "truth" else _perturbed(kind)
    wc = world_check(calib, _board(sc), _device(), wall=(8, 5))
    wall = wc.wall
    ok = np.array([st == "found" for st in wall.status])
    assert ok.sum() >= 10 and set(wall.status) <= {"found", "faint", "board", "edge"}
    assert len(set(wall.frame)) > 1          # spots on nearby epipolar lines are shown in different frames
    lands, dist = _wall_truth(calib, wall.proj_pts[ok])
    assert np.abs(wall.found[ok] - lands).max() <= 0.3
    assert (np.abs(np.hypot(*wall.miss_px[ok].T) - dist) <= 0.05 + 3 * wall.sd_px[ok]).all()
    wall_reason = wc.reasons[-1]
    if kind == "truth":
        assert wc.verdict == "holds" and wall.rms_px <= 0.3 and wall.max_px <= 0.3, wc.reasons
        assert "within 0.5 px" in wall_reason and wall_reason.startswith("the wall:")
        # the wall the calibration triangulates is the scene's (950 mm deep; 0.1 px along the line is ~0.6 mm there)
        (plane,) = sc.surfaces().surfaces
        assert np.abs((wall.points[ok] - plane.point) @ plane.normal).max() < 3.0
    else:
        assert np.sqrt(np.mean(dist ** 2)) > 0.9                  # a miss the wall must see
        assert wc.verdict == "off" and wall.rms_px > 0.9 and "more than 0.5 px" in wall_reason
        assert "the wall's spots lie" in wc.diagnosis
    doc = wc.to_dict()["wall"]
    assert doc["found"] == ok.sum() and len(doc["markers"]) == len(wall.status)


def test_spots_not_seen_are_reported_not_guessed():
    """A projector that shows the white frame but not the spots: no spot found, the verdict 'inconclusive'."""
    sc = small_scene()
    dev = _device()
    dark = np.zeros(sc.proj_size[::-1], np.uint8)

    def no_spots(image):
        return dev(image if image.min() == 255 else dark)

    wc = world_check(simulate.truth_calibration(sc), _board(sc), no_spots)
    assert wc.verdict == "inconclusive" and set(wc.status) == {"faint"}
    assert np.isnan(wc.found).all() and np.isnan(wc.rms_px)
    assert "only 0 of" in wc.reasons[0]


def test_a_calibration_of_another_rig_is_off_not_inconclusive():
    """The projector moved 20 mm since the calibration (16-22 mm: the same): the spots land far from where it puts
    them (none within half a square), yet the camera sees them; 'inconclusive' (light the board better) was the wrong advice: 'off'.  A
    dimly lit board (spots under the noise) stays inconclusive."""
    sc = small_scene()
    truth = simulate.truth_calibration(sc)
    moved = truth.replace(T=np.asarray(truth.T) + [20.0, 0.0, 0.0])
    wc = world_check(moved, _board(sc), _device())
    assert wc.verdict == "off" and "found" not in set(wc.status), (wc.verdict, wc.status)
    assert "yet the camera sees" in wc.reasons[0] and "does not describe this camera and projector" in wc.reasons[0]
    dev = _device()

    def faint(image):  # the white frame as it is, the spots at 2 % of their level: under the camera's noise
        return dev(image if image.min() == 255 else np.rint(image * 0.02).astype(np.uint8))

    wc = world_check(moved, _board(sc), faint)
    assert wc.verdict == "inconclusive" and "light the board better" in wc.reasons[0], wc.reasons
    speckle = (np.random.default_rng(3).random(sc.proj_size[::-1]) > 0.995).astype(np.uint8) * 255

    def changing(image):  # something else lit between the frames (hundreds of blobs): not the spots, no verdict
        return dev(image if image.min() == 255 or image.max() == 0 else speckle)

    wc = world_check(moved, _board(sc), changing)
    assert wc.verdict == "inconclusive" and "light the board better" in wc.reasons[0], wc.reasons


def test_no_board_or_no_projector_is_a_one_line_error():
    sc = small_scene()
    calib = simulate.truth_calibration(sc)
    W, H = sc.cam_size
    with pytest.raises(BoardNotFoundError, match="board is not in the camera's white frame"):
        world_check(calib, _board(sc), lambda image: np.zeros((H, W), np.uint8))
    with pytest.raises(CalibrationError, match="frames are 320x200"):
        world_check(calib, _board(sc), lambda image: np.zeros((200, 320), np.uint8))
    with pytest.raises(CalibrationError, match="no projector"):
        world_check(calib.replace(projector=None, R=None, T=None), _board(sc), _device())
    with pytest.raises(Exception, match="tolerance_px"):
        WorldCheckOptions(tolerance_px=0.0)
    with pytest.raises(ProcamError, match="wall must be"):
        world_check(calib, _board(sc), _device(), wall=(8, 1))


def test_capture_device_shows_and_grabs_through_the_capture_layer():
    """capture_device on a VirtualProjector and a streaming camera whose first frame after each change is stale
    (the previous image): the check waits for a frame of the image shown, and the truth holds."""
    from procam.acquire import Frame, VirtualProjector
    from procam.world_check import capture_device

    sc = small_scene()
    r = _renderer()
    rng = np.random.default_rng(2)

    class StaleCamera:
        streaming = True

        def __init__(self, projector):
            self.projector, self.seen, self.lin, self.grabs = projector, None, None, 0

        def grab(self):
            self.grabs += 1
            stale = self.lin
            if self.seen is not self.projector.current:
                self.seen = self.projector.current
                self.lin = r.linear_image(self.seen)
                if stale is not None:
                    return Frame(r.finish(stale, rng), 0.0)
            return Frame(r.finish(self.lin, rng), 0.0)

    with VirtualProjector(sc.proj_size) as proj:
        cam = StaleCamera(proj)
        wc = world_check(simulate.truth_calibration(sc), _board(sc), capture_device(proj, cam, settle_s=0.0))
    assert proj.shown == 3 and cam.grabs >= 7      # white (2 grabs), spots and black (3 each: stale, fresh, fresh)
    assert wc.verdict == "holds" and wc.rms_px <= 0.3


@pytest.fixture
def small_rig(monkeypatch):
    """``--virtual`` renders the small scene (the CLI's rig is the capture's demo scene, 1280x800 at 3x3)."""
    from procam.acquire import cameras

    monkeypatch.setattr(cameras, "demo_scene", lambda *a, **kw: small_scene())


def test_cli_world_check_virtual(tmp_path, small_rig):
    """``procam world-check CAL --virtual``: exit 0 and the numbers for the truth, exit 3 'off' for f_p +1 %."""
    from procam.io import save_calibration

    good, bad = tmp_path / "truth.json", tmp_path / "fp.json"
    save_calibration(simulate.truth_calibration(small_scene()), good)
    save_calibration(_perturbed("f_p +1%"), bad)
    code, out, err = run_cli(["world-check", good, "--virtual", "--png", tmp_path / "wc.png",
                              "--json", tmp_path / "wc.json"])
    assert code == 0, err
    assert "verdict: holds" in out
    doc = json.loads((tmp_path / "wc.json").read_text())
    assert doc["verdict"] == "holds" and doc["rms_px"] <= 0.3 and doc["found"] == doc["targets"] == 22
    assert (tmp_path / "wc.png").read_bytes()[:4] == b"\x89PNG"
    code, out, err = run_cli(["world-check", good, "--virtual", "--json", tmp_path / "wc.json"])  # its own: rewritten
    assert code == 0, err
    code, out, err = run_cli(["world-check", bad, "--virtual"])
    assert code == 3 and "off:" in err and "focal length looks too long" in err and "Traceback" not in err


def test_cli_world_check_wall(tmp_path, small_rig):
    """``--wall 8x5``: the wall's numbers printed and in the JSON, its reason in the verdict; the picture drawn."""
    from procam.io import save_calibration

    save_calibration(simulate.truth_calibration(small_scene()), tmp_path / "truth.json")
    code, out, err = run_cli(["world-check", tmp_path / "truth.json", "--virtual", "--wall", "8x5",
                              "--json", tmp_path / "wc.json", "--png", tmp_path / "wc.png"])
    assert code == 0, err
    assert "wall: " in out and "from their epipolar lines" in out and "verdict: holds" in out
    doc = json.loads((tmp_path / "wc.json").read_text())
    assert doc["wall"]["found"] >= 10 and doc["wall"]["rms_px"] <= 0.3
    assert doc["reasons"][-1].startswith("the wall:")
    assert (tmp_path / "wc.png").read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize("args, message", [
    (["{missing}", "--virtual"], "no such calibration file"),
    (["{cal}", "--pose", "10,10"], "--pose belongs to --virtual"),
    (["{cal}"], "give the board in view"),
    (["{cal}", "--virtual", "--png", "{tmp}/x.txt"], "--png"),
    (["{cal}", "--virtual", "--tolerance-px", "0"], "--tolerance-px"),
    (["{cal}", "--virtual", "--camera", "opencv:1"], "--virtual uses the simulator"),
    (["{camonly}", "--virtual"], "camera-only calibration"),
    (["{wrongsize}", "--virtual"], "--virtual checks a calibration of that rig"),
    (["{cal}", "--virtual", "--wall", "8"], "--wall must look like COLSxROWS"),
    (["{cal}", "--virtual", "--wall", "1x5"], "--wall must look like COLSxROWS"),
], ids=["missing", "pose", "board", "png", "tolerance", "camera", "camera-only", "size", "wall", "wall-1"])
def test_cli_world_check_bad_inputs(tmp_path, small_rig, args, message):
    """Bad input: one line naming what is wrong, exit 2, nothing written, before any device opens."""
    from procam.io import save_calibration

    truth = simulate.truth_calibration(small_scene())
    save_calibration(truth, tmp_path / "cal.json")
    save_calibration(truth.replace(projector=None, R=None, T=None, method="camera-only"), tmp_path / "camonly.json")
    cam = truth.camera
    save_calibration(truth.replace(camera=Device(np.diag([2.0, 2.0, 1.0]) @ cam.K, (1280, 800), cam.distortion)),
                     tmp_path / "wrongsize.json")
    names = {"missing": tmp_path / "nope.json", "cal": tmp_path / "cal.json", "camonly": tmp_path / "camonly.json",
             "wrongsize": tmp_path / "wrongsize.json", "tmp": tmp_path}
    before = sorted(p.name for p in tmp_path.iterdir())
    code, out, err = run_cli(["world-check", *(a.format(**names) for a in args)])
    assert code == 2, (out, err)
    assert message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == before
