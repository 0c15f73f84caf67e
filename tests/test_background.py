"""The background behind the board: the check of the single-pose projector model and its refinement.

Most tests use a faithful stand-in for a rendered capture that is ~20x faster: the simulator's board
corners plus Gaussian noise of the size rendered corners have (0.05 px camera, 0.08 px projector;
``benchmarks/background.py`` measures the renders), and for the background the EXACT projector
coordinates of the simulator's wall at every camera pixel (hidden by the board and in its shadow left
out), rounded to whole projector pixels as the decoder returns them. The rounding is the decoding's
noise on a wall (uniform, 0.29 px per axis; the renders' wall decodes with 0.25-0.3 px). A rendered
capture of each rig (the session's ``paper_capture`` / ``ideal_capture``) checks the whole pipeline.

The paper rig has u0p = 1013, alpha_p = 1.002 (the single-pose assumptions u0p = W/2 = 960, alpha_p = 1
are wrong); the ideal rig satisfies them.
"""

from __future__ import annotations

import numpy as np
import pytest

from procam.single_pose import background as bg
from procam import correspond, patterns, pipeline, simulate
from procam import single_pose as sp
from procam.board import Board
from procam.errors import ModelErrorWarning
from procam.decode import DecodeResult
from procam.view import Background, View
from conftest import expect_warning, verdict_warnings

OFF = bg.BackgroundOptions(mode="off")


def _calibrate(view, **kw):
    """:func:`procam.single_pose.calibrate`, its verdict warnings recorded (the result's ``warnings`` and verdict
    carry them: these tests check those)."""
    with verdict_warnings():
        return sp.calibrate(view, **kw)


def wall_maps(scene) -> DecodeResult:
    """Decoded maps of the wall behind the board: exact projector coordinates, rounded; NaN elsewhere."""
    W, H = scene.cam_size
    xs, ys = np.meshgrid(np.arange(W, dtype=float), np.arange(H, dtype=float))
    pix = np.column_stack([xs.ravel(), ys.ravel()])
    und = simulate.undistort(scene, pix)
    K = np.asarray(scene.K_cam)
    ray = np.column_stack([(und[:, 0] - K[0, 2]) / K[0, 0], (und[:, 1] - K[1, 2]) / K[1, 1], np.ones(len(und))])
    Rb, tb = np.asarray(scene.R_board), np.asarray(scene.t_board)
    nw = np.asarray(scene.wall_normal)
    pw = tb + scene.wall_offset * np.array([0.0, 0.0, 1.0])
    x0, x1, y0, y1 = simulate.board_extent(scene)

    def on_board(P):
        b = (P - tb) @ Rb
        return (b[:, 0] >= x0) & (b[:, 0] <= x1) & (b[:, 1] >= y0) & (b[:, 1] <= y1)

    with np.errstate(all="ignore"):
        X = ray * ((nw @ pw) / (ray @ nw))[:, None]
        nb = Rb[:, 2]
        Xb = ray * ((nb @ tb) / (ray @ nb))[:, None]
        hidden = on_board(Xb) & (Xb[:, 2] < X[:, 2])
        L = np.asarray(scene.proj_center_cam) - X
        u = (nb @ tb - X @ nb) / (L @ nb)
        shadow = (u > 0) & (u < 1) & on_board(X + u[:, None] * L)
        Xp = X @ np.asarray(scene.R).T + np.asarray(scene.T)
        p = simulate.project(scene.K_proj, Xp)
    Wp, Hp = scene.proj_size
    ok = ~hidden & ~shadow & (Xp[:, 2] > 0) & (p[:, 0] >= 0) & (p[:, 0] <= Wp - 1) & (p[:, 1] >= 0) & (p[:, 1] <= Hp - 1)
    col = np.full(H * W, np.nan, np.float32)
    row = col.copy()
    col[ok], row[ok] = np.round(p[ok, 0]), np.round(p[ok, 1])
    col, row = col.reshape(H, W), row.reshape(H, W)
    v = np.isfinite(col)
    z = np.zeros((H, W), np.uint8)
    return DecodeResult(col, row, v, v.copy(), z, z.copy(), np.ones((H, W), np.float32), None, None,
                        patterns.pattern_set(Wp, Hp), z.copy(), z.copy())


