"""Is a set of poses able to determine a multi-pose calibration? Judged BEFORE any fit, from the corners alone.

Zhang's method reads each device's intrinsics from the boards' homographies: every pose gives two constraints
on ``(fx, fy, u0, v0)``, and only if the boards are tilted differently. Boards that all face a device squarely
leave its focal length free; boards all turned about one axis leave a combination of the intrinsics free; two
poses at the same orientation count once. A fit of such a set still returns numbers -- a focal length of
14,000 px for a 256-px image, a baseline of 41 m -- with a tiny ``±``, because the fit's covariance is only
valid where the problem is well posed.

Method, per device (camera: board -> camera corners; projector: board -> projector corners):

1. each pose's homography (:func:`procam.models.homography`, normalised DLT) and its pose with nominal
   intrinsics: the principal point at the image centre, the focal length the median of the poses' closed-form
   Zhang estimates when plausible (0.3-3 x the image diagonal), else the diagonal;
2. the **predicted** standard deviations of ``fx, fy, u0, v0`` (the Cramer-Rao bound of a pinhole fit of all
   the poses for a typical corner noise, lens distortion known; every pose's 6 parameters eliminated by their
   Schur complement) -- a bound the geometry alone sets, not the fit's ``±``;
3. the geometry in words: each board's tilt (angle between its normal and the optical axis) and tilt axis
   (the image direction it is turned about), how many distinct orientations there are.

A device whose predicted focal length (or principal point) is known to worse than
:attr:`PoseSetOptions.degenerate_rel_std` is **degenerate**: the message names the parameters, says why from
the geometry (every board square to the device; every board turned about one axis; too few distinct
orientations; only one pose tilted) and what to capture instead. The bound assumes the nominal intrinsics and
Gaussian noise: it can miss a set made degenerate by a strong lens distortion the pinhole bound ignores
(the leave-one-out spread after the fit catches that, :mod:`procam.multi_pose.evidence`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import models

__all__ = ["PoseSetOptions", "PoseSetCheck", "check_pose_set"]


@dataclass(frozen=True)
class PoseSetOptions:
    """Thresholds of :func:`check_pose_set`.

    Attributes
    ----------
    camera_noise_px, projector_noise_px : corner noise (px) the predicted bound assumes.
    degenerate_rel_std : a focal length predicted to worse than this fraction, or a principal point to worse
        than this fraction of the image size, is not determined (degenerate).
    square_deg : a board tilted less than this faces the device squarely.
    same_orientation_deg : two boards whose normals differ by less than this are one orientation.
    one_axis_deg : tilt axes within this of each other are one axis.
    """

    camera_noise_px: float = 0.1
    projector_noise_px: float = 0.2
    degenerate_rel_std: float = 0.10
    square_deg: float = 5.0
    same_orientation_deg: float = 3.0
    one_axis_deg: float = 10.0


@dataclass(frozen=True)
class DeviceSetCheck:
    """One device's judgement of a pose set.

    Attributes
    ----------
    device : ``"camera"`` or ``"projector"``.
    rel_std : predicted std of ``fx, fy`` over the nominal focal length and of ``u0, v0`` over the image width /
        height (``inf`` when the set determines nothing), by name (``f``, ``fy``, ``u0``, ``v0``).
    tilts_deg : (n,) each board's tilt from the device's optical axis.
    axes_deg : (n,) the image direction of each board's tilt axis (0 = the image's x axis, 90 = its y axis).
    distinct : how many distinct board orientations.
    undetermined : names of the parameters the set does not determine.
    message : why, in words, and what to capture instead ("" when the set is sound for this device).
    """

    device: str
    rel_std: dict
    tilts_deg: np.ndarray
    axes_deg: np.ndarray
    distinct: int
    undetermined: tuple = ()
    message: str = ""


@dataclass(frozen=True)
class PoseSetCheck:
    """The judgement of a pose set before fitting: ``level`` ``"good"`` or ``"degenerate"``, ``reasons`` (one
    message per degenerate device) and the per-device details ``devices``."""

    level: str
    reasons: tuple = ()
    devices: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {"level": self.level, "reasons": list(self.reasons),
                "devices": {k: {"rel_std": {n: float(v) for n, v in d.rel_std.items()},
                                "tilts_deg": [float(t) for t in d.tilts_deg], "distinct": int(d.distinct),
                                "undetermined": list(d.undetermined)} for k, d in self.devices.items()}}


def _nominal(Hs, size):
    """Nominal K from the homographies: the image centre and the median plausible Zhang focal length."""
    W, H = size
    c = ((W - 1) / 2.0, (H - 1) / 2.0)
    diag = float(np.hypot(W, H))
    fs = []
    for Hm in Hs:
        z = models.zhang_camera(Hm, c)
        if z is not None and 0.3 * diag <= z[0] <= 3.0 * diag:
            fs.append(z[0])
    f = float(np.median(fs)) if fs else diag
    return models.intrinsic_matrix(f, c[0], c[1])


def _pose_block(K, R, t, X):
    """``(J_int (2N, 4), J_pose (2N, 6))``: derivatives of the pinhole projection of board points ``X`` (N, 3) at
    pose ``(R, t)`` with respect to ``(fx, fy, u0, v0)`` and to a small rotation and a translation of the pose."""
    P = X @ R.T + t
    x, y, z = P[:, 0], P[:, 1], P[:, 2]
    fx, fy = K[0, 0], K[1, 1]
    n = len(X)
    Ji = np.zeros((2 * n, 4))
    Ji[0::2, 0] = x / z
    Ji[0::2, 2] = 1.0
    Ji[1::2, 1] = y / z
    Ji[1::2, 3] = 1.0
    dP = np.zeros((2 * n, 3))  # d(u, v) / dP
    dP[0::2, 0] = fx / z
    dP[0::2, 2] = -fx * x / z ** 2
    dP[1::2, 1] = fy / z
    dP[1::2, 2] = -fy * y / z ** 2
    Q = X @ R.T  # d P / d omega = -[Q]x
    skew = np.zeros((n, 3, 3))
    skew[:, 0, 1], skew[:, 0, 2], skew[:, 1, 2] = -Q[:, 2], Q[:, 1], -Q[:, 0]
    skew[:, 1, 0], skew[:, 2, 0], skew[:, 2, 1] = Q[:, 2], -Q[:, 1], Q[:, 0]
    dPw = -skew
    Jw = np.einsum("nij,njk->nik", dP.reshape(n, 2, 3), dPw).reshape(2 * n, 3)
    return Ji, np.hstack([Jw, dP])


def _bound(K, poses, objs, sigma):
    """Predicted std (4,) of ``(fx, fy, u0, v0)`` from every pose (Schur complement of the poses)."""
    info = np.zeros((4, 4))
    for (R, t), X in zip(poses, objs):
        Ji, Jp = _pose_block(K, R, t, X)
        A, B, C = Ji.T @ Ji, Ji.T @ Jp, Jp.T @ Jp
        try:
            info += A - B @ np.linalg.solve(C, B.T)
        except np.linalg.LinAlgError:
            continue
    scale = np.sqrt(np.maximum(np.diag(info), 1e-300))
    n = info / np.outer(scale, scale)
    w = np.linalg.eigvalsh(n)
    if not (w[0] > 1e-10 * max(w[-1], 1e-300)):
        return np.full(4, np.inf)
    cov = sigma ** 2 * np.linalg.inv(n) / np.outer(scale, scale)
    return np.sqrt(np.abs(np.diag(cov)))


def _orientation(R):
    """Tilt (deg), tilt-axis direction in the image (deg, mod 180) and the board normal of a board pose."""
    nrm = R[:, 2] * (1.0 if R[2, 2] >= 0 else -1.0)
    tilt = float(np.degrees(np.arccos(np.clip(nrm[2], -1.0, 1.0))))
    axis = np.cross([0.0, 0.0, 1.0], nrm)
    ang = float(np.degrees(np.arctan2(axis[1], axis[0]))) % 180.0
    return tilt, ang, nrm


def _axis_words(a: float) -> str:
    a = a % 180.0
    if min(a, 180.0 - a) < 15.0:
        return "the image's horizontal axis (the board tipped forward/back only)"
    if abs(a - 90.0) < 15.0:
        return "the image's vertical axis (the board turned left/right only)"
    return f"one axis ({a:.0f} deg from the image's horizontal)"


def _distinct(normals, tol):
    """How many distinct board planes (normals within ``tol`` degrees count once: a board turned within its own
    plane gives Zhang's method no new constraint)."""
    reps = []
    for nrm in normals:
        if not any(np.degrees(np.arccos(np.clip(float(nrm @ n2), -1.0, 1.0))) < tol for n2 in reps):
            reps.append(nrm)
    return len(reps)


def _device_check(device, objs, pts, names, size, sigma, o: PoseSetOptions) -> DeviceSetCheck | None:
    Hs, used, used_names = [], [], []
    for X, m, nm in zip(objs, pts, names):
        ok = np.isfinite(X).all(1) & np.isfinite(m).all(1)
        if ok.sum() < 4:
            continue
        try:
            with np.errstate(all="ignore"):
                Hm = models.homography(X[ok, :2], m[ok])
        except (ValueError, np.linalg.LinAlgError):
            continue
        if not np.all(np.isfinite(Hm)):
            continue
        Hs.append(Hm)
        used.append(X[ok])
        used_names.append(nm)
    if len(Hs) < 2:
        return None
    K = _nominal(Hs, size)
    poses = [models.pose_from_homography(K, Hm) for Hm in Hs]
    sd = _bound(K, poses, used, sigma)
    W, H = size
    f = K[0, 0]
    rel = {"f": sd[0] / f, "fy": sd[1] / f, "u0": sd[2] / W, "v0": sd[3] / H}
    geo = [_orientation(R) for R, _ in poses]
    tilts = np.array([g[0] for g in geo])
    axes = np.array([g[1] for g in geo])
    distinct = _distinct([g[2] for g in geo], o.same_orientation_deg)
    bad = tuple(k for k, v in rel.items() if not v <= o.degenerate_rel_std)
    msg = ""
    if bad:
        first = [f"{device} focal length" if ("f" in bad or "fy" in bad) else None,
                 f"{device} principal point" if ("u0" in bad or "v0" in bad) else None]
        undet = " and ".join(w for w in first if w)
        dev = "c" if device == "camera" else "p"
        label = {"f": f"f_{dev}", "fy": f"fy_{dev}", "u0": f"u0{dev}", "v0": f"v0{dev}"}
        bound = ", ".join(f"{label[k]} ±{_pct(rel[k])}" for k in ("f", "fy", "u0", "v0") if k in bad)
        tilted = tilts >= o.square_deg
        lo, hi = float(tilts.min()), float(tilts.max())
        if not tilted.any():
            why = f"every board faces the {device} squarely (tilted {lo:.1f}-{hi:.1f} deg from its optical axis)"
        elif tilted.sum() == 1:
            k = int(np.flatnonzero(tilted)[0])
            others = [n for j, n in enumerate(used_names) if j != k]
            why = (f"only pose {used_names[k]!r} is tilted ({tilts[k]:.0f} deg); {_list(others)} "
                   f"face{'s' if len(others) == 1 else ''} the {device} squarely, so everything rests on that one pose")
        else:
            d = (axes[tilted] - axes[tilted][0] + 90.0) % 180.0 - 90.0
            one_axis = bool(np.ptp(d) <= 2 * o.one_axis_deg)
            if distinct == 1:
                why = (f"the {len(used)} boards are parallel to one another (normals within "
                       f"{o.same_orientation_deg:g} deg; turning a board within its own plane adds nothing)")
            elif one_axis:
                why = f"every tilted board is turned about {_axis_words(float(axes[tilted][0] + np.mean(d)))}"
            elif distinct < len(used):
                why = (f"the {len(used)} poses have only {distinct} distinct board orientations (normals within "
                       f"{o.same_orientation_deg:g} deg count once)")
            else:
                why = "the boards' tilts are too small or too alike"
        msg = (f"{device}: degenerate pose set: {why}: {undet} {'is' if ' and ' not in undet else 'are'} not "
               f"determined (predicted {bound} for {sigma:g} px corner noise, before any fit); capture 3 or more "
               f"poses tilted 15-30 deg from the {device} about different axes (left/right, up/down and diagonally), "
               "each a distinct orientation")
    return DeviceSetCheck(device, rel, tilts, axes, distinct, bad, msg)


def _pct(r) -> str:
    return "inf" if not np.isfinite(r) else f"{100 * r:.0f} %" if r >= 0.1 else f"{100 * r:.1f} %"


def _list(names) -> str:
    names = [repr(str(n)) for n in names]
    if len(names) <= 4:
        return ", ".join(names)
    return ", ".join(names[:3]) + f" and {len(names) - 3} more"


def check_pose_set(views, cam_size, proj_size=None, options: PoseSetOptions = PoseSetOptions(), *,
                   devices=("camera", "projector")) -> PoseSetCheck:
    """Judge a multi-pose set before fitting (module docstring).

    Parameters
    ----------
    views : :class:`procam.view.View` sequence (their valid corners are used).
    cam_size, proj_size : (W, H) of each device (the projector is skipped when None).
    devices : which devices to judge (``("camera",)`` for photos without a projector).

    Returns
    -------
    :class:`PoseSetCheck`
    """
    from pathlib import Path

    names = [Path(str(v.name)).name or f"pose{k + 1}" for k, v in enumerate(views)]
    out, reasons = {}, []
    for device, size, key, sigma in (("camera", cam_size, "cam_pts", options.camera_noise_px),
                                     ("projector", proj_size, "proj_pts", options.projector_noise_px)):
        if device not in devices or size is None:
            continue
        objs = [np.asarray(v.obj_pts, float) for v in views]
        pts = [np.asarray(getattr(v, key), float) for v in views]
        d = _device_check(device, objs, pts, names, tuple(int(s) for s in size), sigma, options)
        if d is None:
            continue
        out[device] = d
        if d.message:
            reasons.append(d.message)
    return PoseSetCheck("degenerate" if reasons else "good", tuple(reasons), out)
