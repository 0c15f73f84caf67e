"""Every solver reports its uncertainty under the names procam.parameters declares (the one vocabulary)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from procam import multi_pose, simulate
from procam import single_pose as sp
from procam.calibration import Calibration, Device
from procam.parameters import PARAMETERS
from procam.view import View

POSES = [(15, 12, 0), (-10, 20, 5), (20, -15, -5)]


def _view(pose, seed=0, preset="ideal"):
    scene = simulate.with_board_pose(simulate.preset(preset), pose)
    obj, cam, proj = simulate.correspondences(scene, 0.05, 0.1, seed=seed)
    return scene, View(obj, cam, proj, f"p{seed}", scene.cam_size, scene.proj_size)


def _declared(calib: Calibration, *, empty: bool = False):
    assert bool(calib.std) != empty, calib.method
    undeclared = set(calib.std) - set(PARAMETERS)
    assert not undeclared, (calib.method, sorted(undeclared))


def test_every_solver_reports_only_declared_parameters():
    scene, view = _view(POSES[0])
    views = [_view(p, seed=k)[1] for k, p in enumerate(POSES)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")          # the verdicts' warnings are not what this test is about
        results = [
            sp.calibrate(view),
            sp.calibrate_camera_only(view.obj_pts, view.cam_pts, scene.cam_size),
            sp.calibrate(view, known_camera=simulate.truth_calibration(scene).camera),
            multi_pose.calibrate(views),
            multi_pose.calibrate_camera(views, dist="k1k2"),
        ]
        unrefined = multi_pose.calibrate(views, refine=False)
    for calib in results:
        _declared(calib)
    _declared(unrefined, empty=True)        # no joint refinement, no covariance: no std at all


def test_background_refinement_reports_only_declared_parameters():
    from test_background import standin

    _, view, _ = standin("paper", (25, 20, 5))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        calib = sp.calibrate(view, background=sp.background.BackgroundOptions(free=("u0p", "alpha_p")))
    assert calib.info["background_model"] != "single-pose"
    assert {"u0p", "alpha_p"} <= set(calib.std)
    _declared(calib)


def test_an_undeclared_name_is_refused():
    dev = Device(np.eye(3), (10, 10))
    with pytest.raises(ValueError, match="not declared in procam.parameters: focal"):
        Calibration(dev, None, None, None, "camera-only", std={"f_c": 1.0, "focal": 2.0})