def standin(preset, pose, seed=0):
    """(scene, view with background, the paper's single-pose calibration without the background)."""
    scene = simulate.with_board_pose(simulate.preset(preset), pose)
    obj, cam, proj = simulate.correspondences(scene, 0.05, 0.08, seed=seed)
    back = Background(*correspond.background_points(wall_maps(scene), cam))
    view = View(obj, cam, proj, f"{preset}{pose}", scene.cam_size, scene.proj_size, background=back)
    return scene, view, _calibrate(view, background=OFF)


# poses (camera frame) where the paper rig's error is visible in the background, and others for the ideal rig
PAPER_POSES = [(25, 20, 5), (-20, -10, 0), (20, 25, 0)]
IDEAL_POSES = [(15, 12, 0), (-10, 20, 5), (5, 25, 10)]


@pytest.fixture(scope="module")
def paper_standins():
    return {pose: standin("paper", pose, seed=k) for k, pose in enumerate(PAPER_POSES)}


@pytest.fixture(scope="module")
def ideal_standins():
    return {pose: standin("ideal", pose, seed=k) for k, pose in enumerate(IDEAL_POSES)}


def _check(view, cal, cam=None, proj=None, **kw):
    b = view.background
    return bg.epipolar_check(cal, b.cam_pts if cam is None else cam, b.proj_pts if proj is None else proj,
                             bg.BackgroundOptions(**kw))


# ------------------------------------------------------------------------------------------------
# the points
# ------------------------------------------------------------------------------------------------

def test_background_points_are_off_the_board_and_decode_the_wall():
    from sim_small import small_capture

    scene, stack, truth, maps = small_capture()
    corners = np.asarray(truth["corners"]["camera_distorted"], float)
    cam, proj = correspond.background_points(maps, corners, max_points=1500)
    assert 500 < len(cam) <= 1600 and cam.shape == proj.shape == (len(cam), 2)
    assert np.all(np.isfinite(cam)) and np.all(np.isfinite(proj))
    # none inside the board: every point is farther from the corners' hull than one square
    import cv2

    hull = cv2.convexHull(corners.astype(np.float32))
    inside = [cv2.pointPolygonTest(hull, (float(x), float(y)), True) for x, y in cam]
    assert max(inside) < -20
    # the decoded projector coordinates are the wall's (exact geometry, rounded)
    exact = wall_maps(scene)
    ix, iy = cam[:, 0].astype(int), cam[:, 1].astype(int)
    truth_pts = np.column_stack([exact.col[iy, ix], exact.row[iy, ix]])
    ok = np.isfinite(truth_pts).all(1)
    assert ok.mean() > 0.9
    d = np.linalg.norm(proj[ok] - truth_pts[ok], axis=1)
    assert np.median(d) < 1.0 and np.mean(d < 3) > 0.97
    # pipeline: the view carries them (or not)
    ps = patterns.pattern_set(*scene.proj_size, "opencv")
    board = Board(scene.board_cols, scene.board_rows, scene.square)
    view, _ = pipeline.view_from_stack(stack, ps, board)
    # the view carries window samples (procam.correspond.samples), of the wall and of the board
    assert view.background is not None and len(view.background) > 200 and view.background.window > 1
    assert view.board_samples is not None and len(view.board_samples) > 200
    assert view.subset(view.valid).background is view.background
    view, _ = pipeline.view_from_stack(stack, ps, board, options=pipeline.PoseOptions(background=False))
    assert view.background is None


