"""Which corners a single-pose fit may use: input checks and iterative outlier rejection.

Generic over the device: :func:`fit_robust` takes a ``fit(used_mask) -> solution`` and a
``predict(solution) -> (N, 2)`` and returns the fit on the corners it keeps.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .. import models
from ..errors import CalibrationError
from ..stats import robust_sigma
from ..verdict import rejection_message


def clean(obj_pts, img_pts, what):
    """``(obj (N, 3), img (N, 2), finite mask (N,))`` from board points (N, 2|3) and image points (N, 2)."""
    obj = np.asarray(obj_pts, float)
    if obj.ndim != 2 or obj.shape[1] not in (2, 3):
        raise CalibrationError(f"{what}: board points must be (N, 2) or (N, 3), got {obj.shape}")
    if obj.shape[1] == 2:
        obj = np.column_stack([obj, np.zeros(len(obj))])
    img = np.asarray(img_pts, float).reshape(-1, 2)
    if len(img) != len(obj):
        raise CalibrationError(f"{what}: {len(obj)} board points but {len(img)} image points")
    mask = np.isfinite(obj).all(1) & np.isfinite(img).all(1)
    return obj, img, mask


@dataclass(frozen=True)
class RobustOptions:
    """Which corners a single-pose fit uses: the minimum it needs and the outlier rejection.

    After the fit, corners whose residual norm exceeds ``max(floor_px, k * sigma_r)`` are rejected and
    the device is refitted without them, until the set is stable (at most ``max_iter`` refits; a
    rejected corner comes back if a later fit explains it). ``sigma_r`` = 1.4826 MAD of the residual
    components (a robust noise estimate). With Gaussian noise a clean corner exceeds ``k sigma`` with
    probability ``exp(-k^2 / 2)`` (4e-6 for the default k = 5; the floor of 0.5 px keeps every corner of
    clean, low-noise data). Nothing is rejected when more than ``max_fraction`` of the corners would be:
    then the model, not a few corners, is wrong, and a warning says so.

    Attributes
    ----------
    reject_outliers : bool, turn the rejection on (default) or off.
    k, floor_px, max_fraction, max_iter : the rule above.
    min_points : minimum number of usable corners of a device (and their spread: not all on one line).
    """

    reject_outliers: bool = True
    k: float = 5.0
    floor_px: float = 0.5
    max_fraction: float = 0.2
    max_iter: int = 5
    min_points: int = 8


def spread_ok(xy, rel_tol: float = 1e-12) -> bool:
    """True unless the planar points (n, 2) are collinear or all but one are (no homography then).

    The test is on the eigenvalues of the 2x2 scatter matrix of the points, and of the points with
    each one left out (rank-one downdates, O(n)): ``lambda_min <= rel_tol * lambda_max`` is a line.
    """
    xy = np.asarray(xy, float).reshape(-1, 2)
    n = len(xy)
    if n < 4:
        return False

    def flat(S, Q, k):
        m = S / k
        C = Q / k - m[..., :, None] * m[..., None, :]
        tr = C[..., 0, 0] + C[..., 1, 1]
        det = C[..., 0, 0] * C[..., 1, 1] - C[..., 0, 1] * C[..., 1, 0]
        disc = np.sqrt(np.maximum(tr * tr / 4 - det, 0.0))
        lmax, lmin = tr / 2 + disc, tr / 2 - disc
        return lmin <= rel_tol * np.maximum(lmax, 1e-300)

    xy = xy - xy.mean(axis=0)
    S, Q = xy.sum(axis=0), xy.T @ xy
    if flat(S, Q, n):
        return False
    leave_one = flat(S - xy, Q - xy[:, :, None] * xy[:, None, :], n - 1)
    return not bool(np.any(leave_one))


def check_corners(obj, mask, min_points: int, name: str, what: str, hint: str) -> None:
    """Raise :class:`CalibrationError` (saying how many corners are usable and needed) unless the
    usable corners ``obj[mask]`` can determine a single-pose fit."""
    n, n_all = int(mask.sum()), len(mask)
    need = (f"single-pose calibration needs at least {max(min_points, 4)}, spread over at least 2 rows and "
            f"2 columns of the board")
    if n < min_points:
        raise CalibrationError(f"pose {name!r}: only {n} of {n_all} {what} are usable; {need}; {hint}")
    if not spread_ok(obj[mask, :2]):
        raise CalibrationError(f"pose {name!r}: the {n} usable {what} all (or all but one) lie on one line of the "
                               f"board (e.g. one row or column); {need}; {hint}")


def _prescreen(obj, obs, valid, k: float, floor_px: float):
    """Corners consistent with a least-median-of-squares homography board -> image: ((N,) bool, robust
    sigma of the homography's residuals in px), or (None, nan).

    Only a rescue start for poses whose plain fit is wrecked by gross outliers (hundreds of px): the
    threshold ``max(floor, k * robust sigma)`` of the homography residuals is wide enough for lens
    distortion, and every corner is re-tested against the real model afterwards.
    """
    import cv2

    src, dst = obj[valid, :2].astype(np.float64), obs[valid].astype(np.float64)
    try:
        H, _ = cv2.findHomography(src, dst, cv2.LMEDS)
    except cv2.error:
        return None, float("nan")
    if H is None or not np.all(np.isfinite(H)):
        return None, float("nan")
    with np.errstate(all="ignore"):
        r = models.apply_homography(H, src) - dst
        norm = np.hypot(r[:, 0], r[:, 1])
    sig = robust_sigma(r)
    keep = norm <= max(floor_px, k * sig)
    out = np.zeros_like(valid)
    out[np.flatnonzero(valid)[keep]] = True
    return out, sig


def fit_robust(fit, predict, obs, obj, valid, opts: RobustOptions):
    """Fit, flag corners whose residual norm exceeds ``max(floor_px, k * robust_sigma)``, refit without
    them, repeat until the set of used corners is stable (at most ``max_iter`` refits).

    ``fit(used_mask) -> solution``; ``predict(solution) -> (N, 2)`` for every row. Rejected corners are
    re-tested against every new fit (a corner pulled off by a gross outlier comes back). Nothing is
    rejected when more than ``max_fraction`` of the corners would be (the model, not a few corners,
    is wrong), or when the rest would be too few or degenerate. When the plain fit fails, flags
    outliers, or fits worse than a plain homography (gross outliers wrecked it), a second start
    without the corners a robust (LMedS) homography calls outliers competes with it.

    Returns (solution, used (N,) bool, threshold_px, notes list of str).
    """
    k, floor_px, max_fraction, max_iter, min_points = opts.k, opts.floor_px, opts.max_fraction, opts.max_iter, \
        opts.min_points
    if not opts.reject_outliers:
        return fit(valid), valid, float("nan"), []
    n_valid = int(valid.sum())

    def flag(sol):
        with np.errstate(all="ignore"):
            res = predict(sol) - obs
            norm = np.hypot(res[:, 0], res[:, 1])
        thr = max(float(floor_px), float(k) * robust_sigma(res[valid]))
        return valid & (norm <= thr), thr          # NaN (unpredictable) counts as an outlier

    def too_many(mask):
        return n_valid - int(mask.sum()) > max_fraction * n_valid

    def median_residual(sol):
        with np.errstate(all="ignore"):
            res = predict(sol) - obs
            norm = np.hypot(res[valid, 0], res[valid, 1])
        return float(np.median(np.where(np.isfinite(norm), norm, np.inf)))

    error = None
    try:
        sol, used = fit(valid), valid.copy()
    except CalibrationError as e:
        sol, used, error = None, valid.copy(), e
    # a second start without the corners a robust homography calls outliers (outliers can wreck the
    # COD, the closed forms and the LM starts) when the plain fit failed, flags outliers or fits worse
    # than a homography; the start with the lower median residual over all corners (least median of
    # squares) wins, and every corner is re-tested below
    pre, sig_h = _prescreen(obj, obs, valid, k, floor_px)
    suspicious = sol is None
    if not suspicious:
        with np.errstate(all="ignore"):
            sig_m = robust_sigma(predict(sol)[valid] - obs[valid])
        suspicious = bool(flag(sol)[0].sum() < n_valid or not sig_m <= 2.0 * sig_h + 1e-9)
    if suspicious and pre is not None and min_points <= pre.sum() < n_valid and spread_ok(obj[pre, :2]):
        try:
            sol2 = fit(pre)
            if sol is None or median_residual(sol2) < median_residual(sol):
                sol, used = sol2, pre
        except CalibrationError:
            pass
    if sol is None:
        raise error
    seen = {used.tobytes()}
    notes: list[str] = []
    thr = float("nan")
    for it in range(max_iter + 1):
        new, thr_i = flag(sol)
        if too_many(new):
            notes.append(f"{n_valid - int(new.sum())} of {n_valid} corners have residuals above {thr_i:.2f} px: "
                         f"the model does not fit this pose well (not a few outliers), so no corner was rejected")
            if used.sum() < n_valid:      # an earlier pass rejected some: go back to all corners
                try:
                    sol, used = fit(valid), valid.copy()
                except CalibrationError:
                    pass
            thr = thr_i
            break
        if int(new.sum()) < min_points or not spread_ok(obj[new, :2]):
            break
        thr = thr_i
        if np.array_equal(new, used) or new.tobytes() in seen or it == max_iter:
            break
        try:
            sol_new = fit(new)
        except CalibrationError:
            break
        sol, used = sol_new, new
        seen.add(new.tobytes())
    return sol, used, thr, notes


def rejection_report(sol, predict, obs, valid, used, thr, notes, name: str, what: str, opts: RobustOptions,
                     max_list: int = 8):
    """The solution with all valid corners' residuals, the rejected corners and their warning (the words
    :func:`procam.verdict.rejection_message` makes of the data kept in ``info["rejection"]``, so a renumbering of the corners
    re-words it from the data: :func:`procam.board.labelling.given_labelling`)."""
    with np.errstate(all="ignore"):
        res = obs - predict(sol)  # observed - predicted, as documented on the solutions
    res[~valid] = np.nan
    rej = np.flatnonzero(valid & ~used)
    norms = np.hypot(res[rej, 0], res[rej, 1])
    words = {"name": name, "what": what, "n_valid": int(valid.sum()), "n_used": int(used.sum()),
             "threshold_px": float(thr), "floor_px": float(opts.floor_px), "k": float(opts.k), "max_list": max_list}
    warnings = list(sol.warnings)
    msg = rejection_message(rej, norms, words)
    if msg:
        warnings.append(msg)
    warnings += [f"pose {name!r}: {what}: {n}" for n in notes]
    return replace(sol, residuals=res, rejected=rej, rejected_residuals_px=norms, outlier_threshold_px=float(thr),
                   warnings=tuple(warnings), info={**(sol.info or {}), "rejection": words})
