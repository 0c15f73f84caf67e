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