def test_background_points_without_corners_or_background():
    from sim_small import small_capture

    _, _, _, maps = small_capture()
    cam, proj = correspond.background_points(maps, np.full((60, 2), np.nan))
    assert cam.shape == proj.shape == (0, 2)
    big = np.array([[-5.0, -5.0], [700.0, -5.0], [700.0, 500.0], [-5.0, 500.0]])
    cam, _ = correspond.background_points(maps, big)
    assert len(cam) == 0


def test_epipolar_distances_vanish_for_the_true_calibration():
    from procam.simulate import truth_calibration

    scene = simulate.preset("paper")
    maps = wall_maps(scene)
    cam, _ = correspond.background_points(maps, simulate.corner_truth(scene)["camera_distorted"])
    # exact (unrounded) projector points of those pixels
    exact = np.column_stack([maps.col[cam[:, 1].astype(int), cam[:, 0].astype(int)],
                             maps.row[cam[:, 1].astype(int), cam[:, 0].astype(int)]])
    d = bg.epipolar_distances(truth_calibration(scene), cam, exact)
    assert np.all(np.abs(d) <= 0.75)             # rounding only (<= 0.5 sqrt 2)
    assert abs(np.median(d)) < 0.02


# ------------------------------------------------------------------------------------------------
# the check
# ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("pose", PAPER_POSES)
def test_check_fires_on_the_paper_rig(paper_standins, pose):
    _, view, cal = paper_standins[pose]
    c = _check(view, cal)
    assert c.status == "model error" and c.model_error, c.message
    assert c.statistic > 2 * c.threshold
    assert c.message.startswith("model error") and "u0p = W/2 = 960 px" in c.message and " px" in c.message
    assert c.size_px > 5 and c.noise_px < 0.5 and c.inlier_fraction > 0.95
    # the background puts u0p near the truth (1013) and far from the assumption
    u0, s = c.estimate["u0p"], c.estimate_std["u0p"]
    assert abs(u0 - 1013.0) < 4 * s and abs(u0 - 960.0) > 3 * s


@pytest.mark.parametrize("pose", IDEAL_POSES)
def test_check_is_silent_on_the_ideal_rig(ideal_standins, pose):
    _, view, cal = ideal_standins[pose]
    c = _check(view, cal)
    assert c.status == "consistent" and not c.model_error, c.message
    assert c.statistic < 0.5 * c.threshold
    assert abs(c.estimate["u0p"] - 960.0) < 4 * c.estimate_std["u0p"]


@pytest.mark.parametrize("pose", PAPER_POSES)
def test_refined_projector_against_the_truth(paper_standins, pose):
    scene, view, cal = paper_standins[pose]
    fit, check = bg.refine_projector(cal, view.background.cam_pts, view.background.proj_pts)
    assert fit is not None and check.status == "model error"
    K = fit.calibration.projector.K
    f_true, u0_true = scene.K_proj[0, 0], scene.K_proj[0, 2]
    assert abs(K[0, 0] - f_true) < 4 * fit.std["f_p"] + 5
    assert abs(K[0, 2] - u0_true) < 4 * fit.std["u0p"] + 2
    # far better than the paper's assumption, whose f_p is off by 50-700 px here
    assert abs(K[0, 0] - f_true) < 0.5 * abs(cal.projector.K[0, 0] - f_true)
    # the std of the result covers the camera's uncertainty: wider than the paper's conditional one
    assert fit.std["f_p"] > cal.std["f_p"]
    assert fit.calibration.std["u0p"] == pytest.approx(fit.std["u0p"])


def test_alpha_p_freed_with_care(paper_standins):
    """alpha_p (truth 1.002) is freed only when it improves the fit significantly; its estimate is honest."""
    scene, view, cal = paper_standins[(-20, -10, 0)]
    c = _check(view, cal, free=("u0p", "alpha_p"))
    assert c.model_error and set(c.fits) == {"assumed", "u0p", "u0p+alpha_p"}
    assert c.selected in ("u0p", "u0p+alpha_p") and c.dof == 2
    a, s = c.estimate["alpha_p"], c.estimate_std["alpha_p"]
    assert abs(a - 1.002) < 4 * s and s < 0.01
    fit = c.fits["u0p+alpha_p"]
    K = fit.calibration.projector.K
    assert abs(K[0, 0] - scene.K_proj[0, 0]) < 4 * fit.std["f_p"] + 5
    assert fit.calibration.std["alpha_p"] == pytest.approx(s)


