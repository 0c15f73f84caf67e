"""A rig's calibration: every device in the reference camera's frame, every relative pose with its ±.

Conventions: the reference frame is the first camera's; a device's pose is ``x_dev = R x_ref + T`` (board units,
mm for a board in mm); a relative pose ``a->b`` maps device ``a``'s frame to ``b``'s, ``x_b = R x_a + T``; angles
are intrinsic XYZ Euler angles in degrees (:func:`procam.models.euler_deg`).  The std of a relative pose comes
from the delta method (:func:`procam.uncertainty.propagate`) through the covariance of the poses it is composed of:
the joint refinement's full covariance (multi-pose), or the pairs' own std taken as independent (single pose).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .. import models
from .. import uncertainty as unc

__all__ = ["RigDevice", "RelativePose", "RigCalibration", "relative_poses"]


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
