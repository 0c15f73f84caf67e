"""Exports: OpenGL matrices vs cv2.projectPoints, remap tables on a render, kamino410 files, intrinsics loaders."""

import json

import cv2
import numpy as np
import pytest
from scipy.ndimage import map_coordinates

from procam import io, models, simulate
from procam.calibration import Device, Distortion
from procam.board.corners import detect_corners
from procam.errors import CalibrationError, CalibrationFileError
from procam.simulate import truth_calibration
from procam import export as ex
from sim_small import small_capture, small_scene


def _paper():
    sc = simulate.preset("paper")
    return sc, truth_calibration(sc)


def _board_cam(sc):
    c = simulate.corner_truth(sc)
    return c["board"] @ sc.R_board.T + sc.t_board


# ---------------------------------------------------------------------------------------------------
# OpenGL / Unity
# ---------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("y_up", [True, False])
@pytest.mark.parametrize("zero_to_one", [False, True])
@pytest.mark.parametrize("world", ["camera", "projector"])
def test_projection_matrix_reprojects_like_cv2_projectpoints(y_up, zero_to_one, world):
    sc, calib = _paper()
    Xc = _board_cam(sc)
    Xw = Xc if world == "camera" else Xc @ sc.R.T + sc.T
    V = ex.view_matrices(calib, world)
    for name, dev, rvec, tvec in (("camera", calib.camera, np.zeros(3), np.zeros(3)),
                                  ("projector", calib.projector, cv2.Rodrigues(np.array(sc.R))[0], np.array(sc.T))):
        P = ex.opengl_projection(dev.K, dev.image_size, 100.0, 5000.0, y_up=y_up, zero_to_one=zero_to_one)
        clip = (P @ V[name] @ np.column_stack([Xw, np.ones(len(Xw))]).T).T
        pix, depth = ex.clip_to_pixels(clip, dev.image_size, y_up=y_up, zero_to_one=zero_to_one)
        ref, _ = cv2.projectPoints(Xc, rvec, tvec, np.asarray(dev.K, float), None)
        np.testing.assert_allclose(pix, ref.reshape(-1, 2), atol=1e-8)
        assert np.all((depth > 0) & (depth < 1))


def test_projection_matrix_edges_depth_and_skew():
    K = np.array([[800.0, 3.0, 330.0], [0, 810.0, 235.0], [0, 0, 1]])
    W, H, near, far = 640, 480, 10.0, 1000.0
    P = ex.opengl_projection(K, (W, H), near, far)
    X = np.array([[30.0, -20, 400], [0, 0, near], [5, 5, far]])
    eye = (ex.GL_FROM_CV[:3, :3] @ X.T).T
    clip = (P @ np.column_stack([eye, np.ones(3)]).T).T
    pix, depth = ex.clip_to_pixels(clip, (W, H))
    ref = models.project(K, np.eye(3), np.zeros(3), X)        # cv2.projectPoints ignores skew
    np.testing.assert_allclose(pix, ref, atol=1e-9)
    np.testing.assert_allclose(depth[1:], [0.0, 1.0], atol=1e-12)
    # the top-left pixel's outer corner (-0.5, -0.5) is NDC (-1, +1)
    Kc = np.array([[500.0, 0, 319.5], [0, 500.0, 239.5], [0, 0, 1]])
    P = ex.opengl_projection(Kc, (W, H), near, far)
    Xe = np.array([(-0.5 - 319.5) / 500 * 100, -(-0.5 - 239.5) / 500 * 100, -100, 1.0])
    c = P @ Xe
    np.testing.assert_allclose(c[:2] / c[3], [-1.0, 1.0], atol=1e-12)
    with pytest.raises(CalibrationError, match="0 < near < far"):
        ex.opengl_projection(K, (W, H), 10.0, 5.0)
    with pytest.raises(CalibrationError, match="0 < near < far"):
        ex.opengl_projection(K, (W, H), float("nan"), 5.0)


# ---------------------------------------------------------------------------------------------------
# remap tables
# ---------------------------------------------------------------------------------------------------

