"""The one place for Jacobians and covariances (solvers' ``±``, Cramer-Rao bounds, the delta method).

For residuals ``r(p)`` (m,) with i.i.d. Gaussian noise of standard deviation sigma, the
Gauss-Newton covariance of the least-squares estimate is ``Cov = sigma^2 (J^T J)^-1`` with
``J = dr/dp``. sigma is estimated from the residuals as ``sqrt(sum r^2 / (m - n))``. Evaluated at
the ground truth with the true sigma this is the Cramer-Rao bound (:mod:`procam.crlb`); evaluated at an
estimate it is the usual "parameter +- std" of a calibration: 1 sigma **under the model**, assuming
the model is right and the corner noise i.i.d.

The one degeneracy rule (every solver's covariance, plain or forward-mode Jacobian, the bounds of
:mod:`procam.crlb`): the Jacobian of the residuals in noise sigmas, prior rows included, has its columns
normalised to unit norm; if its condition ``s_min / s_max`` (singular values, :func:`condition`) is at or
below :data:`RCOND` = 1e-9 the covariance is infinite (``inv``, never ``pinv``: a pseudo-inverse silently
reports tiny errors for degenerate poses).  The covariance is computed from that SVD, never by inverting
the normal matrix ``J^T J``, whose eigenvalue ratio is the square of the condition (1e-18 at the limit) and
which loses twice the digits: a solver that works on ``J^T J`` must use ``RCOND ** 2`` on its eigenvalues.
(The single-pose joint fit inverted ``J^T J`` with an eigenvalue limit of 1e-14, i.e. a condition of 1e-7,
before it called :func:`covariance`: its fits in ``benchmarks/real_projector.py`` have conditions of 4e-7 or more,
or are exactly singular, so the one limit changes none of them; the limit stays at 1e-9 because the single-pose
projector's fit, with central differences, reaches conditions from 1e-9 to 1e-8 at near-degenerate poses in
the tests, which a limit of 1e-7 would turn infinite.)
"""

from __future__ import annotations

from typing import Callable

import numpy as np

#: The degeneracy rule's limit (module docstring): ``s_min / s_max`` of the column-normalised Jacobian at or below
#: which a covariance is infinite.
RCOND = 1e-9

#: Imaginary step of complex-step derivatives (exact to rounding for analytic functions).
COMPLEX_STEP = 1e-30


def jacobian(fun: Callable[[np.ndarray], np.ndarray], p, *, method: str = "central", rel_step: float = 1e-6,
             typical=1.0) -> np.ndarray:
    """Jacobian ``d fun / d p`` (m, n).

    Parameters
    ----------
    fun : callable ``(n,) -> (m,)``; with ``method="complex"`` it must accept complex parameters and be
        analytic in them.
    p : (n,) point.
    method : ``"central"`` -- central differences with the step of parameter k
        ``rel_step * max(typical_k, |p_k|)``; ``"complex"`` -- complex-step derivatives
        ``Im(fun(p + i h e_k)) / h`` with ``h = 1e-30``, exact to rounding (keeps degeneracy tests clean:
        at an exactly degenerate pose the condition is ~1e-15 with complex steps, ~1e-10..1e-8 with
        central differences).
    typical : scalar or (n,), the parameters' typical magnitudes (central differences only).

    >>> J = jacobian(lambda q: np.array([q[0] ** 2 * q[1], np.sin(q[1])]), np.array([3.0, 0.5]), method="complex")
    >>> J.round(6).tolist()
    [[3.0, 9.0], [0.0, 0.877583]]
    """
    p = np.asarray(p, float).reshape(-1)
    cols = []
    if method == "complex":
        for k in range(p.size):
            dp = np.zeros(p.size, dtype=complex)
            dp[k] = 1j * COMPLEX_STEP
            cols.append(np.imag(np.asarray(fun(p + dp))).reshape(-1) / COMPLEX_STEP)
    elif method == "central":
        typ = np.broadcast_to(np.asarray(typical, float), p.shape)
        for k in range(p.size):
            h = rel_step * max(float(typ[k]), abs(p[k]))
            dp = np.zeros_like(p)
            dp[k] = h
            fp = np.asarray(fun(p + dp), float).reshape(-1)
            fm = np.asarray(fun(p - dp), float).reshape(-1)
            cols.append((fp - fm) / (2 * h))
    else:
        raise ValueError(f"method must be 'central' or 'complex', got {method!r}")
    return np.column_stack(cols) if cols else np.zeros((np.asarray(fun(p)).size, 0))


