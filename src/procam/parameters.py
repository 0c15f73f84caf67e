"""One vocabulary of parameter names: ``Calibration.std``, the JSON ``std``, the solvers' parameter vectors,
the Cramer-Rao bounds and every table use these names.

Intrinsics of device ``d`` in ``{c (camera), p (projector)}``: ``f_d`` = fx, ``fy_d`` = fy = alpha f,
``alpha_d`` = fy / fx, ``(u0d, v0d)`` the principal point (pixels). Division-model distortion of the
single-pose camera: ``k1`` [px^-2], ``k2`` [px^-4] about the principal point. OpenCV distortion vectors:
``cam_dist`` / ``proj_dist`` (OpenCV's order). Extrinsics camera -> projector: ``R_euler_deg`` (the Euler
angles of ``R``, degrees) and ``T`` (board units). Board angles: ``camera_angles_deg`` /
``projector_angles_deg``.
"""

from __future__ import annotations

#: name -> (unit, meaning)
PARAMETERS: dict[str, tuple[str, str]] = {
    "f_c": ("px", "camera focal length fx"),
    "fy_c": ("px", "camera focal length fy = alpha_c f_c"),
    "alpha_c": ("", "camera aspect ratio fy / fx"),
    "u0c": ("px", "camera principal point x"),
    "v0c": ("px", "camera principal point y"),
    "k1": ("px^-2", "division-model k1 of the camera (about its principal point)"),
    "k2": ("px^-4", "division-model k2 of the camera"),
    "cam_dist": ("", "camera OpenCV distortion coefficients (k1, k2, p1, p2[, k3 ...])"),
    "f_p": ("px", "projector focal length fx"),
    "fy_p": ("px", "projector focal length fy = alpha_p f_p"),
    "alpha_p": ("", "projector aspect ratio fy / fx"),
    "u0p": ("px", "projector principal point x"),
    "v0p": ("px", "projector principal point y"),
    "proj_dist": ("", "projector OpenCV distortion coefficients"),
    "R_euler_deg": ("deg", "camera -> projector rotation as intrinsic XYZ Euler angles (psi, nu, phi)"),
    "T": ("board units", "camera -> projector translation (x_p = R x_c + T)"),
    "camera_angles_deg": ("deg", "board angles (psi, nu, phi) in the camera frame"),
    "projector_angles_deg": ("deg", "board angles (psi, nu, phi) in the projector frame"),
}

#: The single-pose camera parameter vector (:func:`procam.models.camera_predict`): intrinsics, the
#: conditioned division coefficients ``kappa1 = k1 S^2``, ``kappa2 = k2 S^4`` (``S`` =
#: :data:`procam.models.KAPPA_SCALE`), the board pose as a rotation vector and a translation.
CAMERA_VECTOR = ("f_c", "alpha_c", "u0c", "v0c", "k1", "k2", "rx", "ry", "rz", "tx", "ty", "tz")

#: The single-pose projector parameter vector (:func:`procam.models.projector_predict`; ``u0p`` and
#: ``alpha_p = 1`` fixed).
PROJECTOR_VECTOR = ("f_p", "v0p", "rx", "ry", "rz", "tx", "ty", "tz")

#: The std of the prior ``alpha_p = 1 +- std`` that every single-pose projector fit puts on square projector pixels
#: while it does not estimate ``alpha_p`` (the dense fit's and the background's default, and what the tables name).
ALPHA_PRIOR_STD = 0.003
