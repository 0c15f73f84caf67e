"""The labelling of a board's corners: no step of a calibration may depend on how they were numbered.

A board given as ``9x7`` or ``7x9``, with its origin in any of its corners, is the same physical board, and the
same pose of it must give the same calibration and the same verdict. Sums, starts and the robust steps of a fit
(the least-median homography that screens outliers samples points by their index) all see the corners in the
order they come, so the solvers work in one canonical labelling of each board and report in the given one:

* :func:`canonical_labelling` -- the labelling that does not depend on the numbering: :func:`procam.board.corners.
  canonical_order`'s rule (the grid's axes right-handed in the image with y down, corner 0 nearest the image's
  top-left corner) over all 8 labellings of the grid (rows and columns may swap), from an affine fit of the
  image points (NaN rows allowed); the board points rebuilt from the grid's integer indices, so that every
  labelling gives the same bytes;
* :func:`canonical_view` / :func:`canonical_points` -- a view (or a photo's points) in that labelling, with the
  :class:`Labelling` that undoes it;
* :func:`given_labelling` -- a single-pose calibration of the canonical view as the given view's: rejected
  corners and the messages that list them by the given numbers, board poses and angles in the given board frame.

Assumptions: the board points are a full regular grid in a plane (``z = 0``), one pitch in both directions;
anything else (a partial grid, other points) is left as given (nothing is renumbered). Ties of the rule (a board
turned exactly 45 deg in the image) are measure-zero with real data.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .. import models

__all__ = ["canonical_labelling", "Labelling", "canonical_view", "canonical_points", "given_labelling"]

#: The 8 labellings of a grid: (u, v) -> M (u, v) (origin in any corner, COLSxROWS either way round).
_GRID_SYMMETRIES = tuple(np.array(m, float) for m in (
    [[1, 0], [0, 1]], [[-1, 0], [0, 1]], [[1, 0], [0, -1]], [[-1, 0], [0, -1]],
    [[0, 1], [1, 0]], [[0, -1], [1, 0]], [[0, 1], [-1, 0]], [[0, -1], [-1, 0]]))


def canonical_labelling(obj_pts, img_pts):
    """The labelling of a full planar grid of board points that does not depend on how it was numbered.

    A board given as ``9x7`` or ``7x9``, with its origin in any corner, is the same physical board; a solver fed
    with its canonical labelling gives the same result, bit for bit, whichever the user chose. The rule is
    :func:`procam.board.corners.canonical_order`'s, over all 8 labellings (rows and columns may swap): the grid's axes as the image
    sees them (an affine fit of the finite image points) right-handed with y down, and of those, corner 0 nearest
    the image's top-left corner.

    Parameters
    ----------
    obj_pts : (N, 3) board points of a full regular grid (z = 0), in any numbering.
    img_pts : (N, 2) their image points (NaN where missing; at least 3 finite, not on a line).

    Returns
    -------
    ``(order (N,) int, obj (N, 3), G (3, 3))``: the canonical corner ``k`` is the given corner ``order[k]``; ``obj``
    the canonical board points (``(i s, j s, 0)`` minus their centroid, ``k = j * cols + i``); ``G`` the proper
    rotation of the board frame with ``obj[k] = G @ obj_pts[order[k]]`` (a board pose ``R`` in the canonical frame
    is ``R @ G`` in the given one). None when the points are not a full grid or the image points too few.
    """
    obj = np.asarray(obj_pts, float).reshape(-1, 3)
    img = np.asarray(img_pts, float).reshape(-1, 2)
    n = len(obj)
    if n < 4 or len(img) != n or not np.all(np.isfinite(obj)) or np.any(obj[:, 2] != 0):
        return None
    steps = []
    for c in (obj[:, 0], obj[:, 1]):
        d = np.diff(np.unique(c))
        d = d[d > 1e-9 * max(np.ptp(c), 1e-300)]
        steps.append(float(d.min()) if len(d) else np.inf)
    s = min(steps)
    if not np.isfinite(s) or s <= 0:
        return None
    s = float(f"{s:.10g}")  # the same pitch whichever the numbering (the centroid rounds differently)
    ij = (obj[:, :2] - obj[:, :2].min(axis=0)) / s
    grid = np.rint(ij)
    if np.max(np.abs(ij - grid)) > 1e-6:
        return None
    grid = grid.astype(int)
    ni, nj = grid.max(axis=0) + 1
    if ni * nj != n or len({(a, b) for a, b in grid}) != n:
        return None
    uv = 2 * grid - np.array([ni - 1, nj - 1])  # centred coordinates, doubled: integers
    ok = np.isfinite(img).all(1)
    if ok.sum() < 3:
        return None
    X = np.column_stack([uv[ok] / 2.0, np.ones(int(ok.sum()))])
    coef, *_ = np.linalg.lstsq(X, img[ok], rcond=None)
    A, b = coef[:2].T, coef[2]
    if not abs(np.linalg.det(A)) > 0:
        return None
    best = None
    for M in _GRID_SYMMETRIES:
        Ag = A @ M.T  # the image directions of the labelling's axes
        if np.linalg.det(Ag) <= 0:  # right-handed with y down only
            continue
        w = np.abs(M @ np.array([ni - 1, nj - 1], float))  # the labelling's half extent (in uv units)
        corner0 = b + Ag @ (-w / 2.0)  # its corner 0 (centred coordinates are halves of uv)
        key = float(corner0.sum())
        if best is None or key < best[0]:
            best = (key, M, w)
    _, M, w = best
    uv2 = np.rint(uv @ M.T).astype(int)  # exact: M holds 0 and +-1
    w0, w1 = (int(round(x)) for x in w)
    cols2 = w0 + 1
    i2, j2 = (uv2[:, 0] + w0) // 2, (uv2[:, 1] + w1) // 2
    k2 = j2 * cols2 + i2
    order = np.empty(n, int)
    order[k2] = np.arange(n)
    ii, jj = np.arange(n) % cols2, np.arange(n) // cols2
    obj2 = np.column_stack([ii * s, jj * s, np.zeros(n)])
    obj2[:, :2] -= obj2[:, :2].mean(axis=0)
    # the frame change: obj2 = M (obj - centroid); z flipped with a mirror, so that G is a rotation
    G = np.eye(3)
    G[:2, :2] = M
    G[2, 2] = np.linalg.det(M)
    return order, obj2, G


@dataclass(frozen=True)
class Labelling:
    """How a view's corners were renumbered into the canonical labelling (:func:`canonical_labelling`).

    Attributes
    ----------
    order : (N,) int: canonical corner ``k`` is the given corner ``order[k]``.
    G : (3, 3) rotation of the board frame: a board pose ``R`` in the canonical frame is ``R @ G`` in the given one.
    """

    order: np.ndarray
    G: np.ndarray

    @property
    def identity(self) -> bool:
        return bool(np.array_equal(self.order, np.arange(len(self.order))) and np.array_equal(self.G, np.eye(3)))

    def to_given(self, k):
        """The given index of canonical corner(s) ``k``."""
        return self.order[k]

    def given_rows(self, a):
        """Per-corner rows ``a`` (N, ...) in the canonical order, put back in the given order."""
        a = np.asarray(a)
        out = np.empty_like(a)
        out[self.order] = a
        return out

    def given_words(self, sol) -> dict:
        """``{canonical rejection message: the same message with the given corners' numbers}`` of a solution's
        rejected corners, both worded from its data (:func:`procam.verdict.rejection_message`); empty
        when it rejected none."""
        words = (getattr(sol, "info", None) or {}).get("rejection")
        rej = np.asarray(getattr(sol, "rejected", ()), int)
        if words is None or not len(rej):
            return {}
        from ..verdict import rejection_message

        norms = sol.rejected_residuals_px
        return {rejection_message(rej, norms, words): rejection_message(self.to_given(rej), norms, words)}


def _reworded(texts, changes: dict) -> tuple:
    """``texts`` with every canonical message of ``changes`` replaced by its given-numbered wording."""
    out = []
    for t in texts:
        for old, new in changes.items():
            t = t.replace(old, new)
        out.append(t)
    return tuple(out)


def canonical_view(view):
    """``(view in the canonical labelling, Labelling)`` -- the same physical corners, numbered the way
    :func:`canonical_labelling` does whatever the user's ``COLSxROWS`` and origin; ``(view, None)``
    when its board points are not a full grid (nothing to renumber)."""
    cam = np.asarray(view.cam_pts, float)
    lab = canonical_labelling(view.obj_pts, cam if np.isfinite(cam).all(1).sum() >= 3 else view.proj_pts)
    if lab is None:
        return view, None
    order, obj, G = lab
    diag = {k: (np.asarray(v)[order] if isinstance(v, np.ndarray) and len(v) == len(order) else v)
            for k, v in view.diagnostics.items()}
    return replace(view, obj_pts=obj, cam_pts=view.cam_pts[order], proj_pts=view.proj_pts[order], diagnostics=diag,
                    board=None), Labelling(order, G)


def canonical_points(obj_pts, img_pts):
    """``(obj, img, Labelling or None)``: board and image points in the canonical labelling (as
    :func:`canonical_view`, for a camera-only photo)."""
    obj = np.asarray(obj_pts, float)
    obj = np.column_stack([obj, np.zeros(len(obj))]) if obj.ndim == 2 and obj.shape[1] == 2 else obj
    img = np.asarray(img_pts, float).reshape(-1, 2)
    lab = canonical_labelling(obj, img) if obj.ndim == 2 and len(obj) == len(img) else None
    if lab is None:
        return obj_pts, img_pts, None
    order, obj2, G = lab
    return obj2, img[order], Labelling(order, G)


def _given_solution(sol, lab: Labelling):
    if sol is None or getattr(sol, "residuals", None) is None:
        return sol
    R = np.asarray(sol.R, float) @ lab.G
    return replace(sol, R=R, angles_deg=models.board_angles_deg(R, sol.t),
                   residuals=lab.given_rows(sol.residuals),
                   mask=None if sol.mask is None else lab.given_rows(sol.mask),
                   rejected=lab.to_given(np.asarray(sol.rejected, int)),
                   warnings=_reworded(sol.warnings, lab.given_words(sol)))


def given_labelling(calib, view, lab: Labelling | None):
    """A single-pose calibration of the canonical view (:func:`canonical_view`) as the given ``view``'s: the
    rejected corners, the residuals and the messages that name corners in the given numbering, the board angles
    and poses in the given board frame, ``views`` the given one. The calibration itself (intrinsics, ``R, T``,
    the ``±``, the verdict) is the canonical view's, so it is the same for every labelling of the board.
    ``info["labelling"]`` records the renumbering (the solutions' parameter vectors stay canonical)."""
    if lab is None:
        return calib
    poses = []
    for p in calib.poses:
        p = dict(p)
        rej = p.get("rejected_corners")
        if rej:
            p["rejected_corners"] = {d: [{**r, "index": int(lab.to_given(int(r["index"])))} for r in rs]
                                     for d, rs in rej.items()}
        fitted = calib.info.get("board_poses") or {}  # the poses the result's angles came from (a dense fit's)
        for key, device in (("camera_angles_deg", "camera"), ("projector_angles_deg", "projector")):
            sol = calib.info.get(device)
            R, t = fitted.get(device) or (getattr(sol, "R", None), getattr(sol, "t", None))
            if p.get(key) is not None and R is not None:
                p[key] = [float(a) for a in models.board_angles_deg(np.asarray(R, float) @ lab.G, t)]
        poses.append(p)
    info = dict(calib.info)
    changes = {}
    for k in ("camera", "projector"):
        if k in info:
            changes.update(lab.given_words(info[k]))
            info[k] = _given_solution(info[k], lab)
    info["labelling"] = {"order": lab.order.tolist(), "G": lab.G.tolist(),
                         "note": "solved in the canonical labelling of the board (procam.board.labelling.canonical_labelling)"}
    return calib.replace(views=calib.views if view is None else (view,), poses=tuple(poses), info=info,
                         warnings=_reworded(calib.warnings, changes),
                         verdict_reasons=_reworded(calib.verdict_reasons, changes))
