"""Tests of the simulator (procam.simulate): geometry oracle, rendering, capture output."""

from __future__ import annotations

import ast
import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from procam import simulate as sim

SRC = Path(sim.__file__).parent  # the package: every one of its files is checked
_PRESET = sim.preset


# ---------------------------------------------------------------------------------------------
# geometry
# ---------------------------------------------------------------------------------------------

def _imported_modules(path: Path) -> set[str]:
    """Absolute names of the modules a file of procam.simulate imports (relative imports resolved)."""
    package = ["procam", "simulate"]
    mods = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            mods.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level == 0:
                mods.add(node.module)
                continue
            base = ".".join(package[:len(package) - node.level + 1])
            if node.module:
                mods.add(f"{base}.{node.module}")
            else:  # from .. import capture, patterns: the names are modules
                mods.update(f"{base}.{a.name}" for a in node.names)
    return mods


def test_imports_no_solver_code():
    files = sorted(SRC.glob("*.py"))
    assert {f.name for f in files} >= {"__init__.py", "lens.py", "scene.py", "renderer.py"}
    allowed_prefix = ("numpy", "scipy", "cv2", "__future__", "dataclasses", "functools", "json", "os", "pathlib",
                      "typing", "time", "math", "copy")
    for f in files:
        for m in _imported_modules(f):
            if m.startswith("procam."):
                # only the package itself, procam.patterns, procam.capture (the folder format),
                # procam.io.files and procam.io.formats (file names and format marks, no solver code) and
                # procam.calibration, the result container that
                # truth_calibration fills with the scene's numbers (it computes nothing with procam.models)
                assert m.startswith("procam.simulate.") or m in ("procam.patterns", "procam.capture",
                                                                 "procam.io.files", "procam.io.formats",
                                                                 "procam.calibration"), (f.name, m)
            else:
                assert m.startswith(allowed_prefix), (f.name, m)


@pytest.mark.parametrize("name", ["paper", "ideal"])
def test_presets(name):
    s = sim.preset(name)
    assert s.cam_size == (1280, 800) and s.proj_size == (1920, 1080)
    np.testing.assert_allclose(s.K_cam, [[1539, 0, 674], [0, 1539 * 1.004, 512], [0, 0, 1]])
    np.testing.assert_allclose(sim.matrix_euler(s.R), [0.87, 14.44, -0.25], atol=1e-9)
    np.testing.assert_allclose(s.T, [-170.05, -41.25, -65.35])
    assert (s.board_cols, s.board_rows, s.square) == (10, 6, 24.0)
    if name == "paper":
        np.testing.assert_allclose(s.K_proj, [[2421, 0, 1013], [0, 2421 * 1.002, 1065], [0, 0, 1]])
    else:
        np.testing.assert_allclose(s.K_proj, [[2421, 0, 960], [0, 2421, 1065], [0, 0, 1]])
        c = sim.corner_truth(s)
        d = np.linalg.norm(c["camera_distorted"] - c["camera_undistorted"], axis=1)
        assert 3 < d[[0, 9, 50, 59]].max() < 20  # distortion observable at the outer corners
    with pytest.raises(ValueError):
        sim.preset("nope")


@pytest.mark.parametrize("name", ["paper", "ideal"])
def test_recommended_pose_is_good_and_fully_visible(name):
    s = sim.preset(name)
    t = sim.truth(s)
    psi_c, nu_c, _ = t["pose"]["camera"]["angles_deg"]
    _, nu_p, _ = t["pose"]["projector"]["angles_deg"]
    np.testing.assert_allclose(t["pose"]["camera"]["angles_deg"], sim.RECOMMENDED_POSE, atol=1e-9)
    assert abs(psi_c) + abs(nu_c) > 10 and abs(nu_p) > 13
    assert t["fit_margin_px"] > 5
    cam = np.array(t["corners"]["camera_distorted"])
    proj = np.array(t["corners"]["projector"])
    # every corner with its 60x60 local-homography window inside the camera image
    assert cam.min() > 31 and cam[:, 0].max() < 1280 - 31 and cam[:, 1].max() < 800 - 31
    assert proj.min() > 0 and proj[:, 0].max() < 1919 and proj[:, 1].max() < 1079
    # canonical order: corner 0 top-left in the camera image, index runs right along the 10 cols
    assert cam[1, 0] > cam[0, 0] + 20 and abs(cam[1, 1] - cam[0, 1]) < 10
    assert cam[10, 1] > cam[0, 1] + 20
    assert np.argmin(cam.sum(axis=1)) == 0


