"""procam.method: the method a set of views calls for, and the calibration by it."""

from __future__ import annotations

import pytest

from conftest import verdict_warnings
from procam import method, simulate, single_pose
from procam.errors import CalibrationError
from procam.view import View


def _view(angles=simulate.RECOMMENDED_POSE, name="pose1"):
    sc = simulate.with_board_pose(simulate.preset("ideal"), angles)
    obj, cam, proj = simulate.correspondences(sc, 0.1, 0.2, seed=0)
    return View(obj, cam, proj, name, sc.cam_size, sc.proj_size)


def test_choose_by_the_number_of_views_unless_asked():
    assert method.choose(1) == "single-pose"
    assert method.choose(3) == "multi-pose"
    assert method.choose(1, "camera-only") == "camera-only" and method.choose(2, "single-pose") == "single-pose"
    with pytest.raises(CalibrationError, match="unknown calibration method 'zhang'"):
        method.choose(2, "zhang")


def test_a_method_that_cannot_work_with_the_views_is_refused():
    v = _view()
    with pytest.raises(CalibrationError, match="single-pose calibration takes one view, got 2"):
        method.calibrate([v, v], method="single-pose")
    with pytest.raises(CalibrationError, match="multi-pose calibration needs at least two views"):
        method.calibrate([v], method="multi-pose")
    with pytest.raises(CalibrationError, match="known camera intrinsics are for a single-pose calibration"):
        method.calibrate([v], method="camera-only", known_camera=object())


def test_one_view_is_the_single_pose_calibration():
    v = _view()
    with verdict_warnings():        # corners alone: weak (what the assumed u0p can cost); not this test's subject
        calib = method.calibrate([v])
        again = single_pose.calibrate(v)
    assert calib.method == "single-pose"
    assert calib.camera.K.tolist() == again.camera.K.tolist()
    photo = method.calibrate([v], method="camera-only")
    assert photo.method == "camera-only" and photo.projector is None and photo.views == (v,)