# ------------------------------------------------------------------------------------------------
# no check, never a false alarm
# ------------------------------------------------------------------------------------------------

def test_flat_or_empty_background_is_no_check_and_keeps_the_paper_result(paper_standins):
    _, view, cal = paper_standins[PAPER_POSES[0]]
    cam = view.background.cam_pts
    # the same pixels, but on the board's plane (e.g. a table flush with the board): no parallax
    H = bg._plane_homography(cal.camera.K, cal.info["camera"].R, cal.info["camera"].t, cal.projector.K, cal.R, cal.T)
    from procam import models

    flat = np.round(models.apply_homography(H, cal.camera.undistort(cam)))
    c = _check(view, cal, cam, flat)
    assert c.status == "no check" and not c.model_error and "flat" in c.reason
    out = bg.apply(cal, cam, flat)
    np.testing.assert_array_equal(out.projector.K, cal.projector.K)
    assert out.info["background_model"] == "single-pose" and out.warnings == cal.warnings
    # too few points
    c = _check(view, cal, cam[:50], view.background.proj_pts[:50])
    assert c.status == "no check" and "too small" in c.reason
    c = _check(view, cal, np.zeros((0, 2)), np.zeros((0, 2)))
    assert c.status == "no check" and "no decoded background" in c.reason


def _corruptions(cam, proj, rng):
    n = len(cam)
    p = proj.copy()
    m = rng.random(n) < 0.3                                     # 30 % wrong codes anywhere
    p[m] = rng.uniform([0, 0], [1919, 1079], (int(m.sum()), 2))
    yield "30% random codes", cam, p
    p = proj.copy()                                             # interreflection: a region whose bits flip
    d = np.linalg.norm(cam - cam[rng.integers(n)], axis=1)
    i = np.nonzero(d < np.percentile(d, 30))[0]
    axis = rng.integers(0, 2, len(i))
    p[i, axis] += rng.choice([-1, 1], len(i)) * 2.0 ** rng.integers(4, 10, len(i))
    yield "a region with flipped bits", cam, p
    m = cam[:, 0] > np.median(cam[:, 0])                        # half the background unlit
    yield "left half unlit", cam[m], proj[m]
    m = cam[:, 1] > np.median(cam[:, 1])
    yield "top half unlit", cam[m], proj[m]


@pytest.mark.parametrize("pose", [IDEAL_POSES[0], pytest.param(IDEAL_POSES[1], marks=pytest.mark.slow)])
def test_no_false_alarm_with_interreflections_or_half_the_background_unlit(ideal_standins, pose):
    _, view, cal = ideal_standins[pose]
    rng = np.random.default_rng(7)
    for what, cam, proj in _corruptions(view.background.cam_pts, view.background.proj_pts, rng):
        c = _check(view, cal, cam, proj)
        assert not c.model_error, (what, c.message)


def test_corrupted_background_still_reveals_the_paper_rig(paper_standins):
    _, view, cal = paper_standins[(-20, -10, 0)]
    rng = np.random.default_rng(8)
    for what, cam, proj in _corruptions(view.background.cam_pts, view.background.proj_pts, rng):
        c = _check(view, cal, cam, proj)
        assert c.model_error, (what, c.message)
        assert abs(c.estimate["u0p"] - 1013.0) < 4 * c.estimate_std["u0p"], what


