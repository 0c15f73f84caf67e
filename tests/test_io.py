import json

import cv2
import numpy as np
import pytest

from procam import io
from procam.calibration import Calibration, Device, Distortion
from procam.errors import CalibrationFileError
from procam.view import View


def _calib(division=True):
    Kc = np.array([[1539.0, 0, 674], [0, 1545.2, 512], [0, 0, 1]])
    Kp = np.array([[2421.0, 0, 960], [0, 2421.0, 1065], [0, 0, 1]])
    dist = Distortion("division", (674.0, 512.0), -1e-7, 2e-14) if division else \
        Distortion("opencv", coeffs=(-0.1, 0.05, 0.001, -0.002, 0.0))
    R = cv2.Rodrigues(np.array([0.01, 0.25, -0.004]))[0]
    obj = np.column_stack([np.arange(4.0), np.arange(4.0) * 2, np.zeros(4)])
    view = View(obj, np.arange(8.0).reshape(4, 2), np.array([[1, 2], [np.nan, np.nan], [5, 6], [7, 8.0]]), "p1",
                (1280, 800), (1920, 1080), {"reason": np.array([0, 2, 0, 0], np.uint8)})
    return Calibration(Device(Kc, (1280, 800), dist), Device(Kp, (1920, 1080)), R, np.array([-170.05, -41.25, -65.35]),
                       "single-pose", 0.05, 0.1, 0.08, std={"f_c": 4.2, "T": [1.0, 2.0, 3.0]},
                       poses=({"name": "p1", "camera_angles_deg": [15.0, 12.0, 0.0]},), views=(view,),
                       warnings=("a warning",))


@pytest.mark.parametrize("division", [True, False])
def test_json_roundtrip(tmp_path, division):
    c = _calib(division)
    io.save_calibration(c, tmp_path / "c.json")
    d = io.load_calibration(tmp_path / "c.json")
    assert np.array_equal(d.camera.K, c.camera.K) and np.array_equal(d.projector.K, c.projector.K)
    assert np.array_equal(d.R, c.R) and np.array_equal(d.T, c.T)
    assert d.camera.distortion == c.camera.distortion and d.camera.image_size == (1280, 800)
    assert (d.cam_rms, d.proj_rms, d.stereo_rms, d.method) == (0.05, 0.1, 0.08, "single-pose")
    assert d.std == c.std and d.warnings == c.warnings
    v, w = d.views[0], c.views[0]
    assert np.array_equal(v.obj_pts, w.obj_pts) and np.allclose(v.proj_pts, w.proj_pts, equal_nan=True)
    assert list(v.diagnostics["reason"]) == [0, 2, 0, 0]
    raw = json.loads((tmp_path / "c.json").read_text())
    assert raw["format"] == "procam-calibration" and "x_projector = R @ x_camera + T" in raw["conventions"]["extrinsics"]
    if division:
        assert raw["camera"]["opencv_fit"]["max_err_px"] < 0.5


def test_opencv_yaml_loads_in_opencv(tmp_path):
    c = _calib(True)
    io.save_opencv_yaml(c, tmp_path / "c.yml")
    fs = cv2.FileStorage(str(tmp_path / "c.yml"), cv2.FILE_STORAGE_READ)
    for key in ("cam_K", "cam_kc", "proj_K", "proj_kc", "R", "T"):
        assert not fs.getNode(key).empty(), key
    assert np.allclose(fs.getNode("cam_K").mat(), c.camera.K)
    assert np.allclose(fs.getNode("R").mat(), c.R) and np.allclose(fs.getNode("T").mat().ravel(), c.T)
    assert fs.getNode("cam_kc").mat().size == 5
    assert abs(fs.getNode("stereo_error").real() - 0.08) < 1e-12
    fs.release()
    # the OpenCV fit reproduces the division model: undistorting with cam_kc ~ undistorting with the division model
    d = io.load_calibration(tmp_path / "c.yml")
    pts = np.array([[100.0, 80.0], [640, 400], [1200, 700], [300, 650]])
    assert np.abs(d.camera.undistort(pts) - c.camera.undistort(pts)).max() < 0.5
    assert np.allclose(d.R, c.R) and d.proj_rms == pytest.approx(0.1)




