"""The fields every single-pose device solution shares (:class:`~procam.single_pose.CameraSolution`,
:class:`~procam.single_pose.ProjectorSolution`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..calibration import Distortion


@dataclass(frozen=True)
class DeviceSolution:
    """Fields shared by :class:`CameraSolution` and :class:`ProjectorSolution` (documented there)."""

    K: np.ndarray
    distortion: Distortion
    R: np.ndarray
    t: np.ndarray
    rms_px: float
    residuals: np.ndarray
    std: dict
    angles_deg: np.ndarray
    cost: float
    warnings: tuple = ()
    params: np.ndarray | None = None
    covariance: np.ndarray | None = None
    mask: np.ndarray | None = None
    image_size: tuple | None = None
    info: dict = field(default_factory=dict)
    rejected: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    rejected_residuals_px: np.ndarray = field(default_factory=lambda: np.zeros(0))
    outlier_threshold_px: float = float("nan")
