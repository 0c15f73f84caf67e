"""Cramér–Rao bounds: METHOD §13's reference tables, degeneracies, a Monte-Carlo check."""

import numpy as np
import pytest
from scipy.optimize import least_squares

from procam.board import object_points
from procam.crlb import camera_bound, extrinsics_bound, projector_bound
from procam.models import euler_to_matrix, intrinsic_matrix, project

M = object_points(10, 6, 24.0)
KC = intrinsic_matrix(1539.0, 674.0, 512.0, alpha=1.004)
KP = intrinsic_matrix(2421.0, 1013.0, 1065.0, alpha=1.002)
T500 = np.array([0.0, 0.0, 500.0])
K1 = -1e-7


def rot(psi, nu, phi=0.0):
    return euler_to_matrix(*np.radians([psi, nu, phi]))


def cam(psi, nu, model="full", **kw):
    return camera_bound(KC, None, K1, 0.0, rot(psi, nu), T500, M, kw.pop("sigma", 0.1), model, **kw)


# (psi, nu) -> sqrt(CRLB(f_c)) from METHOD §13, sigma_c = 0.1 px
FULL = {(2, 2): 85, (2, 10): 31, (5, 5): 20, (10, 10): 8.3, (10, 20): 6.9, (20, 20): 4.1,
        (30, 30): 3.0, (45, 45): 5.4, (45, 2): 25}
KNOWN = {(2, 2): 78, (5, 10): 8.8, (10, 10): 4.7, (20, 20): 2.3, (30, 20): 1.8, (45, 45): 2.2}
PROJ = {(0, 2): 303, (0, 10): 14, (10, 5): 25, (10, 10): 11, (10, 13): 7.9, (30, 20): 3.9,
        (30, 45): 2.5}


@pytest.mark.parametrize("cell,ref", FULL.items())
def test_camera_full_reference_table(cell, ref):
    b = cam(*cell)
    assert b.std["f_c"] == pytest.approx(ref, rel=0.03, abs=0.06)
    assert 4.5 < b.std["u0c"] < 8.5  # "sqrt(CRLB(c_u)) ~ 5-8 px everywhere non-degenerate"


@pytest.mark.parametrize("cell,ref", KNOWN.items())
def test_camera_known_distortion_reference_table(cell, ref):
    assert cam(*cell, model="known_distortion").std["f_c"] == pytest.approx(ref, rel=0.03, abs=0.06)


def test_camera_known_alpha_reference_cells():
    assert cam(0, 10, model="known_alpha").std["f_c"] == pytest.approx(7.2, abs=0.06)
    assert cam(0, 20, model="known_alpha").std["f_c"] == pytest.approx(2.5, abs=0.06)
    assert cam(10, 10, model="known_alpha").std["f_c"] == pytest.approx(4.5, abs=0.06)


@pytest.mark.parametrize("cell,ref", PROJ.items())
def test_projector_reference_table(cell, ref):
    b = projector_bound(KP, rot(*cell), T500, M, 0.2)
    assert b.std["f_p"] == pytest.approx(ref, rel=0.03, abs=0.06)
    assert 2.0 <= b.std["v0p"] < 22


def test_degenerate_poses_are_infinite_not_tiny():
    # camera (f, alpha): psi = 0 or nu = 0; alpha known: only fronto-parallel
    for cell in [(0, 0), (0, 20), (20, 0)]:
        for model in ("full", "known_distortion"):
            b = cam(*cell, model=model)
            assert np.isinf(b.std["f_c"]) and np.isinf(b.std["alpha_c"]), (cell, model)
            assert b.condition < 1e-12
    assert np.isinf(cam(0, 0, model="known_alpha").std["f_c"])
    assert np.isfinite(cam(0, 20, model="known_alpha").std["f_c"])
    # full model without distortion: the COD (= principal point) is unobservable
    b = camera_bound(KC, None, 0.0, 0.0, rot(20, 20), T500, M, 0.1, "full")
    assert np.isinf(b.std["f_c"]) and np.isinf(b.std["u0c"])
    # projector (f, v0): degenerate iff nu_p = 0, whatever psi_p
    for psi in (0, 10, 45):
        assert np.isinf(projector_bound(KP, rot(psi, 0), T500, M).std["f_p"])
    # near-degenerate is large but finite
    assert 300 < projector_bound(KP, rot(10, 0.2), T500, M).std["f_p"] < np.inf


def test_bound_is_linear_in_sigma_and_jacobians_agree():
    a, b = cam(10, 20, sigma=0.1), cam(10, 20, sigma=0.3)
    assert b.std["f_c"] == pytest.approx(3 * a.std["f_c"], rel=1e-9)
    c = cam(10, 20, jacobian="central")
    assert c.std["f_c"] == pytest.approx(a.std["f_c"], rel=1e-4)
    assert c.std["k1"] == pytest.approx(a.std["k1"], rel=1e-4)


def test_distinct_cod_and_principal_point_is_accepted():
    b = camera_bound(KC, (680.0, 500.0), K1, 0.0, rot(20, 20), T500, M, 0.1, "full")
    assert np.isfinite(b.std["f_c"]) and b.std["f_c"] == pytest.approx(cam(20, 20).std["f_c"], rel=0.2)
    with pytest.raises(ValueError):
        cam(20, 20, model="nonsense")