def sigma_from_residuals(residuals, n_params: int) -> float:
    """Noise estimate ``sqrt(sum r^2 / (m - n))`` from the (m,) residual vector (NaN if m <= n)."""
    r = np.asarray(residuals, float).reshape(-1)
    dof = r.size - n_params
    return float(np.sqrt(np.sum(r * r) / dof)) if dof > 0 else float("nan")


def _weighted(J, sigma, prior_precision):
    Ja = np.asarray(J, float) / max(float(sigma), 1e-300)
    if prior_precision is not None:
        P = np.asarray(prior_precision, float)
        P = np.diag(P) if P.ndim == 1 else P
        w, V = np.linalg.eigh(P)
        Ja = np.vstack([Ja, (V * np.sqrt(np.clip(w, 0, None))).T])
    return Ja


def condition(J) -> float:
    """``s_min / s_max`` of the column-normalised (m, n) matrix ``J`` (0 for a zero or non-finite column)."""
    J = np.asarray(J, float)
    if J.shape[1] == 0:
        return 1.0
    d = np.linalg.norm(J, axis=0)
    if not np.all(np.isfinite(J)) or np.any(d == 0):
        return 0.0
    s = np.linalg.svd(J / d, compute_uv=False)
    return float(s[-1] / s[0]) if len(s) >= J.shape[1] else 0.0


def covariance(J, sigma: float, *, prior_precision=None, rcond: float = RCOND) -> np.ndarray:
    """``Cov = (J^T J / sigma^2 + P)^-1`` (n, n); all-infinite if the problem is (near-)singular.

    Parameters
    ----------
    J : (m, n) Jacobian of the residuals (pixels per parameter unit).
    sigma : float
        Standard deviation of one residual component (px).
    prior_precision : (n,) or (n, n), optional
        Information from a Gaussian prior on some parameters (``1 / prior_std^2`` on the diagonal,
        0 elsewhere). A prior makes an otherwise unobservable parameter's uncertainty finite and
        propagates it into the others (used for a principal point assumed, not measured).
    rcond : float
        Threshold on ``s_min / s_max`` of the column-normalised information matrix's square root.

    >>> X = np.column_stack([np.ones(4), [0.0, 1, 2, 3]])
    >>> bool(np.allclose(covariance(X, 0.5), 0.25 * np.linalg.inv(X.T @ X)))
    True
    """
    J = np.asarray(J, float)
    n = J.shape[1]
    if not np.all(np.isfinite(J)) or not np.isfinite(sigma):
        return np.full((n, n), np.inf)
    Ja = _weighted(J, sigma, prior_precision)
    d = np.linalg.norm(Ja, axis=0)
    if np.any(d == 0):
        return np.full((n, n), np.inf)
    try:
        _, s, Vt = np.linalg.svd(Ja / d, full_matrices=False)
    except np.linalg.LinAlgError:  # the SVD did not converge: nothing to report but that
        return np.full((n, n), np.inf)
    if len(s) < n or s[-1] <= rcond * s[0]:
        return np.full((n, n), np.inf)
    cov_n = (Vt.T / s ** 2) @ Vt
    return cov_n / np.outer(d, d)


def std(cov) -> np.ndarray:
    """Standard deviations (n,) from a covariance (inf stays inf)."""
    c = np.asarray(cov, float)
    with np.errstate(invalid="ignore"):
        return np.sqrt(np.abs(np.diag(c)))


def propagate(cov, fun: Callable[[np.ndarray], np.ndarray], p, **jac_kw) -> np.ndarray:
    """Delta method: covariance of ``fun(p)`` given ``Cov(p)``: ``G Cov G^T`` with ``G = dfun/dp``
    (:func:`jacobian`, keyword options passed on)."""
    cov = np.asarray(cov, float)
    G = jacobian(fun, p, **jac_kw)
    if not np.all(np.isfinite(cov)):
        m = G.shape[0]
        return np.full((m, m), np.inf)
    return G @ cov @ G.T