def test_a_background_that_follows_no_single_geometry_is_no_check(ideal_standins):
    """A coherent shift of part of the background (a reflective surface, say) is not a model error."""
    _, view, cal = ideal_standins[IDEAL_POSES[0]]
    cam, proj = view.background.cam_pts, view.background.proj_pts.copy()
    left = cam[:, 0] < np.percentile(cam[:, 0], 40)
    proj[left] += [0.0, 4.0]
    c = _check(view, cal, cam, proj)
    assert not c.model_error
    assert c.status == "no check" and "do not fit one epipolar geometry" in c.reason


# ------------------------------------------------------------------------------------------------
# single_pose.calibrate and options
# ------------------------------------------------------------------------------------------------

def test_calibrate_applies_the_background_only_when_the_view_has_one(paper_standins):
    scene, view, base = paper_standins[PAPER_POSES[0]]
    plain = _calibrate(View(view.obj_pts, view.cam_pts, view.proj_pts, view.name, view.cam_size, view.proj_size))
    np.testing.assert_array_equal(plain.projector.K, base.projector.K)
    assert "background" not in plain.info
    checked = _calibrate(view, background=bg.BackgroundOptions(mode="check"))
    np.testing.assert_array_equal(checked.projector.K, base.projector.K)
    assert checked.info["background"].model_error and checked.info["background_model"] == "single-pose"
    assert any(w.startswith("model error") for w in checked.warnings)
    assert checked.poses[0]["background"]["status"] == "model error"
    # kept assumptions that the background refutes: the verdict says so (a weak pose at best)
    assert checked.verdict != "good" and any("model error" in r for r in checked.verdict_reasons)
    auto = _calibrate(view)
    assert auto.info["background_model"] == "u0p" and auto.info["background"].model_error
    assert abs(auto.projector.K[0, 2] - auto.projector.image_size[0] / 2) > 20
    assert "refined with u0p" in auto.warnings[-1]
    assert abs(auto.projector.K[0, 0] - scene.K_proj[0, 0]) < abs(base.projector.K[0, 0] - scene.K_proj[0, 0])
    assert {"u0p", "f_p", "v0p", "f_c", "T"} <= set(auto.std)


def test_calibrate_on_the_ideal_rig(ideal_standins):
    scene, view, base = ideal_standins[IDEAL_POSES[0]]
    cal = _calibrate(view)            # default: the assumptions lifted, and found right
    assert cal.info["background"].status == "consistent" and cal.info["background_model"] == "u0p"
    assert abs(cal.projector.K[0, 2] - 960.0) < 4 * cal.std["u0p"]
    assert not any("model error" in w for w in cal.warnings)
    auto = _calibrate(view, background=bg.BackgroundOptions(mode="auto"))   # consistent: kept, with the background
    assert auto.info["background_model"] == "assumed" and auto.projector.K[0, 2] == 960.0
    # the background pins the camera's weakest parameter too
    f_c = scene.K_cam[0, 0]
    assert abs(auto.camera.K[0, 0] - f_c) < abs(base.camera.K[0, 0] - f_c)
    assert abs(auto.camera.K[0, 0] - f_c) < 4 * auto.std["f_c"]


@pytest.mark.parametrize("kw", [{"mode": "always"}, {"free": ("f_p",)}, {"free": ()}, {"false_alarm": float("nan")},
                                {"false_alarm": 0.0}, {"min_points": 3}, {"outlier_k": -1.0},
                                {"alpha_prior_std": float("inf")}])
def test_options_are_checked(kw):
    with pytest.raises(ValueError):
        bg.BackgroundOptions(**kw)


def test_no_check_for_a_calibration_that_is_not_single_pose(paper_standins):
    _, view, cal = paper_standins[PAPER_POSES[0]]
    c = _check(view, cal.replace(info={}))
    assert c.status == "no check" and "single-pose" in c.reason


# ------------------------------------------------------------------------------------------------
# rendered captures, end to end
# ------------------------------------------------------------------------------------------------

