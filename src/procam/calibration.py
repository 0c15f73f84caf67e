"""Calibration results: small frozen dataclasses shared by the single- and multi-pose solvers, and a rig's
(:class:`RigCalibration`: several devices, their relative poses with their ±).

Conventions: ``x_p = R @ x_c + T`` maps camera coordinates to projector coordinates
(OpenCV ``stereoCalibrate`` with the camera first); lengths in the board's unit.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from . import models
from . import uncertainty as unc
from .parameters import PARAMETERS


@dataclass(frozen=True)
class Distortion:
    """Lens distortion of one device.

    ``model`` is one of

    * ``"none"``;
    * ``"division"``: ``center`` (x, y) px, ``k1`` [px^-2], ``k2`` [px^-4]; maps distorted ->
      undistorted pixels (:func:`procam.models.undistort_division`);
    * ``"opencv"``: ``coeffs`` in OpenCV's order (k1, k2, p1, p2[, k3[, k4, k5, k6]]) applied
      in normalised coordinates with the device's K.
    """

    model: str = "none"
    center: tuple[float, float] | None = None
    k1: float = 0.0
    k2: float = 0.0
    coeffs: tuple[float, ...] = ()

    def __post_init__(self):
        if self.model not in ("none", "division", "opencv"):
            raise ValueError(f"unknown distortion model {self.model!r}")

    def undistort(self, pts: np.ndarray, K: np.ndarray) -> np.ndarray:
        """Distorted -> undistorted pixels, (N, 2) -> (N, 2) (same K before and after)."""
        pts = np.asarray(pts, float).reshape(-1, 2)
        if self.model == "none":
            return pts.copy()
        if self.model == "division":
            return models.undistort_division(pts, self.center, self.k1, self.k2)
        import cv2

        out = np.full_like(pts, np.nan)
        ok = np.isfinite(pts).all(1)
        if ok.any():
            # OpenCV 4 has undistortPointsIter; OpenCV 5 folded the criteria into undistortPoints.
            und_fn = getattr(cv2, "undistortPointsIter", cv2.undistortPoints)
            und = und_fn(pts[ok].reshape(-1, 1, 2), np.asarray(K, float), np.asarray(self.coeffs, float),
                         None, np.asarray(K, float),
                         criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12))
            out[ok] = und.reshape(-1, 2)
        return out

    def distort(self, pts: np.ndarray, K: np.ndarray) -> np.ndarray:
        """Undistorted -> distorted pixels, (N, 2) -> (N, 2)."""
        pts = np.asarray(pts, float).reshape(-1, 2)
        if self.model == "none":
            return pts.copy()
        if self.model == "division":
            return models.distort_division(pts, self.center, self.k1, self.k2)
        import cv2

        K = np.asarray(K, float)
        xn = np.column_stack([(pts[:, 0] - K[0, 2]) / K[0, 0], (pts[:, 1] - K[1, 2]) / K[1, 1],
                              np.ones(len(pts))])
        out, _ = cv2.projectPoints(xn.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), K,
                                   np.asarray(self.coeffs, float))
        return out.reshape(-1, 2)

    def to_dict(self) -> dict:
        if self.model == "division":
            return {"model": "division", "center": [float(self.center[0]), float(self.center[1])],
                    "k1": float(self.k1), "k2": float(self.k2)}
        if self.model == "opencv":
            return {"model": "opencv", "coeffs": [float(c) for c in self.coeffs]}
        return {"model": "none"}

    @staticmethod
    def from_dict(d: dict) -> "Distortion":
        """Inverse of :meth:`to_dict`; raises ``ValueError`` for a model procam does not know (never guesses)."""
        m = d.get("model", "none")
        if m == "division":
            return Distortion("division", tuple(float(v) for v in d["center"]), float(d["k1"]),
                              float(d.get("k2", 0.0)))
        if m == "opencv":
            return Distortion("opencv", coeffs=tuple(float(c) for c in d["coeffs"]))
        if m == "none":
            return Distortion()
        raise ValueError(f"unknown distortion model {m!r} (procam reads 'division', 'opencv' and 'none')")


@dataclass(frozen=True)
class Device:
    """Intrinsics of one device: ``K`` (3, 3), ``image_size`` (width, height), distortion; ``covariance``: None,
    or its own uncertainty as ``(names, matrix)`` -- the parameters (``f_c, fy_c, u0c, v0c`` and OpenCV's
    coefficients ``k1, k2, p1, p2, k3 ...``, :data:`procam.crlb.VIEW_PARAMS`) and their (k, k) covariance, as a
    camera file carries it (a solver that holds the device carries it into its own ``±``)."""

    K: np.ndarray
    image_size: tuple[int, int]
    distortion: Distortion = Distortion()
    covariance: tuple | None = field(default=None, compare=False, repr=False)

    def undistort(self, pts):
        return self.distortion.undistort(pts, self.K)

    def project(self, R, t, X) -> np.ndarray:
        """Distorted pixels (N, 2) of board points X (N, 3) at pose (R, t)."""
        return self.distortion.distort(models.project(self.K, R, t, X), self.K)


@dataclass(frozen=True)
class Calibration:
    """A procam calibration.

    Attributes
    ----------
    camera, projector : :class:`Device` (``projector`` is None for a camera-only result).
    R : (3, 3), T : (3,)
        Camera -> projector: ``x_p = R x_c + T`` (board units); None for a camera-only result.
    method : "single-pose", "multi-pose" or "camera-only" (camera intrinsics from one pose, no
        projector; :func:`procam.single_pose.calibrate_camera_only`), with variant details in ``info``.
    cam_rms, proj_rms, stereo_rms : RMS reprojection errors in pixels (NaN if not computed).
    std : dict name -> standard deviation (same units as the parameter; angles in degrees),
        from the Jacobian at the solution. Every name is a declared parameter
        (:data:`procam.parameters.PARAMETERS`): a result with another name is refused (``ValueError``), so a
        solver cannot report a number no table, file or reader knows.
    poses : list of per-pose dicts (name, angles, advice, errors).
    views : the :class:`procam.view.View` s it was computed from.
    warnings : human-readable caveats (unreliable centre of distortion, degenerate pose, ...).
    info : anything else worth keeping (solver costs, covariance matrices as lists, ...).
    verdict : ``"good"``, ``"weak"`` (usable, less precise than it could be), ``"degenerate"`` (the poses do
        not determine some parameters: they may be anything) or ``"failed"`` (an impossible estimate).
    verdict_reasons : the verdict's reasons in words (also in ``warnings``).
    """

    camera: Device
    projector: Device | None
    R: np.ndarray | None
    T: np.ndarray | None
    method: str
    cam_rms: float = float("nan")
    proj_rms: float = float("nan")
    stereo_rms: float = float("nan")
    std: dict = field(default_factory=dict)
    poses: tuple = ()
    views: tuple = ()
    warnings: tuple = ()
    info: dict = field(default_factory=dict)
    verdict: str = "good"
    verdict_reasons: tuple = ()

    def __post_init__(self):
        unknown = sorted(set(self.std) - set(PARAMETERS))
        if unknown:
            raise ValueError(f"std names not declared in procam.parameters: {', '.join(unknown)}")

    @property
    def trusted(self) -> bool:
        """The verdict is good or weak: the numbers mean what they say (within their ±)."""
        return self.verdict in ("good", "weak")

    def replace(self, **kw) -> "Calibration":
        return replace(self, **kw)


# ------------------------------------------------------------------------------------------------
# a rig's calibration
# ------------------------------------------------------------------------------------------------
#
# A rig's calibration: every device in the reference camera's frame, every relative pose with its ±.
#
# Conventions: the reference frame is the first camera's; a device's pose is ``x_dev = R x_ref + T`` (board units,
# mm for a board in mm); a relative pose ``a->b`` maps device ``a``'s frame to ``b``'s, ``x_b = R x_a + T``; angles
# are intrinsic XYZ Euler angles in degrees (:func:`procam.models.euler_deg`).  The std of a relative pose comes
# from the delta method (:func:`procam.uncertainty.propagate`) through the covariance of the poses it is composed of:
# the joint refinement's full covariance (multi-pose), or the pairs' own std taken as independent (single pose).

@dataclass(frozen=True)
class RigDevice:
    """One device of a calibrated rig: ``name``, ``kind`` (``camera``/``projector``), its intrinsics ``device``
    (:class:`procam.calibration.Device`), ``R, T`` reference -> device, ``std`` of its intrinsics (``f``,
    ``fy``, ``u0``, ``v0`` px; ``dist``: per coefficient, 0 for a fixed one), its ``verdict`` and
    ``verdict_reasons``."""

    name: str
    kind: str
    device: object
    R: np.ndarray
    T: np.ndarray
    std: dict = field(default_factory=dict)
    verdict: str = "good"
    verdict_reasons: tuple = ()

    @property
    def center(self) -> np.ndarray:
        """Centre of projection in the reference frame, ``-R^T T``."""
        return -np.asarray(self.R).T @ np.asarray(self.T)


@dataclass(frozen=True)
class RelativePose:
    """``x_b = R x_a + T`` with 1-sigma ``std_angles_deg`` (3,), ``std_T`` (3,) and ``std_baseline``."""

    a: str
    b: str
    R: np.ndarray
    T: np.ndarray
    std_angles_deg: np.ndarray
    std_T: np.ndarray
    std_baseline: float

    @property
    def angles_deg(self) -> np.ndarray:
        return models.euler_deg(self.R)

    @property
    def baseline(self) -> float:
        return float(np.linalg.norm(self.T))

    def to_dict(self) -> dict:
        return {"R": np.asarray(self.R).tolist(), "T": np.asarray(self.T).tolist(),
                "angles_deg": self.angles_deg.tolist(), "baseline": self.baseline,
                "std": {"angles_deg": np.asarray(self.std_angles_deg).tolist(), "T": np.asarray(self.std_T).tolist(),
                        "baseline": float(self.std_baseline)}}


@dataclass(frozen=True)
class RigCalibration:
    """A calibrated rig (:func:`procam.rig.calibrate_rig`).

    method : ``"single-pose"`` or ``"multi-pose"``.
    cameras, projectors : :class:`RigDevice` tuples; ``cameras[0]`` is the reference.
    relative : ``{"a->b": RelativePose}`` for every ordered pair of distinct devices.
    pairs : ``{"camera/projector": Calibration}``: each pair as an ordinary procam calibration in its camera's
        frame (what :func:`procam.io.load_calibration` reads from a rig file with ``pair=``).
    pose_names : the rig poses; ``uncertainty`` : what every ± assumes; ``info`` : solver details;
    ``warnings``; ``verdict`` / ``verdict_reasons`` : the worst device's.
    """

    method: str
    cameras: tuple
    projectors: tuple
    relative: dict
    pairs: dict
    pose_names: tuple = ()
    uncertainty: str = ""
    info: dict = field(default_factory=dict)
    warnings: tuple = ()
    verdict: str = "good"
    verdict_reasons: tuple = ()

    @property
    def reference(self) -> str:
        return self.cameras[0].name

    @property
    def devices(self) -> tuple:
        return self.cameras + self.projectors

    def device(self, name: str) -> RigDevice:
        for d in self.devices:
            if d.name == name:
                return d
        raise KeyError(f"no device {name!r} in the rig (devices: {', '.join(d.name for d in self.devices)})")

    def pair(self, name: str):
        """The pair calibration ``"camera/projector"``, or the one pair of a device name."""
        if name in self.pairs:
            return self.pairs[name]
        hits = [k for k in self.pairs if name in k.split("/")]
        if len(hits) == 1:
            return self.pairs[hits[0]]
        raise KeyError(f"no single pair {name!r} in the rig (pairs: {', '.join(self.pairs)})")

    def relative_pose(self, a: str, b: str) -> RelativePose:
        """``a -> b`` (``KeyError`` naming the devices when there is none)."""
        key = f"{a}->{b}"
        if key not in self.relative:
            raise KeyError(f"no relative pose {key!r} (devices: {', '.join(d.name for d in self.devices)})")
        return self.relative[key]

    @property
    def trusted(self) -> bool:
        return self.verdict in ("good", "weak")


def relative_poses(names, x, cov, poses: Callable[[np.ndarray], dict]) -> dict:
    """Every relative pose ``a->b`` (every ordered pair of distinct devices) with its std by the delta method.

    ``poses(x)`` gives ``{name: (R, T)}`` reference -> device for a parameter vector ``x`` whose covariance is
    ``cov``; the std of ``(angles of R_ab, T_ab, |T_ab|)`` is propagated through it (central differences)."""
    x = np.asarray(x, float)
    P = poses(x)
    out = {}
    for a in names:
        for b in names:
            if a == b:
                continue
            def f(q, a=a, b=b):
                pq = poses(q)
                (Ra, Ta), (Rb, Tb) = pq[a], pq[b]
                R = Rb @ Ra.T
                T = Tb - R @ Ta
                return np.r_[models.euler_deg(R), T, np.linalg.norm(T)]

            s = unc.std(unc.propagate(cov, f, x)) if x.size else np.zeros(7)
            (Ra, Ta), (Rb, Tb) = P[a], P[b]
            R = Rb @ Ra.T
            out[f"{a}->{b}"] = RelativePose(a, b, R, Tb - R @ Ta, s[:3], s[3:6], float(s[6]))
    return out
