"""Single-pose calibration with the camera's intrinsics known (issue 16 §2): the projector and R, T only,
against the Cramer-Rao bound of that case and against the single-pose calibration without them."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from conftest import run_cli

from procam import crlb, io, multi_pose, simulate, single_pose
from procam.calibration import Calibration, Device, Distortion
from procam.errors import CalibrationError, ProcamWarning
from procam.view import View


@pytest.fixture(scope="module")
def rig():
    sc = simulate.with_board_pose(simulate.preset("ideal"), simulate.RECOMMENDED_POSE)
    dev = Device(np.array(sc.K_cam), sc.cam_size, Distortion("division", tuple(sc.cam_center), *sc.cam_dist_coeffs))
    return sc, dev


def _calibrations(sc, dev, trials):
    known, free = [], []
    for s in range(trials):
        o, c, p = simulate.correspondences(sc, 0.1, 0.2, 1000 + s)
        v = View(o, c, p, "s", sc.cam_size, sc.proj_size)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ProcamWarning)
            known.append(single_pose.calibrate(v, known_camera=dev))
            free.append(single_pose.calibrate(v))
    return known, free


@pytest.mark.slow    # its fast siblings: the other known-camera tests
def test_known_camera_reaches_its_bound_and_beats_the_free_camera(rig):
    sc, dev = rig
    obj = simulate.board_corners(sc)
    cb = crlb.camera_bound(sc.K_cam, None, sc.cam_dist_coeffs[0], 0.0, sc.R_board, sc.t_board, obj, 0.1,
                           "known_intrinsics")
    pb = crlb.projector_bound(sc.K_proj, sc.R_board_proj, sc.t_board_proj, obj, 0.2)
    eb = crlb.extrinsics_bound(cb, pb, sc.R_board, sc.t_board, sc.R_board_proj, sc.t_board_proj)
    known, free = _calibrations(sc, dev, 30)
    dT_known = np.array([c.T - sc.T for c in known])
    dT_free = np.array([c.T - sc.T for c in free])
    # 30 trials: the sample std is within ~25 % (2 sigma) of the truth; the estimator is efficient
    np.testing.assert_allclose(dT_known.std(axis=0), eb.T, rtol=0.35)
    assert np.all(np.abs(dT_known.mean(axis=0)) < 3 * eb.T / np.sqrt(30) + 0.05)
    assert np.all(dT_known.std(axis=0) < 0.5 * dT_free.std(axis=0))  # T is much better known
    fp = np.array([c.projector.K[0, 0] for c in known]) - sc.K_proj[0, 0]
    assert fp.std() == pytest.approx(pb.std["f_p"], rel=0.35)  # the projector's bound does not change
    c = known[0]
    assert np.array_equal(c.camera.K, dev.K) and c.method == "single-pose, camera given"
    assert c.std["f_c"] == 0.0 and c.poses[0]["advice"]["camera"]["given"]
    assert np.allclose(c.std["T"], eb.T, rtol=0.3)  # the reported ± is the bound's size


def test_known_camera_of_another_size_is_refused(rig):
    sc, dev = rig
    o, c, p = simulate.correspondences(sc, 0.1, 0.2, 0)
    other = Device(dev.K, (640, 400), dev.distortion)
    with pytest.raises(CalibrationError, match="intrinsics are for 640x400 images"):
        single_pose.calibrate(View(o, c, p, "s", sc.cam_size, sc.proj_size), known_camera=other)


def test_cli_camera_file(ideal_capture, tmp_path):
    """The ideal rig (the projector's single-pose assumptions hold), camera intrinsics from a file."""
    truth = ideal_capture[2]
    sc = ideal_capture[3]
    cam = Calibration(Device(np.array(sc.K_cam), sc.cam_size,
                             Distortion("division", tuple(sc.cam_center), *sc.cam_dist_coeffs)), None, None, None,
                      "camera-only")
    io.save_calibration(cam, tmp_path / "cam.json")
    out = tmp_path / "calib.json"
    code, stdout, err = run_cli(["calibrate", ideal_capture[0], "--board", "10x6", "--square", "24", "-o", out,
                                 "--camera", tmp_path / "cam.json"])
    assert code == 0, err
    c = io.load_calibration(out)
    np.testing.assert_allclose(c.camera.K, sc.K_cam)
    assert np.linalg.norm(c.T - np.array(truth["extrinsics"]["T"])) < 3.0
    assert abs(c.projector.K[0, 0] - truth["projector"]["f"]) < 15


def test_camera_only_from_several_photos(shared_data):
    """OpenCV's 13 left photos: Zhang's calibration with checks; the published fx = 536.1 (their corners)."""
    from procam import multi_pose, pipeline
    from procam.board import Board

    files = sorted((shared_data / "opencv-left-right").glob("left*.jpg"))
    views = [pipeline.camera_only_view(f, Board(9, 6, 25.0)) for f in files]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ProcamWarning)
        calib = multi_pose.calibrate_camera(views, fix_aspect_ratio=True)
    assert calib.method == "camera-only" and calib.projector is None and len(calib.poses) == 13
    assert abs(calib.camera.K[0, 0] - 536.1) < 0.01 * 536.1 and calib.cam_rms < 0.25
    assert 0 < calib.std["f_c"] < 2.0 and calib.info["coverage"] > 0.3


