"""Dense triangulation, plane fits and PLY point clouds against the simulator's ground truth."""

import sys

import numpy as np
import pytest

from procam import io, simulate
from procam.calibration import Device, Distortion
from procam.errors import ProcamError
from procam.board import board_region
from procam.io import read_ply, write_ply
from procam.reconstruct import PointCloud, fit_plane, reconstruct, residual_image, residual_map
from procam.triangulate import triangulate_dense
from procam.simulate import truth_calibration
from sim_small import small_capture, small_scene

plyfile = pytest.importorskip("plyfile", reason="the PLY tests need the plyfile package")


def _board_plane(scene):
    """True board plane (unit normal n, point p) in the camera frame."""
    return scene.R_board[:, 2], scene.t_board


def _wall_plane(scene):
    return scene.wall_normal, scene.t_board + scene.wall_offset * np.array([0.0, 0.0, 1.0])


def _dist(X, plane):
    n, p = plane
    return (np.asarray(X) - p) @ n


def _angle_deg(a, b):
    c = abs(float(np.dot(a, b)) / (np.linalg.norm(a) * np.linalg.norm(b)))
    return float(np.degrees(np.arccos(min(1.0, c))))


# ---------------------------------------------------------------------------------------------------
# dense triangulation on exact maps
# ---------------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def exact_maps():
    scene = small_scene()
    col, row, lit_board = simulate.true_projector_maps(scene)
    return scene, col, row, lit_board


@pytest.mark.parametrize("use", ["both", "col", "row"])
def test_dense_triangulation_of_exact_maps_lands_on_board_and_wall(exact_maps, use):
    scene, col, row, lit_board = exact_maps
    out = triangulate_dense(truth_calibration(scene), col, row, use=use)
    X, px = out["points"], out["pixels"]
    assert len(X) == np.count_nonzero(np.isfinite(col))
    on_board = lit_board[px[:, 1], px[:, 0]]
    assert np.abs(_dist(X[on_board], _board_plane(scene))).max() < 1e-6
    d_wall = np.abs(_dist(X[~on_board], _wall_plane(scene)))
    d_board = np.abs(_dist(X[~on_board], _board_plane(scene)))
    assert np.all(np.minimum(d_wall, d_board) < 1e-6)      # board-edge pixels lie on one or the other
    assert np.mean(d_wall < 1e-6) > 0.9
    assert out["both"].all() == (use == "both")
    assert np.abs(out["residual_px"]).max() < 1e-6


def test_dense_triangulation_with_a_distorted_projector(exact_maps):
    scene, col, row, lit_board = exact_maps
    base = truth_calibration(scene)
    X_true = triangulate_dense(base, col, row)
    proj = Device(base.projector.K, base.projector.image_size, Distortion("opencv", coeffs=(0.08, -0.05, 0, 0, 0)))
    calib = base.replace(projector=proj)
    # what a distorted projector's decoding would give at those camera pixels
    pd = proj.project(scene.R, scene.T, X_true["points"])
    H, W = col.shape
    col_d = np.full((H, W), np.nan)
    row_d = np.full((H, W), np.nan)
    px = X_true["pixels"]
    col_d[px[:, 1], px[:, 0]] = pd[:, 0]
    row_d[px[:, 1], px[:, 0]] = pd[:, 1]
    for use in ("both", "col", "row"):
        out = triangulate_dense(calib, col_d, row_d, use=use, pixels=px[::5])
        np.testing.assert_array_equal(out["pixels"], px[::5])
        assert np.abs(out["points"] - X_true["points"][::5]).max() < 1e-5, use


def test_dense_triangulation_of_chosen_pixels(exact_maps):
    scene, col, row, _ = exact_maps
    calib = truth_calibration(scene)
    full = triangulate_dense(calib, col, row)
    pick = full["pixels"][::97]
    part = triangulate_dense(calib, col, row, pixels=pick)
    np.testing.assert_array_equal(part["pixels"], pick)
    np.testing.assert_allclose(part["points"], full["points"][::97])


# ---------------------------------------------------------------------------------------------------
# plane fit
# ---------------------------------------------------------------------------------------------------

