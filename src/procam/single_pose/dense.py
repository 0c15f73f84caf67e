"""A real projector from one pose: the joint fit of :mod:`.joint`, its lens model chosen by evidence, honest ±.

The single-pose projector of the seed paper assumes ``u0p = W / 2``, ``alpha_p = 1`` and no lens distortion; real
projectors have lens shift (``v0p`` near or beyond the panel's last row, ``u0p`` a few percent off centre) and
radial distortion. This module estimates what one pose's decoded samples determine, uses what the user knows, and
carries everything else into the ``±``:

1. **Start**: the camera from its corners (:mod:`.camera`), the projector from the paper's principal-axis LM on its
   corners; then the projector's pinhole and pose on the board samples with the camera held, then everything.
2. **Noise** is measured per block (camera corners, board samples, background samples): the robust scale of the
   residuals of the richest model; samples beyond ``outlier_k`` scales are left out and the fit repeated. A
   background sample's distance to its epipolar line is measured from here on in the projector's pixels, to first
   order (:attr:`.joint.JointModel.pixel_distance`): measured in normalised coordinates times ``f_p``, a pixel of
   noise moves it by a gain that depends on ``alpha_p`` and the projector's lens, and a fit free to change the gain
   shrinks the noise by moving them, a bias that does not shrink with the noise (``f_c`` 1 % low on a far, narrow
   rig: issue 38's study, case 58). The start keeps the normalised form: from far off, the pixel form let one fit
   of the ``hard`` rig shrink the residuals through ``alpha_p`` to ``f_p`` = 9 px.
3. **What is assumed becomes a prior** whose width is what the assumption can cost: ``alpha_p = 1 ± 0.003``,
   ``u0p = W / 2 ± 3 % of W`` (the spread of real projectors; a datasheet's lens shift replaces it), a datasheet's
   throw ratio on ``f_p``. A prior the data outweigh costs nothing; one they cannot check shows in the ``±``.
4. **The lens model is chosen by held-out error**: each candidate (:data:`MODELS`: none, ``k1``, ``k1 k2``,
   ``k1 k2 k3``, and ``k1 k2 p1 p2`` when asked for) is fitted; the data are split into spatial blocks of the
   camera image and each block's residuals are predicted from the fit without it (the linearised
   leave-one-block-out, from the Jacobian);
   the models within ``model_tolerance`` of the smallest held-out chi-square are those the data cannot tell apart,
   and the simplest of them is the result (more terms than the data ask for trade the principal point against
   tangential distortion).
5. **The ± covers** the fit's noise (the Jacobian), noise that is correlated across neighbouring samples or
   structured by a lens no model describes exactly (the same leave-one-block-out: a block jackknife, used where it
   is larger), the camera's own uncertainty (it is a parameter of the fit), the spread of the indistinguishable
   lens models (and of a richer one whose terms the likelihood ratio demands where the held-out test did not keep
   it, :func:`.trust.demanded`), the priors' widths, and where each lens's distortion is centred (a decentring from
   its principal point, ``decentring_prior_px`` a priori). With the camera given and the background used, the
   background spans the panel and the data see the projector lens's decentring: it is estimated under that prior (a
   lens decentred by a few pixels otherwise drags the principal point onto its distortion centre: 5-7 px on the
   ``hard`` rig, ``benchmarks/camera_once.py``) and written as OpenCV's tangential terms
   (:func:`procam.models.brown_recentred`). Otherwise it is held at zero and freed under its prior for the
   covariance only: the board alone cannot tell it from the principal point, and with the camera estimated too its
   decentring and principal point trade against the projector's (estimating both moved ``benchmarks/
   real_projector.py``'s wall rows from 0.06 % to 0.22 % median f_p error). A decoder's systematic phase error (the
   harmonic a projector's gamma leaves in a 3-step phase shift) is alike on neighbouring windows and, sampled on
   their grid, a pattern across the board the lens models absorb in part; the residuals' means over cells of
   ``batch_windows`` windows tell it (batch means: their spread against the residuals' own, 1 for independent
   errors), and where it is beyond chance the board samples' noise counts that many times over.
6. **What the fit trusts: a board whose rim agrees with the rest of it.** A decoder errs systematically at the
   board's rim and at the edge of the region the projector lights (a window partly dark, fringes cut by the
   panel's edge), an error alike on every window there, which no noise scale and no block jackknife sees, and
   which on a small board (or the lit part of one) is a large share of the samples. The fit without the rim
   (linearised) against the fit tells it, by a chi-square on the move's own noise at ``rim_alarm``; a rim that
   disagrees is left out and the next one in tested, until one agrees: the estimate and its ± are then those of
   the board that agrees with itself (and the notes say how much was left out).
7. **The background must follow one epipolar geometry**: the background samples' mean epipolar distance per
   quadrant of the camera image, against its uncertainty (noise and the lens models' spread); a background that
   fails is left out, with a warning that says by how much, against which tolerance.

Returns a :class:`DenseFit`; :func:`procam.single_pose.calibrate` turns it into the calibration.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .. import models
from ..parameters import ALPHA_PRIOR_STD
from ..stats import robust_sigma
from . import joint as J
from .trust import (background_disagrees, batch_inflation, camera_pattern, contradicted, demanded,
                    given_projector_moved, rim, rim_shift)

#: The projector's lens models tried, simplest first: the distortion terms each frees.
MODELS = {"none": (), "k1": ("k1p",), "k1k2": ("k1p", "k2p"), "k1k2k3": ("k1p", "k2p", "k3p"),
          "k1k2p1p2": ("k1p", "k2p", "p1p", "p2p")}


@dataclass(frozen=True)
class ProjectorPrior:
    """What the user knows of the projector, as Gaussian priors (None = not known).

    throw_ratio, throw_ratio_std : the datasheet's throw ratio (``f_p / W``) and its tolerance (1 sigma).
    shift_h_pct, shift_v_pct, shift_std_pct : the datasheet's lens shift in percent of the image width / height
        (:mod:`procam.datasheet` for the conventions) and its tolerance (1 sigma, percent).
    """

    throw_ratio: float | None = None
    throw_ratio_std: float = 0.02
    shift_h_pct: float | None = None
    shift_v_pct: float | None = None
    shift_std_pct: float = 2.0

    def __post_init__(self):
        for name in ("throw_ratio", "throw_ratio_std", "shift_h_pct", "shift_v_pct", "shift_std_pct"):
            v = getattr(self, name)
            if v is not None and not (isinstance(v, (int, float, np.number)) and np.isfinite(v)):
                raise ValueError(f"projector prior {name} must be a finite number, got {v!r}")
        if self.throw_ratio is not None and not 0.05 <= self.throw_ratio <= 20:
            raise ValueError(f"throw ratio must be from 0.05 to 20, got {self.throw_ratio}")
        if not 0 < self.throw_ratio_std <= 5:
            raise ValueError(f"throw ratio tolerance must be > 0 and <= 5, got {self.throw_ratio_std}")
        for name in ("shift_h_pct", "shift_v_pct"):
            v = getattr(self, name)
            if v is not None and abs(v) > 300:
                raise ValueError(f"lens shift {name[6]} must be within +-300 %, got {v}")
        if not 0 < self.shift_std_pct <= 100:
            raise ValueError(f"lens shift tolerance must be > 0 and <= 100 %, got {self.shift_std_pct}")


@dataclass(frozen=True)
class DenseOptions:
    """Options of the dense projector fit.

    models : the lens models tried (names of :data:`MODELS`); radial ones by default: tangential terms trade
        against the principal point, which a single pose cannot then tell apart (``k1k2p1p2`` is there to ask for).
    alpha_prior_std : ``alpha_p = 1 ±`` this (0 = estimated freely).
    decentring_prior_px : each device's distortion centre is its principal point ± this (px) a priori: the
        projector's estimated under it with the camera given and the background used, held there otherwise with the ±
        including what that costs (module docstring, 5; 0: taken as exact).
    u0_prior_pct : ``u0p = W / 2 ±`` this percent of ``W`` when no datasheet gives the horizontal lens shift.
    prior : :class:`ProjectorPrior` (a datasheet), or None.
    use_background : use the background samples (False: the board alone).
    outlier_k : samples beyond this many noise scales are left out.
    max_samples : at most this many board and this many background samples (an even subsample: beyond a few hundred
        they add time, not information, to a dozen parameters).
    blocks : the camera image is split into ``blocks x blocks`` cells for the held-out error and the jackknife.
    model_tolerance : models whose held-out chi-square exceeds the best's by less than this fraction are ones the
        data cannot tell apart (their spread enters the ±).
    min_samples : fewer board samples: no dense fit.
    rim_windows : the board samples within this many windows of the edge of what was decoded on the board (the
        board's rim, the edge of the region the projector lights) are the rim (0: no rim test).
    rim_alarm : the rim disagrees with the rest of the board when the fit without it moves the parameters further
        than its noise allows with this probability (chi-square); it is then left out (module docstring, 6).
    rim_peels : at most this many rims are left out, one after the other, while the next still disagrees.
    batch_windows : the board samples' errors are tested for correlation over cells of this many windows a side
        (0: not tested; module docstring, 5).
    """

    models: tuple = ("none", "k1", "k1k2", "k1k2k3")
    alpha_prior_std: float = ALPHA_PRIOR_STD
    decentring_prior_px: float = 5.0
    u0_prior_pct: float = 3.0
    prior: ProjectorPrior | None = None
    use_background: bool = True
    outlier_k: float = 4.0
    max_samples: int = 800
    blocks: int = 4
    model_tolerance: float = 0.01
    min_samples: int = 50
    rim_windows: int = 1
    rim_alarm: float = 1e-3
    rim_peels: int = 4
    batch_windows: int = 4

    def __post_init__(self):
        bad = [m for m in self.models if m not in MODELS]
        if not self.models or bad:
            raise ValueError(f"projector lens models must be names of {', '.join(MODELS)}, got {self.models!r}")


@dataclass(frozen=True)
class ModelFit:
    """One lens model's fit: its parameters ``p`` (31,), chi-square ``cost``, held-out chi-square ``held_out``,
    covariance from the Jacobian with the decentrings free under their priors ``cov_fit``, with them held at the
    estimate ``cov_held`` (what the pose determines), and from the block jackknife ``cov_jackknife`` (31, 31)."""

    name: str
    p: np.ndarray
    cost: float
    held_out: float
    cov_fit: np.ndarray
    cov_jackknife: np.ndarray
    n_residuals: int
    free: tuple
    cov_held: np.ndarray | None = None


@dataclass(frozen=True)
class DenseFit:
    """The result of :func:`fit`.

    model : the chosen lens model; p : (31,) its parameters (:data:`procam.single_pose.joint.NAMES`);
    cov : (31, 31) the reported covariance (module docstring, 5); cov_pose : the same without the decentrings'
    cost, what this pose determines (the rating judges the pose by it); fits : every model's :class:`ModelFit`;
    indistinguishable : the models counted in the ±; scales : the measured noise (px) of each block;
    n_board, n_background : samples used; background_used : False when left out (``background_reason`` says why);
    notes : lines for the user (what was estimated, assumed as a prior, left out).
    conflicts : warnings: a prior the data contradict (more than 3 of its sigmas away), said, never kept silently.
    lit_corners : (corners with projector coordinates, corners of the board): the part of the board that speaks
        for the projector; rim_left_out : board samples left out at the rim that disagreed with the rest;
        board_correlation : how many times the board samples' noise counts for their correlated errors (1: none).
    camera_pattern : with the camera given and a smooth pattern in its corners' residuals (its lens model not quite
        this pose's; :mod:`procam.single_pose.misfit`), what the pattern moves the results by -- ``{name: shift}`` for
        ``f_p, u0p, v0p`` (px) and ``ptx, pty, ptz`` (the projector's board position, board units), its
        ``field_rms_px`` and ``message`` -- a shift already in ``cov`` (added as a systematic term); None otherwise.
    given_projector : with the projector given, whether this pose still agrees with its intrinsics
        (:func:`.trust.given_projector_moved`); None otherwise.
    """

    model: str
    p: np.ndarray
    cov: np.ndarray
    fits: dict
    indistinguishable: tuple
    scales: J.Scales
    n_board: int
    n_background: int
    background_used: bool
    background_reason: str = ""
    notes: tuple = ()
    priors: tuple = field(default_factory=tuple)
    conflicts: tuple = ()
    cov_pose: np.ndarray | None = None
    lit_corners: tuple = ()
    rim_left_out: int = 0
    board_correlation: float = 1.0
    camera_pattern: dict | None = None
    given_projector: dict | None = None

    def std(self, name: str, *, pose_only: bool = False) -> float:
        """The reported std of ``name``; ``pose_only``: without what holding the decentrings at zero can cost."""
        C = self.cov_pose if (pose_only and self.cov_pose is not None) else self.cov
        return float(np.sqrt(max(C[J.IDX[name], J.IDX[name]], 0.0)))


def _even(n: int, most: int) -> np.ndarray:
    """Indices of an even subsample of ``n`` items, at most ``most``."""
    if n <= most:
        return np.arange(n)
    return np.round(np.linspace(0, n - 1, most)).astype(int)


def _cells(pix, size, blocks: int) -> np.ndarray:
    W, H = size
    cx = np.clip((pix[:, 0] / W * blocks).astype(int), 0, blocks - 1)
    cy = np.clip((pix[:, 1] / H * blocks).astype(int), 0, blocks - 1)
    return cy * blocks + cx


def _labels(model: J.JointModel, cam_size, blocks: int) -> np.ndarray:
    """The spatial block of every residual row of ``model`` (the order of :meth:`JointModel.residuals`); -1 for the
    priors (they are in every refit)."""
    d = model.data
    lc = _cells(d.cam, cam_size, blocks)
    lb = _cells(d.board_cam[model.keep_board], cam_size, blocks)
    lg = _cells(d.back_cam[model.keep_back], cam_size, blocks)
    n_pri = (2 if (d.pp_prior is not None and d.camera_fixed is None) else 0) + len(d.priors)
    return np.concatenate([lc, lc, lb, lb, lg, -np.ones(n_pri, int)])


def _held_out(fit: J.JointFit, labels) -> tuple[float, np.ndarray]:
    """Linearised leave-one-block-out: the held-out chi-square and the jackknife covariance (free parameters)."""
    Jm, r = fit.jac, fit.residuals
    s = np.linalg.norm(Jm, axis=0)
    s = np.where(s > 0, s, 1.0)
    Jn = Jm / s
    A = Jn.T @ Jn
    groups = [g for g in np.unique(labels) if g >= 0]
    held, deltas = 0.0, []
    for g in groups:
        m = labels == g
        Jb, rb = Jn[m], r[m]
        try:
            delta = np.linalg.solve(A - Jb.T @ Jb, Jb.T @ rb)       # the fit without block g, minus the fit
        except np.linalg.LinAlgError:
            return float("inf"), np.full(A.shape, np.inf)
        held += float(np.sum((rb - Jb @ delta) ** 2))
        deltas.append(delta / s)
    deltas = np.array(deltas)
    G = len(deltas)
    if G < 3:
        return held, np.full(A.shape, np.inf)
    d = deltas - deltas.mean(0)
    return held, (G - 1) / G * d.T @ d


def _embed(C_free, free) -> np.ndarray:
    idx = [J.IDX[n] for n in free]
    C = np.zeros((len(J.NAMES), len(J.NAMES)))
    C[np.ix_(idx, idx)] = C_free
    return C


def _start(cam_sol, proj_sol, known_projector) -> np.ndarray:
    """The joint vector at the camera's single-pose solution and the paper's projector."""
    p = np.zeros(len(J.NAMES))
    p[:J.NC] = cam_sol.params
    if known_projector is not None:
        K = np.asarray(known_projector.K, float)
        p[J.IDX["f_p"]], p[J.IDX["alpha_p"]] = K[0, 0], K[1, 1] / K[0, 0]
        p[J.IDX["u0p"]], p[J.IDX["v0p"]] = K[0, 2], K[1, 2]
    else:
        K = proj_sol.K
        p[J.IDX["f_p"]], p[J.IDX["alpha_p"]], p[J.IDX["u0p"]], p[J.IDX["v0p"]] = K[0, 0], 1.0, K[0, 2], K[1, 2]
    p[J.IDX["prx"]:J.IDX["prx"] + 3] = models.matrix_to_rvec(proj_sol.R)
    p[J.IDX["ptx"]:J.IDX["ptx"] + 3] = proj_sol.t
    return p


def priors_for(proj_size, options: DenseOptions) -> list:
    """The Gaussian priors ``(name, mean, std)`` of the projector's intrinsics (module docstring, 3)."""
    from .. import datasheet

    W, H = proj_size
    pri = []
    o = options.prior
    if options.alpha_prior_std > 0:
        pri.append(("alpha_p", 1.0, float(options.alpha_prior_std)))
    if o is not None and o.throw_ratio is not None:
        pri.append(("f_p", datasheet.focal_from_throw_ratio(o.throw_ratio, W), o.throw_ratio_std * W))
    sh = o.shift_h_pct if o is not None else None
    sv = o.shift_v_pct if o is not None else None
    u0, v0 = datasheet.principal_point_from_shift(sh or 0.0, sv or 0.0, (W, H))
    if sh is not None:
        pri.append(("u0p", u0, o.shift_std_pct / 100.0 * W))
    else:
        pri.append(("u0p", u0, options.u0_prior_pct / 100.0 * W))
    if sv is not None:
        pri.append(("v0p", v0, o.shift_std_pct / 100.0 * H))
    return pri


def fit(view, cam_sol, proj_sol, proj_size, options: DenseOptions = DenseOptions(), *, known_camera=None,
        known_projector=None) -> DenseFit | None:
    """The dense projector fit of one pose (module docstring); None when the view has too few board samples.

    Parameters
    ----------
    view : :class:`procam.view.View` with ``board_samples`` (and ``background``).
    cam_sol : the camera's single-pose solution (or :func:`procam.single_pose.known_camera_pose`'s).
    proj_sol : the paper's projector solution (its pose starts the fit).
    proj_size : (W, H) of the projector.
    known_camera, known_projector : a :class:`procam.calibration.Device` held fixed, or None.
    """
    b, g = view.board_samples, view.background
    if b is None or len(b) < options.min_samples:
        return None
    ib = _even(len(b), options.max_samples)
    use_bg = options.use_background and g is not None and len(g) > 0
    ig = _even(len(g), options.max_samples) if use_bg else np.zeros(0, int)
    bw = b.sigma[ib] / np.median(b.sigma[ib]) if b.sigma is not None else None
    gw = (g.sigma[ig] / np.median(g.sigma[ig]) if (use_bg and g.sigma is not None and len(ig)) else None)
    pp_prior = None
    if known_camera is None and cam_sol.principal_point_source == "image-center" and cam_sol.info.get("pp_prior_std"):
        Wc, Hc = cam_sol.image_size
        pp_prior = (np.array([(Wc - 1) / 2.0, (Hc - 1) / 2.0]), float(cam_sol.info["pp_prior_std"]))
    priors = priors_for(proj_size, options) if known_projector is None else []
    dc = options.decentring_prior_px
    held = ((("dcx", "dcy") if known_camera is None else ()) + (("dpx", "dpy") if known_projector is None else ())
            if dc > 0 else ())
    priors = priors + [(n, 0.0, float(dc)) for n in held]
    data = J.JointData(view.obj_pts, np.where(view.valid[:, None], view.cam_pts, np.nan), b.cam_pts[ib],
                       b.proj_pts[ib], g.cam_pts[ig] if use_bg else np.zeros((0, 2)),
                       g.proj_pts[ig] if use_bg else np.zeros((0, 2)), bw, gw,
                       camera_fixed=None if known_camera is None else J.FixedDevice(np.asarray(known_camera.K, float),
                                                                                    known_camera),
                       projector_fixed=None if known_projector is None else J.FixedDevice(
                           np.asarray(known_projector.K, float), known_projector),
                       pp_prior=pp_prior, priors=priors)
    sig_c = cam_sol.info.get("sigma_px", 0.05)
    scales = J.Scales(max(float(sig_c) if np.isfinite(sig_c) else 0.05, 0.005),
                      float(np.median(b.sigma[ib])) if b.sigma is not None else 0.3,
                      float(np.median(g.sigma[ig])) if (use_bg and g.sigma is not None and len(ig)) else 0.3)
    model = J.JointModel(data, scales)
    cam_free = () if known_camera is not None else tuple(
        n for n, v in zip(J.CAMERA_VECTOR, np.diag(np.asarray(cam_sol.covariance))) if v > 0)
    cam_free = cam_free + (J.POSE_C if known_camera is not None else ())
    pin = () if known_projector is not None else ("f_p", "alpha_p", "u0p", "v0p")
    p = _start(cam_sol, proj_sol, known_projector)
    richest = max((MODELS[m] for m in options.models), key=len) if known_projector is None else ()
    # 1. the projector on the board samples with the camera held, then everything, the richest model
    p = J.solve(model, p, pin + J.POSE_P).p
    full = cam_free + pin + richest + J.POSE_P
    fit0 = J.solve(model, p, full)
    # 2. the background's distances in projector pixels from here on (module docstring, 2), the noise of each block,
    # the outliers out, the fit again (twice: the scales move with the outliers)
    model.pixel_distance = True
    for _ in range(2):
        model.scales = _measured_scales(model, fit0.p)
        _trim(model, fit0.p, options.outlier_k)
        fit0 = J.solve(model, fit0.p, full)
    # 3. the background: one epipolar geometry?
    background_reason = ""
    if use_bg:
        background_reason = background_disagrees(model, fit0, getattr(known_camera, "covariance", None))
        if background_reason:
            model.keep_back[:] = False
            fit0 = J.solve(model, fit0.p, full)
    # with the camera given, the background spans the panel and the data see where the projector lens's distortion is
    # centred: its decentring is estimated under its prior (module docstring, 5)
    seen = tuple(n for n in held if n in ("dpx", "dpy")) if known_camera is not None and use_bg and not \
        background_reason else ()
    if seen:
        full = full + seen
        fit0 = J.solve(model, fit0.p, full)
    # 4. the board's rim: does it agree with the rest of the board? (module docstring, 6)
    alive, peeled = np.ones(len(b), bool), 0
    before = (fit0, model.keep_board.copy(), model.scales)
    while peeled < options.rim_peels:
        ring = rim(b.cam_pts, b.window, options.rim_windows, alive)
        if rim_shift(fit0, model, ring[ib], options.rim_alarm) is None:
            break
        alive &= ~ring
        model.keep_board &= ~ring[ib]
        model.scales = _measured_scales(model, fit0.p)
        fit0 = J.solve(model, fit0.p, full)
        peeled += 1
    if peeled and contradicted(fit0.p, priors):
        # a prior the data contradict forces the model wrong everywhere, the rim too: leaving rims out explained
        # nothing and would only blur the conflict, which the rating names (the prior, not the pose)
        fit0, model.keep_board, model.scales = before
        alive, peeled = np.ones(len(b), bool), 0
    # 5. the board samples' errors: correlated over neighbouring windows? (module docstring, 5)
    phi = batch_inflation(model, fit0.p, b.window, options.batch_windows)
    if phi > 1:
        model.scales = J.Scales(model.scales.camera, model.scales.board * float(np.sqrt(phi)), model.scales.background)
        fit0 = J.solve(model, fit0.p, full)
    # 6. every lens model, its held-out error and jackknife
    names = [m for m in options.models] if known_projector is None else ["given"]
    fits = {}
    labels = None
    for name in sorted(names, key=lambda m: -len(MODELS.get(m, ()))):      # richest first: warm starts
        terms = MODELS.get(name, ())
        p_m = fit0.p.copy()
        for t in J.DIST_TERMS:
            if t not in terms and known_projector is None:
                p_m[J.IDX[t]] = 0.0
        free = cam_free + pin + terms + J.POSE_P + seen
        f = J.solve(model, p_m, free, max_nfev=60 if not fits else 20)
        if labels is None:
            labels = _labels(model, cam_sol.image_size, options.blocks)
        h_out, C_jk = _held_out(f, labels)
        # the decentrings are estimated under their priors; the covariance with them held at their estimate is what
        # the pose determines (the rating's)
        # the covariance with the decentrings free under their priors (the reported one) and held at the estimate
        # (what the pose determines: the rating's)
        cov_fit = J.linearise(model, f.p, free + held)[2] if held and not seen else f.cov
        cov_held = J.linearise(model, f.p, tuple(n for n in free if n not in seen))[2] if seen else f.cov
        fits[name] = ModelFit(name, f.p, f.cost, h_out, cov_fit, _embed(C_jk, f.free), f.n_residuals, f.free,
                              cov_held)
        lowest = min((m.held_out for m in fits.values() if np.isfinite(m.held_out)), default=np.inf)
        if h_out > (1 + 10 * options.model_tolerance) * lowest:
            break      # the models are nested: the simpler ones left can only fit worse
    # a model whose held-out cost is not finite (a fit the data cannot resolve) is never the best; with none finite,
    # the simplest model is kept and the fit's own +- (infinite where undetermined) says what it is worth
    held = [m.held_out for m in fits.values() if np.isfinite(m.held_out)]
    lowest = min(held) if held else np.inf
    near = tuple(m.name for m in fits.values()
                 if np.isfinite(m.held_out) and m.held_out - lowest <= options.model_tolerance * lowest)
    near = near or (next(iter(fits)),)
    best = min((fits[n] for n in near), key=lambda m: len(MODELS.get(m.name, ())))      # the simplest of them
    # a richer model the likelihood ratio demands joins the ± (trust.demanded); the estimate stays the held-out choice
    spread = [fits[n] for n in near] + [m for m in fits.values() if m.name not in near and demanded(len(MODELS.get(m.name, ())) - len(MODELS.get(best.name, ())), best.cost, m.cost)]
    cov = _reported_covariance(best, spread, seen)
    cov_pose = _reported_covariance(replace(best, cov_fit=best.cov_held), spread, seen)
    if known_camera is not None and getattr(known_camera, "covariance", None) is not None:
        # the camera file's own uncertainty, carried through the fit: the projector follows the camera's f_c
        names, C = known_camera.covariance
        extra = J.held_covariance(model, best.p, best.free, "camera", names, C)
        cov, cov_pose = cov + extra, cov_pose + extra
    pattern = None
    if known_camera is not None:
        # the given camera's residual pattern counts by what it does to the results: its shift joins the ±
        pattern, shift = camera_pattern(model, best.p, best.free)
        if shift is not None and np.all(np.isfinite(shift)):
            extra = np.outer(shift, shift)[:len(J.NAMES), :len(J.NAMES)]
            cov, cov_pose = cov + extra, cov_pose + extra
    notes = _notes(best, near, fits, data, model, background_reason, known_projector)
    # a given projector: do this pose's data still agree with its intrinsics (a zoom or focus change since)?
    given = given_projector_moved(model, best.p, best.free, known_projector) if known_projector is not None else None
    if phi > 1:
        notes = (*notes, (f"the board samples' errors are correlated over neighbouring windows (a decoder's "
                          f"systematic phase error?): their noise counts {phi:.1f} times over in the ±"))
    if peeled:
        notes = (*notes, (f"the board's rim disagrees with the rest of it (a decoder's error along the board's edge "
                          f"or the lit region's edge): the samples within {peeled * options.rim_windows} windows of "
                          f"that edge are left out, {int(len(b) - alive.sum())} of {len(b)}"))
    return DenseFit(model=best.name, p=best.p, cov=cov, fits=fits, indistinguishable=near, scales=model.scales,
                    n_board=int(model.keep_board.sum()), n_background=int(model.keep_back.sum()),
                    background_used=bool(use_bg and not background_reason), background_reason=background_reason,
                    notes=notes, priors=tuple(priors), conflicts=_conflicts(best, priors, options),
                    cov_pose=cov_pose, lit_corners=(int(np.sum(view.valid)), len(view.obj_pts)),
                    rim_left_out=int(len(b) - alive.sum()), board_correlation=float(phi), camera_pattern=pattern,
                    given_projector=given)


def _conflicts(best: ModelFit, priors, options: DenseOptions) -> tuple:
    """A warning per prior the data contradict: the estimate more than 3 of the prior's sigmas from its mean (the
    prior still pulls the estimate: the user should know; a datasheet number may be wrong)."""
    out = []
    for name, mu, sd in priors:
        if name in J.DECENTRING:
            continue
        est = float(best.p[J.IDX[name]])
        z = (est - mu) / sd
        if abs(z) > 3:
            source = ("the datasheet's" if options.prior is not None and name in ("f_p", "v0p") or
                      (name == "u0p" and options.prior is not None and options.prior.shift_h_pct is not None)
                      else "the assumed")
            out.append(f"projector: the pose puts {name} at {est:.4g}, {abs(z):.1f} sigma from {source} {mu:.4g} +- "
                       f"{sd:.3g} (a prior: it pulls the estimate towards it) -- check that number, or widen its "
                       "tolerance")
    return tuple(out)


def _measured_scales(model: J.JointModel, p) -> J.Scales:
    cr, br, gr, _ = model.blocks(p)
    d = model.data
    old = model.scales
    cam = robust_sigma(np.column_stack(cr)) if len(d.cam) else old.camera
    board = robust_sigma(np.column_stack(br) / d.board_w[model.keep_board][:, None]) if model.keep_board.any() \
        else old.board
    back = robust_sigma(np.asarray(gr) / d.back_w[model.keep_back]) if model.keep_back.any() else old.background
    f = (lambda v, floor: max(float(v), floor) if np.isfinite(v) else floor)
    return J.Scales(f(cam, 0.003), f(board, 0.003), f(back, 0.003))


def _trim(model: J.JointModel, p, k: float) -> None:
    """Leave out the samples beyond ``k`` noise scales (evaluated on all samples, so one comes back when a later
    fit explains it)."""
    keep_b = model.keep_board.copy()
    model.keep_board[:] = True
    model.keep_back[:] = True
    cr, br, gr, _ = model.blocks(p)
    d, s = model.data, model.scales
    if len(br[0]):
        e = np.hypot(br[0], br[1]) / (d.board_w * s.board)
        model.keep_board[:] = e <= k * np.sqrt(2.0)
    if np.size(gr):
        model.keep_back[:] = np.abs(np.asarray(gr)) / (d.back_w * s.background) <= k
    if model.keep_board.sum() < 20:        # nothing sensible left: keep what was kept
        model.keep_board[:] = keep_b


def _reported_covariance(best: ModelFit, near, estimated=()) -> np.ndarray:
    """The fit's covariance, widened to the block jackknife's where that is larger (per parameter, keeping the
    correlations), plus the spread of the indistinguishable models; the rows of the decentrings held at zero go
    (those ``estimated`` stay: the tangential terms they are written as carry them)."""
    C = best.cov_fit.copy()
    gone = [J.IDX[n] for n in J.DECENTRING if n not in estimated]
    C[gone, :] = 0.0
    C[:, gone] = 0.0
    s_fit = np.sqrt(np.clip(np.diag(C), 0, None))
    s_jk = np.sqrt(np.clip(np.diag(best.cov_jackknife), 0, None))
    with np.errstate(all="ignore"):
        g = np.where((s_fit > 0) & np.isfinite(s_jk), np.maximum(s_jk / s_fit, 1.0), 1.0)
    C = C * np.outer(g, g)
    if len(near) > 1:
        D = np.array([m.p - best.p for m in near])
        C = C + D.T @ D / (len(near) - 1)
    return C


def _notes(best, near, fits, data, model, background_reason, known_projector) -> tuple:
    notes = []
    if known_projector is not None:
        notes.append("projector: intrinsics given, not estimated from this pose")
        return tuple(notes)
    terms = MODELS[best.name]
    notes.append(f"projector lens model: {best.name} (chosen by held-out error among {', '.join(fits)}"
                 + (f"; {', '.join(n for n in near if n != best.name)} fit the held-out data as well and their spread "
                    "is in the ±" if len(near) > 1 else "") + ")")
    if not terms:
        notes.append("projector distortion: none estimated")
    for name, mu, sd in data.priors:
        notes.append(f"prior: {name} = {mu:.4g} +- {sd:.3g}")
    if background_reason:
        notes.append(background_reason)
    return tuple(notes)