def test_undistort_maps_put_rendered_corners_where_the_pinhole_model_does():
    scene, stack, truth, maps = small_capture()
    calib = truth_calibration(scene)
    white = stack[maps.pattern_set.white]
    mx, my = ex.undistort_maps(calib.camera)
    assert mx.dtype == np.float32 and mx.shape == (400, 640)
    und_img = cv2.remap(white, mx, my, cv2.INTER_LINEAR)
    found = detect_corners(und_img, (10, 6))
    assert found is not None
    pinhole = np.array(truth["corners"]["camera_undistorted"], float)
    distorted = np.array(truth["corners"]["camera_distorted"], float)
    err = np.hypot(*(found - pinhole).T)
    assert np.sqrt(np.mean(err ** 2)) < 0.15 and err.max() < 0.4
    assert np.hypot(*(distorted - pinhole).T).max() > 3.0     # the distortion being removed is several px
    raw = detect_corners(white, (10, 6))
    assert np.sqrt(np.mean(np.sum((raw - distorted) ** 2, 1))) < 0.15


def test_division_maps_agree_with_opencv_on_its_fitted_model():
    from procam.distortion import opencv_from_division

    cam = truth_calibration(small_scene()).camera
    d = cam.distortion
    coeffs, max_err = opencv_from_division(cam.K, d.center, d.k1, d.k2, cam.image_size)
    ocv = Device(cam.K, cam.image_size, Distortion("opencv", coeffs=tuple(coeffs)))
    mx, my = ex.undistort_maps(cam)
    ox, oy = ex.undistort_maps(ocv)
    gap = np.hypot(mx - ox, my - oy)[20:-20, 20:-20]
    assert gap.max() < max(2 * max_err, 0.05)


def test_rectification_maps_and_rows():
    sc = small_scene()
    calib = truth_calibration(sc)
    rect = ex.stereo_rectify(calib)
    c = simulate.corner_truth(sc)
    K, Kp = calib.camera.K, calib.projector.K

    def rectified(K_dev, und, Rr, Pr):
        ray = np.column_stack([und, np.ones(len(und))]) @ np.linalg.inv(K_dev).T @ Rr.T
        h = ray @ Pr[:, :3].T
        return h[:, :2] / h[:, 2:3]

    rc = rectified(K, c["camera_undistorted"], rect["R1"], rect["P1"])
    rp = rectified(Kp, c["projector"], rect["R2"], rect["P2"])
    np.testing.assert_allclose(rc[:, 1], rp[:, 1], atol=1e-6)      # same rows after rectification
    for k, pts in (("1", rc), ("2", rp)):                          # every corner inside both rectified images
        W, H = rect["size" + k]
        assert np.all((pts > 0) & (pts < [W - 1, H - 1]))
    assert rect["size1"][1] == rect["size2"][1] and rect["P1"][0, 0] == pytest.approx(K[0, 0], rel=0.01)
    # P2's last column: the rectified baseline, so X_p = X_c + (Tx, 0, 0) in the rectified frames
    np.testing.assert_allclose(rect["P2"][1:, 3], 0.0)
    mx, my = ex.undistort_maps(calib.camera, new_K=rect["P1"][:, :3], R=rect["R1"], size=rect["size1"])
    src = np.column_stack([map_coordinates(mx, [rc[:, 1], rc[:, 0]], order=1),
                           map_coordinates(my, [rc[:, 1], rc[:, 0]], order=1)])
    assert np.abs(src - c["camera_distorted"]).max() < 0.02


def test_predistort_maps_invert_the_lens():
    proj = Device(np.array([[1400.0, 0, 960], [0, 1400, 1000], [0, 0, 1]]), (192, 108),
                  Distortion("opencv", coeffs=(0.1, -0.05, 1e-3, 0, 0)))
    mx, my = ex.predistort_maps(proj)
    ys, xs = np.mgrid[0:108, 0:192]
    back = proj.distortion.distort(np.column_stack([mx.ravel(), my.ravel()]), proj.K)
    np.testing.assert_allclose(back, np.column_stack([xs.ravel(), ys.ravel()]), atol=1e-3)
    ident = ex.predistort_maps(Device(proj.K, (192, 108)))
    np.testing.assert_allclose(ident[0], xs, atol=1e-4)


# ---------------------------------------------------------------------------------------------------
# kamino410 and intrinsics files
# ---------------------------------------------------------------------------------------------------

