"""Centre of distortion, division model and its OpenCV fit (METHOD §5)."""

import cv2
import numpy as np
import pytest

from procam import board, distortion, models

OBJ = board.object_points(10, 6, 24.0)
K = models.intrinsic_matrix(1539.0, 674.0, 512.0, alpha=1.004)
C = (674.0, 512.0)


def _view(k1, k2=0.0, angles=(20.0, 20.0, 0.0), sigma=0.0, seed=0, center=C):
    R = models.euler_to_matrix(*np.radians(angles))
    mu = models.project(K, R, [0.0, 0.0, 500.0], OBJ)
    md = models.distort_division(mu, center, k1, k2)
    return md + sigma * np.random.default_rng(seed).standard_normal(md.shape)


@pytest.mark.parametrize("k1,k2", [(-1e-7, 0.0), (-3e-7, 2e-13), (2e-7, 0.0)])
def test_noise_free_cod_and_coefficients_are_exact(k1, k2):
    cam = _view(k1, k2)
    est = distortion.estimate_cod(OBJ, cam, image_size=(1280, 800))
    assert est.reliable and est.reason == ""
    np.testing.assert_allclose(est.center, C, atol=1e-6)
    # left null vector: c^T F = 0
    ch = np.append(est.center, 1.0)
    assert np.linalg.norm(ch @ est.F) < 1e-9 * np.linalg.norm(est.F) * np.linalg.norm(ch)
    g1, g2, H = distortion.estimate_division(OBJ, cam, est.center)
    assert g1 == pytest.approx(k1, rel=1e-8)
    assert g2 == pytest.approx(k2, abs=1e-8 * abs(k1) / 700 ** 2)
    # H maps the board to the undistorted (pinhole) image
    R = models.euler_to_matrix(*np.radians([20.0, 20.0, 0.0]))
    mu = models.project(K, R, [0.0, 0.0, 500.0], OBJ)
    p = np.column_stack([OBJ[:, :2], np.ones(len(OBJ))]) @ H.T
    np.testing.assert_allclose(p[:, :2] / p[:, 2:], mu, atol=1e-6)
    np.testing.assert_allclose(models.undistort_division(cam, C, k1, k2), mu, atol=1e-8)


def test_fronto_parallel_board_is_not_degenerate_for_the_cod():
    est = distortion.estimate_cod(OBJ, _view(-1e-7, angles=(0.0, 0.0, 0.0)), image_size=(1280, 800))
    assert est.reliable
    np.testing.assert_allclose(est.center, C, atol=1e-6)


def test_score_grows_with_distortion_and_flags_weak_distortion():
    """METHOD §5.2's table: s8/s9 ~ 1 without distortion, >> 2.5 with ~14 px at the board edge."""
    scores = []
    for k1 in (0.0, -2e-8, -3e-7):
        s = [distortion.estimate_cod(OBJ, _view(k1, sigma=0.1, seed=i)).score for i in range(5)]
        scores.append(np.median(s))
    assert scores[0] < 1.6 and scores[2] > 5.0
    assert scores[0] < scores[1] < scores[2]
    est = distortion.estimate_cod(OBJ, _view(0.0, sigma=0.1), image_size=(1280, 800))
    assert not est.reliable and "weak distortion" in est.reason


def test_noisy_cod_is_within_a_few_pixels_with_strong_distortion():
    errs = [np.linalg.norm(distortion.estimate_cod(OBJ, _view(-3e-7, sigma=0.1, seed=s)).center - C)
            for s in range(10)]
    assert np.sqrt(np.mean(np.square(errs))) < 5.0


@pytest.mark.parametrize("cam", [
    np.full((60, 2), np.nan),                      # all corners failed
    np.zeros((60, 2)),                             # all at one point
    np.column_stack([np.arange(60.0), np.arange(60.0)]),  # collinear
    np.ones((5, 2)),                               # too few (and count mismatch)
])
def test_cod_never_raises_on_bad_input(cam):
    obj = OBJ if len(cam) == len(OBJ) else OBJ[:5]
    est = distortion.estimate_cod(obj, cam, image_size=(1280, 800))
    assert not est.reliable and est.reason


def test_cod_ignores_nan_rows():
    cam = _view(-1e-7)
    cam[[3, 17, 40]] = np.nan
    est = distortion.estimate_cod(OBJ, cam)
    np.testing.assert_allclose(est.center, C, atol=1e-6)


@pytest.mark.parametrize("k1,k2,center,tol", [(-1e-7, 0.0, C, 0.1), (-3e-7, 0.0, C, 2.0),
                                              (-1e-7, 0.0, (690.0, 500.0), 0.5), (0.0, 0.0, C, 1e-9)])
def test_opencv_fit_reproduces_the_division_model(k1, k2, center, tol):
    coeffs, err = distortion.opencv_from_division(K, center, k1, k2, (1280, 800))
    assert coeffs.shape == (5,) and err < tol
    # independent check: OpenCV's own undistortion of a few distorted pixels ~ division model
    pts = np.array([[100.0, 100.0], [640.0, 400.0], [1200.0, 700.0], [300.0, 650.0]])
    und = cv2.undistortPoints(pts.reshape(-1, 1, 2), K, coeffs, R=np.eye(3), P=K,
                              criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-12)).reshape(-1, 2)
    ref = models.undistort_division(pts, center, k1, k2)
    # OpenCV's inverse can differ by ~ err / (local magnification), allow 3x
    assert np.max(np.hypot(*(und - ref).T)) < 3 * tol + 1e-6


def test_max_displacement():
    cam = _view(-1e-7)
    d = distortion.max_displacement(cam, C, -1e-7)
    r = np.max(np.hypot(*(cam - C).T))
    assert d == pytest.approx(r / (1 - 1e-7 * r * r) - r, rel=1e-9)