def test_distortion_round_trips_and_opencv_agreement():
    s = sim.preset("ideal")
    p = np.random.default_rng(1).uniform([0, 0], [1280, 800], (500, 2))
    np.testing.assert_allclose(sim.undistort(s, sim.distort(s, p)), p, atol=1e-9)
    # barrel distortion (k1 < 0): distorted points lie closer to the centre
    c = s.cam_center
    assert np.all(np.linalg.norm(sim.distort(s, p) - c, axis=1) <= np.linalg.norm(p - c, axis=1) + 1e-9)
    coeffs = (-0.12, 0.05, 0.0015, -0.001, 0.01)
    s2 = s.replace(cam_distortion="opencv", cam_dist_coeffs=coeffs)
    np.testing.assert_allclose(sim.undistort(s2, sim.distort(s2, p)), p, atol=1e-8)
    K = s2.K_cam
    X = np.column_stack([(p[:, 0] - K[0, 2]) / K[0, 0], (p[:, 1] - K[1, 2]) / K[1, 1], np.ones(len(p))])
    q, _ = cv2.projectPoints(X, np.zeros(3), np.zeros(3), K, np.array(coeffs))
    np.testing.assert_allclose(q.reshape(-1, 2), sim.distort(s2, p), atol=1e-6)
    s3 = s.replace(cam_distortion="none", cam_dist_coeffs=())
    np.testing.assert_array_equal(sim.distort(s3, p), p)


def test_truth_geometry_is_consistent():
    s = sim.preset("paper")
    t = json.loads(json.dumps(sim.truth(s)))  # JSON-able
    B = np.array(t["corners"]["board"])
    assert B.shape == (60, 3)
    np.testing.assert_allclose(B[:, :2].mean(axis=0), 0, atol=1e-12)
    np.testing.assert_allclose(B[1] - B[0], [24, 0, 0])
    np.testing.assert_allclose(B[10] - B[0], [0, 24, 0])
    for dev, K in (("camera", s.K_cam), ("projector", s.K_proj)):
        R = np.array(t["pose"][dev]["R"])
        tv = np.array(t["pose"][dev]["t"])
        np.testing.assert_allclose(R, sim.euler_matrix(t["pose"][dev]["angles_deg"]), atol=1e-12)
        m = sim.project(K, B @ R.T + tv)
        key = "camera_undistorted" if dev == "camera" else "projector"
        np.testing.assert_allclose(m, t["corners"][key], atol=1e-9)
    # the division model maps the distorted corners back to the undistorted ones
    k1, k2 = t["camera"]["distortion"]["k1"], t["camera"]["distortion"]["k2"]
    c = np.array(t["camera"]["distortion"]["center"])
    d = np.array(t["corners"]["camera_distorted"]) - c
    r2 = (d ** 2).sum(axis=1, keepdims=True)
    np.testing.assert_allclose(c + d / (1 + k1 * r2 + k2 * r2 ** 2), t["corners"]["camera_undistorted"],
                               atol=1e-9)
    # extrinsics: the board pose in the projector frame is R (camera pose) + T
    Rc, tc = np.array(t["pose"]["camera"]["R"]), np.array(t["pose"]["camera"]["t"])
    Rp, tp = np.array(t["pose"]["projector"]["R"]), np.array(t["pose"]["projector"]["t"])
    np.testing.assert_allclose(Rp @ Rc.T, s.R, atol=1e-12)
    np.testing.assert_allclose(tp - s.R @ tc, s.T, atol=1e-9)


