"""The geometry of the advisor's moves: turning and tilting the board about the camera's axes
(:func:`apply_move`, :func:`move_between`), the board's pose in the camera from its corners (:func:`pose_pnp`)
and in the projector from an earlier capture (:class:`ProjectorSide`, :func:`projector_pose`), and the
area of its image (:func:`polygon_area`).

A *turn* of ``+d`` degrees is a rotation about the camera's vertical axis through the board's centre with
the board's right edge (as the camera sees it) going away from the camera, a *tilt* of ``+d`` degrees one
about the horizontal axis with the top edge going away.  Poses are board -> device (``X_dev = R X_b + t``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import models


@dataclass(frozen=True)
class ProjectorSide:
    """What an earlier capture tells about the projector: ``K`` (3, 3), ``size`` (W, H), the extrinsics
    ``R, T`` (camera -> projector, ``x_p = R x_c + T``, board units) and ``source`` (where they come from)."""

    K: np.ndarray
    size: tuple
    R: np.ndarray
    T: np.ndarray
    source: str = ""


def projector_pose(side: ProjectorSide, R_cb, t_cb):
    """The board's pose in the projector, ``(R_pb, t_pb) = (R R_cb, R t_cb + T)``, from its pose in the camera."""
    return side.R @ R_cb, side.R @ t_cb + side.T


def axis_rotation(turn_deg: float, tilt_deg: float) -> np.ndarray:
    """The rotation (camera frame) of a turn then a tilt (see :func:`apply_move` for the signs)."""
    ry = models.rvec_to_matrix([0.0, -math.radians(turn_deg), 0.0])
    rx = models.rvec_to_matrix([-math.radians(tilt_deg), 0.0, 0.0])
    return rx @ ry


def apply_move(R_cb, t_cb, turn_deg: float = 0.0, tilt_deg: float = 0.0):
    """The board pose after a move: a turn about the camera's vertical axis and a tilt about its
    horizontal axis, both through the board's centre (the corners' centroid, ``t_cb``).

    ``turn_deg > 0``: the board's right edge (larger image x) goes away from the camera;
    ``tilt_deg > 0``: its top edge (smaller image y) goes away.  Returns ``(R_b', t_cb)`` (board -> camera).

    >>> R, t = apply_move(np.eye(3), [0.0, 0.0, 500.0], turn_deg=10.0)
    >>> bool((R @ [100.0, 0, 0] + t)[2] > 500.0)   # the right edge is farther
    True
    """
    R_cb = np.asarray(R_cb, float)
    return axis_rotation(turn_deg, tilt_deg) @ R_cb, np.asarray(t_cb, float).reshape(3).copy()


def move_between(R_from, R_to) -> tuple[float, float]:
    """``(turn_deg, tilt_deg)`` that take the board from rotation ``R_from`` to ``R_to`` (camera frame;
    the small-angle split of ``R_to R_from^T`` into the two axes of :func:`apply_move`)."""
    w = models.matrix_to_rvec(np.asarray(R_to, float) @ np.asarray(R_from, float).T)
    return -math.degrees(w[1]), -math.degrees(w[0])


def pose_pnp(obj, pts_und, K):
    """Board -> camera pose by IPPE on undistorted pixels (None when PnP fails)."""
    import cv2

    ok, rvec, tvec = cv2.solvePnP(obj.astype(np.float64), pts_und.reshape(-1, 1, 2).astype(np.float64),
                                  np.asarray(K, float), None, flags=cv2.SOLVEPNP_IPPE)
    if not ok or not np.all(np.isfinite(tvec)) or tvec[2, 0] <= 0:
        return None
    return models.rvec_to_matrix(rvec.ravel()), tvec.ravel()


def polygon_area(p) -> float:
    """Area of the polygon with vertices ``p`` (N, 2), in their units squared (shoelace formula)."""
    x, y = p[:, 0], p[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))
