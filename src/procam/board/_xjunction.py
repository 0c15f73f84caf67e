"""The model of a chessboard corner that :func:`procam.board.corners.fit_corners` fits, and its fit.

An X-junction -- the corner where two board edges cross -- blurred and unevenly lit::

    I(x) = (1 + g . d) * (a + b * erf(n1 . d / (sqrt(2) s)) * erf(n2 . d / (sqrt(2) s))),   d = x - p

with nine parameters per corner ``(px, py, t1, t2, s, a, b, gx, gy)`` (``n1, n2`` the edge normals at the
angles ``t1, t2``).  :func:`window_samples` cuts the weighted pixels around every corner,
:func:`level_and_contrast` gives the starting ``a, b`` in closed form, :func:`levenberg_marquardt` fits all
corners at once (batched normal equations, one model + Jacobian evaluation per iteration).  Pure numpy
(scipy's ``erf``); see :func:`procam.board.corners.fit_corners` for how the result is judged.
"""

from __future__ import annotations

import numpy as np


def window_samples(f, centre, radius):
    """Pixel grids X, Y (N, n) within ``radius`` of each centre, their values z and weights w."""
    R = int(np.ceil(radius.max()))
    u = np.arange(-R, R + 1, dtype=float)
    U, V = np.meshgrid(u, u)
    near = U * U + V * V <= (R + 0.5) ** 2
    c0 = np.round(centre)
    X = c0[:, :1] + U[near]
    Y = c0[:, 1:] + V[near]
    H, W = f.shape
    inside = (X >= 0) & (X <= W - 1) & (Y >= 0) & (Y <= H - 1)
    z = f[np.clip(Y, 0, H - 1).astype(np.intp), np.clip(X, 0, W - 1).astype(np.intp)].astype(float)
    d2 = (X - centre[:, :1]) ** 2 + (Y - centre[:, 1:]) ** 2
    r = radius[:, None]
    w = np.where(inside & (d2 <= (r + 0.5) ** 2), np.exp(-d2 / (2 * r * r)), 0.0)
    return X, Y, z, w


def model(P, X, Y, jac):
    """:func:`procam.board.corners.fit_corners`' model at the samples (N, n) and, with ``jac``, its Jacobian (N, n, 9)."""
    from scipy.special import erf

    px, py, a1, a2, s, a, b, gx, gy = (P[:, k:k + 1] for k in range(9))
    x, y = X - px, Y - py
    c1, s1, c2, s2 = np.cos(a1), np.sin(a1), np.cos(a2), np.sin(a2)
    d1, d2 = c1 * x + s1 * y, c2 * x + s2 * y
    E1, E2 = erf(d1 / (np.sqrt(2.0) * s)), erf(d2 / (np.sqrt(2.0) * s))
    Q = E1 * E2
    sh = 1.0 + gx * x + gy * y
    base = a + b * Q
    if not jac:
        return sh * base, Q, None
    k = np.sqrt(2.0 / np.pi) / s
    f1 = k * np.exp(-d1 * d1 / (2 * s * s)) * E2  # dQ/dd1
    f2 = k * np.exp(-d2 * d2 / (2 * s * s)) * E1  # dQ/dd2
    sb = sh * b
    J = np.stack([-sb * (f1 * c1 + f2 * c2) - base * gx, -sb * (f1 * s1 + f2 * s2) - base * gy,
                  sb * f1 * (c1 * y - s1 * x), sb * f2 * (c2 * y - s2 * x), -sb * (f1 * d1 + f2 * d2) / s,
                  sh, sh * Q, x * base, y * base], axis=-1)
    return sh * base, Q, J


def level_and_contrast(P, X, Y, z, w):
    """(N, 2) weighted least-squares ``a``, ``b`` for the geometry in ``P`` (no illumination gradient)."""
    _, Q, _ = model(P, X, Y, False)
    sw, swq, swqq = w.sum(1), (w * Q).sum(1), (w * Q * Q).sum(1)
    swz, swqz = (w * z).sum(1), (w * Q * z).sum(1)
    det = sw * swqq - swq * swq
    with np.errstate(divide="ignore", invalid="ignore"):
        ab = np.column_stack([(swqq * swz - swq * swqz) / det, (sw * swqz - swq * swz) / det])
    return np.where(np.isfinite(ab), ab, 0.0)


def levenberg_marquardt(P, X, Y, z, w, active, iterations, tol=1e-4):
    """Weighted Levenberg-Marquardt of :func:`model`, one model + Jacobian evaluation per iteration;
    a corner stops when its position moves less than ``tol`` pixels."""
    P = P.copy()
    active = active.copy()
    sq = np.sqrt(w)
    M, _, J = model(P, X, Y, True)
    res = (z - M) * sq
    J *= sq[..., None]
    cost = np.sum(res * res, 1)
    lam = np.full(len(P), 1e-3)
    eye = np.eye(P.shape[1])
    for _ in range(iterations):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        full = idx.size == len(P)  # every corner still moving: views instead of copies
        Ji = J if full else J[idx]
        Jt = Ji.transpose(0, 2, 1)
        A = np.matmul(Jt, Ji)
        rhs = np.matmul(Jt, res[idx, :, None])[..., 0]
        diag = np.einsum("nii->ni", A)
        A = A + (lam[idx, None] * diag + 1e-12 * diag.max(1, keepdims=True) + 1e-300)[:, :, None] * eye
        with np.errstate(all="ignore"):
            step = np.linalg.solve(A, rhs[..., None])[..., 0]
            Pn = P[idx] + step
            Pn[:, 4] = np.abs(Pn[:, 4])
            Mn, _, Jn = model(Pn, X if full else X[idx], Y if full else Y[idx], True)
            rn = (z if full else z[idx]) - Mn
            rn *= sq if full else sq[idx]
            cn = np.sum(rn * rn, 1)
        better = np.isfinite(cn) & (cn <= cost[idx])
        k = idx[better]
        if full and better.all():
            Jn *= sq[..., None]
            P, cost, res, J = Pn, cn, rn, Jn
        else:
            P[k], cost[k], res[k], J[k] = Pn[better], cn[better], rn[better], Jn[better] * sq[k, :, None]
        lam[idx] = np.where(better, lam[idx] * 0.2, lam[idx] * 10.0)
        done = (better & (np.abs(step[:, :2]).max(1) < tol)) | (lam[idx] > 1e6)
        active[idx[done]] = False
    return P