@pytest.mark.slow
def test_cli_camera_only_then_one_pose(ideal_capture, tmp_path):
    """Camera-only from several rendered photos (white frames of renders at other poses), then one pose
    with --camera: the whole workflow through the command line."""
    import cv2

    from procam import simulate as sim

    base = ideal_capture[3]
    photos = []
    for k, a in enumerate([(15, -25, 0), (-20, 15, 5), (20, 20, -5), (-10, -25, 0), (25, 10, 3)]):
        sc = sim.with_board_pose(base, a)
        r = sim.Renderer(sc, "opencv")
        img = r.frame(r.pattern_set.white, np.random.default_rng(k))
        path = tmp_path / f"photo{k}.png"
        cv2.imwrite(str(path), img)
        photos.append(path)
    cam = tmp_path / "cam.json"
    code, out, err = run_cli(["calibrate", *photos, "--camera-only", "--board", "10x6", "--square", "24", "-o", cam])
    assert code == 0, err
    c = io.load_calibration(cam)
    assert c.method == "camera-only" and abs(c.camera.K[0, 0] - base.K_cam[0, 0]) < 0.01 * base.K_cam[0, 0]
    out = tmp_path / "calib.json"
    code, _, err = run_cli(["calibrate", ideal_capture[0], "--board", "10x6", "--square", "24", "-o", out,
                            "--camera", cam])
    assert code == 0, err
    assert np.linalg.norm(io.load_calibration(out).T - base.T) < 5.0


def test_a_camera_files_uncertainty_is_carried_into_the_projectors_pm():
    """A camera calibrated once from photos is known to its file's covariance, not exactly: a camera 0.2 % off (what
    its file's ± says it may be) moves the one-pose projector's f_p by about as much, beyond a ± that holds the camera
    as exact; carried through the fit (the file's covariance), the ± covers it and the estimate is the same."""
    from sim_dense import dense_view

    scene = simulate.preset("lensshift")
    view = dense_view(scene, seed=0)
    K = np.array(scene.K_cam, float)
    K[0, 0] *= 1.002
    K[1, 1] *= 1.002
    dist = Distortion("division", tuple(scene.cam_center), *scene.cam_dist_coeffs)
    cov = np.diag([(0.002 * K[0, 0]) ** 2, (0.002 * K[1, 1]) ** 2, 1.0, 1.0])
    cov[0, 1] = cov[1, 0] = 0.99 * cov[0, 0]            # fx and fy move together, as from photos
    exact, carried = (single_pose.calibrate(view, known_camera=Device(K, scene.cam_size, dist, covariance=c))
                      for c in (None, (("f_c", "fy_c", "u0c", "v0c"), cov)))
    e = exact.projector.K[0, 0] - scene.K_proj[0, 0]
    np.testing.assert_allclose(carried.projector.K, exact.projector.K)     # the same estimate
    assert abs(e) > 3 * exact.std["f_p"]                                    # held exact: over-confident
    assert abs(e) < 2 * carried.std["f_p"] and carried.std["f_p"] > 3 * exact.std["f_p"]
    assert all(c > x for c, x in zip(carried.std["T"], exact.std["T"]))     # R, T carry it too