def test_kamino410_file_has_their_keys_and_round_trips(tmp_path):
    sc, calib = _paper()
    calib = calib.replace(stereo_rms=0.25)
    path = io.save_kamino410(calib, tmp_path / "calibration_result.xml")
    assert [p.name for p in tmp_path.iterdir()] == ["calibration_result.xml"]
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    assert fs.getNode("img_shape").mat().shape == (2, 1)
    np.testing.assert_array_equal(fs.getNode("img_shape").mat().ravel(), [800, 1280])   # (height, width)
    np.testing.assert_array_equal(fs.getNode("cam_int").mat(), calib.camera.K)
    assert fs.getNode("cam_dist").mat().shape == (1, 5) and fs.getNode("proj_dist").mat().shape == (1, 5)
    np.testing.assert_array_equal(fs.getNode("rotation").mat(), calib.R)
    assert fs.getNode("translation").mat().shape == (3, 1)
    np.testing.assert_array_equal(fs.getNode("translation").mat().ravel(), calib.T)
    assert fs.getNode("rms").real() == 0.25
    fs.release()
    back = io.load_kamino410(path)
    assert back.camera.image_size == (1280, 800) and back.projector.image_size == (1920, 1080)
    np.testing.assert_array_equal(back.R, calib.R)
    np.testing.assert_array_equal(back.projector.K, calib.projector.K)
    assert back.camera.distortion.model == "opencv" and not back.warnings


def test_load_kamino410_file_as_their_tool_writes_it(tmp_path):
    path = tmp_path / "calibration_result.xml"
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    fs.write("img_shape", np.array([[1024.0], [1280.0]]))
    fs.write("rms", 0.4)
    fs.write("cam_int", np.array([[3452.4, 0, 587.2], [0, 3449.9, 521.4], [0, 0, 1]]))
    fs.write("cam_dist", np.array([[-0.22, -0.87, -7e-4, -1.7e-3, 3.13]]))
    fs.write("proj_int", np.array([[1947.2, 0, 448.9], [0, 1934.0, 720.0], [0, 0, 1]]))
    fs.write("proj_dist", np.array([[-0.09, 1.14, -2e-3, -9e-3, -7.8]]))
    fs.write("roration", np.eye(3))              # their early files' spelling
    fs.write("translation", np.array([[39.06], [-278.26], [-61.95]]))
    fs.release()
    c = io.load_kamino410(path, proj_size=(1280, 800))
    assert c.camera.image_size == (1280, 1024) and c.projector.image_size == (1280, 800) and not c.warnings
    np.testing.assert_allclose(c.T, [39.06, -278.26, -61.95])
    c = io.load_kamino410(path)
    assert c.projector.image_size == (898, 1440) and "does not store the projector size" in c.warnings[0]


def test_load_camera_intrinsics_from_procam_files(tmp_path):
    sc, calib = _paper()
    j = io.save_calibration(calib, tmp_path / "calib.json")
    dev = io.load_camera_intrinsics(j)
    assert dev.distortion == calib.camera.distortion and dev.image_size == (1280, 800)
    np.testing.assert_array_equal(dev.K, calib.camera.K)
    y = io.save_opencv_yaml(calib, tmp_path / "calib.yml")
    dev = io.load_camera_intrinsics(y, image_size=(1280, 800))
    assert dev.distortion.model == "opencv" and len(dev.distortion.coeffs) == 5
    x = io.save_kamino410(calib, tmp_path / "k.xml")
    dev = io.load_camera_intrinsics(x)
    assert dev.image_size == (1280, 800)
    cfg = tmp_path / "camera_config.json"       # kamino410's camera file
    cfg.write_text(json.dumps({"camera": {"P": np.asarray(calib.camera.K).ravel().tolist(),
                                          "distortion": [0.1, -0.2, 0, 0, 0.05], "width": 1280, "height": 800}}))
    dev = io.load_camera_intrinsics(cfg)
    assert dev.distortion.coeffs == (0.1, -0.2, 0.0, 0.0, 0.05) and dev.image_size == (1280, 800)


def test_load_camera_intrinsics_from_opencv_sample_files(shared_data):
    dev = io.load_camera_intrinsics(shared_data / "opencv-left-right" / "left_intrinsics.yml")
    assert dev.image_size == (640, 480)
    assert dev.K[0, 0] == pytest.approx(535.9157, abs=1e-3) and dev.K[1, 2] == pytest.approx(235.5708, abs=1e-3)
    assert dev.distortion.coeffs[0] == pytest.approx(-0.26637, abs=1e-5)
    with pytest.raises(CalibrationFileError, match="does not say the image size"):
        io.load_camera_intrinsics(shared_data / "opencv-left-right" / "intrinsics.yml")
    dev = io.load_camera_intrinsics(shared_data / "opencv-left-right" / "intrinsics.yml", image_size=(640, 480))
    assert dev.K[0, 0] == pytest.approx(534.8033, abs=1e-3)
    with pytest.raises(CalibrationFileError, match="for 640x480 images, the images are 1280x960"):
        io.load_camera_intrinsics(shared_data / "opencv-left-right" / "left_intrinsics.yml", image_size=(1280, 960))


