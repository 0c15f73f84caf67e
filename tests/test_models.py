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