def test_projector_bound_matches_monte_carlo_ml_estimate():
    """The ML fit of (f, v0, pose) reaches the bound (METHOD §13: 'the projector LM reaches the CRLB')."""
    R, sigma = rot(10, 13), 0.2
    bound = projector_bound(KP, R, T500, M, sigma)
    clean = project(KP, R, T500, M)
    u0, alpha = KP[0, 2], KP[1, 1] / KP[0, 0]
    rv0 = np.zeros(3)

    def residual(p, obs):
        from procam.models import rvec_to_matrix

        K = intrinsic_matrix(p[0], u0, p[1], alpha)
        return (project(K, rvec_to_matrix(p[2:5]) @ R, p[5:8], M) - obs).ravel()

    rng = np.random.default_rng(7)
    fs = []
    for _ in range(150):
        obs = clean + rng.normal(0, sigma, clean.shape)
        sol = least_squares(residual, np.r_[KP[0, 0], KP[1, 2], rv0, T500], args=(obs,), method="lm",
                            x_scale="jac")
        fs.append(sol.x[0])
    sd = np.std(fs, ddof=1)
    # 150 trials: the sample std is within ~ +-12 % (2 sigma) of the truth
    assert sd == pytest.approx(bound.std["f_p"], rel=0.2)
    assert abs(np.mean(fs) - KP[0, 0]) < 3 * bound.std["f_p"] / np.sqrt(150) + 1.0


def test_extrinsics_bound():
    Rc, Rp = rot(20, 20), rot(10, 13)
    tp = np.array([170.0, 40.0, 520.0])
    cb, pb = cam(20, 20), projector_bound(KP, Rp, tp, M, 0.2)
    e = extrinsics_bound(cb, pb, Rc, T500, Rp, tp)
    assert np.all(np.isfinite(e.T)) and np.all(e.T > 0)
    assert e.sigma_T == pytest.approx(np.sqrt(np.sum(e.T ** 2)))
    assert 0 < e.T_norm <= e.sigma_T + 1e-12
    assert np.all(e.euler_deg < 1.0)
    # bounds grow when the projector pose gets closer to degenerate
    e2 = extrinsics_bound(cb, projector_bound(KP, rot(10, 3), tp, M, 0.2), Rc, T500, rot(10, 3), tp)
    assert e2.sigma_T > e.sigma_T
    dead = extrinsics_bound(cb, projector_bound(KP, rot(10, 0), tp, M), Rc, T500, rot(10, 0), tp)
    assert np.isinf(dead.sigma_T)


def test_bound_is_computed_on_the_model_the_solver_fits():
    """The bound's observation model is the single-pose solver's (procam.models.camera_predict /
    projector_predict): it equals the inverse Fisher information built from the solver's own prediction
    function at the truth (the rotation parameterisations differ -- a rotation vector vs a small rotation
    about the truth -- which leaves the intrinsics' bounds unchanged)."""
    from procam import models
    from procam import uncertainty as unc

    R = rot(20, 20)
    b = cam(20, 20)
    p = np.r_[KC[0, 0], KC[1, 1] / KC[0, 0], KC[0, 2], KC[1, 2], K1 * models.KAPPA_SCALE ** 2, 0.0,
              models.matrix_to_rvec(R), T500]
    J = unc.jacobian(lambda q: models.camera_predict(q, M).ravel(), p, method="complex")
    s = unc.std(unc.covariance(J, 0.1))
    for k, key in enumerate(("f_c", "alpha_c", "u0c", "v0c")):
        assert s[k] == pytest.approx(b.std[key], rel=1e-6), key
    assert s[4] / models.KAPPA_SCALE ** 2 == pytest.approx(b.std["k1"], rel=1e-6)
    Kp = intrinsic_matrix(2421.0, 960.0, 1065.0)  # the solver's projector model has alpha_p = 1
    Rp, tp = rot(10, 13), np.array([170.0, 40.0, 520.0])
    pb = projector_bound(Kp, Rp, tp, M, 0.2)
    q = np.r_[Kp[0, 0], Kp[1, 2], models.matrix_to_rvec(Rp), tp]
    Jp = unc.jacobian(lambda v: models.projector_predict(v, M, 960.0).ravel(), q, method="complex")
    sp_ = unc.std(unc.covariance(Jp, 0.2))
    assert sp_[0] == pytest.approx(pb.std["f_p"], rel=1e-6) and sp_[1] == pytest.approx(pb.std["v0p"], rel=1e-6)


@pytest.mark.parametrize("k1,angles", [(-1e-7, (20.0, 20.0, 0.0)), (0.0, (20.0, 20.0, 0.0)), (-1e-7, (2.0, 1.0, 0.0))])
def test_prior_when_needed_is_the_solvers_rule(k1, angles):
    """pp_prior_when='needed' gives the data-only bound where it pins the principal point to within the prior's
    std, else the bound with the prior -- the same numbers as choosing by hand, from one Jacobian."""
    K = intrinsic_matrix(1539.0, 674.0, 512.0, alpha=1.004)
    R = euler_to_matrix(*np.radians(angles))
    obj = object_points(10, 6, 24.0)
    args = (K, None, k1, 0.0, R, [0, 0, 500], obj)
    free = camera_bound(*args, jacobian="central")
    with_prior = camera_bound(*args, jacobian="central", pp_prior_std=32.0)
    auto = camera_bound(*args, jacobian="central", pp_prior_std=32.0, pp_prior_when="needed")
    pinned = bool(np.isfinite(free.std["u0c"]) and max(free.std["u0c"], free.std["v0c"]) <= 32.0)
    expected = free if pinned else with_prior
    assert auto.prior_used == (not pinned) and with_prior.prior_used and not free.prior_used
    assert auto.std == expected.std and np.array_equal(auto.cov, expected.cov)
