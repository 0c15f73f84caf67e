"""Verify a rig: where two projectors light the same board corners, their triangulated points agree.

For every rig pose, every camera and every two projectors paired with it, the board corners both pairs decoded
are triangulated by each pair's calibration (:func:`procam.triangulate.triangulate_points`, camera corner +
projector corner -> 3-D point in that camera's frame) and compared: the distance between the two points of a
corner, in board units (mm) and as a percentage of the corner's depth (its z in the camera frame).  Two pairs
that agree measure the same surface; a relative pose or a projector's intrinsics that are off shows as a
systematic distance.  The camera corners of the two pairs come from different captures of the same board pose,
so the figure also holds the corner noise.  A pair of cameras sharing a projector is compared the same way, in
the reference camera's frame.

Failure mode: fewer than ``min_corners`` corners common to two pairs gives no figure for them (listed with
``n = 0``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["PairAgreement", "verify_rig"]


@dataclass(frozen=True)
class PairAgreement:
    """Two pairs' triangulations of the same corners: ``a``, ``b`` (pair names ``camera/projector``), ``pose``,
    ``n`` corners, ``rms_mm`` / ``max_mm`` of the 3-D distances, ``rms_pct`` / ``max_pct`` as a percentage of the
    depth, ``mean_depth_mm``, ``bias_mm`` (the mean difference vector, reference frame)."""

    a: str
    b: str
    pose: str
    n: int
    rms_mm: float
    max_mm: float
    rms_pct: float
    max_pct: float
    mean_depth_mm: float
    bias_mm: tuple

    def to_dict(self) -> dict:
        return {"a": self.a, "b": self.b, "pose": self.pose, "n": self.n, "rms_mm": self.rms_mm,
                "max_mm": self.max_mm, "rms_pct": self.rms_pct, "max_pct": self.max_pct,
                "mean_depth_mm": self.mean_depth_mm, "bias_mm": list(self.bias_mm)}


def _points(cal, view):
    from ..triangulate import triangulate_points

    X = np.full((len(view.obj_pts), 3), np.nan)
    m = view.valid
    if m.sum():
        out = triangulate_points(cal, view.cam_pts[m], view.proj_pts[m])
        X[m] = out[0] if isinstance(out, tuple) else out
    return X


def verify_rig(rc, poses, *, min_corners: int = 6) -> list[PairAgreement]:
    """Every two pairs' agreement at every rig pose (module docstring).

    Parameters
    ----------
    rc : :class:`~procam.calibration.RigCalibration`.
    poses : the :class:`~procam.rig.calibrate.RigPoseViews` (the calibration's or others).
    min_corners : fewest common corners for a figure.

    Returns
    -------
    list of :class:`PairAgreement`, one per two pairs per pose.
    """
    out = []
    for pv in poses:
        pts = {}
        for (c, p), view in pv.views.items():
            key = f"{c}/{p}"
            if key not in rc.pairs:
                continue
            X = _points(rc.pairs[key], view)
            d = rc.device(c)
            pts[key] = (X - d.T) @ d.R  # camera frame -> reference frame: X_ref = R^T (X_c - T)
        keys = list(pts)
        for i, a in enumerate(keys):
            for b in keys[i + 1:]:
                Xa, Xb = pts[a], pts[b]
                ok = np.isfinite(Xa).all(1) & np.isfinite(Xb).all(1)
                n = int(ok.sum())
                if n < min_corners:
                    out.append(PairAgreement(a, b, pv.name, 0, *(float("nan"),) * 5, (float("nan"),) * 3))
                    continue
                diff = Xb[ok] - Xa[ok]
                dist = np.linalg.norm(diff, axis=1)
                depth = 0.5 * (Xa[ok, 2] + Xb[ok, 2])
                pct = 100.0 * dist / depth
                out.append(PairAgreement(a, b, pv.name, n, float(np.sqrt(np.mean(dist ** 2))), float(dist.max()),
                                         float(np.sqrt(np.mean(pct ** 2))), float(pct.max()), float(depth.mean()),
                                         tuple(float(v) for v in diff.mean(0))))
    return out