def test_load_camera_intrinsics_errors(tmp_path):
    bad = tmp_path / "bad.yml"
    fs = cv2.FileStorage(str(bad), cv2.FILE_STORAGE_WRITE)
    fs.write("camera_matrix", np.array([[np.nan, 0, 1], [0, 1, 1], [0, 0, 1]]))
    fs.write("image_width", 640)
    fs.write("image_height", 480)
    fs.release()
    with pytest.raises(CalibrationFileError, match=r"bad.yml: camera_matrix holds NaN"):
        io.load_camera_intrinsics(bad)
    other = tmp_path / "other.yml"
    fs = cv2.FileStorage(str(other), cv2.FILE_STORAGE_WRITE)
    fs.write("K", np.eye(3))
    fs.release()
    with pytest.raises(CalibrationFileError, match="no camera matrix found"):
        io.load_camera_intrinsics(other)
    dist = tmp_path / "dist.yml"
    fs = cv2.FileStorage(str(dist), cv2.FILE_STORAGE_WRITE)
    fs.write("cam_K", np.array([[500.0, 0, 320], [0, 500, 240], [0, 0, 1]]))
    fs.write("cam_kc", np.zeros((1, 3)))
    fs.release()
    with pytest.raises(CalibrationFileError, match="cam_kc must have 4, 5, 8, 12, 14 OpenCV coefficients, got 3"):
        io.load_camera_intrinsics(dist, image_size=(640, 480))
    garbage = tmp_path / "garbage.yml"
    garbage.write_text("%YAML:1.0\ncam_K: [1, 2\n")
    with pytest.raises(CalibrationFileError, match="garbage.yml"):
        io.load_camera_intrinsics(garbage)
    txt = tmp_path / "cam.txt"
    txt.write_text("fx 500")
    with pytest.raises(CalibrationFileError, match="unknown file type"):
        io.load_camera_intrinsics(txt)
    with pytest.raises(CalibrationFileError, match="no such file"):
        io.load_camera_intrinsics(tmp_path / "missing.json")


# ---------------------------------------------------------------------------------------------------
# CLI
# ---------------------------------------------------------------------------------------------------

def test_cli_export(tmp_path):
    import procam.cli.export  # noqa: F401  (registers the command)
    from conftest import run_cli

    sc = small_scene()
    calib_path = io.save_calibration(truth_calibration(sc), tmp_path / "calib.json")
    code, out, err = run_cli(["export", calib_path, "--format", "opengl", "-o", tmp_path / "gl.json",
                              "--near", "100", "--far", "3000"])
    assert code == 0, err
    doc = json.loads((tmp_path / "gl.json").read_text())
    np.testing.assert_allclose(doc["projector"]["projection"],
                               ex.opengl_projection(sc.K_proj, sc.proj_size, 100, 3000))
    code, out, err = run_cli(["export", calib_path, "--format", "kamino410", "-o", tmp_path / "k.xml"])
    assert code == 0, err
    assert io.load_kamino410(tmp_path / "k.xml").camera.image_size == (640, 400)
    code, out, err = run_cli(["export", calib_path, "--format", "maps", "-o", tmp_path / "maps", "--rectify"])
    assert code == 0, err
    names = sorted(p.name for p in (tmp_path / "maps").iterdir() if not p.name.startswith("."))
    assert names == ["camera_rectify.npz", "camera_undistort.npz", "projector_predistort.npz",
                     "projector_rectify.npz"]
    with np.load(tmp_path / "maps" / "camera_undistort.npz") as m:
        assert m["map_x"].shape == (400, 640) and m["map_x"].dtype == np.float32
    code, out, err = run_cli(["export", calib_path, "--format", "opengl", "-o", tmp_path / "g.json"])
    assert code == 2 and "--near and --far" in err
    code, out, err = run_cli(["export", calib_path, "--format", "opengl", "-o", tmp_path / "g.json",
                              "--near", "10", "--far", "5"])
    assert code == 2 and "0 < near < far" in err
    code, out, err = run_cli(["export", calib_path, "--format", "ply", "-o", tmp_path / "g.json"])
    assert code == 2 and "--format" in err and "opengl" in err and len(err.strip().splitlines()) == 1


