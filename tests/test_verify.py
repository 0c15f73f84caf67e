"""Triangulation and the metric verification against the simulator's ground truth."""

import functools

import cv2
import numpy as np
import pytest

from procam import simulate
from procam.calibration import Device, Distortion
from procam.errors import CalibrationError
from procam.triangulate import midpoint, rays, triangulate_points
from procam.verify import adjacent_pairs, leave_one_out, single_pose_cross, verify, verify_pose
from procam.simulate import truth_calibration
from procam.view import View
from conftest import verdict_warnings

POSES = [(15, 12, 0), (-10, 20, 5), (20, -15, -5), (5, 25, 10), (-20, -10, 0)]


@functools.lru_cache(maxsize=None)
def _scenes(preset="paper"):
    sc = simulate.preset(preset)
    return sc, tuple(simulate.with_board_pose(sc, p) for p in POSES)


def _views(sigma=0.1, seed=0, preset="paper", n=len(POSES)):
    _, scenes = _scenes(preset)
    out = []
    for k, s in enumerate(scenes[:n]):
        obj, cam, proj = simulate.correspondences(s, sigma_cam=sigma, sigma_proj=2 * sigma, seed=100 * seed + k)
        out.append(View(obj, cam, proj, f"p{k}", s.cam_size, s.proj_size))
    return out


def _fp_off(calib, factor=1.02):
    K = np.array(calib.projector.K, float)
    K[0, 0] *= factor
    K[1, 1] *= factor
    return calib.replace(projector=Device(K, calib.projector.image_size, calib.projector.distortion))


# ---------------------------------------------------------------------------------------------------
# triangulation
# ---------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("refine", [False, True])
def test_triangulate_points_exact_on_true_corners(refine):
    sc = _scenes()[1][1]
    calib = truth_calibration(sc)
    c = simulate.corner_truth(sc)
    X_true = c["board"] @ sc.R_board.T + sc.t_board
    X, rc, rp = triangulate_points(calib, c["camera_distorted"], c["projector"], refine=refine)
    assert np.abs(X - X_true).max() < 1e-8
    assert np.abs(rc).max() < 1e-8 and np.abs(rp).max() < 1e-8


def test_triangulate_points_with_projector_distortion_and_nan_rows():
    sc = _scenes()[1][2]
    base = truth_calibration(sc)
    proj = Device(base.projector.K, base.projector.image_size, Distortion("opencv", coeffs=(0.05, -0.02, 1e-3, 0, 0)))
    calib = base.replace(projector=proj)
    c = simulate.corner_truth(sc)
    X_true = c["board"] @ sc.R_board.T + sc.t_board
    proj_pts = proj.project(sc.R, sc.T, X_true)            # distorted projector pixels
    cam = c["camera_distorted"].copy()
    cam[3] = np.nan
    X, rc, rp = triangulate_points(calib, cam, proj_pts)
    ok = np.arange(len(X)) != 3
    assert np.isnan(X[3]).all() and np.isnan(rc[3]).all()
    assert np.abs(X[ok] - X_true[ok]).max() < 1e-7
    assert np.abs(rp[ok]).max() < 1e-7


def test_refinement_lowers_the_reprojection_error_of_noisy_points():
    sc = _scenes()[1][0]
    calib = truth_calibration(sc)
    _, cam, proj = simulate.correspondences(sc, sigma_cam=0.2, sigma_proj=0.4, seed=5)
    _, rc0, rp0 = triangulate_points(calib, cam, proj, refine=False)
    _, rc1, rp1 = triangulate_points(calib, cam, proj, refine=True)
    e0 = np.sum(rc0 ** 2) + np.sum(rp0 ** 2)
    e1 = np.sum(rc1 ** 2) + np.sum(rp1 ** 2)
    assert e1 < e0


def test_rays_and_midpoint_conventions():
    K = np.array([[1000.0, 0, 320], [0, 1000, 240], [0, 0, 1]])
    dev = Device(K, (640, 480))
    r = rays(dev, [[320, 240], [1320, 240]])
    np.testing.assert_allclose(r, [[0, 0, 1], [1, 0, 1]])
    # two rays meeting at (0, 0, 500): camera at origin, projector 100 to the right
    R, T = np.eye(3), np.array([-100.0, 0, 0])
    X = midpoint(np.array([[0, 0, 1.0]]), np.array([[-100 / 500, 0, 1.0]]), R, T)
    np.testing.assert_allclose(X, [[0, 0, 500]], atol=1e-9)


# ---------------------------------------------------------------------------------------------------
# verification
# ---------------------------------------------------------------------------------------------------

