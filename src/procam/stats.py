"""The small statistics every stage shares: RMS, a robust standard deviation, a total-least-squares plane.

One definition each, so that a residual RMS, an outlier threshold or a planarity figure means the same in
the solvers, the background check, the verification and the point clouds.

* :func:`rms` -- root mean square of residual vectors (point distances) or of scalars, non-finite rows skipped;
* :func:`robust_sigma` -- ``1.4826 x`` the median absolute deviation (about the median, or about a given
  centre such as 0 for distances to a fitted model): the standard deviation of Gaussian noise, unmoved by a
  minority of outliers;
* :func:`tls_plane` -- the plane that minimises the sum of squared orthogonal distances (SVD of the centred
  points).
"""

from __future__ import annotations

import numpy as np

#: ``1 / Phi^-1(3/4)``: the median absolute deviation of Gaussian noise times this is its standard deviation.
MAD_TO_SIGMA = 1.4826


def rms(e, dim: int = 2) -> float:
    """Root mean square ``sqrt(sum_i |e_i|^2 / n)`` of residual vectors, skipping non-finite rows.

    Parameters
    ----------
    e : array reshapeable to (N, dim), or a list/tuple of such arrays (pooled).
    dim : 2 (default) for point residuals (the RMS of point distances, pixels), 1 for scalars, 3 for 3-D.

    Returns
    -------
    float
        In the unit of ``e``; NaN when no finite row is left.

    >>> rms([[3.0, 4.0], [0.0, 0.0]])  # sqrt(25 / 2)
    3.5355339059327378
    >>> rms([1.0, -1.0, np.nan], dim=1)
    1.0
    """
    if isinstance(e, (list, tuple)) and e and not np.isscalar(e[0]):
        parts = [np.asarray(a, float).reshape(-1, dim) for a in e]
        e = np.concatenate(parts) if parts else np.zeros((0, dim))
    e = np.asarray(e, float).reshape(-1, dim)
    e = e[np.isfinite(e).all(axis=1)]
    return float(np.sqrt(np.mean(np.sum(e * e, axis=1)))) if len(e) else float("nan")


def robust_sigma(r, *, about: float | None = None) -> float:
    """Robust standard deviation: ``1.4826 * median |r - centre|`` over the finite values.

    Parameters
    ----------
    r : array of any shape. A 2-D array is a set of residual vectors (rows): a row with a non-finite
        component is skipped whole, and the components of the others are pooled.
    about : the centre; default the median of the values (the median absolute deviation), or a given value
        (e.g. ``0.0`` for distances to a model fitted to the same points).

    Returns
    -------
    float
        NaN when no finite value is left.

    >>> robust_sigma([1.0, 2.0, 3.0, 100.0])  # the median |r - 2.5| is 1
    1.4826
    """
    r = np.asarray(r, float)
    r = r[np.isfinite(r).all(axis=1)].ravel() if r.ndim == 2 else r[np.isfinite(r)].ravel()
    if r.size == 0:
        return float("nan")
    centre = float(np.median(r)) if about is None else float(about)
    return float(MAD_TO_SIGMA * np.median(np.abs(r - centre)))


def tls_plane(X):
    """Total-least-squares plane of points ``X`` (N, 3), N >= 3: ``(normal (3,), centroid (3,))``.

    ``normal`` is a unit vector (its sign is the SVD's: orient it as the caller needs); the signed distance of
    a point ``x`` is ``(x - centroid) @ normal``.
    """
    X = np.asarray(X, float).reshape(-1, 3)
    c = X.mean(axis=0)
    _, _, Vt = np.linalg.svd(X - c, full_matrices=False)
    return Vt[-1], c
