"""Synthetic projector-camera captures with ground truth (the oracle of every accuracy test).

A :class:`Scene` holds everything: the camera and the projector (K, size, lens distortion: the
division model, OpenCV's, or lenses OpenCV's model does not describe exactly), the camera ->
projector extrinsics ``x_p = R x_c + T``, a printed chessboard at a pose (board -> camera), the
background (a wall that moves with the board, or planes and solids fixed in the room) and the
photometry of the capture (projector black level, response and defocus, ambient light, camera gain,
gamma, optical blur, shot and read noise, bit depth).  A :class:`Rig` holds several cameras and
projectors around one board; :meth:`Rig.scene` is the ordinary scene of one of its pairs.

Paths to the truth:

* :func:`correspondences` - the fast corner path: exact corner geometry plus Gaussian noise, no images.
* :func:`true_projector_maps` - the dense fast path: exact projector coordinates at camera pixels, on
  the board and the background, with occlusion and shadow masks, optionally rounded like a Gray-code
  decode and on a subsampled grid.
* :func:`render` - physically plausible Gray-code captures (:class:`Renderer` renders them one
  pattern image at a time); :func:`write_capture` writes one as a capture folder.
* :func:`truth`, :func:`truth_calibration` - everything known (JSON), the perfect calibration.

The package is independent of the solvers: it imports only numpy, scipy, cv2,
:mod:`procam.patterns`, :mod:`procam.capture` (the capture-folder format), :mod:`procam.io.files`
(file writing) and :mod:`procam.calibration` (the result container :func:`truth_calibration` fills),
and has its own projection, division model (with its Newton inverse) and OpenCV-Brown distortion.
Its modules:

* :mod:`~procam.simulate.lens` - the oracle's own projection, lens models (:class:`Lens`) and Euler angles;
* :mod:`~procam.simulate.background` - backgrounds fixed in the room: :class:`Plane`, :class:`Box`,
  :class:`Sphere`, :class:`Background`;
* :mod:`~procam.simulate.scene` - :class:`Scene`, the board's geometry;
* :mod:`~procam.simulate.poses` - board placement (:func:`with_board_pose`, :func:`fit_margin`);
* :mod:`~procam.simulate.presets` - ready rigs (:func:`preset`, :data:`PRESETS`);
* :mod:`~procam.simulate.truth` - the exact ground truth and the corner fast path;
* :mod:`~procam.simulate.geometry` - the per-ray geometry oracle and the dense fast path;
* :mod:`~procam.simulate.renderer` - the renderer and the capture writer;
* :mod:`~procam.simulate.rig` - several cameras and projectors (:class:`Rig`, :func:`rig_preset`);
  :mod:`~procam.simulate.rig_capture` renders and writes them as rig pose folders.

Conventions (see ``procam`` README): pixels ``(x, y)`` = (column, row), origin at the centre of the
top-left pixel; a pose ``(R, t)`` maps board -> device; board corner ``k = j*cols + i`` is at
``(i s, j s, 0)`` minus the centroid, z away from the devices; Euler angles ``(psi, nu, phi)`` are
intrinsic XYZ, ``R = Rx(psi) Ry(nu) Rz(phi)``, degrees at this package's surface; lengths in mm.
"""

from __future__ import annotations

from .background import Background, Box, Plane, Sphere
from .geometry import ProjectorMaps, true_projector_maps
from .lens import Lens, distort, euler_matrix, matrix_euler, project, project_points, undistort
from .poses import fit_margin, with_board_pose
from .presets import PRESETS, RECOMMENDED_POSE, preset
from .renderer import Renderer, render, write_capture
from .rig import RIG_PRESETS, Device, Rig, rig_preset
from .rig_capture import render_rig, write_rig_capture
from .scene import DEFAULT_DISTANCE, Scene, board_corners, board_extent
from .truth import corner_truth, correspondences, truth, truth_calibration

__all__ = [
    "Scene", "preset", "PRESETS", "RECOMMENDED_POSE", "DEFAULT_DISTANCE", "with_board_pose",
    "truth", "truth_calibration", "correspondences", "true_projector_maps", "ProjectorMaps", "render", "Renderer",
    "write_capture", "board_corners", "board_extent", "corner_truth", "fit_margin", "project", "project_points",
    "distort", "undistort", "euler_matrix", "matrix_euler", "Lens", "Background", "Plane", "Box", "Sphere",
    "Rig", "Device", "rig_preset", "RIG_PRESETS", "render_rig", "write_rig_capture",
]