def test_with_board_pose_frames_and_center():
    s = sim.preset("paper")
    a = (5.0, -20.0, 3.0)
    sp = sim.with_board_pose(s, a, frame="projector")
    np.testing.assert_allclose(sim.matrix_euler(sp.R_board_proj), a, atol=1e-9)
    assert sim.fit_margin(sp) > 0
    sc = sim.with_board_pose(s, (10, 10, 0), center=(0, 0, 500))
    np.testing.assert_allclose(sc.t_board, [0, 0, 500])
    np.testing.assert_allclose(sim.matrix_euler(sc.R_board), (10, 10, 0), atol=1e-9)
    s7 = sim.with_board_pose(s, (10, 20, 0), distance=700.0)
    assert s7.t_board[2] == pytest.approx(700.0) and sim.fit_margin(s7) > 0
    with pytest.raises(ValueError):
        sim.with_board_pose(s, (0, 0, 0), frame="wall")


def test_correspondences_fast_path():
    s = sim.preset("paper")
    c = sim.corner_truth(s)
    obj, cam, proj = sim.correspondences(s, sigma_cam=0.0, sigma_proj=0.0)
    np.testing.assert_allclose(cam, c["camera_distorted"])
    np.testing.assert_allclose(proj, c["projector"])
    o1, c1, p1 = sim.correspondences(s, 0.1, 0.2, seed=3)
    o2, c2, p2 = sim.correspondences(s, 0.1, 0.2, seed=3)
    np.testing.assert_array_equal(c1, c2)
    np.testing.assert_array_equal(p1, p2)
    # noise level over many draws
    ec = np.concatenate([sim.correspondences(s, 0.1, 0.2, seed=k)[1] - c["camera_distorted"] for k in range(50)])
    ep = np.concatenate([sim.correspondences(s, 0.1, 0.2, seed=k)[2] - c["projector"] for k in range(50)])
    assert ec.std() == pytest.approx(0.1, rel=0.1) and ep.std() == pytest.approx(0.2, rel=0.1)


# ---------------------------------------------------------------------------------------------
# rendering
# ---------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def paper_capture():
    s = sim.preset("paper")
    calls = []
    stack, t = sim.render(s, seed=0, progress=lambda d, n: calls.append((d, n)))
    return s, stack, t, calls


@pytest.fixture(scope="module")
def paper_maps(paper_capture):
    return sim.true_projector_maps(paper_capture[0])


def small_scene(name="paper", **kw):
    """The preset's rig with both devices scaled down 4x (same angles of view): cheap to render."""
    s = _PRESET(name)
    S = np.diag([0.25, 0.25, 1.0])
    s = s.replace(cam_size=(320, 200), K_cam=S @ s.K_cam, proj_size=(480, 270), K_proj=S @ s.K_proj,
                  cam_dist_coeffs=(s.cam_dist_coeffs[0] * 16, 0.0), **kw)
    return sim.with_board_pose(s, sim.RECOMMENDED_POSE)


def _canonical(c):
    """OpenCV may return the 180-degree-symmetric board backwards: corner 0 must be top-left."""
    return c[::-1] if c[0].sum() > c[-1].sum() else c


def test_render_shape_dtype_progress(paper_capture, paper_maps):
    s, stack, t, calls = paper_capture
    assert stack.shape == (46, 800, 1280) and stack.dtype == np.uint8
    assert calls[-1][0] == calls[-1][1] == 47 and len(calls) == 47
    assert t["render"]["white"] == 44 and t["render"]["black"] == 45
    white, black = stack[44].astype(int), stack[45].astype(int)
    _, _, lit = paper_maps
    assert (white == 255).mean() < 1e-3  # exposure leaves the white squares unsaturated
    assert np.median(white[lit] - black[lit]) > 40


