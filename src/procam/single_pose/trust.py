"""What the dense single-pose fit (:mod:`.dense`) trusts: errors a decoder makes alike on many windows at once.

A decoder's errors are not all independent noise. Two kinds, which no measured noise scale and no block jackknife
sees (issue 38, ``benchmarks/sigma_rigs.py``):

* at the **rim** of what was decoded on the board (the board's edge, the edge of the region the projector lights)
  a window is partly dark or its fringes cut by the panel's edge: an error alike on every window there, a large
  share of the samples on a small or partly lit board. :func:`rim` finds it, :func:`rim_shift` tests whether the
  fit without it moves beyond its own noise;
* a **systematic phase error** (the harmonic a projector's gamma leaves in a 3-step phase shift) is alike on
  neighbouring windows: :func:`batch_inflation` measures how many times over their noise then counts.

And one the user's own file can carry: a given camera whose lens model does not quite fit this pose leaves a smooth
pattern in its corners' residuals; :func:`camera_pattern` measures what it moves the projector by, which then joins
the ± (the pattern counts by what it does to the results, not by itself).
"""

from __future__ import annotations

import numpy as np

from ..stats import robust_sigma
from . import joint as J


def rim(cam_pts, window: float, rings: int, alive=None) -> np.ndarray:
    """(M,) True for the samples at camera pixels ``cam_pts`` (M, 2) on a grid of ``window`` px within ``rings``
    windows of the edge of the sampled region (a sample missing one of its eight grid neighbours is on the edge);
    only the samples ``alive`` (M,) bool count (default all), the others are never on it."""
    from scipy.spatial import cKDTree

    pts = np.asarray(cam_pts, float)
    alive = np.ones(len(pts), bool) if alive is None else np.asarray(alive, bool)
    out = np.zeros(len(pts), bool)
    idx = np.flatnonzero(alive)
    if rings <= 0 or len(idx) < 9 or window <= 1:
        return out
    near = cKDTree(pts[idx]).query_ball_point(pts[idx], 1.5 * float(window))
    edge = np.array([len(n) < 9 for n in near])           # itself and eight neighbours
    for _ in range(rings - 1):
        edge = edge | np.array([edge[n].any() for n in near])
    out[idx] = edge
    return out


def rim_shift(fit: J.JointFit, model: J.JointModel, on_rim, alarm: float) -> np.ndarray | None:
    """The move (free parameters) of the fit when the rim's board samples are left out (linearised), when it is
    beyond what the noise allows at ``alarm`` (a chi-square on the move's own covariance); None when the rim agrees
    (or there is too little of it, or too little besides it)."""
    from scipy.special import chdtri

    d = model.data
    rb = on_rim[model.keep_board]
    if rb.sum() < 10 or (~rb).sum() < 50:
        return None
    n_cam, n_bg = len(d.cam), int(model.keep_back.sum())
    n_pri = (2 if (d.pp_prior is not None and d.camera_fixed is None) else 0) + len(d.priors)
    m = np.concatenate([np.zeros(2 * n_cam, bool), rb, rb, np.zeros(n_bg + n_pri, bool)])
    Jm, r = fit.jac, fit.residuals
    if len(m) != len(r):
        return None
    s = np.linalg.norm(Jm, axis=0)
    s = np.where(s > 0, s, 1.0)
    Jn = Jm / s
    A = Jn.T @ Jn
    Jb = Jn[m]
    try:
        A_out_inv = np.linalg.inv(A - Jb.T @ Jb)
        delta = A_out_inv @ (Jb.T @ r[m])                     # the fit without the rim, minus the fit
        C_delta = A_out_inv - np.linalg.inv(A)                 # its noise (normalised units)
    except np.linalg.LinAlgError:
        return None
    w, V = np.linalg.eigh((C_delta + C_delta.T) / 2)
    keep = w > w.max() * 1e-9
    stat = float(np.sum((V[:, keep].T @ delta) ** 2 / w[keep]))
    if not keep.any() or stat <= float(chdtri(int(keep.sum()), alarm)):
        return None
    return delta / s