def test_fit_plane_ignores_a_third_of_outliers():
    rng = np.random.default_rng(7)
    n = np.array([0.2, -0.3, 1.0])
    n /= np.linalg.norm(n)
    u = np.cross(n, [1.0, 0, 0])
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    ab = rng.uniform(-100, 100, (2000, 2))
    P = 500 * n + ab[:, :1] * u + ab[:, 1:] * v + rng.normal(0, 0.1, (2000, 1)) * n
    out = rng.uniform(-100, 100, (1000, 3)) + [0, 0, 500]
    plane = fit_plane(np.vstack([P, out]), seed=1)
    assert _angle_deg(plane.normal, n) < 0.05
    assert abs(plane.offset - 500) < 0.05            # the origin is 500 in front of the plane
    assert plane.inliers[:2000].mean() > 0.98 and plane.inliers[2000:].mean() < 0.05
    assert plane.rms == pytest.approx(0.1, rel=0.15)
    assert plane.sigma == pytest.approx(0.1, rel=0.15)


# ---------------------------------------------------------------------------------------------------
# a rendered pose: point cloud, plane, wall, PLY
# ---------------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def cloud_of_render():
    scene, stack, truth, maps = small_capture()
    calib = truth_calibration(scene)
    ps = maps.pattern_set
    return scene, stack, truth, maps, reconstruct(calib, maps, stack[ps.white])


def test_rendered_board_fits_a_plane_within_the_noise(cloud_of_render):
    scene, stack, truth, maps, cloud = cloud_of_render
    corners = np.array(truth["corners"]["camera_distorted"], float)
    on_board = cloud.image_mask(board_region(corners, scene.cam_size))
    assert on_board.sum() > 20000
    plane = fit_plane(cloud.points[on_board])
    # decoded projector coordinates are whole projector pixels: depth noise of a few tenths of a mm
    assert plane.rms < 0.4 and plane.inliers.mean() > 0.95
    n_true, p_true = _board_plane(scene)
    assert _angle_deg(plane.normal, n_true) < 0.1
    assert abs(plane.distance(p_true[None])[0]) < 0.2
    # no systematic error: distances to the TRUE plane are as small as to the fitted one
    d_true = _dist(cloud.points[on_board][plane.inliers], (n_true, p_true))
    assert np.sqrt(np.mean(d_true ** 2)) < 1.1 * plane.rms
    res = residual_map(cloud.subset(on_board), plane)
    assert res.shape == (400, 640) and np.isfinite(res).sum() == on_board.sum()
    img = residual_image(res)
    assert img.shape == (400, 640, 3) and img.dtype == np.uint8


def test_rendered_wall_is_where_the_simulator_put_it(cloud_of_render):
    scene, stack, truth, maps, cloud = cloud_of_render
    corners = np.array(truth["corners"]["camera_distorted"], float)
    off_board = ~cloud.image_mask(board_region(corners, scene.cam_size, shrink=-0.6))
    assert off_board.sum() > 20000
    d = _dist(cloud.points[off_board], _wall_plane(scene))
    assert abs(np.median(d)) < 0.5 and np.median(np.abs(d)) < 1.0         # mm, at 950 mm
    wall = fit_plane(cloud.points[off_board])
    n_true, p_true = _wall_plane(scene)
    assert _angle_deg(wall.normal, n_true) < 0.2
    assert abs(wall.distance(p_true[None])[0]) < 0.5


