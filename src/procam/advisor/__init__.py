"""Live pose advice: how to turn the board before a single-pose capture.

Per camera frame (:meth:`Advisor.update`):

1. the board: :func:`procam.board.corners.detect_corners` with its live setting (:data:`procam.board.corners.LIVE`,
   :attr:`AdvisorOptions.detect_options`): OpenCV's chessboard detector on a downscaled copy of the frame
   (``AdvisorOptions.detect_width``, ``CALIB_CB_FAST_CHECK`` so a frame without the board costs little),
   the corners refined with ``cornerSubPix`` in the full-resolution frame, in procam's canonical order
   (:func:`procam.board.corners.canonical_order`);
2. the board's pose in the camera by PnP (``SOLVEPNP_IPPE`` on the undistorted corners) with the camera's
   intrinsics: from a calibration (an earlier capture or a calibration file) when there is one, else a
   guess (``f`` = the image diagonal, the principal point at the image centre, no distortion) -- the advice
   says which (:attr:`Advice.intrinsics`);
3. the board's angles ``(psi_c, nu_c)`` (:func:`procam.models.board_angles_deg`) and the Cramér-Rao bound of
   ``f_c`` at that pose (:func:`procam.crlb.camera_bound`, the ``full`` model the single-pose solver fits:
   ``f, alpha``, the principal point = centre of distortion, ``k1, k2`` and the pose, corner noise
   ``sigma_camera`` px).  When the corners do not pin the principal point (its data-only bound above
   the solver's prior, 2.5 % of the larger image side), the bound is the one with the solver's Gaussian
   prior on it (the image centre), as :func:`procam.single_pose.calibrate` then does;
4. with an earlier capture's calibration (its ``R, T, K_p``), the board in the projector frame
   (``R_pb = R R_cb, t_pb = R t_cb + T``), ``(psi_p, nu_p)`` and the bound of ``f_p, v0p``
   (:func:`procam.crlb.projector_bound`: ``u0p`` and ``alpha_p`` held, corner noise ``sigma_projector``);
   the printed board's footprint in the projector image tells whether it is all in the projector's light;
5. the advice (:class:`Action` s): move into view / closer / into the light first, then which way to turn
   and tilt the board and roughly how far (:meth:`Advisor.search_move`), then "good — hold still" until the
   corners have been still for ``still_s``: the state ``ready``.

The score of a pose is the largest of its terms, each ``<= 1`` when satisfied: ``std(f_c) / f_c / target``
(with known intrinsics), ``std(f_p) / f_p / target`` (with the projector side) and the paper's rule as
:func:`procam.single_pose.rate_pose` applies it (``|psi_c| + |nu_c| > 10``, each ``>= 4`` deg; ``|nu_p| > 13``
deg), as a ratio.  The bounds cover the noise only; the rule keeps clear of poses where the method's
assumptions (``u0p = W/2``, the principal point at the centre of distortion) cost most.  Before the
projector side is known and with guessed intrinsics, the camera's bound is only indicative (no distortion
is known) and the camera rule alone judges the pose: enough for the one quick capture that measures
``R, T``.  The move search (:meth:`Advisor.search_move`) probes a turn and a tilt each way, then walks
along the pure turns/tilts and their gradient-weighted combination until a pose scores below ``aim``
(a margin under 1); camera angles beyond ``max_angle_deg`` are not proposed (the detector and the corner
accuracy suffer).

Moves are rotations of the board about its own centre, about the **camera's** axes (the user's vertical
and horizontal): a *turn* of ``+d`` degrees is about the vertical axis with the board's right edge (as the
camera sees it) going away from the camera, a *tilt* of ``+d`` degrees about the horizontal axis with the
top edge going away (:func:`apply_move`).

Nothing here opens a window or prints: :class:`Advice` is a frozen dataclass per frame with its JSON
form (:meth:`Advice.to_dict`).

The camera mode (:class:`CameraAdvisor`, :mod:`.camera`) guides the photos of a camera calibrated once: where the
corners have been seen, which tilt to take next, the predicted ± of ``f_c``, the principal point and the
distortion after each photo, and "enough" at a stated target; then it writes the camera file.

The package: :mod:`.options` (:class:`AdvisorOptions`, :class:`Advice`, :class:`Action`, :class:`DeviceState`),
:mod:`.moves` (turns and tilts, PnP, the projector side) and :mod:`.advisor` (:class:`Advisor`).
"""

from __future__ import annotations

from .advisor import Advisor, guessed_camera
from .camera import CAMERA_STATES, CameraAdvice, CameraAdvisor
from .moves import ProjectorSide, apply_move, move_between
from .options import STATES, Action, Advice, AdvisorOptions, DeviceState

__all__ = ["AdvisorOptions", "Action", "DeviceState", "Advice", "ProjectorSide", "Advisor", "apply_move",
           "move_between", "guessed_camera", "STATES", "CameraAdvisor", "CameraAdvice", "CAMERA_STATES"]