def test_opencv_finds_board_and_subpixel_corners_match_truth(paper_capture):
    s, stack, t, _ = paper_capture
    white = stack[44]
    ok, corners = cv2.findChessboardCorners(white, (10, 6),
                                            cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE)
    assert ok
    crit = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.1)
    c = _canonical(cv2.cornerSubPix(white, corners, (11, 11), (-1, -1), crit).reshape(-1, 2))
    e = c - np.array(t["corners"]["camera_distorted"])
    rms = np.sqrt((e ** 2).sum(axis=1).mean())
    assert rms < 0.1, rms
    assert np.abs(e.mean(axis=0)).max() < 0.05  # no systematic shift (pixel-centre convention)


def test_decoded_maps_match_true_projector_coordinates(paper_capture, paper_maps):
    from procam import decode as dec
    from procam import patterns as pat

    s, stack, t, _ = paper_capture
    col, row, lit = paper_maps
    assert lit.sum() > 100_000
    ps = pat.pattern_set(1920, 1080, "opencv")
    # plain comparison of each pattern with its inverse: the code the capture carries
    r = dec.decode(stack, ps, method="simple", contrast_threshold=0.0, shadow_threshold=1.0)
    for d, truth_map in ((r.col, col), (r.row, row)):
        match = np.abs(d - truth_map) < 1.0  # one of the (at most two) projector pixels the camera pixel straddles
        assert match[lit].mean() >= 0.99, match[lit].mean()
    # the default (robust) decoder: what it decodes on the board is right
    r = dec.decode(stack, ps)
    for d, truth_map in ((r.col, col), (r.row, row)):
        v = lit & np.isfinite(d)
        assert v.sum() > 0.6 * lit.sum()
        assert (np.abs(d - truth_map)[v] < 1.0).mean() >= 0.99


def test_true_maps_and_shadow_physics(paper_capture, paper_maps):
    s, stack, t, _ = paper_capture
    col, row, lit = paper_maps
    white, black = stack[44].astype(float), stack[45].astype(float)
    # corners of the truth lie on lit board pixels and the map agrees with the corner truth there
    cam = np.array(t["corners"]["camera_distorted"])
    proj = np.array(t["corners"]["projector"])
    ij = np.rint(cam).astype(int)
    assert lit[ij[:, 1], ij[:, 0]].all()
    near = np.abs(col[ij[:, 1], ij[:, 0]] - proj[:, 0])
    assert near.max() < 3  # within a camera pixel's footprint (~1.6 projector px)
    # unlit pixels (shadow of the board on the wall, outside the projector) get no projector light
    unlit = ~np.isfinite(col)
    assert unlit.sum() > 1000
    assert np.median(white[unlit] - black[unlit]) < 2
    # the board's shadow exists: wall pixels inside the projector's image region but unlit
    from procam.simulate.geometry import _geometry

    g = _geometry(s, s=1)
    shadow = (~g["board"]) & np.isfinite(g["xp"]) & (g["xp"] > 0) & (g["xp"] < 1919) & (g["yp"] > 0) \
        & (g["yp"] < 1079) & ~g["lit"]
    assert shadow.sum() > 1000


def test_same_seed_identical_images_and_other_seed_differs():
    s = small_scene()
    a, ta = sim.render(s, seed=7)
    b, tb = sim.render(s, seed=7)
    np.testing.assert_array_equal(a, b)
    assert json.dumps(ta) == json.dumps(tb)
    c, _ = sim.render(s, seed=8)
    assert (a != c).any()


def test_renderer_frames_are_the_rendered_images():
    """Frame by frame with one generator gives render()'s images bit for bit (the capture path's entry)."""
    s = small_scene()
    stack, t = sim.render(s, order="moreno", seed=4)
    r = sim.Renderer(s, "moreno")
    assert r.pattern_set.count == len(stack) == t["render"]["count"]
    rng = np.random.default_rng(4)
    for k in range(r.pattern_set.count):
        np.testing.assert_array_equal(r.frame(k, rng), stack[k])
    with pytest.raises(IndexError):
        r.frame(r.pattern_set.count, rng)


