"""Tests of the simulator's lenses (procam.simulate.Lens): the projector's, OpenCV's model and beyond, the truth
of a lens, and the projector's response (proj_gamma)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from procam import simulate as sim
from procam.simulate.lens import _K

W, H = 1920, 1080


def _panel(n=60, pad=0.5, size=(W, H)):
    """A grid over the whole projector panel (or an image of ``size``: pixel centres to its outer edges)."""
    u, v = np.meshgrid(np.linspace(-pad, size[0] - 1 + pad, n), np.linspace(-pad, size[1] - 1 + pad, n))
    return np.column_stack([u.ravel(), v.ravel()])


#: Projector lenses: lens shift to and beyond the panel's last row, off-centre u0p, OpenCV and beyond it.
LENSES = {
    "lensshift": (_K(2421.0, 1.0, W / 2 + 21, 1.08 * H), sim.Lens("opencv", (-0.10, 0.015, 0.0, 0.0, 0.0))),
    "opencv_tangential": (_K(2300.0, 1.002, 930.0, 1.15 * H), sim.Lens("opencv", (-0.15, 0.08, 8e-4, -5e-4, -0.02))),
    "beyond_opencv": (_K(2421.0, 1.0, 930.0, 1.05 * H),
                      sim.Lens("opencv", (-0.12, 0.04, 0.0, 0.0, 0.0), center=(970.0, 1104.0), higher=(0.2, -0.05))),
    "short_throw": (_K(1400.0, 1.0, 990.0, 1.10 * H), sim.Lens("opencv", (-0.12, 0.03, 0.0, 0.0, 0.0))),
    "division": (_K(2421.0, 1.0, 960.0, 1.02 * H), sim.Lens("division", (-2e-8, 0.0))),
}


@pytest.mark.parametrize("name", sorted(LENSES))
def test_projector_lens_round_trips_over_the_panel_to_1e_9_px(name):
    """undistort(distort(p)) = p and distort(undistort(p)) = p over the whole panel, principal point beyond it."""
    K, lens = LENSES[name]
    assert K[1, 2] > H - 1  # the principal point lies beyond the panel's last row
    _assert_round_trip(K, lens, _panel())


def _assert_round_trip(K, lens, p):
    und = lens.undistort(K, p)
    assert np.isfinite(und).all()
    np.testing.assert_allclose(lens.distort(K, und), p, rtol=0, atol=1e-9)
    np.testing.assert_allclose(lens.undistort(K, lens.distort(K, und)), und, rtol=0, atol=1e-9)
    if lens.model == "opencv":  # the lens moves the image's corners by many pixels: a real test
        assert np.abs(und - p).max() > 10


def test_hard_camera_lens_round_trips_over_the_image_to_1e_9_px():
    s = sim.preset("hard")
    _assert_round_trip(s.K_cam, s.cam_lens, _panel(size=s.cam_size))


def test_projector_distortion_matches_cv2_project_points():
    """The forward map (3-D point -> the panel pixel that lights it) is cv2.projectPoints for an OpenCV lens."""
    rng = np.random.default_rng(3)
    for name in ("lensshift", "opencv_tangential", "short_throw"):
        K, lens = LENSES[name]
        X = np.column_stack([lens.undistort(K, _panel(30)), np.ones(900)])  # rays through the whole panel
        X = np.column_stack([(X[:, 0] - K[0, 2]) / K[0, 0], (X[:, 1] - K[1, 2]) / K[1, 1], np.ones(900)])
        X *= rng.uniform(300, 3000, (900, 1))
        q, _ = cv2.projectPoints(X, np.zeros(3), np.zeros(3), K, np.array(lens.coeffs))
        np.testing.assert_allclose(lens.project(K, X), q.reshape(-1, 2), rtol=0, atol=1e-9)
        # ... also through a scene, its corner truth and its fast corner path
    s = sim.preset("lensshift")
    c = sim.corner_truth(s)
    rv, _ = cv2.Rodrigues(s.R_board_proj)
    q, _ = cv2.projectPoints(c["board"], rv, s.t_board_proj, s.K_proj, np.array(s.proj_dist_coeffs))
    np.testing.assert_allclose(c["projector"], q.reshape(-1, 2), rtol=0, atol=1e-9)
    np.testing.assert_allclose(sim.project_points(s, c["board"] @ s.R_board_proj.T + s.t_board_proj, "projector"),
                               c["projector"], rtol=0, atol=1e-9)
    _, _, proj = sim.correspondences(s, 0.0, 0.0)
    np.testing.assert_array_equal(proj, c["projector"])
    assert np.abs(c["projector"] - c["projector_undistorted"]).max() > 10  # distortion at the board's corners


def test_scene_lenses_are_the_devices_lenses():
    s = sim.preset("lensshift")
    p = _panel(20)
    np.testing.assert_array_equal(sim.distort(s, p, "projector"), s.proj_lens.distort(s.K_proj, p))
    np.testing.assert_array_equal(sim.undistort(s, p, "projector"), s.proj_lens.undistort(s.K_proj, p))
    np.testing.assert_array_equal(sim.distort(s, p), sim.distort(s, p, "camera"))
    with pytest.raises(ValueError, match="device"):
        sim.distort(s, p, "wall")


def test_lenses_beyond_opencv_are_not_described_by_its_five_terms():
    """The 'hard' lenses: higher radial terms and a decentred radial centre, which no 5-term OpenCV lens fits
    exactly (with K free): the fit's residual is what a solver using OpenCV's model must live with (0.005 px for
    the camera, 0.027 px for the projector with their decentrings of a few pixels, as manufacturing leaves them)."""
    from scipy.optimize import least_squares

    s = sim.preset("hard")
    for K, lens, size, rms_min in ((s.K_cam, s.cam_lens, s.cam_size, 0.003), (s.K_proj, s.proj_lens, s.proj_size, 0.015)):
        assert not lens.describable(K)
        words = " ".join(lens.left_out(K))
        assert "r^8" in words and "radial centre" in words
        u, v = np.meshgrid(np.linspace(0, size[0] - 1, 40), np.linspace(0, size[1] - 1, 40))
        p = np.column_stack([u.ravel(), v.ravel()])
        und = lens.undistort(K, p)
        xn = np.column_stack([(und[:, 0] - K[0, 2]) / K[0, 0], (und[:, 1] - K[1, 2]) / K[1, 1], np.ones(len(p))])

        def resid(q):
            Kq = _K(q[0], q[1] / q[0], q[2], q[3])
            m, _ = cv2.projectPoints(xn, np.zeros(3), np.zeros(3), Kq, q[4:])
            return (m.reshape(-1, 2) - p).ravel()

        fit = least_squares(resid, [K[0, 0], K[1, 1], K[0, 2], K[1, 2], *lens.coeffs])
        rms = np.sqrt(np.mean(fit.fun.reshape(-1, 2) ** 2) * 2)
        assert rms > rms_min, rms
    assert sim.Lens("opencv", (-0.1, 0.0, 0.0, 0.0, 0.0), center=tuple(s.K_proj[:2, 2])).describable(s.K_proj)


def test_distortion_beyond_the_fold_is_nan_not_a_folded_point():
    K = _K(1000.0, 1.0, 500.0, 400.0)
    lens = sim.Lens("opencv", (-0.4, 0.0, 0.0, 0.0, 0.0))  # r (1 - 0.4 r^2) turns back at r = 0.913
    assert lens.fold_radius(K) == pytest.approx(np.sqrt(1 / 1.2))
    xn = np.array([[0.5, 0.0], [0.9, 0.0], [1.2, 0.0]])
    d = lens.distort(K, xn * 1000 + [500, 400])
    assert np.isfinite(d[:2]).all() and np.isnan(d[2]).all()
    # no undistorted point beyond the fold: the distorted image ends at the fold's radius
    back = lens.undistort(K, np.array([[500 + 1000 * 0.6, 400.0], [500 + 1000 * 0.7, 400.0]]))
    assert np.isfinite(back[0]).all() and np.isnan(back[1]).all()


def test_lens_refuses_what_it_does_not_know():
    with pytest.raises(ValueError, match="division|opencv|none"):
        sim.Lens("fisheye")
    with pytest.raises(ValueError, match="5 coefficients"):
        sim.Lens("opencv", (0.1, 0.0))
    with pytest.raises(ValueError, match="higher"):
        sim.Lens("division", (-1e-8, 0.0), higher=(0.1,))
    with pytest.raises(ValueError, match="proj_distortion must be"):
        sim.Scene(proj_distortion="fisheye")
    with pytest.raises(ValueError, match="cam_distortion coefficients must be finite"):
        sim.Scene(cam_distortion="opencv", cam_dist_coeffs=(0.1, 0.0, 0.0, 0.0, 0.0), cam_dist_higher=(float("nan"),))


# ---------------------------------------------------------------------------------------------
# the truth of a lens
# ---------------------------------------------------------------------------------------------

def test_truth_calibration_holds_the_projector_distortion():
    """A lens procam's OpenCV model describes is its truth: the calibration's projector projects the board's corners
    to the panel pixels that light them."""
    s = sim.preset("lensshift")
    calib = sim.truth_calibration(s)
    assert calib.projector.distortion.model == "opencv"
    assert calib.projector.distortion.coeffs == (-0.10, 0.015, 0.0, 0.0, 0.0)
    c = sim.corner_truth(s)
    np.testing.assert_allclose(calib.projector.project(s.R_board_proj, s.t_board_proj, c["board"]), c["projector"],
                               atol=1e-9)
    assert not calib.warnings and "truth_left_out" not in calib.info
    # an ideal projector stays "none" (the paper's rig, unchanged)
    assert sim.truth_calibration(sim.preset("paper")).projector.distortion.model == "none"


def test_truth_calibration_refuses_a_lens_it_cannot_hold():
    """A lens procam's models do not describe is never returned as if it were the truth: it raises, naming what is
    left out; asked for, its OpenCV part comes with the flag and a warning."""
    s = sim.preset("hard")
    with pytest.raises(ValueError, match=r"camera's lens.*r\^8.*radial centre.*approximate=True"):
        sim.truth_calibration(s)
    calib = sim.truth_calibration(s, approximate=True)
    assert set(calib.info["truth_left_out"]) == {"camera", "projector"}
    assert len(calib.warnings) == 2 and all("left out" in w for w in calib.warnings)
    assert calib.projector.distortion.coeffs == s.proj_dist_coeffs
    np.testing.assert_array_equal(calib.projector.K, s.K_proj)
    # the JSON truth says it too
    t = sim.truth(s)
    assert t["projector"]["distortion"]["describable"] is False
    assert any("r^8" in w for w in t["projector"]["distortion"]["left_out"])
    assert t["projector"]["distortion"]["higher"] == [0.2]


# ---------------------------------------------------------------------------------------------
# the projector's response
# ---------------------------------------------------------------------------------------------

def _small(name="paper", **kw):
    s = sim.preset(name).scaled(0.25).replace(supersample=2, **kw)
    return sim.with_board_pose(s, sim.RECOMMENDED_POSE)


def test_projector_gamma_leaves_gray_code_captures_unchanged():
    """Gray-code patterns are binary: the projector's response does not change a bit of them."""
    s = _small()
    a, _ = sim.render(s, seed=2)
    b, t = sim.render(s.replace(proj_gamma=2.2), seed=2)
    np.testing.assert_array_equal(a, b)
    assert t["photometry"]["proj_gamma"] == 2.2


def test_projector_gamma_maps_pattern_values_to_light():
    """A pattern value v emits black + (1 - black) (v / 255) ** proj_gamma of white: on the lit board, the light a
    mid-grey adds over black is (128 / 255) ** gamma of what white adds."""
    s = _small(proj_gamma=2.2)
    r = sim.Renderer(s)
    lit = sim.true_projector_maps(s).lit_board
    Wp = s.proj_size[0]
    lin = {v: r.linear_stripes(np.full(Wp, v, np.uint8), "col") for v in (0, 128, 255)}
    ratio = (lin[128] - lin[0])[lit] / (lin[255] - lin[0])[lit]
    np.testing.assert_allclose(np.median(ratio), (128 / 255) ** 2.2, rtol=1e-3)
    np.testing.assert_allclose(r.emitted(np.array([0, 255])), [s.proj_black, 1.0])
    # the white frame of the sequence is the all-255 pattern
    np.testing.assert_allclose(lin[255][lit], r.linear(r.pattern_set.white)[lit], rtol=1e-5)
    with pytest.raises(ValueError):
        r.linear_stripes(np.zeros(7), "col")
    with pytest.raises(ValueError):
        sim.Scene(proj_gamma=0.0)
