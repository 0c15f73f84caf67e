"""Ready scenes: the seed paper's simulated rig and its variants (see :func:`preset`).

Every preset places the board at :data:`RECOMMENDED_POSE` with :func:`~procam.simulate.with_board_pose`,
so that it is seen whole by both devices.  Scenes are immutable: one instance per preset is shared.
"""

from __future__ import annotations

import functools

import numpy as np

from .background import Background, Box, Plane, Sphere
from .lens import _K, euler_matrix
from .poses import with_board_pose
from .scene import Scene

__all__ = ["PRESETS", "RECOMMENDED_POSE", "preset"]

#: Board (psi, nu, phi) in degrees in the CAMERA frame recommended for a single-pose calibration
#: with the ``paper`` / ``ideal`` rigs: |psi_c| + |nu_c| = 27 > 10 and, through the rig's
#: R (nu = 14.44 deg), nu_p = 26.1 deg > 13 (checked in ``tests/test_simulate.py``).
RECOMMENDED_POSE: tuple[float, float, float] = (15.0, 12.0, 0.0)

PRESETS = ("paper", "ideal", "lensshift", "hard", "vertical", "ceiling")


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

    The rigs below keep the paper's camera (and, but for ``hard``, its lens) and have a background
    fixed in the room (camera frame, mm; :class:`~procam.simulate.Background`):

    ``lensshift``
        A real projector: the paper's rig (R, T) with the projector's principal point below its panel
        (vertical lens shift, the image thrown above the lens axis) and off centre: f_p 2421, alpha_p 1,
        u0p = W/2 + 21 = 981, v0p = 1.08 H = 1166.4 (beyond the last row, 1079); OpenCV lens
        k1 = -0.10, k2 = 0.015, p1 = p2 = k3 = 0 (about 18 px at the board's outer corners).  A wall
        through (0, 0, 1000) turned 10 deg about the vertical (normal Ry(-10 deg) e_z), albedo 0.5.
    ``hard``
        What makes real captures hard: lenses OpenCV's 5-term model does not describe exactly and a
        background that is not one plane.  Camera: OpenCV k1 = -0.08, k2 = 0.05, an r^8 term 0.15 and the
        radial centre (+3, -2) px from the principal point (a lens decentred as manufacturing leaves one: a
        few pixels).  Projector: f_p 2421, alpha_p 1, u0p = W/2 - 30 = 930, v0p = 1.05 H = 1134; OpenCV
        k1 = -0.12, k2 = 0.04, an r^8 term 0.2 and the radial centre (+6, -4) px from the principal point.
        Neither lens is one OpenCV's 5-term model (nor procam's single-pose division model) describes
        exactly: the r^8 terms leave about 0.1 px RMS, 1 px at most, over the panel.  The room: a corner - two walls meeting in a vertical edge through
        (200, 0, 1150), normals (0.45, 0, -1) (albedo 0.55) and (-0.6, 0, -1) (albedo 0.45) - a box
        110 x 130 x 110 mm at (170, 30, 880) turned 30 deg about the vertical (albedo 0.7), partly behind the
        board, and a ball of radius 60 mm at (250, -170, 950) (albedo 0.6), each casting a shadow.
    ``vertical``
        A floor / ceiling rig: the paper's devices (and projector intrinsics) with the projector 600 mm
        BELOW the camera (its centre at (0, 600, 0) in the camera frame, y down), pitched up 20 deg
        (R = Rx(-20 deg), T = -R (0, 600, 0) = (0, -563.8, 205.2) mm): a vertical baseline.  A frontal
        wall at z = 1800.
    ``ceiling``
        An upside-down (ceiling-mounted) projector: the paper's projector rolled 180 deg about its axis,
        R = Rx(-10) Ry(-14.44) Rz(180) (Euler (-10, -14.44, 180) deg), its centre at (150, -350, 50) mm
        in the camera frame (350 mm above the camera); its lens shift then throws the image below the
        lens axis, towards the board.  A frontal wall at z = 1500.
    """
    if name not in PRESETS:
        raise ValueError(f"unknown preset {name!r}; choose one of {', '.join(PRESETS)}")
    return _preset_cached(name)


@functools.lru_cache(maxsize=None)
def _preset_cached(name: str) -> Scene:
    # Scenes are immutable (frozen, read-only arrays), so one instance per preset can be shared.
    return with_board_pose(_RIGS[name](), RECOMMENDED_POSE)


def _paper() -> Scene:
    return Scene(name="paper")


def _ideal() -> Scene:
    return Scene(name="ideal", K_proj=_K(2421.0, 1.0, 960.0, 1065.0), cam_dist_coeffs=(-1e-7, 0.0))


def _lensshift() -> Scene:
    W, H = 1920, 1080
    wall = Background.wall(1000.0, normal=euler_matrix((0.0, -10.0, 0.0))[:, 2])
    return Scene(name="lensshift", K_proj=_K(2421.0, 1.0, W / 2 + 21, 1.08 * H), proj_distortion="opencv",
                 proj_dist_coeffs=(-0.10, 0.015, 0.0, 0.0, 0.0), background=wall)


def _hard() -> Scene:
    W, H = 1920, 1080
    u0p, v0p = W / 2 - 30, 1.05 * H
    edge = (200.0, 0.0, 1150.0)
    room = Background((Plane(edge, (0.45, 0.0, -1.0), 0.55), Plane(edge, (-0.6, 0.0, -1.0), 0.45),
                       Box.at((170.0, 30.0, 880.0), (110.0, 130.0, 110.0), (0.0, 30.0, 0.0), 0.7),
                       Sphere((250.0, -170.0, 950.0), 60.0, 0.6)))
    return Scene(name="hard", cam_distortion="opencv", cam_dist_coeffs=(-0.08, 0.05, 0.0, 0.0, 0.0),
                 cam_dist_center=(674.0 + 3, 512.0 - 2), cam_dist_higher=(0.15,),
                 K_proj=_K(2421.0, 1.0, u0p, v0p), proj_distortion="opencv",
                 proj_dist_coeffs=(-0.12, 0.04, 0.0, 0.0, 0.0), proj_dist_center=(u0p + 6, v0p - 4),
                 proj_dist_higher=(0.2,), background=room)


def _vertical() -> Scene:
    R = euler_matrix((-20.0, 0.0, 0.0))
    return Scene(name="vertical", R=R, T=-R @ np.array([0.0, 600.0, 0.0]), background=Background.wall(1800.0))


def _ceiling() -> Scene:
    R = euler_matrix((-10.0, -14.44, 180.0))
    return Scene(name="ceiling", R=R, T=-R @ np.array([150.0, -350.0, 50.0]), background=Background.wall(1500.0))


_RIGS = {"paper": _paper, "ideal": _ideal, "lensshift": _lensshift, "hard": _hard, "vertical": _vertical,
         "ceiling": _ceiling}
