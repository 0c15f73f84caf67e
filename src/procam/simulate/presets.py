"""Ready scenes: the seed paper's simulated rig and its variants (see :func:`preset`).

Every preset places the board at :data:`RECOMMENDED_POSE` with :func:`~procam.simulate.with_board_pose`,
so that it is seen whole by both devices.  Scenes are immutable: one instance per preset is shared.
"""

from __future__ import annotations

import functools

from .lens import _K
from .poses import with_board_pose
from .scene import Scene

__all__ = ["PRESETS", "RECOMMENDED_POSE", "preset"]

#: Board (psi, nu, phi) in degrees in the CAMERA frame recommended for a single-pose calibration
#: with the ``paper`` / ``ideal`` rigs: |psi_c| + |nu_c| = 27 > 10 and, through the rig's
#: R (nu = 14.44 deg), nu_p = 26.1 deg > 13 (checked in ``tests/test_simulate.py``).
RECOMMENDED_POSE: tuple[float, float, float] = (15.0, 12.0, 0.0)

PRESETS = ("paper", "ideal")


def preset(name: str = "paper") -> Scene:
    """A ready scene at :data:`RECOMMENDED_POSE` (board centre placed by :func:`with_board_pose`).

    ``paper``
        The simulated procam of the seed paper's simulation study: camera 1280x800, f 1539, alpha 1.004,
        pp (674, 512); projector 1920x1080, f 2421, alpha 1.002, pp (1013, 1065); R, T from the
        paper's reference calibration (Euler (0.87, 14.44, -0.25) deg, T (-170.05, -41.25, -65.35)
        mm); board 10x6 at 24 mm.  Mild barrel distortion: division model k1 = -3e-8 px^-2 about the
        principal point (about 0.8-5 px at the board's outer corners at the recommended pose).
    ``ideal``
        The same rig with the single-pose method's assumptions true: u0p = 960 (W/2), alpha_p = 1,
        and a division-model distortion k1 = -1e-7 px^-2 about the principal point (the reference
        value of procam's Cramér-Rao analysis), strong enough (about 3-14 px at the board's outer
        corners at the recommended pose) for the centre of distortion to be observable from one
        view (:mod:`procam.distortion`).
    """
    if name not in PRESETS:
        raise ValueError(f"unknown preset {name!r}; choose one of {', '.join(PRESETS)}")
    return _preset_cached(name)


@functools.lru_cache(maxsize=None)
def _preset_cached(name: str) -> Scene:
    # Scenes are immutable (frozen, read-only arrays), so one instance per preset can be shared.
    if name == "paper":
        scene = Scene(name="paper")
    else:
        scene = Scene(name="ideal", K_proj=_K(2421.0, 1.0, 960.0, 1065.0), cam_dist_coeffs=(-1e-7, 0.0))
    return with_board_pose(scene, RECOMMENDED_POSE)