def test_ply_of_a_rendered_pose_loads_back(cloud_of_render, tmp_path):
    scene, stack, truth, maps, cloud = cloud_of_render
    assert cloud.colours is not None and cloud.colours.dtype == np.uint8
    path = write_ply(tmp_path / "sub" / "cloud.ply", cloud.points, cloud.colours, comments=["units mm"])
    assert sorted(p.name for p in path.parent.iterdir()) == ["cloud.ply"]   # no temporary left
    ply = plyfile.PlyData.read(str(path))
    assert not ply.text and ply.byte_order == "<" and ply.comments == ["units mm"]
    v = ply["vertex"].data
    assert len(v) == len(cloud)
    assert [p.name for p in ply["vertex"].properties] == ["x", "y", "z", "red", "green", "blue"]
    np.testing.assert_array_equal(np.column_stack([v["x"], v["y"], v["z"]]), cloud.points.astype(np.float32))
    np.testing.assert_array_equal(np.column_stack([v["red"], v["green"], v["blue"]]), cloud.colours)
    # the white frame's grey value is the colour of each point's camera pixel
    white = stack[maps.pattern_set.white]
    px = cloud.pixels
    np.testing.assert_array_equal(cloud.colours[:, 0], white[px[:, 1], px[:, 0]])
    pts, cols, comments = read_ply(path)
    np.testing.assert_allclose(pts, cloud.points, atol=1e-3)
    assert comments == ["units mm"]


def test_write_ply_extra_properties_and_no_colour(tmp_path):
    P = np.arange(12, dtype=float).reshape(4, 3)
    path = write_ply(tmp_path / "x.ply", P, extra={"confidence": np.array([0.1, 0.2, 0.3, 0.4], np.float32)})
    ply = plyfile.PlyData.read(str(path))
    assert [p.name for p in ply["vertex"].properties] == ["x", "y", "z", "confidence"]
    pts, cols, _ = read_ply(path)
    np.testing.assert_array_equal(pts, P)
    assert cols is None


def test_ply_comments_are_ascii_lines_whatever_the_names(tmp_path):
    """A folder named with non-ASCII characters, or with bytes no encoding decodes (a name read from an old USB
    stick), or a line break, gives an ASCII comment line (it was an internal error in plyfile)."""
    odd = ["pose \u00e9", "pose\udcff1", "two\nlines", "plain"]
    path = write_ply(tmp_path / "x.ply", np.zeros((2, 3)), comments=odd)
    _, _, comments = read_ply(path)
    assert comments == ["pose \\xe9", "pose\\udcff1", "two lines", "plain"]


def test_write_ply_without_plyfile_is_a_clear_error(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "plyfile", None)
    with pytest.raises(ProcamError, match="pip install plyfile"):
        write_ply(tmp_path / "x.ply", np.zeros((1, 3)))
    assert not list(tmp_path.iterdir())


def test_reconstruct_checks_sizes_and_filters_by_residual(cloud_of_render):
    scene, stack, truth, maps, cloud = cloud_of_render
    calib = truth_calibration(scene)
    other = calib.replace(camera=Device(calib.camera.K, (1280, 800), calib.camera.distortion))
    with pytest.raises(ProcamError, match="640x400 but the calibration's camera is 1280x800"):
        reconstruct(other, maps)
    strict = reconstruct(calib, maps, max_residual_px=0.3)
    assert 0 < len(strict) < len(cloud) and strict.colours is None
    assert strict.residual_px.max() <= 0.3
    assert isinstance(strict, PointCloud)


def test_cli_reconstruct(tmp_path):
    import procam.cli.reconstruct  # noqa: F401  (registers the command)
    from conftest import run_cli

    scene, stack, truth, maps = small_capture()
    folder = tmp_path / "pose"
    simulate.write_capture(folder, stack, truth)
    calib_path = io.save_calibration(truth_calibration(scene), tmp_path / "calib.json")
    code, out, err = run_cli(["reconstruct", calib_path, folder, "-o", tmp_path / "cloud.ply", "--board", "10x6",
                              "--residuals", tmp_path / "res.png"])
    assert code == 0, err
    assert "board plane RMS" in out and (tmp_path / "cloud.ply").is_file() and (tmp_path / "res.png").is_file()
    pts, cols, comments = read_ply(tmp_path / "cloud.ply")
    assert len(pts) > 100000 and cols is not None and any("camera" in c for c in comments)
    code, out, err = run_cli(["reconstruct", calib_path, folder, "-o", tmp_path / "c.ply", "--residuals",
                              tmp_path / "r.png"])
    assert code == 2 and "--residuals needs --board" in err
    code, out, err = run_cli(["reconstruct", calib_path, folder, "-o", tmp_path / "c.txt"])
    assert code == 2 and ".ply" in err
