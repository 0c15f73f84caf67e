"""Covariance of estimated parameters from the Jacobian of the residuals at the solution.

For residuals ``r(p)`` (m,) with i.i.d. Gaussian noise of standard deviation sigma, the
Gauss-Newton covariance of the least-squares estimate is ``Cov = sigma^2 (J^T J)^-1`` with
``J = dr/dp``. sigma is estimated from the residuals as ``sqrt(sum r^2 / (m - n))``. Evaluated at
the ground truth with the true sigma this is the Cramer-Rao bound (METHOD §13); evaluated at an
estimate it is the usual "parameter +- std" of a calibration.

Degenerate problems: the Jacobian's columns are normalised to unit norm and, if the condition
number ``s_min / s_max`` is below ``rcond`` (default 1e-9), the covariance is reported as infinite
(``inv``, never ``pinv``: a pseudo-inverse silently reports tiny errors for degenerate poses).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

#: Default condition threshold of the column-normalised Jacobian below which Cov is infinite.
RCOND = 1e-9


def numeric_jacobian(fun: Callable[[np.ndarray], np.ndarray], p, *, rel_step: float = 1e-6,
                     typical=1.0) -> np.ndarray:
    """Central-difference Jacobian ``d fun / d p`` (m, n).

    The step of parameter k is ``rel_step * max(typical_k, |p_k|)``; ``typical`` (scalar or (n,))
    is the parameter's typical magnitude (METHOD §13: step 1e-6 max(1, |p_k|)).
    """
    p = np.asarray(p, float).reshape(-1)
    typ = np.broadcast_to(np.asarray(typical, float), p.shape)
    cols = []
    for k in range(p.size):
        h = rel_step * max(float(typ[k]), abs(p[k]))
        dp = np.zeros_like(p)
        dp[k] = h
        fp = np.asarray(fun(p + dp), float).reshape(-1)
        fm = np.asarray(fun(p - dp), float).reshape(-1)
        cols.append((fp - fm) / (2 * h))
    return np.column_stack(cols) if cols else np.zeros((np.asarray(fun(p)).size, 0))


def sigma_from_residuals(residuals, n_params: int) -> float:
    """Noise estimate ``sqrt(sum r^2 / (m - n))`` from the (m,) residual vector (NaN if m <= n)."""
    r = np.asarray(residuals, float).reshape(-1)
    dof = r.size - n_params
    return float(np.sqrt(np.sum(r * r) / dof)) if dof > 0 else float("nan")


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
    """
    J = np.asarray(J, float)
    n = J.shape[1]
    if not np.all(np.isfinite(J)) or not np.isfinite(sigma):
        return np.full((n, n), np.inf)
    Ja = J / max(float(sigma), 1e-300)
    if prior_precision is not None:
        P = np.asarray(prior_precision, float)
        P = np.diag(P) if P.ndim == 1 else P
        w, V = np.linalg.eigh(P)
        Ja = np.vstack([Ja, (V * np.sqrt(np.clip(w, 0, None))).T])
    d = np.linalg.norm(Ja, axis=0)
    if np.any(d == 0):
        return np.full((n, n), np.inf)
    _, s, Vt = np.linalg.svd(Ja / d, full_matrices=False)
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
    """Delta method: covariance of ``fun(p)`` given ``Cov(p)``: ``G Cov G^T`` with ``G = dfun/dp``."""
    cov = np.asarray(cov, float)
    G = numeric_jacobian(fun, p, **jac_kw)
    if not np.all(np.isfinite(cov)):
        m = G.shape[0]
        out = np.full((m, m), np.inf)
        return out
    return G @ cov @ G.T