def test_adjacent_pairs_of_a_board_and_a_subset():
    from procam.board import object_points

    obj = object_points(10, 6, 24.0)
    pairs, s = adjacent_pairs(obj)
    assert s == pytest.approx(24.0)
    assert len(pairs) == 9 * 6 + 10 * 5
    keep = np.ones(len(obj), bool)
    keep[11] = False                      # an inner corner: 4 pairs lost
    assert len(adjacent_pairs(obj[keep])[0]) == len(pairs) - 4


def test_correct_calibration_noise_free_is_exact():
    ver = verify(truth_calibration(_scenes()[0]), _views(sigma=0.0))
    o = ver.overall
    assert o.n_pairs == 5 * 104 and o.square == pytest.approx(24.0)
    assert abs(o.scale_error_pct) < 1e-9 and o.planarity_rms < 1e-9 and o.rigid_rms < 1e-9


def test_correct_calibration_scale_zero_planarity_at_noise_level():
    calib = truth_calibration(_scenes()[0])
    v1 = verify(calib, _views(sigma=0.1)).overall
    v2 = verify(calib, _views(sigma=0.2)).overall
    assert abs(v1.scale_error_pct) < 0.05                 # of 520 pairs of 24 mm
    assert v1.planarity_rms < 0.3                        # mm, at ~500-700 mm
    # it is noise: twice the corner noise, twice the planarity and spacing errors (same seeds)
    assert 1.7 < v2.planarity_rms / v1.planarity_rms < 2.3
    assert 1.7 < v2.spacing_rms / v1.spacing_rms < 2.3
    assert v1.reproj_rms < 0.2


def test_projector_focal_length_two_percent_off_is_visible():
    calib = truth_calibration(_scenes()[0])
    views = _views(sigma=0.1)
    good = verify(calib, views).overall
    bad = verify(_fp_off(calib, 1.02), views).overall
    assert bad.scale_error_pct > 0.8 > 20 * abs(good.scale_error_pct)
    assert bad.planarity_rms > 1.2 * good.planarity_rms
    assert bad.rigid_rms > 5 * good.rigid_rms
    # noise-free: the board is bent, not only scaled
    nf = verify(_fp_off(calib, 1.02), _views(sigma=0.0)).overall
    assert nf.planarity_rms > 0.1


def test_projector_focal_length_off_with_refitted_extrinsics_is_visible():
    """The harder case: R, T refitted with f_p 2 % off (the reprojection error stays sub-pixel)."""
    calib = truth_calibration(_scenes()[0])
    views = _views(sigma=0.1)
    Kp = np.array(calib.projector.K, float)
    Kp[0, 0] *= 1.02
    Kp[1, 1] *= 1.02
    objs = [v.obj_pts.astype(np.float32) for v in views]
    cams = [calib.camera.undistort(v.cam_pts).astype(np.float32) for v in views]
    projs = [v.proj_pts.astype(np.float32) for v in views]
    rms, *_, R, T, _, _ = cv2.stereoCalibrate(objs, cams, projs, np.array(calib.camera.K), None, Kp, None,
                                              calib.camera.image_size, flags=cv2.CALIB_FIX_INTRINSIC)
    assert rms < 0.6
    wrong = calib.replace(projector=Device(Kp, calib.projector.image_size), R=R, T=T.ravel())
    good = verify(calib, views).overall
    bad = verify(wrong, views).overall
    assert bad.rigid_rms > 1.5 * good.rigid_rms
    assert abs(bad.scale_error_pct) > 3 * abs(good.scale_error_pct)


def test_leave_one_out_is_worse_than_in_sample_by_a_plausible_margin():
    views = _views(sigma=0.1, seed=1)
    cv = leave_one_out(views)
    assert cv.kind == "leave-one-out" and not cv.failures
    assert [p.name for p in cv.held_out.poses] == [v.name for v in views]
    ins, out = cv.in_sample, cv.held_out
    worse = [h.rigid_rms >= i.rigid_rms for i, h in zip(ins.poses, out.poses)]
    assert np.mean(worse) >= 0.8
    ratio = out.overall.rigid_rms / ins.overall.rigid_rms
    assert 1.0 < ratio < 1.5
    # and the held-out figure is what the true calibration achieves on the same corners
    truth = verify(truth_calibration(_scenes()[0]), views).overall
    assert out.overall.rigid_rms == pytest.approx(truth.rigid_rms, rel=0.3)
    assert abs(out.overall.scale_error_pct) < 0.1