def test_cli_commands_read_a_kamino410_file(tmp_path):
    """The one reader: a kamino410 XML is a calibration for every command, not only for calibrate --camera."""
    import procam.cli.export  # noqa: F401  (registers the command)
    from conftest import run_cli

    sc = small_scene()
    calib_path = io.save_calibration(truth_calibration(sc), tmp_path / "calib.json")
    assert run_cli(["export", calib_path, "--format", "kamino410", "-o", tmp_path / "k.xml"])[0] == 0
    code, out, err = run_cli(["export", tmp_path / "k.xml", "--format", "opengl", "-o", tmp_path / "gl.json",
                              "--near", "100", "--far", "3000"])
    assert code == 0, err
    doc = json.loads((tmp_path / "gl.json").read_text())
    np.testing.assert_allclose(doc["projector"]["projection"], ex.opengl_projection(sc.K_proj, sc.proj_size, 100, 3000))


# ---------------------------------------------------------------------------------------------------
# rectification for any rig orientation
# ---------------------------------------------------------------------------------------------------

RECT_POSES = [(15, 12, 0), (-10, 20, 5), (20, -15, -5), (5, 25, 10), (-20, -10, 0)]


def _rectified(dev, pts_distorted, R_rect, P):
    """Distorted device pixels (N, 2) -> rectified pixels (N, 2) (the forward map of the rectification)."""
    und = dev.undistort(pts_distorted)
    ray = np.column_stack([und, np.ones(len(und))]) @ np.linalg.inv(dev.K).T @ np.asarray(R_rect).T
    h = ray @ np.asarray(P)[:, :3].T
    return h[:, :2] / h[:, 2:3]


def _inside(pts, size):
    W, H = size
    return (pts[:, 0] >= -0.5) & (pts[:, 0] <= W - 0.5) & (pts[:, 1] >= -0.5) & (pts[:, 1] <= H - 0.5)


def _calibrated(preset, seed=0):
    """A multi-pose calibration of five poses of the rig (corner fast path, 0.1 / 0.2 px noise)."""
    from procam import multi_pose
    from procam.view import View
    from conftest import verdict_warnings

    sc = simulate.preset(preset)
    views = []
    for k, p in enumerate(RECT_POSES):
        s = simulate.with_board_pose(sc, p)
        obj, cam, proj = simulate.correspondences(s, sigma_cam=0.1, sigma_proj=0.2, seed=100 * seed + k)
        views.append(View(obj, cam, proj, f"p{k}", s.cam_size, s.proj_size))
    with verdict_warnings():
        return multi_pose.calibrate(views)


@pytest.mark.parametrize("preset", ["vertical", "ceiling", "paper", "lensshift"])
def test_rectified_rows_agree_and_hold_the_board_for_any_rig_orientation(preset):
    """A projector below the camera (vertical), an upside-down one above it (ceiling), beside it (paper, lensshift):
    the true corners' rectified rows agree to <= 0.1 px through a calibration fitted to noisy corners (1e-6 through
    the true one), and >= 90 % of the board lies inside both rectified images; the stored P2 carries the baseline
    and the maps say how each image was turned."""
    sc = simulate.preset(preset)
    c = simulate.corner_truth(sc)
    for calib, tol in ((truth_calibration(sc, approximate=True), 1e-6), (_calibrated(preset), 0.1)):
        rect = ex.stereo_rectify(calib)
        rc = _rectified(calib.camera, c["camera_distorted"], rect["R1"], rect["P1"])
        rp = _rectified(calib.projector, c["projector"], rect["R2"], rect["P2"])
        assert np.abs(rc[:, 1] - rp[:, 1]).max() <= tol, preset
        both = _inside(rc, rect["size1"]) & _inside(rp, rect["size2"])
        assert both.mean() >= 0.9, (preset, both.mean())
        # the baseline is on the rectified x axis: X_p = X_c + (Tx, 0, 0), and P2 carries f Tx
        X1 = (c["board"] @ np.asarray(sc.R_board).T + sc.t_board) @ rect["R1"].T
        X2 = ((c["board"] @ np.asarray(sc.R_board).T + sc.t_board) @ calib.R.T + calib.T) @ rect["R2"].T
        np.testing.assert_allclose(X2 - X1, np.tile([rect["baseline"], 0, 0], (len(X1), 1)), atol=1e-6)
        assert rect["P2"][0, 3] == pytest.approx(rect["P1"][0, 0] * rect["baseline"])
        assert abs(rect["baseline"]) == pytest.approx(np.linalg.norm(calib.T), rel=1e-9)
        for R in (rect["R1"], rect["R2"]):
            assert np.linalg.det(R) == pytest.approx(1.0)          # rotations, never mirrors
    turn = rect["rows_along_deg"]          # the nearest quarter turn of each image (the rows of a tilted baseline
    expect = {"vertical": (1, 1), "ceiling": (1, -1), "paper": (0, 0), "lensshift": (0, 0)}[preset]   # are not level)
    assert (round(turn["camera"] / 90), round(turn["projector"] / 90)) == expect, turn


