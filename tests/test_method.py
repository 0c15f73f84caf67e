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
    with pytest.raises(CalibrationError, match="known camera or projector intrinsics are for a single-pose calibration"):
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


@pytest.mark.parametrize("unit", ["view", "pose folder", "rig pose", "rig pose folder"])
def test_one_method_rule_worded_once_for_every_caller(unit):
    """The library, the rig path and the CLI ask :func:`procam.method.check`: one rule, one wording."""
    from procam import method

    with pytest.raises(CalibrationError, match=rf"a single-pose calibration takes one {unit}, got 3; .*--method multi"):
        method.check("single-pose", 3, unit=unit)
    with pytest.raises(CalibrationError, match=rf"a multi-pose calibration needs at least two {unit}s"):
        method.check("multi-pose", 1, unit=unit)
    method.check("multi-pose", 2, unit=unit)
    method.check("single-pose", 1, known_intrinsics=True, unit=unit)
    with pytest.raises(CalibrationError, match="known camera or projector intrinsics are for a single-pose"):
        method.check("multi-pose", 3, known_intrinsics=True, unit=unit)


def test_the_rig_path_and_the_cli_use_the_one_rule(tmp_path):
    from conftest import run_cli

    from procam.rig import calibrate_rig

    with pytest.raises(CalibrationError, match="a multi-pose calibration needs at least two rig poses"):
        calibrate_rig([object()], method="multi-pose")
    folder = tmp_path / "pose"
    folder.mkdir()
    code, _, err = run_cli(["calibrate", str(folder), "--method", "multi", "--board", "10x6", "--square", "24",
                            "-o", tmp_path / "c.json"])
    assert code == 2 and "a multi-pose calibration needs at least two pose folders" in err
