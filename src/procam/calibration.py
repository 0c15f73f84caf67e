"""Calibration results: small frozen dataclasses shared by the single- and multi-pose solvers.

Conventions: ``x_p = R @ x_c + T`` maps camera coordinates to projector coordinates
(OpenCV ``stereoCalibrate`` with the camera first); lengths in the board's unit.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from . import models
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
    """Intrinsics of one device: ``K`` (3, 3), ``image_size`` (width, height), distortion."""

    K: np.ndarray
    image_size: tuple[int, int]
    distortion: Distortion = Distortion()

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