def test_a_given_cameras_residual_pattern_counts_by_what_it_does_to_the_projector():
    """A camera file whose lens model does not quite fit this pose (its k1 20 % short) leaves a smooth pattern in the
    corners' residuals. It made the pose weak by itself, whatever it did to the projector, while the projector's ±
    held the camera exact (u0p 11 px off, ± 5.1). Now what the pattern does to the projector's numbers joins their ±,
    which covers the errors, and the pose is rated by what it then determines (here u0p, to a few tens of px: weak,
    for that reason, with the pattern said in a warning)."""
    from sim_dense import dense_view

    scene = simulate.preset("lensshift")
    view = dense_view(scene, seed=0)
    k1, k2 = scene.cam_dist_coeffs
    dev = Device(np.array(scene.K_cam, float), scene.cam_size, Distortion("division", tuple(scene.cam_center),
                                                                          0.8 * k1, k2))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ProcamWarning)
        cal = single_pose.calibrate(view, known_camera=dev)
    assert cal.poses[0]["misfit"]["camera"]["model_error"]            # the pattern is there, and said
    said = [w for w in cal.warnings if "counts by what it does to the projector" in w]
    assert len(said) == 1
    reasons = " ".join(cal.verdict_reasons)
    assert "model error" not in reasons and cal.verdict == "weak" and "u0p to ±" in reasons
    for name, k in (("f_p", (0, 0)), ("u0p", (0, 2)), ("v0p", (1, 2))):
        assert abs(cal.projector.K[k] - scene.K_proj[k]) <= 1.5 * cal.std[name], name


def test_the_background_is_judged_against_what_a_given_camera_is_known_to():
    """A camera calibrated once from five photos is least sure in the image's corners, where the wall behind a
    board is seen: its error there moved one quadrant of the background 0.3 px off the others' epipolar lines,
    and the background check (noise and lens tolerance only) refused a plain wall, leaving the projector to the
    board (f_p 0.7 %, u0p 17 px off). The camera file's covariance, carried through the fit to each quadrant, is
    part of the check's tolerance now: the wall is used, and the projector's numbers are within their ±."""
    from dataclasses import replace

    from sim_dense import dense_view

    base = simulate.preset("lensshift")
    photos = []
    for i, ang in enumerate([(20, 10, 0), (-20, 15, 5), (15, -20, -5), (-15, -15, 0), (5, 25, 10)]):
        sc = simulate.with_board_pose(base, ang)
        o, c, p = simulate.correspondences(sc, 0.1, 0.2, 100 + i)
        photos.append(View(o, c, p, f"photo{i}", sc.cam_size, sc.proj_size))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ProcamWarning)
        cam = multi_pose.calibrate_camera(photos).camera
    assert cam.covariance is not None and cam.distortion.model == "opencv"
    scene = simulate.with_board_pose(base, (-24, 6, 0))
    view = dense_view(scene, seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ProcamWarning)
        carried, exact = (single_pose.calibrate(view, known_camera=d) for d in (cam, replace(cam, covariance=None)))
    assert carried.poses[0]["projector_model"]["background_used"]
    assert not exact.poses[0]["projector_model"]["background_used"]      # held exact, the camera's error is the wall's
    assert "does not follow one epipolar geometry" in exact.poses[0]["projector_model"]["background_reason"]
    for name, k in (("f_p", (0, 0)), ("u0p", (0, 2)), ("v0p", (1, 2))):
        e = carried.projector.K[k] - scene.K_proj[k]
        assert abs(e) <= 3 * carried.std[name], (name, e, carried.std[name])
    for k in ((0, 0), (0, 2)):      # the wall measures f_p and u0p (0.2 % and 7 px off, against 0.7 % and 17 px)
        assert abs(carried.projector.K[k] - scene.K_proj[k]) < 0.6 * abs(exact.projector.K[k] - scene.K_proj[k])
