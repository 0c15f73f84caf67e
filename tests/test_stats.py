"""procam.stats: the shared RMS, robust sigma and plane fit against their definitions."""

import numpy as np
import pytest

from procam.stats import MAD_TO_SIGMA, rms, robust_sigma, tls_plane


def test_rms_skips_nan_rows():
    e = np.array([[3.0, 4.0], [np.nan, 1.0], [0.0, 0.0], [np.inf, 0.0]])
    assert rms(e) == pytest.approx(np.sqrt(25 / 2))
    assert np.isnan(rms(np.full((3, 2), np.nan)))
    assert np.isnan(rms(np.zeros((0, 2))))
    assert np.isnan(rms([]))
    # lists of arrays of different lengths are pooled
    assert rms([np.array([[3.0, 4.0]]), np.zeros((3, 2)), e]) == pytest.approx(np.sqrt(50 / 6))


def test_rms_of_scalars_and_3d_points():
    assert rms(np.array([3.0, -4.0]), dim=1) == pytest.approx(np.sqrt(12.5))
    assert rms(np.array([[1.0, 2.0, 2.0]]), dim=3) == pytest.approx(3.0)


def test_robust_sigma_is_gaussian_sigma_and_ignores_outliers():
    rng = np.random.default_rng(3)
    x = rng.normal(5.0, 2.0, 200_000)
    assert robust_sigma(x) == pytest.approx(2.0, rel=0.01)
    x[:20_000] = 1e6                      # 10 % gross outliers move it little
    assert robust_sigma(x) == pytest.approx(2.0, rel=0.2)
    assert robust_sigma(np.array([np.nan, np.inf])) != robust_sigma(np.array([np.nan, np.inf]))  # NaN


def test_robust_sigma_rows_and_centre():
    r = np.array([[1.0, -1.0], [np.nan, 5.0], [2.0, -2.0]])
    # the row with a NaN is skipped whole; the components of the others pooled about their median 0
    assert robust_sigma(r) == pytest.approx(MAD_TO_SIGMA * 1.5)
    d = np.array([1.0, 2.0, 3.0])
    assert robust_sigma(d, about=0.0) == pytest.approx(MAD_TO_SIGMA * 2.0)
    assert robust_sigma(d) == pytest.approx(MAD_TO_SIGMA * 1.0)


def test_tls_plane_recovers_a_noisy_plane():
    rng = np.random.default_rng(7)
    n_true = np.array([1.0, -2.0, 3.0]) / np.sqrt(14.0)
    basis = np.linalg.svd(n_true[None])[2][1:]            # two unit vectors in the plane
    X = rng.uniform(-100, 100, (500, 2)) @ basis + 50.0 * n_true + rng.normal(0, 0.01, (500, 1)) * n_true
    n, c = tls_plane(X)
    assert abs(abs(n @ n_true) - 1.0) < 1e-8
    assert np.linalg.norm(n) == pytest.approx(1.0)
    assert (c @ n_true) == pytest.approx(50.0, abs=0.01)