def test_load_errors(tmp_path):
    with pytest.raises(CalibrationFileError, match="no such file"):
        io.load_calibration(tmp_path / "nope.json")
    (tmp_path / "bad.json").write_text("{not json")
    with pytest.raises(CalibrationFileError, match="not a procam calibration"):
        io.load_calibration(tmp_path / "bad.json")
    (tmp_path / "other.json").write_text('{"a": 1}')
    with pytest.raises(CalibrationFileError, match="not a procam calibration"):
        io.load_calibration(tmp_path / "other.json")


# ------------------------------------------------------------------------------------------------
# the one reader: every format procam writes comes back through load_calibration
@pytest.mark.parametrize("name", ["c.json", "c.yml", "c.yaml", "c.xml", "kamino.xml", "kamino.yml"])
def test_every_format_procam_writes_round_trips_through_load_calibration(tmp_path, name):
    c = _calib(division=False)
    path = tmp_path / name
    if name.startswith("kamino"):
        io.save_kamino410(c, path)
    else:
        io.save_calibration(c, path)
    d = io.load_calibration(path)
    # FileStorage writes doubles with all their digits: exact in every format
    for got, want in ((d.camera, c.camera), (d.projector, c.projector)):
        assert np.array_equal(got.K, want.K) and got.image_size == want.image_size
        assert got.distortion == want.distortion or (want.distortion.model == "none" and not any(
            got.distortion.coeffs))
    assert np.array_equal(d.R, c.R) and np.array_equal(d.T, c.T)
    assert d.method == ("kamino410" if name.startswith("kamino") else "single-pose")


def test_a_kamino410_file_as_their_tool_writes_it_loads(tmp_path):
    """Their calibrate.py: cv2.FileStorage XML, img_shape (height, width), rms, cam_int, cam_dist, proj_int,
    proj_dist, rotation, translation; no projector size."""
    def mat(rows, cols, values):
        return (f'type_id="opencv-matrix">\n  <rows>{rows}</rows>\n  <cols>{cols}</cols>\n  <dt>d</dt>\n'
                f'  <data>\n    {" ".join(map(str, values))}</data>')
    rotation = [0.999986, 0.001847, -0.004944, -0.001695, 0.999684, 0.025076, 0.004988, -0.025067, 0.999673]
    path = tmp_path / "calibration_result.xml"
    path.write_text(
        '<?xml version="1.0"?>\n<opencv_storage>\n'
        f'<img_shape {mat(2, 1, [1024.0, 1280.0])}</img_shape>\n'
        '<rms>4.0e-01</rms>\n'
        f'<cam_int {mat(3, 3, [3452.4, 0, 587.2, 0, 3449.9, 521.4, 0, 0, 1])}</cam_int>\n'
        f'<cam_dist {mat(1, 5, [-0.22, -0.87, -7e-4, -1.7e-3, 3.13])}</cam_dist>\n'
        f'<proj_int {mat(3, 3, [1947.2, 0, 448.9, 0, 1934.0, 720.0, 0, 0, 1])}</proj_int>\n'
        f'<proj_dist {mat(1, 5, [-0.09, 1.14, -2e-3, -9e-3, -7.8])}</proj_dist>\n'
        f'<rotation {mat(3, 3, rotation)}</rotation>\n'
        f'<translation {mat(3, 1, [39.06, -278.26, -61.95])}</translation>\n'
        '</opencv_storage>\n')
    c = io.load_calibration(path)
    assert c.method == "kamino410" and c.camera.image_size == (1280, 1024) and c.stereo_rms == 0.4
    assert c.camera.K[0, 0] == 3452.4 and c.projector.K[1, 2] == 720.0
    assert c.camera.distortion.coeffs == (-0.22, -0.87, -7e-4, -1.7e-3, 3.13)
    np.testing.assert_array_equal(c.T, [39.06, -278.26, -61.95])
    assert c.projector.image_size == (898, 1440) and "does not store the projector size" in c.warnings[0]
    assert io.load_camera_intrinsics(path).image_size == (1280, 1024)


def test_a_file_no_reader_knows_names_the_formats_read(tmp_path):
    for name, text in (("notes.txt", "fx 500"), ("other.json", '{"a": 1}'), ("k.yml", "%YAML:1.0\nK: 1\n")):
        (tmp_path / name).write_text(text)
        with pytest.raises(CalibrationFileError) as e:
            io.load_calibration(tmp_path / name)
        msg = str(e.value)
        assert len(msg.splitlines()) == 1 and name in msg
        assert "procam calibration JSON" in msg and "kamino410" in msg and "cam_K" in msg, msg


