"""Synthetic projector-camera captures with ground truth (the oracle of every accuracy test).

A :class:`Scene` holds everything: the camera (K, size, lens distortion), the projector (K, size),
the camera -> projector extrinsics ``x_p = R x_c + T``, a printed chessboard at a pose (board ->
camera) and a background wall, plus the photometry of the capture (projector black level and
defocus, ambient light, camera gain, gamma, optical blur, shot and read noise, bit depth).

Two paths:

* :func:`correspondences` - the fast path: exact corner geometry plus Gaussian noise, no images.
* :func:`render` - physically plausible Gray-code captures (:class:`Renderer` renders them one
  pattern image at a time); :func:`write_capture` writes one as a capture folder.

The package is independent of the solvers: it imports only numpy, scipy, cv2,
:mod:`procam.patterns`, :mod:`procam.capture` (the capture-folder format) and :mod:`procam.io.files`
(file writing), and has its own projection, division model (with its Newton inverse) and
OpenCV-Brown distortion.  Its modules:

* :mod:`~procam.simulate.lens` - the oracle's own projection, lens distortion and Euler angles;
* :mod:`~procam.simulate.scene` - :class:`Scene`, presets, board poses, the exact ground truth;
* :mod:`~procam.simulate.renderer` - the renderer and the capture writer.

Conventions (see ``procam`` README): pixels ``(x, y)`` = (column, row), origin at the centre of the
top-left pixel; a pose ``(R, t)`` maps board -> device; board corner ``k = j*cols + i`` is at
``(i s, j s, 0)`` minus the centroid, z away from the devices; Euler angles ``(psi, nu, phi)`` are
intrinsic XYZ, ``R = Rx(psi) Ry(nu) Rz(phi)``, degrees at this package's surface.
"""

from __future__ import annotations

from .lens import distort, euler_matrix, matrix_euler, project, undistort
from .renderer import Renderer, render, true_projector_maps, write_capture
from .scene import (DEFAULT_DISTANCE, PRESETS, RECOMMENDED_POSE, Scene, board_corners, board_extent,
                    corner_truth, correspondences, fit_margin, preset, truth, truth_calibration,
                    with_board_pose)

__all__ = [
    "Scene", "preset", "PRESETS", "RECOMMENDED_POSE", "DEFAULT_DISTANCE", "with_board_pose",
    "truth", "truth_calibration", "correspondences", "true_projector_maps", "render", "Renderer", "write_capture",
    "board_corners", "board_extent", "corner_truth", "fit_margin", "project", "distort", "undistort",
    "euler_matrix", "matrix_euler",
]
