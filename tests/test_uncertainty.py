"""Covariance from the Jacobian: analytic identities, degeneracy, priors, delta method."""

import numpy as np
import pytest

from procam import uncertainty as unc


def test_jacobian_matches_analytic():
    def f(p):
        return np.array([p[0] ** 2 * p[1], np.sin(p[1]), p[0] * 1e3])

    p = np.array([3.0, 0.7])
    J = unc.jacobian(f, p)
    Ja = np.array([[2 * p[0] * p[1], p[0] ** 2], [0.0, np.cos(p[1])], [1e3, 0.0]])
    np.testing.assert_allclose(J, Ja, rtol=1e-8)
    np.testing.assert_allclose(unc.jacobian(f, p, method="complex"), Ja, rtol=1e-14)


def test_linear_regression_covariance_is_textbook():
    rng = np.random.default_rng(0)
    X = np.column_stack([np.ones(50), rng.uniform(-1, 1, 50), rng.uniform(0, 5, 50)])
    sigma = 0.3
    cov = unc.covariance(X, sigma)
    np.testing.assert_allclose(cov, sigma ** 2 * np.linalg.inv(X.T @ X), rtol=1e-10)


def test_sigma_from_residuals_unbiased():
    rng = np.random.default_rng(1)
    vals = [unc.sigma_from_residuals(0.5 * rng.standard_normal(40), 8) for _ in range(400)]
    assert np.mean(np.square(vals)) == pytest.approx(0.25 * 40 / 32, rel=0.1)  # pure noise, m - n = 32
    assert np.isnan(unc.sigma_from_residuals(np.ones(3), 3))


def test_degenerate_jacobian_gives_infinite_covariance_not_pinv():
    J = np.column_stack([np.arange(10.0), 2 * np.arange(10.0), np.ones(10)])  # columns 0, 1 dependent
    cov = unc.covariance(J, 0.1)
    assert np.all(np.isinf(cov))
    assert np.all(np.isinf(unc.std(cov)))


def test_prior_makes_unobservable_parameter_finite_and_widens_others():
    x = np.linspace(-1, 1, 20)
    # y = a + b x + c (x + 0 * something): column 2 duplicates column 0 -> unobservable without prior
    J = np.column_stack([np.ones(20), x, np.ones(20)])
    assert np.all(np.isinf(unc.covariance(J, 0.1)))
    cov = unc.covariance(J, 0.1, prior_precision=np.array([0.0, 0.0, 1 / 0.5 ** 2]))
    s = unc.std(cov)
    assert np.all(np.isfinite(s))
    assert s[2] == pytest.approx(0.5, rel=0.05)   # data say nothing about c alone
    assert s[0] == pytest.approx(np.hypot(0.5, 0.1 / np.sqrt(20)), rel=0.05)  # a inherits the prior


def test_propagate_linear_and_infinite():
    cov = np.diag([4.0, 9.0])
    out = unc.propagate(cov, lambda p: np.array([p[0] + p[1], 2 * p[0]]), np.zeros(2))
    np.testing.assert_allclose(out, [[13.0, 8.0], [8.0, 16.0]], rtol=1e-8)
    assert np.all(np.isinf(unc.propagate(np.full((2, 2), np.inf), lambda p: p, np.zeros(2))))


def _conditioned(cond, m=40, seed=2):
    """(m, 3) Jacobian with unit columns, condition about ``cond``, and its exact (J^T J)^-1."""
    rng = np.random.default_rng(seed)
    U, _ = np.linalg.qr(rng.standard_normal((m, 3)))
    V, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    s = np.array([1.0, 0.3, cond])
    A = (U * s) @ V.T
    d = np.linalg.norm(A, axis=0)
    return A / d, ((V / s ** 2) @ V.T) * np.outer(d, d)


def test_one_degeneracy_rule_on_the_condition_of_the_jacobian():
    """Finite, to its digits, above RCOND = 1e-9 (here between it and the single-pose joint fit's old eigenvalue
    limit of 1e-14, a condition of 1e-7, where inverting J^T J keeps only ~2 digits); infinite below."""
    J, exact = _conditioned(3e-8)
    assert 1e-9 < unc.condition(J) < 1e-7
    np.testing.assert_allclose(unc.covariance(J, 1.0), exact, rtol=1e-6)
    for c in (1e-11, 1e-13):
        J, _ = _conditioned(c)
        assert unc.condition(J) < unc.RCOND
        assert np.all(np.isinf(unc.covariance(J, 1.0)))