def test_rendered_captures_end_to_end(paper_capture, ideal_capture):
    board = Board(10, 6, 24.0)
    folder, _, truth, _ = paper_capture
    view, _ = pipeline.view_from_folder(folder, board)
    cal = _calibrate(view, dense=None)           # the paper's projector, checked against the background
    c = cal.info["background"]
    assert c.model_error and any(w.startswith("model error") for w in cal.warnings)
    f_true = truth["projector"]["f"]
    assert abs(cal.projector.K[0, 0] - f_true) < 4 * cal.std["f_p"] + 5
    assert abs(cal.projector.K[0, 2] - truth["projector"]["u0"]) < 4 * cal.std["u0p"] + 2
    folder, _, truth, _ = ideal_capture
    view, _ = pipeline.view_from_folder(folder, board)
    cal = _calibrate(view, dense=None)
    assert cal.info["background"].status == "consistent"
    assert not any("model error" in w for w in cal.warnings)


@pytest.mark.parametrize("model", ["division", "opencv"])
def test_known_camera_with_the_background(paper_standins, model):
    """Camera intrinsics given (any distortion model): the background lifts u0p with the camera held fixed."""
    from procam import distortion
    from procam.calibration import Device, Distortion

    scene, view, _ = paper_standins[PAPER_POSES[0]]
    K = np.array(scene.K_cam, float)
    if model == "division":
        dist = Distortion("division", tuple(scene.cam_center), *scene.cam_dist_coeffs)
    else:
        fit = distortion.opencv_from_division(K, scene.cam_center, *scene.cam_dist_coeffs, scene.cam_size)
        dist = Distortion("opencv", coeffs=tuple(float(c) for c in fit[0]))
    dev = Device(K, scene.cam_size, dist)
    with expect_warning(ModelErrorWarning):
        kept = sp.calibrate(view, known_camera=dev, background=bg.BackgroundOptions(mode="check"))
    lifted = _calibrate(view, known_camera=dev)
    assert kept.info["background"].model_error and lifted.info["background_model"].startswith("u0p")
    assert lifted.camera is dev and np.array_equal(lifted.camera.K, K)
    f_true, u0_true = scene.K_proj[0, 0], scene.K_proj[0, 2]
    Kp = lifted.projector.K
    assert abs(Kp[0, 2] - u0_true) < 4 * lifted.std["u0p"] + 2
    assert abs(Kp[0, 0] - f_true) < 4 * lifted.std["f_p"] + 3
    assert abs(Kp[0, 0] - f_true) < 0.5 * abs(kept.projector.K[0, 0] - f_true)


def test_every_output_says_what_the_background_estimated(paper_standins):
    """When the background lifts u0p, the report, the JSON and the check line say it was estimated (with its
    value and std), not the paper's 'u0p = W/2 is ASSUMED'; when the assumption is kept, they say that."""
    import warnings

    from procam import io, report, summary
    from procam.errors import ProcamWarning

    _, view, _ = paper_standins[PAPER_POSES[0]]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ProcamWarning)
        lifted = _calibrate(view)
        kept = _calibrate(view, background=bg.BackgroundOptions(mode="check"))
    assert lifted.info["background_model"].startswith("u0p")
    assert kept.info["background_model"] in ("single-pose", "assumed")
    u0, s = lifted.projector.K[0, 2], lifted.std["u0p"]
    words = summary.projector_assumptions(lifted)
    assert words[0] == f"u0p = {u0:.1f} ± {s:.1f} px is ESTIMATED from the background behind the board"
    assert io.calibration_to_dict(lifted)["assumptions"] == words
    page = report.build_report(lifted, name="lifted.json")
    assert "ESTIMATED from the background" in page and "(from the background)" in page
    assert "is ASSUMED, not estimated" not in page and "(assumed W/2)" not in page
    W = kept.projector.image_size[0]
    assert summary.projector_assumptions(kept)[0] == f"u0p = W/2 = {W / 2:g} px is ASSUMED, not estimated"
    page = report.build_report(kept, name="kept.json")
    assert "(assumed W/2)" in page and "ESTIMATED from the background" not in page
