"""Evaluation of a calibration on a set of poses: reprojection, stereo, PnP precision.

For every pose ``j`` and a calibration (single- or multi-pose, any distortion model):

* camera and projector points are undistorted with the calibration's own distortion model
  (:meth:`procam.calibration.Device.undistort`; division or OpenCV), so every error below is measured
  in undistorted pixels with a plain pinhole, whatever the model;
* ``cam_rms`` / ``proj_rms``: ``cv2.solvePnP`` (ITERATIVE) with the intrinsics fixed, RMS over the
  corners;
* ``stereo_rms``: both intrinsics and ``(R, T)`` fixed, only the board pose (camera frame) optimised
  over the camera and projector residuals, started from the camera's PnP;
* the per-pose procam extrinsics ``R_j = R_pj R_cj^T``, ``T_j = T_pj - R_j T_cj`` from the two PnP
  poses, and their spread ``sigma_T = sqrt(var X + var Y + var Z)``, ``sigma_|T| = std |T_j|``
 , with ``ddof = 1`` (default) and ``ddof = 0``;
* the board's Euler angles ``(psi, nu, phi)`` in the camera and the projector frames
  (:func:`procam.models.board_angles_deg`, as the solvers report them).

RMS = ``sqrt(sum |e|^2 / n)`` over points (Euclidean pixel distances). PnP, the stereo pose and the
RMS are :mod:`procam.residuals` (the same code the solvers use for ``Calibration.cam_rms`` etc.);
residuals are observed - predicted.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Sequence

import numpy as np

from . import models
from .calibration import Calibration
from .errors import CalibrationError
from .residuals import pnp, stereo_pose
from .stats import rms
from .view import View





@dataclass(frozen=True)
class PoseEvaluation:
    """Metrics of one pose (pixels, board units, degrees).

    ``R``, ``T``: the procam extrinsics from this pose's two PnP solutions (camera -> projector);
    ``R_cam, t_cam`` / ``R_proj, t_proj``: the PnP board poses; ``cam_angles`` / ``proj_angles``:
    board ``(psi, nu, phi)`` in each device frame; ``R_angles``: Euler angles of ``R``.
    """

    name: str
    n_points: int
    cam_rms: float
    proj_rms: float
    stereo_rms: float
    cam_angles: tuple[float, float, float]
    proj_angles: tuple[float, float, float]
    R: np.ndarray
    T: np.ndarray
    R_angles: tuple[float, float, float]
    R_cam: np.ndarray
    t_cam: np.ndarray
    R_proj: np.ndarray
    t_proj: np.ndarray

    def to_dict(self) -> dict:
        d = asdict(self)
        for k, v in d.items():
            if isinstance(v, np.ndarray):
                d[k] = v.tolist()
            elif isinstance(v, tuple):
                d[k] = [float(a) for a in v]
        return d


@dataclass(frozen=True)
class Evaluation:
    """Metrics of a calibration over a set of poses.

    Attributes
    ----------
    poses : per-pose :class:`PoseEvaluation`.
    cam_rms, proj_rms : mean over poses of the per-pose RMS (the paper's "average reprojection error").
    cam_rms_all, proj_rms_all : RMS pooled over every point of every pose.
    stereo_rms : stereo RMS pooled over every camera and projector point of every pose.
    sigma_xyz : (3,) std of X, Y, Z of the per-pose ``T_j`` (ddof = 1).
    sigma_T, sigma_abs_T : ``sqrt(var X + var Y + var Z)`` and ``std |T_j|`` (ddof = 1).
    sigma_T_ddof0, sigma_abs_T_ddof0 : the same with ddof = 0.
    T_mean : (3,) mean of the ``T_j``; T_calib : (3,) the calibration's ``T``.
    R_angles : Euler angles (deg) of the calibration's ``R``.
    """

    poses: tuple
    cam_rms: float
    proj_rms: float
    cam_rms_all: float
    proj_rms_all: float
    stereo_rms: float
    sigma_xyz: np.ndarray
    sigma_T: float
    sigma_abs_T: float
    sigma_T_ddof0: float
    sigma_abs_T_ddof0: float
    T_mean: np.ndarray
    T_calib: np.ndarray
    R_angles: tuple[float, float, float]

    def to_dict(self) -> dict:
        out = {}
        for k in self.__dataclass_fields__:
            v = getattr(self, k)
            if k == "poses":
                out[k] = [p.to_dict() for p in v]
            elif isinstance(v, np.ndarray):
                out[k] = v.tolist()
            elif isinstance(v, tuple):
                out[k] = [float(a) for a in v]
            else:
                out[k] = float(v)
        return out


def _angles(a) -> tuple[float, float, float]:
    return tuple(float(v) for v in a)


def _spread(Ts: np.ndarray, ddof: int):
    if len(Ts) <= ddof:
        return np.full(3, np.nan), float("nan"), float("nan")
    sx = np.std(Ts, axis=0, ddof=ddof)
    return sx, float(np.sqrt(np.sum(sx ** 2))), float(np.std(np.linalg.norm(Ts, axis=1), ddof=ddof))


def check_units(calib: Calibration, views: Sequence[View], tolerance: float = 0.01) -> None:
    """Raise :class:`CalibrationError` when the views' board square differs from the one the calibration was made
    with (recorded with its views): ``T`` is in square units, so another square size is another length unit and
    every stereo residual is wrong (a 75 mm calibration evaluated with 24 mm squares gives 120 px)."""
    made = {round(v.board.square, 9) for v in calib.views if getattr(v, "board", None) is not None}
    given = {round(v.board.square, 9) for v in views if getattr(v, "board", None) is not None}
    if len(made) != 1 or not given:
        return
    s0 = made.pop()
    for s in given:
        if abs(s - s0) > tolerance * s0:
            raise CalibrationError(f"the calibration was made with a board of {s0:g}-unit squares, these poses are "
                                   f"read with {s:g}: its T and every length are in units of {s0:g}; evaluate with "
                                   f"--square {s0:g} (or the calibration of this board)")


def check_baseline(ev: "Evaluation", factor: float = 1.5) -> None:
    """Raise :class:`CalibrationError` when the poses, each placed by PnP in both devices, put the projector at a
    distance from the camera that differs from the calibration's ``|T|`` by more than ``factor``: the length unit
    differs (another square size than the calibration's, when the file does not record it) or the calibration is
    not of this rig. (Single-pose calibrations differ from the per-pose baselines by a few percent.)"""
    base = float(np.median(np.linalg.norm([p.T for p in ev.poses], axis=1)))
    ratio = base / max(float(np.linalg.norm(ev.T_calib)), 1e-300)
    if not 1 / factor <= ratio <= factor:
        raise CalibrationError(
            f"the poses put the projector {ratio:.2f} times as far from the camera as the calibration does (baseline "
            f"{base:.4g} against {np.linalg.norm(ev.T_calib):.4g}): the board's square size is not the one the "
            f"calibration was made with (--square {1 / ratio:.3g} times the one given?), or the calibration is not of "
            "this camera and projector")


def evaluate(calib: Calibration, views: Sequence[View], *, min_points: int = 6) -> Evaluation:
    """Evaluate ``calib`` on ``views``; see the module docstring for the definitions.

    Parameters
    ----------
    calib : a :class:`procam.calibration.Calibration` with a projector and ``(R, T)``.
    views : poses to evaluate on (NaN corners are skipped: ``view.valid``).
    min_points : poses with fewer valid corners raise.

    Returns
    -------
    :class:`Evaluation`

    Raises
    ------
    CalibrationError
        No views, a calibration without projector/extrinsics, or a pose with too few corners.
    """
    views = list(views)
    if not views:
        raise CalibrationError("nothing to evaluate: give at least one pose")
    if calib.projector is None or calib.R is None or calib.T is None:
        raise CalibrationError("the calibration has no projector or no camera->projector extrinsics")
    check_units(calib, views)
    Kc, Kp = np.asarray(calib.camera.K, float), np.asarray(calib.projector.K, float)
    R, T = np.asarray(calib.R, float), np.asarray(calib.T, float).ravel()
    poses = []
    cam_all, proj_all, st_all = [], [], []
    for k, v in enumerate(views):
        name = v.name or f"pose{k + 1}"
        m = v.valid
        if m.sum() < min_points:
            raise CalibrationError(f"pose {name!r}: only {int(m.sum())} valid corners (need {min_points})")
        obj = v.obj_pts[m]
        cam_u = calib.camera.undistort(v.cam_pts[m])
        proj_u = calib.projector.undistort(v.proj_pts[m])
        ok = np.isfinite(cam_u).all(1) & np.isfinite(proj_u).all(1)
        if ok.sum() < min_points:
            raise CalibrationError(f"pose {name!r}: undistortion failed for most corners; "
                                   "is the calibration for this camera?")
        obj, cam_u, proj_u = obj[ok], cam_u[ok], proj_u[ok]
        try:
            R_cb, t_cb, ec = pnp(obj, cam_u, Kc)
            R_pb, t_pb, ep = pnp(obj, proj_u, Kp)
        except CalibrationError as e:
            raise CalibrationError(f"pose {name!r}: {e}") from None
        _, _, sc, sp = stereo_pose(obj, cam_u, proj_u, Kc, Kp, R, T, R_cb, t_cb)
        Rj = R_pb @ R_cb.T
        Tj = t_pb - Rj @ t_cb
        cam_all.append(ec)
        proj_all.append(ep)
        st_all += [sc, sp]
        poses.append(PoseEvaluation(
            name=name, n_points=int(len(obj)), cam_rms=rms(ec), proj_rms=rms(ep),
            stereo_rms=rms(np.vstack([sc, sp])), cam_angles=_angles(models.board_angles_deg(R_cb, t_cb)),
            proj_angles=_angles(models.board_angles_deg(R_pb, t_pb)), R=Rj, T=Tj,
            R_angles=_angles(models.euler_deg(Rj)),
            R_cam=R_cb, t_cam=t_cb, R_proj=R_pb, t_proj=t_pb))
    Ts = np.array([p.T for p in poses])
    sx1, sT1, sA1 = _spread(Ts, 1)
    _, sT0, sA0 = _spread(Ts, 0)
    return Evaluation(
        poses=tuple(poses),
        cam_rms=float(np.mean([p.cam_rms for p in poses])),
        proj_rms=float(np.mean([p.proj_rms for p in poses])),
        cam_rms_all=rms(np.vstack(cam_all)), proj_rms_all=rms(np.vstack(proj_all)),
        stereo_rms=rms(np.vstack(st_all)),
        sigma_xyz=sx1, sigma_T=sT1, sigma_abs_T=sA1, sigma_T_ddof0=sT0, sigma_abs_T_ddof0=sA0,
        T_mean=Ts.mean(axis=0), T_calib=T, R_angles=_angles(models.euler_deg(R)))
