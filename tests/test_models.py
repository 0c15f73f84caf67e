"""procam.models and procam.residuals: round trips and analytic identities."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from procam import models, residuals
from procam.errors import CalibrationError

FLIP = np.diag([1.0, -1.0, -1.0])  # the same board with its frame turned 180 deg about x


def test_distort_undistort_round_trip():
    rng = np.random.default_rng(0)
    c = np.array([652.0, 481.0])
    p = c + rng.uniform(-600, 600, size=(200, 2))
    for k1, k2 in [(-2e-7, 0.0), (-1.5e-7, 3e-14), (1e-7, -2e-14), (0.0, 0.0)]:
        d = models.distort_division(p, c, k1, k2)
        assert np.all(np.isfinite(d))
        assert np.allclose(models.undistort_division(d, c, k1, k2), p, atol=1e-8)
    assert np.allclose(models.distort_division(c[None], c, -2e-7), c[None])


def test_lens_models_one_implementation_for_arrays_complex_steps_and_duals():
    """The division model on coordinates gives the (N, 2) functions' values exactly, NaN where no root exists, and
    its Dual derivatives equal the complex-step ones; OpenCV's model (brown) is cv2's own, and inverts."""
    import cv2

    from procam import _dual as D

    rng = np.random.default_rng(3)
    c = np.array([652.0, 481.0])
    p = c + rng.uniform(-900, 900, size=(300, 2))
    k1, k2 = 4e-7, 2e-13  # strong pincushion: the far corners have no distorted point
    d = models.distort_division(p, c, k1, k2)
    bad = np.isnan(d).any(1)
    assert 0 < bad.sum() < len(p) and np.isnan(d[bad]).all()
    x = D.Dual(np.array([k1, k2]), np.eye(2))   # d/dk1, d/dk2
    xd, yd = models.distort_division_xy(p[:, 0], p[:, 1], c[0], c[1], x[0], x[1])
    np.testing.assert_array_equal(np.isnan(xd.v), bad)
    np.testing.assert_allclose(xd.v[~bad], d[~bad, 0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(yd.v[~bad], d[~bad, 1], rtol=0, atol=1e-9)
    for j, (h1, h2) in enumerate([(1e-30, 0.0), (0.0, 1e-37)]):
        dc = models.distort_division(p[~bad], c, k1 + 1j * h1, k2 + 1j * h2).imag / (h1 + h2)
        np.testing.assert_allclose(xd.d[~bad, j], dc[:, 0], rtol=1e-9, atol=1e-12 * np.abs(dc).max())
        np.testing.assert_allclose(yd.d[~bad, j], dc[:, 1], rtol=1e-9, atol=1e-12 * np.abs(dc).max())
    ux, uy = models.undistort_division_xy(xd, yd, c[0], c[1], x[0], x[1])  # the round trip's derivative is zero
    np.testing.assert_allclose(ux.v[~bad], p[~bad, 0], atol=1e-8)
    assert np.abs(ux.d[~bad]).max() < 1e-6 * np.abs(xd.d[~bad]).max()

    coeffs = np.array([-0.12, 0.05, 0.001, -0.0007, -0.01])
    xn = rng.uniform(-0.6, 0.6, size=(200, 2))
    ref, _ = cv2.projectPoints(np.column_stack([xn, np.ones(len(xn))]), np.zeros(3), np.zeros(3), np.eye(3), coeffs)
    bx, by = models.brown(xn[:, 0], xn[:, 1], *coeffs)
    np.testing.assert_allclose(np.column_stack([bx, by]), ref.reshape(-1, 2), rtol=0, atol=1e-12)
    ix, iy = models.brown_inverse(bx, by, *coeffs)
    np.testing.assert_allclose(np.column_stack([ix, iy]), xn, rtol=0, atol=1e-10)


def test_euler_matrix_round_trip():
    rng = np.random.default_rng(1)
    for _ in range(50):
        a = rng.uniform([-np.pi, -1.5, -np.pi], [np.pi, 1.5, np.pi])
        R = models.euler_to_matrix(*a)
        assert np.allclose(R, Rotation.from_euler("XYZ", a).as_matrix())
        assert np.allclose(models.matrix_to_euler(R), a, atol=1e-10)
        assert np.allclose(models.euler_deg(R), np.degrees(a), atol=1e-8)
        assert np.allclose(models.rvec_to_matrix(models.matrix_to_rvec(R)), R)


def test_euler_deg_of_the_identity_and_a_known_rotation():
    assert models.euler_deg(np.eye(3)) == pytest.approx((0.0, 0.0, 0.0))
    R = models.euler_to_matrix(*np.radians([12.0, -7.0, 3.0]))
    assert models.euler_deg(R) == pytest.approx((12.0, -7.0, 3.0))


def test_invert_compose():
    rng = np.random.default_rng(2)
    R, t = Rotation.random(random_state=3).as_matrix(), rng.normal(size=3)
    Ri, ti = models.invert(R, t)
    Rc, tc = models.compose(R, t, Ri, ti)
    assert np.allclose(Rc, np.eye(3)) and np.allclose(tc, 0, atol=1e-12)


def test_board_angles_fronto_parallel_is_zero_on_either_side():
    t = np.array([10.0, -5.0, 800.0])
    assert np.allclose(models.board_angles_deg(np.eye(3), t), 0.0)
    # the device on the board's +z side (corners numbered the other way round): still fronto-parallel
    assert np.allclose(models.board_angles_deg(FLIP, t), 0.0, atol=1e-12)


def test_board_angles_same_physical_pose_same_angles():
    ang = np.radians([12.0, -25.0, 4.0])
    R = models.euler_to_matrix(*ang)
    t = np.array([20.0, 30.0, 900.0])
    assert np.allclose(models.board_angles_deg(R, t), np.degrees(ang))
    # board frame flipped (X_board' = FLIP X_board): same points in the device, same angles
    assert np.allclose(models.board_angles_deg(R @ FLIP, t), np.degrees(ang))


def _scene(seed=4):
    rng = np.random.default_rng(seed)
    gx, gy = np.meshgrid(np.arange(9) * 20.0, np.arange(6) * 20.0)
    obj = np.column_stack([gx.ravel() - 80, gy.ravel() - 50, np.zeros(54)])
    K = models.intrinsic_matrix(1200.0, 640.0, 480.0)
    R = models.euler_to_matrix(*np.radians([15.0, -20.0, 3.0]))
    t = np.array([10.0, -20.0, 700.0])
    return obj, K, R, t, rng


def test_pnp_recovers_pose_and_residual_sign():
    obj, K, R, t, rng = _scene()
    pts = models.project(K, R, t, obj)
    R1, t1, e = residuals.pnp(obj, pts, K)
    assert np.allclose(R1, R, atol=1e-8) and np.allclose(t1, t, atol=1e-5) and np.abs(e).max() < 1e-6
    # observed - predicted: a corner moved by +2 px in x has a positive x residual
    moved = pts.copy()
    moved[0, 0] += 2.0
    assert residuals.pnp(obj, moved, K)[2][0, 0] > 1.0
    with pytest.raises(CalibrationError):
        residuals.pnp(obj, np.full_like(pts, np.nan), K)


def test_stereo_pose_exact_and_sign():
    obj, Kc, Rb, tb, rng = _scene()
    Kp = models.intrinsic_matrix(1500.0, 512.0, 700.0)
    R = models.euler_to_matrix(*np.radians([2.0, 20.0, -1.0]))
    T = np.array([-250.0, 10.0, 30.0])
    cam = models.project(Kc, Rb, tb, obj)
    proj = models.project(Kp, *models.compose(R, T, Rb, tb), obj)
    R0 = models.euler_to_matrix(*np.radians([14.0, -19.0, 2.0]))
    Rs, ts, rc, rp = residuals.stereo_pose(obj, cam, proj, Kc, Kp, R, T, R0, tb + 5)
    assert np.allclose(Rs, Rb, atol=1e-8) and np.allclose(ts, tb, atol=1e-5)
    assert max(np.abs(rc).max(), np.abs(rp).max()) < 1e-6
    noisy = cam + 0.3 * rng.standard_normal(cam.shape)
    _, _, rc, _ = residuals.stereo_pose(obj, noisy, proj, Kc, Kp, R, T, Rb, tb)
    # observed - predicted: with the pose pinned by the exact projector points, rc ~ the added noise
    assert np.corrcoef(rc.ravel(), (noisy - cam).ravel())[0, 1] > 0.9