def test_16bit_moreno_order_capture_round_trip(tmp_path):
    from procam import capture
    from procam import decode as dec

    s = small_scene("ideal", bits=16)
    stack, t = sim.render(s, order="moreno", seed=2)
    assert stack.dtype == np.uint16 and stack.max() > 40000 and len(stack) == 2 + 2 * (9 + 9)
    assert t["render"]["white"] == 0 and t["render"]["black"] == 1
    paths = sim.write_capture(tmp_path / "pose", stack, t, order="moreno")
    assert [p.name for p in paths][:2] == ["00.png", "01.png"] and len(paths) == 38
    assert not [p for p in (tmp_path / "pose").iterdir() if "tmp" in p.name]
    cap = capture.load_capture(tmp_path / "pose")
    np.testing.assert_array_equal(cap.stack, stack)
    assert cap.pattern_set.order == "moreno"
    t2 = json.loads((tmp_path / "pose" / "truth.json").read_text())
    np.testing.assert_allclose(t2["corners"]["projector"], t["corners"]["projector"])
    col, row, lit = sim.true_projector_maps(s)
    r = dec.decode(stack, cap.pattern_set, method="simple", contrast_threshold=0.0, shadow_threshold=1.0)
    assert (np.abs(r.col - col) < 1)[lit].mean() > 0.98
    assert (np.abs(r.row - row) < 1)[lit].mean() > 0.98


def test_write_capture_rejects_wrong_stack(tmp_path):
    t = sim.truth(sim.preset("paper"))
    with pytest.raises(ValueError):
        sim.write_capture(tmp_path, np.zeros((10, 8, 8), np.uint8), t)


def test_write_capture_removes_stale_frames(tmp_path):
    """Frames of an earlier, longer simulated sequence are removed; files procam did not write never are."""
    from procam import patterns
    from procam.errors import OutputError

    big, ps = patterns.pattern_set(640, 480), patterns.pattern_set(37, 19)
    sim.write_capture(tmp_path, np.zeros((big.count, 4, 6), np.uint8), {"projector": {"size": [640, 480]}})
    paths = sim.write_capture(tmp_path, np.zeros((ps.count, 4, 6), np.uint8), {"projector": {"size": [37, 19]},
                                                                             "x": np.nan})
    assert big.count > ps.count and sorted(p.name for p in tmp_path.glob("*.png")) == sorted(p.name for p in paths)
    assert json.loads((tmp_path / "truth.json").read_text())["x"] is None
    (tmp_path / "photo.png").write_bytes(b"keep")
    with pytest.raises(OutputError, match="photo.png"):
        sim.write_capture(tmp_path, np.zeros((big.count, 4, 6), np.uint8), {"projector": {"size": [640, 480]}})
    sim.write_capture(tmp_path, np.zeros((ps.count, 4, 6), np.uint8), {"projector": {"size": [37, 19]}}, force=True)
    assert (tmp_path / "photo.png").read_bytes() == b"keep"
    mine = tmp_path / "mine"
    mine.mkdir()
    for name in ("24.png", "99.png", "5.png", "00.png"):
        (mine / name).write_bytes(b"user's")
    for force in (False, True):
        with pytest.raises(OutputError):
            sim.write_capture(mine, np.zeros((ps.count, 4, 6), np.uint8), {"projector": {"size": [37, 19]}},
                              force=force)
    assert sorted(p.name for p in mine.iterdir()) == ["00.png", "24.png", "5.png", "99.png"]
    assert all(p.read_bytes() == b"user's" for p in mine.iterdir())


