"""Does the model fit the data, or only the noise? A misfit test on a fit's residuals over the board.

Residual noise is independent from corner to corner; model error is not: a lens the distortion model does
not describe, a board that is not flat, a projector that distorts, all leave a **smooth field** of residuals
across the board. The test fits such a field -- a quadratic polynomial of the board position per residual
component -- and calls it model error when it explains much more than noise would (an F-test against
independent noise) and is large enough to matter in pixels.

What it cannot see: an error the model's own parameters absorb. With ``u0p`` fixed, the single-pose
projector model has exactly the 8 degrees of freedom of the board's homography, so any ``u0p`` fits the board
perfectly: only correspondences off the board plane (the background) reveal it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..stats import rms


@dataclass(frozen=True)
class Misfit:
    """The misfit test of one device's residuals.

    ``model_error``: the residuals hold a smooth field beyond noise and above ``floor_px``; ``field_rms_px``
    the RMS of that field (px); ``rms_px`` of the residuals; ``explained`` the fraction of the residuals'
    variance the field explains; ``f_statistic`` and ``p_value`` of the F-test against independent noise;
    ``message`` in words (empty when the model fits).
    """

    model_error: bool
    field_rms_px: float
    rms_px: float
    explained: float
    f_statistic: float
    p_value: float
    message: str = ""


def _design(xy: np.ndarray) -> np.ndarray:
    s = np.ptp(xy, axis=0)
    s[s == 0] = 1.0
    u = (xy - xy.mean(axis=0)) / s
    x, y = u[:, 0], u[:, 1]
    return np.column_stack([np.ones_like(x), x, y, x * x, x * y, y * y])


def misfit(obj_xy, residuals, *, device: str = "camera", floor_px: float = 0.1, p_max: float = 1e-4,
           min_explained: float = 0.3) -> Misfit:
    """The misfit test of (N, 2) ``residuals`` (px; NaN rows ignored) at (N, 2) board positions ``obj_xy``.

    Model error when the smooth field is significant (``p < p_max``), explains at least ``min_explained`` of
    the variance, and its RMS is at least ``floor_px`` pixels (smaller fields do not matter, and noise-free
    simulations have tiny structured residuals).
    """
    from scipy.special import fdtrc  # the F distribution's survival function (scipy.stats costs 0.4 s to import)

    xy = np.asarray(obj_xy, float)[:, :2]
    r = np.asarray(residuals, float).reshape(-1, 2)
    ok = np.isfinite(xy).all(1) & np.isfinite(r).all(1)
    xy, r = xy[ok], r[ok]
    n = len(r)
    nan = float("nan")
    if n < 15:
        return Misfit(False, nan, nan, nan, nan, nan, "")
    A = _design(xy)
    coef, *_ = np.linalg.lstsq(A, r, rcond=None)
    field = A @ coef
    ss_tot = float(np.sum((r - r.mean(axis=0)) ** 2))
    ss_res = float(np.sum((r - field) ** 2))
    k = 2 * (A.shape[1] - 1)            # the field's parameters beyond the two means
    dof = 2 * n - 2 * A.shape[1]
    rms_px = rms(r)
    if ss_tot <= 0 or dof <= 0:
        return Misfit(False, 0.0, rms_px, 0.0, nan, nan, "")
    explained = 1.0 - ss_res / ss_tot
    F = (explained / k) / (max(1.0 - explained, 1e-12) / dof)
    p = float(fdtrc(k, dof, F))
    centred = field - field.mean(axis=0)
    field_rms = rms(centred)
    error = bool(p < p_max and explained >= min_explained and field_rms >= floor_px)
    msg = ""
    if error:
        cause = ("the lens distorts in a way the distortion model does not describe (decentring, a stronger or "
                 "wider-angle lens), or the board is not flat" if device == "camera" else
                 "the projector's lens distorts (the single-pose model assumes it does not), or the board is not flat")
        msg = (f"{device}: model error: its residuals form a smooth pattern across the board ({field_rms:.2f} px of "
               f"the {rms_px:.2f} px RMS, {explained:.0%} of the variance; independent noise would leave no pattern): "
               f"{cause}; the ± does not cover this")
    return Misfit(error, field_rms, rms_px, float(explained), float(F), p, msg)