def test_rectification_of_a_vertical_rig_through_the_maps_and_q(tmp_path):
    """The CLI's rectification maps of the vertical rig: each rectified true corner samples its distorted corner
    (maps), the maps record the quarter turn, and Q triangulates a rectified pair back to the 3-D corner."""
    import procam.cli.export  # noqa: F401
    from conftest import run_cli

    sc = simulate.preset("vertical")
    calib = truth_calibration(sc)
    path = io.save_calibration(calib, tmp_path / "calib.json")
    code, out, err = run_cli(["export", path, "--format", "maps", "-o", tmp_path / "maps", "--rectify"])
    assert code == 0, err
    assert "turned a quarter turn" in out
    c = simulate.corner_truth(sc)
    with np.load(tmp_path / "maps" / "camera_rectify.npz") as m:
        mx, my, R1, P1, Q = m["map_x"], m["map_y"], m["R"], m["P"], m["Q"]
        assert 45 < float(m["rows_along_deg"]) < 135
    with np.load(tmp_path / "maps" / "projector_rectify.npz") as m:
        R2, P2 = m["R"], m["P"]
    rc = _rectified(calib.camera, c["camera_distorted"], R1, P1)
    rp = _rectified(calib.projector, c["projector"], R2, P2)
    src = np.column_stack([map_coordinates(mx, [rc[:, 1], rc[:, 0]], order=1),
                           map_coordinates(my, [rc[:, 1], rc[:, 0]], order=1)])
    assert np.abs(src - c["camera_distorted"]).max() < 0.05
    h = np.column_stack([rc, rc[:, 0] - rp[:, 0], np.ones(len(rc))]) @ Q.T
    X = h[:, :3] / h[:, 3:4]
    X_true = (c["board"] @ np.asarray(sc.R_board).T + sc.t_board) @ R1.T
    np.testing.assert_allclose(X, X_true, atol=1e-6 * np.abs(X_true).max())


@pytest.mark.parametrize("near, far, words", [
    (1.0, 1.0000000000000002, "hardly beyond near"), (100.0, 100.001, "hardly beyond near"),
    (1e-300, 1000.0, "far / near is"), (10.0, 5.0, "0 < near < far"), (1.0, float("inf"), "finite"),
    (float("nan"), 10.0, "finite"), (1.0, 2e12, "<= 1e+12"), ("x", 10.0, "must be numbers")])
def test_a_clipping_range_no_projection_matrix_can_hold_is_refused(near, far, words):
    """One check of near and far (the CLI's, the app's and the library's): a range too thin (the depth terms ~ 1 /
    (far - near) explode: with far one ulp beyond near the matrix's depth row is ~ 1e16) or too deep is refused; a
    range at the least accepted thickness still gives a projection whose depth maps near to -1 and far to +1."""
    from procam.export.frames import MIN_DEPTH_RATIO, check_clip

    K = np.array([[800.0, 0, 320], [0, 800.0, 240], [0, 0, 1]])
    with pytest.raises(CalibrationError) as e:
        ex.opengl_projection(K, (640, 480), near, far)
    assert words in str(e.value)
    near, far = check_clip(1000.0, 1000.0 * MIN_DEPTH_RATIO)
    P = ex.opengl_projection(K, (640, 480), near, far)
    for z, want in ((near, -1.0), (far, 1.0)):
        clip = P @ [0.0, 0.0, -z, 1.0]
        assert clip[2] / clip[3] == pytest.approx(want, abs=1e-6)
