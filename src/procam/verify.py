"""Metric verification of a calibration: triangulate the board and compare it with the printed one.

A reprojection RMS says how well a model fits its own data; it does not say whether the model
measures correctly.  Here every pose's chessboard corners are triangulated from the camera and the
projector with the calibration (:func:`procam.triangulate.triangulate_points`: ray midpoint refined
to the least reprojection error in both devices), and the resulting 3-D board is compared with the
printed one, whose geometry is known exactly:

* **scale**: the distance of every pair of grid-adjacent corners (one square apart along a row or
  a column) against the printed square ``s``.  ``scale_error_pct = 100 (mean d - s) / s`` (signed:
  positive = the reconstruction is too large); ``spacing_rms = sqrt(mean (d - s)^2)`` in board
  units (systematic and random parts together).
* **planarity**: the distances of the triangulated corners to their total-least-squares plane
  (SVD); ``planarity_rms`` and ``planarity_max`` in board units.
* **rigid_rms**: RMS distance between the triangulated corners and the printed board after the
  best rigid motion (Kabsch, no scaling), board units: the whole 3-D error of the board's shape.

Assumptions: the printed board is flat and its squares are exactly ``s`` (``s`` = the smallest
distance between two board points of the view, i.e. the grid pitch of ``View.obj_pts``); corner
noise is what limits a correct calibration, so on a correct calibration ``scale_error_pct`` is
~ 0 (within a few hundredths of a percent for ~100 pairs) and ``planarity_rms`` is the depth
noise of the triangulated corners.  Wrong intrinsics or extrinsics show up as a scale error, as a
bent board (planarity) or both.

In-sample figures (a calibration verified on the poses it was fitted to) are optimistic;
:func:`leave_one_out` gives the honest figure for a multi-pose calibration (refit without pose i,
verify on pose i) and :func:`single_pose_cross` for single-pose calibrations (calibrate on pose i,
verify on every other pose).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from . import multi_pose
from .multi_pose.evidence import parameter_spread, refit_each  # noqa: F401 -- parameter_spread: here before
from .errors import CalibrationError, ProcamError, ProcamWarning
from .stats import rms, tls_plane
from .triangulate import triangulate_points
from .view import View


@dataclass(frozen=True)
class PoseMetric:
    """Metric verification of one pose (or, with ``name="all"``, of several pooled).

    Attributes
    ----------
    name : pose name.
    n_corners : corners triangulated (finite camera and projector points).
    n_pairs : grid-adjacent corner pairs measured.
    square : printed square ``s`` (board units).
    mean_spacing : mean triangulated distance of the adjacent pairs (board units).
    scale_error_pct : ``100 (mean_spacing - s) / s`` (pooled: the mean of the per-pair relative
        errors, in percent).
    spacing_rms : ``sqrt(mean (d - s)^2)`` over the pairs, board units.
    planarity_rms, planarity_max : RMS / largest distance of the triangulated corners to their best
        plane (fitted per pose), board units.
    rigid_rms : RMS corner distance after the best rigid alignment of the printed board to the
        triangulated one (per pose), board units.
    reproj_rms : RMS reprojection residual of the triangulated corners over both devices, pixels
        (how consistent the two devices' observations are with the calibration's epipolar geometry).
    distance : mean distance of the triangulated corners from the camera centre, board units.
    """

    name: str
    n_corners: int
    n_pairs: int
    square: float
    mean_spacing: float
    scale_error_pct: float
    spacing_rms: float
    planarity_rms: float
    planarity_max: float
    rigid_rms: float
    reproj_rms: float
    distance: float

    def to_dict(self) -> dict:
        return {k: (v if isinstance(v, (str, int)) else float(v)) for k, v in self.__dict__.items()}


@dataclass(frozen=True)
class Verification:
    """Per-pose metrics and their pooled summary (``overall``, a :class:`PoseMetric` named "all").

    ``overall`` pools every pair and every corner of every pose: ``scale_error_pct`` is the mean
    relative pair error, ``spacing_rms`` / ``planarity_rms`` / ``rigid_rms`` / ``reproj_rms`` are RMS
    over all pairs / corners (each pose keeps its own plane and rigid fit), ``planarity_max`` the
    largest, ``distance`` the mean over corners; ``square`` is that of the first pose (NaN if the
    poses' squares differ).
    """

    poses: tuple
    overall: PoseMetric

    def to_dict(self) -> dict:
        return {"poses": [p.to_dict() for p in self.poses], "overall": self.overall.to_dict()}


@dataclass(frozen=True)
class CrossVerification:
    """In-sample and held-out verification side by side.

    Attributes
    ----------
    kind : ``"leave-one-out"`` (multi-pose) or ``"single-pose-cross"``.
    in_sample : :class:`Verification` -- leave-one-out: the calibration from all poses verified on
        all poses; single-pose-cross: every pose verified by its own single-pose calibration.
    held_out : :class:`Verification` -- leave-one-out: pose i verified by the calibration fitted
        without it (one entry per pose); single-pose-cross: pose j verified by the calibration from
        pose i, for every ordered pair i != j (entries named ``"j <- i"``).
    failures : tuple of ``(name, message)``: fits that failed and were left out.
    refits : the calibrations fitted without each pose (leave-one-out), for their parameters' spread
        (:func:`parameter_spread`).
    """

    kind: str
    in_sample: Verification
    held_out: Verification | None
    failures: tuple = field(default=())
    refits: tuple = field(default=(), compare=False)

    def to_dict(self) -> dict:
        return {"kind": self.kind, "in_sample": self.in_sample.to_dict(),
                "held_out": None if self.held_out is None else self.held_out.to_dict(),
                "failures": [list(f) for f in self.failures]}


# --------------------------------------------------------------------------------------------------
# geometry helpers
# --------------------------------------------------------------------------------------------------

def adjacent_pairs(obj_pts, rel_tol: float = 1e-6):
    """Grid-adjacent corner pairs of a board.

    Parameters
    ----------
    obj_pts : (N, 3) board points (a regular grid, any subset).

    Returns
    -------
    pairs : (M, 2) int indices ``(i, j)``, ``i < j``, of points exactly one pitch apart.
    square : the pitch (smallest distance between two distinct points); NaN for fewer than 2 points.
    """
    P = np.asarray(obj_pts, float).reshape(-1, 3)
    if len(P) < 2:
        return np.zeros((0, 2), int), float("nan")
    D = np.linalg.norm(P[:, None, :] - P[None, :, :], axis=2)
    iu = np.triu_indices(len(P), 1)
    dist = D[iu]
    pos = dist[dist > 0]
    if not len(pos):
        return np.zeros((0, 2), int), float("nan")
    s = float(pos.min())
    sel = np.abs(dist - s) <= rel_tol * s
    return np.column_stack([iu[0][sel], iu[1][sel]]), s


def plane_fit(X):
    """Total-least-squares plane of points X (N, 3) (:func:`procam.stats.tls_plane`): ``(normal (3,),
    centroid (3,), distances (N,))``."""
    X = np.asarray(X, float).reshape(-1, 3)
    n, c = tls_plane(X)
    return n, c, (X - c) @ n


def rigid_fit(A, B):
    """Best rigid motion ``B ~ R A + t`` (Kabsch, no scale) of matching points (N, 3).

    Returns ``(R, t, residuals (N,))``, residuals the point distances after alignment.
    """
    A = np.asarray(A, float).reshape(-1, 3)
    B = np.asarray(B, float).reshape(-1, 3)
    ca, cb = A.mean(0), B.mean(0)
    H = (A - ca).T @ (B - cb)
    U, _, Vt = np.linalg.svd(H)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T)) or 1.0])
    R = Vt.T @ D @ U.T
    t = cb - R @ ca
    return R, t, np.linalg.norm(B - (A @ R.T + t), axis=1)


# --------------------------------------------------------------------------------------------------
# verification
# --------------------------------------------------------------------------------------------------

def _pose_raw(calib, view: View, name: str, min_corners: int):
    m = view.valid
    if m.sum() < min_corners:
        raise CalibrationError(f"pose {name!r}: only {int(m.sum())} corners have camera and projector points "
                               f"(need {min_corners}) for the metric verification")
    obj = view.obj_pts[m]
    X, rc, rp = triangulate_points(calib, view.cam_pts[m], view.proj_pts[m])
    ok = np.isfinite(X).all(1)
    if ok.sum() < min_corners:
        raise CalibrationError(f"pose {name!r}: triangulation failed for most corners; "
                               "is the calibration for this camera and projector?")
    obj, X, rc, rp = obj[ok], X[ok], rc[ok], rp[ok]
    pairs, s = adjacent_pairs(obj)
    if not len(pairs):
        raise CalibrationError(f"pose {name!r}: no two grid-adjacent corners were triangulated")
    d = np.linalg.norm(X[pairs[:, 0]] - X[pairs[:, 1]], axis=1)
    _, _, pd = plane_fit(X)
    _, _, rd = rigid_fit(obj, X)
    return {"name": name, "n": len(X), "s": s, "d": d, "pd": pd, "rd": rd,
            "reproj": np.concatenate([rc, rp]), "dist": np.linalg.norm(X, axis=1)}


def _metric(name, n, s, d, pd, rd, reproj, dist) -> PoseMetric:
    rel = (d - s) / s
    return PoseMetric(
        name=name, n_corners=int(n), n_pairs=int(len(d)), square=float(s), mean_spacing=float(np.mean(d)),
        scale_error_pct=float(100.0 * np.mean(rel)), spacing_rms=rms(d - s, dim=1), planarity_rms=rms(pd, dim=1),
        planarity_max=float(np.max(np.abs(pd))), rigid_rms=rms(rd, dim=1),
        reproj_rms=rms(reproj), distance=float(np.mean(dist)))


def _pool(raws) -> PoseMetric:
    squares = np.array([r["s"] for r in raws])
    s = float(squares[0]) if np.allclose(squares, squares[0]) else float("nan")
    rel = np.concatenate([(r["d"] - r["s"]) / r["s"] for r in raws])
    dev = np.concatenate([r["d"] - r["s"] for r in raws])
    d = np.concatenate([r["d"] for r in raws])
    pd = np.concatenate([r["pd"] for r in raws])
    reproj = np.concatenate([r["reproj"] for r in raws])
    return PoseMetric(
        name="all", n_corners=int(sum(r["n"] for r in raws)), n_pairs=int(len(d)), square=s,
        mean_spacing=float(np.mean(d)), scale_error_pct=float(100.0 * np.mean(rel)), spacing_rms=rms(dev, dim=1),
        planarity_rms=rms(pd, dim=1), planarity_max=float(np.max(np.abs(pd))),
        rigid_rms=rms(np.concatenate([r["rd"] for r in raws]), dim=1),
        reproj_rms=rms(reproj),
        distance=float(np.mean(np.concatenate([r["dist"] for r in raws]))))


def verify_pose(calib, view: View, *, min_corners: int = 6) -> PoseMetric:
    """Metric verification of ``calib`` on one pose (see the module docstring for each number).

    Parameters
    ----------
    calib : :class:`procam.calibration.Calibration` with a projector and ``(R, T)``.
    view : the pose's correspondences (corners with a NaN are skipped).
    min_corners : fewer usable corners raise :class:`procam.errors.CalibrationError`.
    """
    name = view.name or "pose"
    return _metric(**_pose_raw(calib, view, name, min_corners))


def _verify_raws(raws) -> Verification:
    return Verification(poses=tuple(_metric(**r) for r in raws), overall=_pool(raws))


def verify(calib, views: Sequence[View], *, min_corners: int = 6) -> Verification:
    """Metric verification of ``calib`` on every pose of ``views``, per pose and pooled.

    Raises :class:`procam.errors.CalibrationError` for no views, a calibration without projector,
    or a pose with fewer than ``min_corners`` usable corners.
    """
    views = list(views)
    if not views:
        raise CalibrationError("nothing to verify: give at least one pose")
    raws = [_pose_raw(calib, v, v.name or f"pose{k + 1}", min_corners) for k, v in enumerate(views)]
    return _verify_raws(raws)


def leave_one_out(views: Sequence[View], *, min_train: int = 3, min_corners: int = 6,
                  calibration=None, **multi_pose_options) -> CrossVerification:
    """Leave-one-pose-out verification of a multi-pose calibration.

    For every pose i, :func:`procam.multi_pose.calibrate` is run on the other poses (with
    ``multi_pose_options``) and the result verified on pose i (:func:`verify_pose`); the in-sample
    figure is the calibration from all poses verified on all poses.

    Parameters
    ----------
    views : the poses (at least ``min_train + 1``).
    min_train : poses each refit must keep (default 3: multi-pose intrinsics from 2 poses are
        weakly constrained, so a held-out figure from them would say more about the refit than
        about the calibration).
    calibration : the all-pose calibration if already computed (else it is fitted here).

    Returns
    -------
    :class:`CrossVerification` (``kind="leave-one-out"``).  A refit that fails
    (:class:`procam.errors.ProcamError`) is recorded in ``failures`` and its pose left out of
    ``held_out`` (``held_out`` is None when every refit failed).

    Raises
    ------
    CalibrationError
        Fewer than ``min_train + 1`` poses: there is no honest held-out figure; report the
        in-sample one (:func:`verify`) and say why.
    """
    views = list(views)
    if len(views) < min_train + 1:
        raise CalibrationError(f"leave-one-out needs at least {min_train + 1} poses ({min_train} to calibrate, "
                               f"1 to verify), got {len(views)}; only the in-sample verification is available")
    names = [v.name or f"pose{k + 1}" for k, v in enumerate(views)]
    options = {**multi_pose_options, "leave_one_out": False}
    if calibration is None:
        with warnings.catch_warnings():  # the calibration's own verdict is not this function's subject
            warnings.simplefilter("ignore", ProcamWarning)
            calibration = multi_pose.calibrate(views, **multi_pose_options)
    full = calibration
    in_raws = [_pose_raw(full, v, n, min_corners) for v, n in zip(views, names)]
    out_raws, failures, refits = [], [], []
    results = full.info.get("leave_one_out_refits")
    same = (results is not None and len(results) == len(views) == len(full.views)
            and all(same_pose(a, b) for a, b in zip(views, full.views))
            and {k: v for k, v in multi_pose_options.items() if k != "leave_one_out"} == _options_of(full))
    if not same:  # the refits the calibration made (same poses, same options), else made here
        results = refit_each(views, multi_pose.calibrate, **options)
    for v, n, calib_i in zip(views, names, results):
        try:
            if isinstance(calib_i, ProcamError):
                raise calib_i
            refits.append(calib_i)
            out_raws.append(_pose_raw(calib_i, v, n, min_corners))
        except ProcamError as e:
            failures.append((n, str(e)))
    return CrossVerification("leave-one-out", _verify_raws(in_raws), _verify_raws(out_raws) if out_raws else None,
                             tuple(failures), tuple(refits))


def single_pose_cross(views: Sequence[View], *, min_corners: int = 6, **single_pose_options) -> CrossVerification:
    """Single-pose analogue of :func:`leave_one_out`: calibrate on pose i, verify on every other pose.

    Every pose is calibrated alone with :func:`procam.single_pose.calibrate`
    (``single_pose_options``); ``in_sample`` verifies each calibration on its own pose, ``held_out``
    on each other pose (entries ``"j <- i"``: pose j verified with the calibration from pose i).
    Poses whose calibration fails are recorded in ``failures``.  Needs at least 2 poses
    (:class:`procam.errors.CalibrationError` otherwise).
    """
    from . import single_pose

    views = list(views)
    if len(views) < 2:
        raise CalibrationError(f"single-pose cross-verification needs at least 2 poses (calibrate on one, verify "
                               f"on the others), got {len(views)}")
    names = [v.name or f"pose{k + 1}" for k, v in enumerate(views)]
    in_raws, out_raws, failures = [], [], []
    for i, (v, n) in enumerate(zip(views, names)):
        try:
            calib_i = single_pose.calibrate(v, **single_pose_options)
            in_raws.append(_pose_raw(calib_i, v, n, min_corners))
        except ProcamError as e:
            failures.append((n, str(e)))
            continue
        for j, (w, m) in enumerate(zip(views, names)):
            if j == i:
                continue
            try:
                out_raws.append(_pose_raw(calib_i, w, f"{m} <- {n}", min_corners))
            except ProcamError as e:
                failures.append((f"{m} <- {n}", str(e)))
    if not in_raws:
        raise CalibrationError("every single-pose calibration failed: " + "; ".join(f"{n}: {m}" for n, m in failures))
    return CrossVerification("single-pose-cross", _verify_raws(in_raws),
                             _verify_raws(out_raws) if out_raws else None, tuple(failures))


# --------------------------------------------------------------------------------------------------
# the verification a calibration's summaries show
# --------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class CalibrationVerification:
    """The metric verification of one calibration, as ``procam calibrate`` / ``evaluate`` / ``report`` show it.

    Attributes
    ----------
    in_sample : :class:`Verification` on the given poses the calibration was fitted to (optimistic), or None.
    held_out : :class:`Verification` on the given poses it was not fitted to, or None.
    leave_one_out : :class:`CrossVerification` of a multi-pose calibration's own poses (refit without
        pose i with the calibration's options, verify on pose i), or None.
    notes : why a figure is missing or partial (too few poses for leave-one-out, poses that could
        not be verified), one line each.
    """

    in_sample: Verification | None
    held_out: Verification | None
    leave_one_out: CrossVerification | None
    notes: tuple = ()

    def to_dict(self) -> dict:
        return {"in_sample": None if self.in_sample is None else self.in_sample.to_dict(),
                "held_out": None if self.held_out is None else self.held_out.to_dict(),
                "leave_one_out": None if self.leave_one_out is None else self.leave_one_out.to_dict(),
                "notes": list(self.notes)}


def _options_of(calib) -> dict:
    return multi_pose_options(calib)


def multi_pose_options(calib) -> dict:
    """The :func:`procam.multi_pose.calibrate` options a multi-pose calibration was made with (from its
    ``info``: distortion models and whether it was refined), for refits such as :func:`leave_one_out`."""
    info = calib.info or {}
    out = {}
    if info.get("cam_dist_model"):
        out["cam_dist"] = info["cam_dist_model"]
    if info.get("proj_dist_model"):
        out["proj_dist"] = info["proj_dist_model"]
    if "refined" in info:
        out["refine"] = bool(info["refined"])
    return out


def same_pose(a: View, b: View) -> bool:
    """The same capture: identical camera and projector corners (NaN where the other has NaN)."""
    return (a.cam_pts.shape == b.cam_pts.shape and a.proj_pts.shape == b.proj_pts.shape
            and np.array_equal(a.cam_pts, b.cam_pts, equal_nan=True)
            and np.array_equal(a.proj_pts, b.proj_pts, equal_nan=True))


def _verify_each(calib, views, min_corners, notes) -> Verification | None:
    ok = []
    for v in views:
        try:
            verify_pose(calib, v, min_corners=min_corners)
            ok.append(v)
        except ProcamError as e:
            notes.append(f"not verified: {e}")
    return verify(calib, ok, min_corners=min_corners) if ok else None


def verify_calibration(calib, views=None, *, leave_one_out_poses: int = 4, min_corners: int = 6) -> CalibrationVerification:
    """The metric verification a calibration's summaries show.

    * the given poses (default: the calibration's own ``views``) split into those the calibration
      was fitted to (same corners as one of ``calib.views``, or with no stored views the same name as
      one of ``calib.poses``) -- ``in_sample`` -- and the others -- ``held_out``;
    * a multi-pose calibration with at least ``leave_one_out_poses`` stored views: also
      :func:`leave_one_out` on them with the calibration's options (:func:`multi_pose_options`).

    Poses that cannot be verified (too few corners, triangulation failure) are left out with a note;
    nothing here raises for them.  A calibration without projector gives an empty check with a note.

    Returns
    -------
    :class:`CalibrationVerification`
    """
    notes: list[str] = []
    if calib.projector is None or calib.R is None:
        return CalibrationVerification(None, None, None, ("a camera-only calibration has no metric verification "
                                                   "(it needs the projector to triangulate the board)",))
    own = list(calib.views)
    views = own if views is None else list(views)
    own_names = {str(p.get("name", "")) for p in calib.poses}

    def fitted(v):
        return any(same_pose(v, w) for w in own) if own else str(v.name) in own_names

    ins = [v for v in views if fitted(v)]
    outs = [v for v in views if not fitted(v)]
    in_sample = _verify_each(calib, ins, min_corners, notes) if ins else None
    held_out = _verify_each(calib, outs, min_corners, notes) if outs else None
    loo = None
    if calib.method == "multi-pose":
        if len(own) >= leave_one_out_poses:
            try:
                loo = leave_one_out(own, min_train=leave_one_out_poses - 1, min_corners=min_corners,
                                    calibration=calib, **multi_pose_options(calib))
                notes += [f"leave-one-out: refit without {n} failed: {m}" for n, m in loo.failures]
            except ProcamError as e:
                notes.append(f"leave-one-out not available: {e}")
        else:
            why = ("the calibration file holds no poses" if not own else
                   f"the calibration has {len(own)} poses")
            notes.append(f"leave-one-pose-out needs at least {leave_one_out_poses} poses and {why}; "
                         "the in-sample figures are optimistic")
    elif calib.method == "single-pose" and held_out is None:
        notes.append("a single-pose calibration verified on its own pose only (optimistic); give other poses "
                     "(procam evaluate CALIB POSES..., procam report CALIB POSES...) for a held-out figure")
    return CalibrationVerification(in_sample, held_out, loo, tuple(notes))