def test_the_format_is_known_by_content_not_by_suffix(tmp_path):
    c = _calib(division=False)
    io.save_calibration(c, tmp_path / "c.yml")
    io.save_calibration(c, tmp_path / "c.json")
    (tmp_path / "yaml.json").write_bytes((tmp_path / "c.yml").read_bytes())
    (tmp_path / "json.calib").write_bytes((tmp_path / "c.json").read_bytes())
    for name in ("yaml.json", "json.calib"):
        assert np.array_equal(io.load_calibration(tmp_path / name).R, c.R)


# ------------------------------------------------------------------------------------------------
# the rules the two old validator sets disagreed on (procam.io.validate)
def _kamino(path, **change):
    mats = {"img_shape": np.array([[800.0], [1280.0]]), "rms": 0.3,
            "cam_int": np.array([[1500.0, 0, 640], [0, 1500, 400], [0, 0, 1]]), "cam_dist": np.zeros((1, 5)),
            "proj_int": np.array([[2400.0, 0, 960], [0, 2400, 1000], [0, 0, 1]]), "proj_dist": np.zeros((1, 5)),
            "rotation": np.eye(3), "translation": np.array([[-170.0], [-40], [-60]]),
            "proj_shape": np.array([[1080.0], [1920.0]]), **change}
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    for k, v in mats.items():
        if v is not None:
            fs.write(k, v)
    fs.release()
    return path


def _edited_json(tmp_path, fn):
    io.save_calibration(_calib(division=False), tmp_path / "c.json")
    doc = json.loads((tmp_path / "c.json").read_text())
    fn(doc)
    (tmp_path / "e.json").write_text(json.dumps(doc))
    return tmp_path / "e.json"


def test_rule_image_side_at_least_2_px(tmp_path):
    path = _edited_json(tmp_path, lambda d: d["camera"].__setitem__("image_size", [1, 800]))
    with pytest.raises(CalibrationFileError, match=r"camera.image_size must be \[width, height\], whole pixels from 2"):
        io.load_calibration(path)
    with pytest.raises(CalibrationFileError, match="img_shape .*from 2"):
        io.load_calibration(_kamino(tmp_path / "k.xml", img_shape=np.array([[1.0], [1280.0]])))
    assert io.load_calibration(_kamino(tmp_path / "k2.xml", img_shape=np.array([[2.0], [2.0]]))).camera.image_size \
        == (2, 2)


def test_rule_rotation_tolerance_takes_a_yaml_written_with_few_digits(tmp_path):
    R = cv2.Rodrigues(np.array([0.01, 0.25, -0.004]))[0]
    few = np.round(R, 5)                                   # 5 decimals: |R^T R - I| about 1e-5
    assert 1e-6 < np.abs(few.T @ few - np.eye(3)).max() < 1e-4
    assert np.array_equal(io.load_calibration(_kamino(tmp_path / "k.xml", rotation=few)).R, few)
    path = _edited_json(tmp_path, lambda d: d.__setitem__("R", few.tolist()))
    assert np.array_equal(io.load_calibration(path).R, few)
    bent = R * 1.01                                        # scaled by 1 %: not a rotation
    with pytest.raises(CalibrationFileError, match="rotation is not a rotation matrix"):
        io.load_calibration(_kamino(tmp_path / "k2.xml", rotation=bent))
    with pytest.raises(CalibrationFileError, match="R is not a rotation matrix"):
        io.load_calibration(_edited_json(tmp_path, lambda d: d.__setitem__("R", bent.tolist())))