def test_cli_simulate(tmp_path, monkeypatch):
    from typer.testing import CliRunner

    from procam.cli import app

    monkeypatch.setattr(sim, "preset", lambda name="paper": small_scene(name))
    runner = CliRunner()
    res = runner.invoke(app, ["simulate", str(tmp_path / "p"), "--pose", "10,-30,0", "--noise", "0",
                              "--seed", "1"])
    assert res.exit_code == 0, res.output
    t = json.loads((tmp_path / "p" / "truth.json").read_text())
    np.testing.assert_allclose(t["pose"]["camera"]["angles_deg"], [10, -30, 0], atol=1e-9)
    assert t["photometry"]["read_noise"] == 0 and t["photometry"]["full_well"] == 0
    assert len(list((tmp_path / "p").glob("*.png"))) == 38
    bad = runner.invoke(app, ["simulate", str(tmp_path / "q"), "--bits", "12"])
    assert bad.exit_code == 2 and "--bits" in bad.output


@pytest.mark.slow
@pytest.mark.parametrize("name", ["ideal", "opencv"])
def test_corners_strong_distortion_slow(name):
    if name == "opencv":  # OpenCV-Brown lens instead of the division model
        s = sim.preset("paper").replace(cam_distortion="opencv", cam_dist_coeffs=(-0.15, 0.1, 5e-4, -5e-4, 0.0))
        s = sim.with_board_pose(s, sim.RECOMMENDED_POSE)
    else:
        s = sim.preset(name)
    stack, t = sim.render(s, seed=5)
    ok, corners = cv2.findChessboardCorners(stack[44], (10, 6),
                                            cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE)
    assert ok
    crit = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.1)
    c = _canonical(cv2.cornerSubPix(stack[44], corners, (11, 11), (-1, -1), crit).reshape(-1, 2))
    e = c - np.array(t["corners"]["camera_distorted"])
    assert np.sqrt((e ** 2).sum(axis=1).mean()) < 0.1


def test_board_grain_is_a_fixed_texture_of_the_print():
    """``board_grain``: a texture of the board's print, the same in every frame (two noise seeds' white frames carry
    the same one), of the order of the stated albedo deviation, on the board only; refused outside [0, 1]."""
    import sim_small

    sc = sim.with_board_pose(sim_small.small_scene(), (-12.0, 15.0, 5.0))
    plain, grainy = sim.Renderer(sc), sim.Renderer(sc.replace(board_grain=0.3))
    k = plain.pattern_set.white
    lit = plain.linear(k)
    white = lit > 0.7 * lit.max()                   # the board's white squares (and its white margin)
    texture = [grainy.frame(k, np.random.default_rng(s)).astype(float)
               - plain.frame(k, np.random.default_rng(s)).astype(float) for s in (0, 1)]
    assert np.corrcoef(texture[0][white], texture[1][white])[0, 1] > 0.95
    rel = texture[0][white] / (lit[white] / sc.albedo_white * 255)   # in albedo units
    # 0.15 here: a camera pixel (0.8 mm at this pose, 2x2 rays) averages the 1 mm cells, and bright grains saturate
    assert 0.1 < rel.std() < 0.3 and abs(rel.mean()) < 0.1       # -0.06: the clipped bright grains
    x0, x1, y0, y1 = sim.board_extent(sc)
    outline = sim.project_points(sc, np.array([[x0, y0, 0], [x1, y0, 0], [x1, y1, 0], [x0, y1, 0]])
                                 @ np.asarray(sc.R_board).T + sc.t_board)
    board = np.zeros(lit.shape, np.uint8)
    cv2.fillConvexPoly(board, np.round(outline).astype(np.int32), 1)
    board = cv2.dilate(board, np.ones((5, 5), np.uint8)) > 0      # the printed board, one blurred pixel more
    grain = grainy.linear(k) - lit                 # noise-free
    assert np.abs(grain[board]).max() > 0.2 and np.abs(grain[~board]).max() < 1e-6
    with pytest.raises(ValueError, match="board_grain"):
        sc.replace(board_grain=1.5)
