"""Board placement: put the board at given angles so that it is seen whole by both devices.

* :func:`with_board_pose` - the scene with the board at new angles, its centre chosen to keep the
  whole printed board (corners, outer squares, white margin) inside the camera and the projector
  images (through their lenses) with the largest border, and - with a background fixed in the room -
  neither hidden from the camera nor shadowed from the projector by it.
* :func:`fit_margin` - that border, in camera pixels (negative when the board does not fit).

The search is also used for a rig's board (:meth:`procam.simulate.Rig.with_board_pose`), with the
smallest margin over its device pairs.  Angles are intrinsic XYZ ``(psi, nu, phi)`` in degrees of the
board -> device rotation; lengths in mm.
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import numpy as np
from scipy.optimize import minimize

from .lens import distort, euler_matrix, project
from .scene import DEFAULT_DISTANCE, Scene, _outline, board_corners

__all__ = ["with_board_pose", "fit_margin"]

#: Margin of a placement that cannot be used (a point behind a device, hidden or shadowed by the background).
BAD = -1e9


def _pose_in_camera(scene: Scene, R_bd: np.ndarray, c_d: np.ndarray, frame: str):
    """Board -> camera pose from a board -> device rotation and board centre in that device frame."""
    if frame == "camera":
        return R_bd, c_d
    return scene.R.T @ R_bd, scene.R.T @ (c_d - scene.T)


def _margins(scene: Scene, R_b: np.ndarray, t_b: np.ndarray) -> np.ndarray:
    """:func:`fit_margin` for M board -> camera poses sharing ``R_b`` (3, 3); ``t_b`` (M, 3) -> (M,)."""
    t_b = np.asarray(t_b, float).reshape(-1, 3)
    P = (_outline(scene) @ R_b.T)[None, :, :] + t_b[:, None, :]          # (M, K, 3) camera frame
    Pp = P @ scene.R.T + scene.T
    bad = np.any(P[..., 2] <= 1e-6, axis=1) | np.any(Pp[..., 2] <= 1e-6, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        mc = distort(scene, project(scene.K_cam, P.reshape(-1, 3))).reshape(P.shape[0], -1, 2)
        mp = scene.proj_lens.project(scene.K_proj, Pp.reshape(-1, 3)).reshape(P.shape[0], -1, 2)
    bad |= ~np.all(np.isfinite(mc), axis=(1, 2)) | ~np.all(np.isfinite(mp), axis=(1, 2))
    (wc, hc), (wp, hp) = scene.cam_size, scene.proj_size
    dc = np.minimum(np.minimum(mc[..., 0] + 0.5, wc - 0.5 - mc[..., 0]),
                    np.minimum(mc[..., 1] + 0.5, hc - 0.5 - mc[..., 1])).min(axis=1)
    dp = np.minimum(np.minimum(mp[..., 0] + 0.5, wp - 0.5 - mp[..., 0]),
                    np.minimum(mp[..., 1] + 0.5, hp - 0.5 - mp[..., 1])).min(axis=1)
    m = np.minimum(dc, dp * scene.K_cam[0, 0] / scene.K_proj[0, 0])
    m = np.where(bad | ~np.isfinite(m), BAD, m)
    if scene.background is not None:  # only where the board fits (the costly part): hidden there is unusable
        fits = np.flatnonzero(m >= 0)
        if fits.size:
            m[fits[_hidden(scene, R_b, t_b[fits])]] = BAD
    return m


def _hidden(scene: Scene, R_b: np.ndarray, t_b: np.ndarray) -> np.ndarray:
    """(M,) True where a point of the board (its outline and corners) is hidden from the camera or
    shadowed from the projector by the fixed background."""
    B = np.concatenate([_outline(scene), board_corners(scene)])
    P = (B @ R_b.T)[None, :, :] + t_b[:, None, :]                        # (M, K, 3)
    bg = scene.background
    blocked = bg.blocks(np.zeros(3), P) | bg.blocks(P, scene.proj_center_cam - P)
    return np.any(blocked, axis=1)


def fit_margin(scene: Scene, R_board=None, t_board=None) -> float:
    """Smallest distance (camera px) of the printed board's outline to the border of either image.

    Negative when part of the board (with its margin) is outside the camera image or the projector
    image (through the lenses), or behind a device, or (a background fixed in the room; checked where
    the board fits the images) hidden from the camera or shadowed from the projector by it.  Projector pixels are scaled by ``f_c / f_p`` to
    camera pixels.
    """
    R_b = scene.R_board if R_board is None else np.asarray(R_board, float)
    t_b = scene.t_board if t_board is None else np.asarray(t_board, float)
    return float(_margins(scene, R_b, t_b)[0])


# ------------------------------------------------------------------------------------------------
# the search (generic: a margin function of board -> camera poses, and the frame of the angles)
# ------------------------------------------------------------------------------------------------

#: ``margins(R_b (3, 3), t_b (M, 3)) -> (M,)`` for board -> (reference) camera poses.
Margins = Callable[[np.ndarray, np.ndarray], np.ndarray]
#: ``to_camera(R_bd, c)`` -> the board -> camera pose ``(R_b, t_b)`` of a board -> device rotation and centres
#: ``c`` (3,) or (M, 3) in that device's frame.
ToCamera = Callable[[np.ndarray, np.ndarray], tuple]


def _grid_center(margins: Margins, to_camera: ToCamera, R_bd, distance: float, n: int = 41, span: float = 0.6):
    """Best board centre (x, y, distance) in the device frame on an n x n grid; returns (c, margin)."""
    g = np.linspace(-span, span, n) * distance
    X, Y = np.meshgrid(g, g)
    C = np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, distance)])
    m = margins(*to_camera(R_bd, C))
    k = int(np.argmax(m))
    return C[k], float(m[k])


def _best_center(margins: Margins, to_camera: ToCamera, R_bd, distance: float):
    """Board centre (x, y, distance) in the device frame maximising the margin; returns (c, margin)."""
    c0, m0 = _grid_center(margins, to_camera, R_bd, distance)

    def score(xy):
        c = np.array([xy[0], xy[1], distance])
        R_b, t_b = to_camera(R_bd, c)
        return float(margins(R_b, t_b)[0])

    step = 0.03 * distance
    res = minimize(lambda v: -score(v), x0=c0[:2], method="Nelder-Mead",
                   options={"xatol": 1e-3, "fatol": 1e-4, "initial_simplex":
                            [c0[:2], c0[:2] + [step, 0], c0[:2] + [0, step]]})
    if -res.fun >= m0:
        return np.array([res.x[0], res.x[1], distance]), float(-res.fun)
    return c0, m0


def _place(margins: Margins, to_camera: ToCamera, angles_deg, distance, center, border_px: float,
           max_distance: float, step: float):
    """Board -> camera pose ``(R_b, t_b)`` of :func:`with_board_pose`'s search."""
    R_bd = euler_matrix(angles_deg)
    if center is not None:
        c = np.asarray(center, float).reshape(3)
    elif distance is not None:
        c, _ = _best_center(margins, to_camera, R_bd, float(distance))
    else:
        best = None
        d = DEFAULT_DISTANCE
        while d <= max_distance + 1e-9:  # grid per depth, refined where it is nearly feasible
            c_d, m = _grid_center(margins, to_camera, R_bd, d)
            if m > border_px - 50:
                c_d, m = _best_center(margins, to_camera, R_bd, d)
            if best is None or m > best[1]:
                best = (c_d, m)
            if m >= border_px:
                best = (c_d, m)
                break
            d += step
        c = best[0]
    return to_camera(R_bd, c)