def test_the_single_pose_joint_fit_covariance_is_the_one_rule():
    from procam import models, simulate
    from procam.single_pose import joint

    scene = simulate.preset("paper")
    obj, cam, _ = simulate.correspondences(scene, 0.1, 0.2, seed=3)
    empty = np.zeros((0, 2))
    model = joint.JointModel(joint.JointData(obj, cam, empty, empty, empty, empty), joint.Scales(0.1, 1.0, 1.0))
    p = np.zeros(len(joint.NAMES))
    K = scene.K_cam
    p[:12] = [K[0, 0], K[1, 1] / K[0, 0], K[0, 2], K[1, 2], 0.0, 0.0, *models.matrix_to_rvec(scene.R_board),
              *scene.t_board]
    p[12] = p[13] = 1.0  # the projector is not in these residuals
    free = ("f_c", "alpha_c") + joint.POSE_C  # what one view of a plane determines, its centre given
    _, Jm, cov = joint.linearise(model, p, free)
    idx = [joint.IDX[n] for n in free]
    np.testing.assert_array_equal(cov[np.ix_(idx, idx)], unc.covariance(Jm, 1.0))
    assert np.all(np.isfinite(cov[np.ix_(idx, idx)]))
    _, Jm, cov = joint.linearise(model, p, free + ("u0p",))   # u0p: no residual sees it -> infinite
    assert np.all(np.isinf(cov[np.ix_(idx, idx)]))


def test_a_held_cameras_uncertainty_moves_the_free_parameters_as_a_refit_does():
    """held_covariance's sensitivity is the fit's own: moving the held camera's f_c (or k1) by a small step and
    refitting moves the projector's parameters by what the linearised rule predicts."""
    from procam import models, simulate
    from procam.calibration import Device, Distortion
    from procam.single_pose import joint

    scene = simulate.preset("lensshift")
    obj = simulate.board_corners(scene)
    rng = np.random.default_rng(5)
    camera = Device(np.array(scene.K_cam, float), scene.cam_size, Distortion("opencv", coeffs=(-0.05, 0.01, 0, 0, 0)))
    # the board samples: board points seen by the camera (its own model) and lit by the projector
    X = np.column_stack([rng.uniform(obj[:, 0].min(), obj[:, 0].max(), 600),
                         rng.uniform(obj[:, 1].min(), obj[:, 1].max(), 600), np.zeros(600)])
    rvec, t = models.matrix_to_rvec(scene.R_board), np.asarray(scene.t_board, float)
    import cv2
    bc = cv2.projectPoints(X, rvec, t, camera.K, np.array(camera.distortion.coeffs))[0].reshape(-1, 2)
    cc = cv2.projectPoints(obj, rvec, t, camera.K, np.array(camera.distortion.coeffs))[0].reshape(-1, 2)
    Rp, tp = scene.R_board_proj, np.asarray(scene.t_board_proj, float)
    bp = models.project(scene.K_proj, Rp, tp, X)
    data = joint.JointData(obj, cc, bc, bp, np.zeros((0, 2)), np.zeros((0, 2)),
                           camera_fixed=joint.FixedDevice(camera.K, camera))
    model = joint.JointModel(data, joint.Scales(0.1, 0.05, 1.0))
    p0 = np.zeros(len(joint.NAMES))
    p0[joint.IDX["rx"]:joint.IDX["rx"] + 3], p0[joint.IDX["tx"]:joint.IDX["tx"] + 3] = rvec, t
    K = scene.K_proj
    p0[[joint.IDX[n] for n in ("f_p", "alpha_p", "u0p", "v0p")]] = K[0, 0], K[1, 1] / K[0, 0], K[0, 2], K[1, 2]
    p0[joint.IDX["prx"]:joint.IDX["prx"] + 3], p0[joint.IDX["ptx"]:joint.IDX["ptx"] + 3] = \
        models.matrix_to_rvec(Rp), tp
    free = ("f_p", "v0p") + joint.POSE_P + joint.POSE_C     # one plane: u0p and alpha_p held (the paper's)
    fit = joint.solve(model, p0, free)
    names = ("f_c", "k1")
    for k, step in enumerate((2.0, 0.002)):       # 0.1 % of f_c; k1 by 4 % of itself
        cov = np.zeros((2, 2))
        cov[k, k] = step ** 2
        predicted = np.sqrt(np.diag(joint.held_covariance(model, fit.p, free, "camera", names, cov)))
        moved = joint._moved(camera, names, np.array([camera.K[0, 0], -0.05]) + step * np.eye(2)[k])
        m2 = joint.JointModel(joint.JointData(obj, cc, bc, bp, np.zeros((0, 2)),
                                              np.zeros((0, 2)), camera_fixed=joint.FixedDevice(moved.K, moved)),
                              model.scales)
        refit = joint.solve(m2, fit.p, free)
        for n in ("f_p", "v0p", "ptz"):
            i = joint.IDX[n]
            assert abs(refit.p[i] - fit.p[i]) == pytest.approx(predicted[i], rel=0.05, abs=1e-6), n
        assert predicted[joint.IDX["f_p"]] > 0.5 * step if k == 0 else True   # f_c's step reaches f_p
    infinite = joint.held_covariance(model, fit.p, free, "camera", names, np.full((2, 2), np.inf))
    assert np.isinf(infinite[joint.IDX["f_p"], joint.IDX["f_p"]])