def test_rule_a_distortion_no_lens_has_is_refused(tmp_path):
    """A division k1 of 1e10 (the whole image on its centre: every pixel of an exported undistortion map invalid,
    exit 0 before) or OpenCV coefficients that fold the image's edge are refused naming the field; strong real
    lenses (a wide angle's barrel, a pincushion) are read."""
    import dataclasses

    c = _calib()
    for dist in (Distortion("division", (674.0, 512.0), -4e-7, 0.0), Distortion("division", (674.0, 512.0), 2e-7, 0.0),
                 Distortion("opencv", coeffs=(-0.4, 0.15, 0.0, 0.0, -0.02))):
        io.save_calibration(dataclasses.replace(c, camera=dataclasses.replace(c.camera, distortion=dist)),
                            tmp_path / "ok.json")
        assert io.load_calibration(tmp_path / "ok.json").camera.distortion == dist
    for dist in (Distortion("division", (674.0, 512.0), 1e10, 0.0), Distortion("division", (674.0, 512.0), -1e-3, 0.0),
                 Distortion("opencv", coeffs=(1e6, 0.0, 0.0, 0.0, 0.0))):
        io.save_calibration(dataclasses.replace(c, camera=dataclasses.replace(c.camera, distortion=dist)),
                            tmp_path / "bad.json")
        with pytest.raises(CalibrationFileError, match="bad.json: camera.distortion puts the image's edge .* times as "
                                                       "far from the principal point .*: not a lens"):
            io.load_calibration(tmp_path / "bad.json")


def test_rule_an_empty_distortion_vector_is_no_distortion(tmp_path):
    c = io.load_calibration(_kamino(tmp_path / "k.xml", cam_dist=np.zeros((1, 0))))    # OpenCV's empty Mat
    assert c.camera.distortion == Distortion()
    assert io.load_calibration(_kamino(tmp_path / "k0.xml", cam_dist=None)).camera.distortion == Distortion()
    path = tmp_path / "empty.yml"
    path.write_text("%YAML:1.0\ncam_int: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
                    "   data: [ 1500., 0., 640., 0., 1500., 400., 0., 0., 1. ]\ncam_dist: []\n"
                    "img_shape: [ 800, 1280 ]\n")
    dev = io.load_camera_intrinsics(path)
    assert dev.distortion == Distortion() and dev.image_size == (1280, 800)
    path = _edited_json(tmp_path, lambda d: d["camera"].__setitem__("distortion", {"model": "opencv", "coeffs": []}))
    assert io.load_calibration(path).camera.distortion == Distortion()
    # a vector of another length is refused, zeros or not
    with pytest.raises(CalibrationFileError, match="cam_dist must have 4, 5, 8, 12, 14 OpenCV coefficients, got 3"):
        io.load_calibration(_kamino(tmp_path / "k3.xml", cam_dist=np.zeros((1, 3))))


# ------------------------------------------------------------------------------------------------
# decoded maps
def test_decoded_maps_round_trip_and_are_checked(tmp_path):
    from conftest import camera_view_of_patterns

    from procam import decode, patterns
    from procam.errors import CaptureError

    ps = patterns.pattern_set(64, 32)
    yy, xx = np.mgrid[:32, :64]
    res = decode.decode(camera_view_of_patterns(64, 32), ps)
    path = io.save_decoded_maps(tmp_path / "maps.npz", res)
    m = io.load_decoded_maps(path)
    assert np.array_equal(m["col"], xx) and np.array_equal(m["row"], yy) and m["valid_col"].all()
    assert m["projector_size"] == (64, 32) and m["order"] == ps.order
    assert io.save_decoded_maps(tmp_path / "again.npz", res).read_bytes() == path.read_bytes()
    with np.load(path) as f:
        z = dict(f)
    del z["row"]
    np.savez(tmp_path / "short.npz", **z)
    with pytest.raises(CaptureError, match="short.npz: has no row"):
        io.load_decoded_maps(tmp_path / "short.npz")
    # a map of another kind of value or another shape is refused in one line (it was an internal error further on)
    with np.load(path) as f:
        good = dict(f)
    for key, value, words in (("valid_col", good["valid_col"].astype(float), "valid_col holds float64 values, not "
                               "true/false"), ("col", good["col"] * 1j, "col holds complex64 values, not real"),
                              ("reason_row", good["reason_row"].astype(np.int8), "reason_row holds int8 values"),
                              ("col", good["col"][..., None], "col is 32x64x1, not a map"),
                              ("col", np.float32(1), "col is a single value, not a map"),
                              ("row", good["row"][:16], "row is 16x64, the maps are 32x64"),
                              # decoded coordinates beyond the projector (a map scaled by 10), or NaN where decoded
                              ("col", good["col"] * 10, "col holds decoded values outside the projector's 0 to 64"),
                              ("row", np.full_like(good["row"], np.nan), "row holds decoded values outside")):
        np.savez(tmp_path / "odd.npz", **{**good, key: value})
        with pytest.raises(CaptureError, match=f"odd.npz: {words}"):
            io.load_decoded_maps(tmp_path / "odd.npz")