def with_board_pose(scene: Scene, angles_deg, distance: float | None = None, frame: str = "camera",
                    center=None, border_px: float = 8.0, max_distance: float = 3000.0,
                    step: float = 25.0) -> Scene:
    """The scene with the board at a new pose.

    Parameters
    ----------
    angles_deg : (psi, nu, phi) in degrees: ``R_board->device = Rx(psi) Ry(nu) Rz(phi)`` in ``frame``.
    distance : depth (mm, along the device's optical axis) of the board centre when ``center`` is
        None.  The lateral position is chosen to maximise the smallest distance of the printed board
        (all corners, outer squares and white margin) to the borders of BOTH the camera and the
        projector images (:func:`fit_margin`; with a fixed background, positions where the board is
        hidden or shadowed by it are refused).  If ``distance`` is None, depths from
        :data:`DEFAULT_DISTANCE` upwards in ``step`` mm are tried until that distance is at least
        ``border_px`` camera pixels (if none up to ``max_distance`` fits, the best-fitting depth is
        used: check :func:`fit_margin`).
    frame : ``"camera"`` or ``"projector"``: the device frame of ``angles_deg`` and ``center``.
    center : (3,) board centre in ``frame`` (mm); overrides ``distance``.

    Returns
    -------
    Scene with ``R_board``, ``t_board`` (board -> camera) set.
    """
    if frame not in ("camera", "projector"):
        raise ValueError(f"frame must be 'camera' or 'projector', got {frame!r}")

    def to_camera(R_bd, c):
        if frame == "camera":
            return R_bd, c
        if np.ndim(c) == 1:
            return _pose_in_camera(scene, R_bd, c, frame)
        return scene.R.T @ R_bd, (c - scene.T) @ scene.R

    R_b, t_b = _place(lambda R, t: _margins(scene, R, t), to_camera, angles_deg, distance, center, border_px,
                      max_distance, step)
    return dataclasses.replace(scene, R_board=R_b, t_board=t_b)