def batch_inflation(model: J.JointModel, p, window: float, cell_windows: int) -> float:
    """How many times the board samples' noise counts when their errors are correlated over neighbouring windows
    (batch means): the residuals' means over cells of ``cell_windows`` x ``cell_windows`` windows, squared and
    times their counts, against the residuals' variance -- 1 for independent errors; the larger of the two axes,
    when beyond what chance gives (3 sigma of a chi-square over the cells), else 1."""
    if cell_windows <= 0 or window <= 1 or not model.keep_board.any():
        return 1.0
    _, br, _, _ = model.blocks(p)
    d = model.data
    res = np.column_stack(br) / d.board_w[model.keep_board][:, None]
    cell = np.floor(d.board_cam[model.keep_board] / (cell_windows * float(window))).astype(int)
    _, inv = np.unique(cell, axis=0, return_inverse=True)
    inv = np.ravel(inv)
    n = np.bincount(inv)
    ok = n >= max(2, cell_windows * cell_windows // 2)
    if ok.sum() < 20:
        return 1.0
    phi = 0.0
    for a in range(2):
        r = res[:, a] - np.median(res[:, a])
        sig2 = robust_sigma(r) ** 2
        if not sig2 > 0:
            return 1.0
        m = np.bincount(inv, r) / n
        phi = max(phi, float(np.mean(n[ok] * m[ok] ** 2) / sig2))
    return phi if phi > 1 + 3 * np.sqrt(2 / ok.sum()) else 1.0


def camera_pattern(model: J.JointModel, p, free) -> tuple[dict | None, np.ndarray | None]:
    """A given camera's corner residuals tested for a smooth pattern (:func:`procam.single_pose.misfit.misfit`: its
    lens model not quite this pose's) and what that pattern moves the fit by: the pattern, a quadratic of the camera
    pixel fitted to the corners' residuals, taken as an error of the camera pixels on the board (its corners and the
    board samples), through the fit's own sensitivity (``-(J^T J)^-1 J^T dr``):
    ``(DenseFit.camera_pattern, the shift (P,) over :attr:`~procam.single_pose.joint.JointModel.names`)``;
    ``(None, None)`` without a pattern."""

    from .misfit import misfit

    d = model.data
    cam_res = np.column_stack(model.blocks(p)[0])                 # (N, 2) observed - predicted, px
    mf = misfit(d.obj[:, :2], cam_res, device="camera", floor_px=0.1) if len(d.obj) >= 15 else None
    if mf is None or not mf.model_error:
        return None, None
    centre, scale = d.cam.mean(axis=0), np.maximum(np.ptp(d.cam, axis=0), 1.0)

    def design(uv):
        x, y = ((uv - centre) / scale).T
        return np.column_stack([np.ones_like(x), x, y, x * x, x * y, y * y])

    coef = np.linalg.lstsq(design(d.cam), cam_res, rcond=None)[0]
    coef[0] = 0.0                                                 # a shift of every pixel is the pose's, not a pattern

    def moved(uv):
        return uv - design(uv) @ coef if len(uv) else uv

    # the board's pixels only: a quadratic fitted over the board says nothing of the wall beyond it
    shifted = model.on(cam=moved(d.cam), board_cam=moved(d.board_cam))
    r, Jm, cov = J.linearise(model, p, free)
    dr = shifted.residuals(np.asarray(p, float)) - r
    idx = np.flatnonzero([nm in free for nm in model.names])
    shift = np.zeros(len(model.names))
    with np.errstate(invalid="ignore"):
        shift[idx] = -cov[np.ix_(idx, idx)] @ (Jm.T @ dr)
    out = {k: float(shift[J.IDX[k]]) for k in ("f_p", "u0p", "v0p", "ptx", "pty", "ptz")}
    out.update(field_rms_px=float(mf.field_rms_px), message=mf.message)
    return out, shift


def contradicted(p, priors) -> bool:
    """Does the estimate ``p`` sit more than 3 of a prior's sigmas from its mean (any prior ``(name, mean, std)`` but
    the decentrings')? Then the prior forces the model wrong everywhere, the rim included: a rim that disagrees
    says nothing of the decoder."""
    return any(abs(p[J.IDX[n]] - mu) > 3 * sd for n, mu, sd in priors if n not in J.DECENTRING)


def demanded(extra: int, cost: float, richer_cost: float, alarm: float = 1e-3) -> bool:
    """Does the likelihood ratio want a richer nested model's ``extra`` terms (its chi-square ``richer_cost`` against
    ``cost``, at ``alarm``)? The held-out test that chooses the lens model is noisier: a model the data demand is
    not excluded from the ± by it (on a rendered scanner pose it kept k1 alone against k1 and k2 by 4.7 % held out,
    where k2 lowered the chi-square by 29, and the ± then missed T by 4.5 of itself)."""
    from scipy.special import chdtri

    return extra > 0 and bool(np.isfinite(richer_cost)) and cost - richer_cost > float(chdtri(extra, alarm))


def background_disagrees(model: J.JointModel, fit: J.JointFit, camera_cov=None) -> str:
    """Why the background does not follow one epipolar geometry, or '' when it does (:mod:`.dense`'s docstring, 7).

    The background samples' mean epipolar distance per quadrant of the camera image (``fit`` the solution of
    ``model`` as it stands) must agree within its noise, a tolerance for a lens no model describes exactly and, for a
    given camera with its covariance ``camera_cov = (names, (k, k))`` (a camera file's), what that camera's own
    uncertainty moves each quadrant by after the fit has adjusted to it (the quadrants far from the board are where
    a camera calibrated from a few photos is least sure); a chi-square at 1e-4 on the quadrants' generalised
    least-squares mean.
    """
    from scipy.special import chdtri

    d = model.data
    _, _, gr, _ = model.blocks(fit.p)
    gr = np.asarray(gr)
    pts = d.back_cam[model.keep_back]
    if len(gr) < 40:
        return ""
    c = np.median(pts, axis=0)
    q = (pts[:, 0] > c[0]).astype(int) + 2 * (pts[:, 1] > c[1])
    sig = model.scales.background
    means, errs, names, masks = [], [], [], []
    for k, name in enumerate(("upper left", "upper right", "lower left", "lower right")):
        m = q == k
        if m.sum() < 10:
            continue
        means.append(float(np.mean(gr[m])))
        # the noise of a quadrant's mean, and a tolerance for a lens no model describes exactly (a tenth of the
        # noise scale, at least 0.02 px)
        errs.append(float(np.hypot(sig / np.sqrt(m.sum()), max(0.1 * sig, 0.02))))
        names.append(name)
        masks.append(m)
    if len(means) < 2:
        return ""
    means, errs = np.array(means), np.array(errs)
    V = np.diag(errs ** 2)
    camera = _camera_share(model, fit, masks, camera_cov)
    if camera is not None:
        if not np.all(np.isfinite(camera)):
            return ""           # a camera known to nothing: the background cannot be judged against it
        V = V + camera
    W = np.linalg.inv(V)
    one = np.ones(len(means))
    mu = float(one @ W @ means / (one @ W @ one))
    res = means - mu
    stat = float(res @ W @ res)
    thr = float(chdtri(len(means) - 1, 1e-4))
    if stat <= thr:
        return ""
    tol = np.sqrt(np.diag(V))
    given = " and the given camera's own uncertainty" if camera is not None else ""
    worst = int(np.argmax(np.abs(res) / tol))
    return (f"the background does not follow one epipolar geometry: its {names[worst]} quadrant sits "
            f"{res[worst]:+.2f} px from the others' epipolar lines (tolerance +-{tol[worst]:.2f} px: the "
            f"decoding noise {sig:.2f} px over {int(masks[worst].sum())} samples, a lens no model describes exactly"
            f"{given}; "
            f"chi-square {stat:.0f} > {thr:.0f}) -- interreflections, "
            "a reflective or moving surface?; the background is left out and the board alone calibrates the "
            "projector")


def _camera_share(model: J.JointModel, fit: J.JointFit, masks, camera_cov) -> np.ndarray | None:
    """(Q, Q) px^2: the covariance of the quadrants' mean epipolar distances (``masks`` over the kept background
    samples) from a given camera's own uncertainty, after the fit's free parameters have adjusted to it; None
    without a given camera and its covariance."""
    if camera_cov is None or model.data.camera_fixed is None or model.cauchy is not None:
        return None
    names, C = camera_cov
    C = np.asarray(C, float)
    if not np.all(np.isfinite(C)):
        return np.full((len(masks), len(masks)), np.inf)
    d = model.data
    Jc = J.held_jacobian(model, fit.p, "camera", names)
    Jm = fit.jac
    left = Jc - Jm @ np.linalg.lstsq(Jm, Jc, rcond=None)[0]        # what the fit's adjustment leaves
    start = 2 * len(d.cam) + 2 * int(model.keep_board.sum())
    wg = d.back_w[model.keep_back] * model.scales.background
    rows = left[start:start + len(wg)] * wg[:, None]               # px per unit of each camera parameter
    G = np.array([rows[m].mean(axis=0) for m in masks])
    return G @ C @ G.T


#: A given projector's intrinsics no longer hold when this pose moves them beyond chance (a chi-square on the move's
#: covariance at this probability, 2 degrees of freedom) AND by more than matters (issue 33's targets for one pose:
#: f_p 0.3 %, the principal point 5 px): a zoom or focus change, which ``R, T`` would otherwise absorb.
GIVEN_ALARM = 1e-6
GIVEN_F_REL = 0.003
GIVEN_PP_PX = 5.0


def given_projector_moved(model: J.JointModel, p, free, device) -> dict | None:
    """Does this pose still agree with a given projector's intrinsics? The fit again with ``f_p`` and ``v0p`` free
    (what one plane determines with ``u0p`` and ``alpha_p`` held: the paper's projector; the given lens held): their
    move from the given values against its covariance (the fit's, plus the projector file's own where it has one).
    A pose turned about the projector's vertical axis determines ``f_p`` to a small fraction of a percent; holding a
    wrong one, the fit moves the projector along its axis instead (a 1 % zoom: ``T`` 5-10 mm off, every residual
    small, the world check at this pose 0.2 px).

    ``model`` the known-projector fit's model, ``p`` its solution, ``free`` its free names, ``device`` the given
    :class:`procam.calibration.Device`. Returns ``{"f_p"|"v0p": (given, this pose, std), "chi2", "limit",
    "moved"}``, or None when the given lens is not OpenCV's (or none) or the fit fails.
    """

    from scipy.special import chdtri

    dist = device.distortion
    coeffs = list(getattr(dist, "coeffs", ()) or ())
    if dist.model not in ("opencv", "none") or any(coeffs[5:]):
        return None
    q = np.asarray(p, float).copy()
    K = np.asarray(device.K, float)
    i = J.IDX
    q[[i["f_p"], i["alpha_p"], i["u0p"], i["v0p"]]] = K[0, 0], K[1, 1] / K[0, 0], K[0, 2], K[1, 2]
    q[[i[t] for t in J.DIST_TERMS]] = (coeffs + [0.0] * 5)[:5]
    m = model.on(projector_fixed=None)
    try:
        fit = J.solve(m, q, tuple(free) + ("f_p", "v0p"), max_nfev=40)
    except (ValueError, np.linalg.LinAlgError):
        return None
    names = ("f_p", "v0p")
    idx = [i[n] for n in names]
    d = fit.p[idx] - q[idx]
    C = fit.cov[np.ix_(idx, idx)].copy()
    if getattr(device, "covariance", None) is not None:     # the file's own uncertainty of the same numbers
        held, Ch = device.covariance
        mine = [a for a, n in enumerate(names) if n in held]
        theirs = [list(held).index(names[a]) for a in mine]
        C[np.ix_(mine, mine)] += np.asarray(Ch, float)[np.ix_(theirs, theirs)]
    if not np.all(np.isfinite(C)) or not np.all(np.isfinite(d)):
        return None
    chi2 = float(d @ np.linalg.pinv(C) @ d)
    limit = float(chdtri(len(names), GIVEN_ALARM))
    s = np.sqrt(np.clip(np.diag(C), 0, None))
    matters = abs(d[0]) > GIVEN_F_REL * q[i["f_p"]] or abs(d[1]) > GIVEN_PP_PX
    out = {n: (float(q[j]), float(fit.p[j]), float(sd)) for n, j, sd in zip(names, idx, s)}
    out.update(chi2=chi2, limit=limit, moved=bool(chi2 > limit and matters))
    return out