def test_the_leave_one_out_refits_start_from_the_solution_and_land_where_calibrations_from_scratch_do():
    """Issue 35: each refit is the joint refinement of the other poses from the full solution (no per-device
    calibrations, no stereo step, no pose-set judgment). It lands where the calibration of the other poses from
    scratch does, to a small fraction of each parameter's ± (only the projector's weight differs: the full
    fit's, not estimated again from the other poses)."""
    import warnings

    from procam import multi_pose
    from procam.errors import ProcamWarning
    from procam.multi_pose.evidence import PARAMS, _params

    views = _views(sigma=0.1, seed=2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ProcamWarning)
        full = multi_pose.calibrate(views)
        refits = full.info["leave_one_out_refits"]
        assert len(refits) == len(views)
        spread = full.info["leave_one_out"]["spread"]
        for i, refit in enumerate(refits):
            assert refit.info["warm_start"] and "frozen" not in refit.info and "pose_set" not in refit.info
            assert refit.info["refinement"]["proj_weight"] == full.info["refinement"]["proj_weight"]
            cold = multi_pose.calibrate(views[:i] + views[i + 1:], cam_dist=full.info["cam_dist_model"],
                                        proj_dist=full.info["proj_dist_model"], leave_one_out=False)
            assert [v.name for v in refit.views] == [v.name for v in cold.views]
            warm, scratch = _params(refit), _params(cold)
            for k in PARAMS:
                value, fit_std, jack = spread[k]
                assert abs(warm[k] - scratch[k]) < 0.25 * fit_std, k  # measured: under 0.06 of it
                assert abs(warm[k] - value) < 5 * fit_std, k          # and a refit moves, by about its ±


def test_a_warm_refit_that_diverges_or_leaves_a_parameter_free_gives_way_to_one_from_scratch():
    """refit_each takes the warm-started refit only where it converged and its own ± fixes every judged parameter
    within 2 % of its scale; a refit that raised, or one whose ± is wider, is replaced by the calibration of the other
    poses from scratch (the same bits as calling it)."""
    import warnings

    from procam import multi_pose
    from procam.errors import ProcamWarning
    from procam.multi_pose import evidence

    views = _views(sigma=0.1, seed=2)
    options = dict(cam_dist="k1k2p1p2k3", proj_dist="k1k2p1p2k3", leave_one_out=False, judge_pose_set=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ProcamWarning)
        full = multi_pose.calibrate(views, leave_one_out=False)
        cold = [multi_pose.calibrate(views[:i] + views[i + 1:], **options) for i in range(len(views))]

        def warm(i):
            if i == 0:
                raise CalibrationError("diverged")
            refit = multi_pose.refit_without(full, i)
            if i == 1:  # as a refit whose ± leaves f_c free would say
                refit = refit.replace(std={**refit.std, "f_c": 0.05 * refit.camera.K[0, 0]})
            return refit

        refits = evidence.refit_each(views, multi_pose.calibrate, warm, **options)
    assert [bool(r.info.get("warm_start")) for r in refits] == [False, False, True, True, True]
    for i in (0, 1):
        assert np.array_equal(refits[i].camera.K, cold[i].camera.K) and np.array_equal(refits[i].T, cold[i].T)
    assert evidence.determined(refits[2]) and not evidence.determined(warm(1))


def test_leave_one_out_needs_four_poses():
    with pytest.raises(CalibrationError, match="at least 4 poses"):
        leave_one_out(_views(n=3))


def test_single_pose_cross_verification():
    views = _views(sigma=0.1, preset="ideal", n=2)
    with verdict_warnings():            # each pose's own verdict is not this test's subject
        cv = single_pose_cross(views)
    assert cv.kind == "single-pose-cross"
    assert [p.name for p in cv.in_sample.poses] == ["p0", "p1"]
    assert [p.name for p in cv.held_out.poses] == ["p1 <- p0", "p0 <- p1"]
    assert cv.held_out.overall.rigid_rms > cv.in_sample.overall.rigid_rms


def test_verify_errors():
    calib = truth_calibration(_scenes()[0])
    v = _views(n=1)[0]
    few = v.subset(np.arange(len(v.valid)) < 4)
    with pytest.raises(CalibrationError, match="only 4 corners"):
        verify_pose(calib, few)
    with pytest.raises(CalibrationError, match="at least one pose"):
        verify(calib, [])
    with pytest.raises(CalibrationError, match="no projector"):
        verify(calib.replace(projector=None, R=None, T=None), [v])


def test_verification_tables_render():
    from rich.console import Console

    from procam.cli._show import cross_table, verification_table

    views = _views(sigma=0.1, n=4)
    cv = leave_one_out(views)
    con = Console(record=True, width=200)
    con.print(verification_table(cv.in_sample))
    con.print(cross_table(cv))
    text = con.export_text()
    assert "scale error (%)" in text and "leave-one-pose-out" in text and "all" in text
    d = cv.to_dict()
    assert d["held_out"]["overall"]["n_pairs"] == 4 * 104
