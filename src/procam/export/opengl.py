"""OpenGL / TouchDesigner rendering matrices of both devices: 4x4 projection and view matrices.

* :func:`opengl_projection` -- the projection matrix of a pinhole ``K`` (clip space from eye space);
* :func:`view_matrices` -- world -> eye of the camera and the projector, world = a procam device frame;
* :func:`clip_to_pixels` -- the inverse of the whole chain (clip -> NDC -> window -> procam pixels);
* :func:`opengl_document` -- both devices' matrices, image sizes, K, distortion and the conventions as one
  JSON-able document (``procam export --format opengl``).

Conventions (docs/exports.md has the tables): procam pixels ``(x, y)`` have their origin at the centre of the
top-left pixel (OpenCV's); device frames are OpenCV's (x right, y down, z forward); OpenGL's eye frame is x right,
y up, looking down -z (``GL_FROM_CV``); ``x_p = R x_c + T`` maps camera to projector coordinates, board units.
The matrices render the pinhole (undistorted) image: lens distortion is no matrix (see :mod:`.maps`).
TouchDesigner's Camera COMP takes the same matrices (its custom projection and its transform are OpenGL's).
"""

from __future__ import annotations

import numpy as np

from ..calibration import Calibration
from ..io.formats import OPENGL_FORMAT
from .frames import check_clip, check_world, device_poses, rt4

#: OpenCV camera frame (x right, y down, z forward) -> OpenGL eye frame (x right, y up, z backward).
GL_FROM_CV = np.diag([1.0, -1.0, -1.0, 1.0])


def opengl_projection(K, image_size, near: float, far: float, *, y_up: bool = True,
                      zero_to_one: bool = False) -> np.ndarray:
    """4x4 projection matrix of a pinhole ``K`` for OpenGL-style rendering.

    Eye coordinates are OpenGL's: x right, y up, the device looks down **-z** (an OpenCV camera
    point ``X`` is ``GL_FROM_CV[:3, :3] @ X``).  ``clip = P @ [X_eye, 1]``, ``ndc = clip[:3] / clip[3]``.

    * x: ``ndc_x = -1`` at the left edge of the image, +1 at the right edge (pixel edges, not centres).
    * y: with ``y_up`` (OpenGL; Unity's ``Camera.projectionMatrix``) ``ndc_y = +1`` at the top edge of
      the image, -1 at the bottom, i.e. window coordinates with the origin at the **bottom-left
      corner** of the bottom-left pixel; ``y_up=False`` (Vulkan-style) flips it (+1 at the bottom).
    * z: ``ndc_z = -1`` at ``near``, +1 at ``far`` (OpenGL); ``zero_to_one``: 0 at near, 1 at far
      (Vulkan / Direct3D / ``glClipControl(GL_ZERO_TO_ONE)``).

    The window position of procam pixel ``(x, y)`` (origin at the centre of the top-left pixel) is
    ``(x + 0.5, H - (y + 0.5))`` with ``y_up``, ``(x + 0.5, y + 0.5)`` without; :func:`clip_to_pixels`
    undoes the whole chain.  Lens distortion cannot be expressed by a matrix: the rendered image is
    the undistorted (pinhole) one -- see :func:`predistort_maps` / :func:`undistort_maps`.

    Parameters
    ----------
    K : (3, 3) intrinsics (pixels; skew allowed).
    image_size : (width, height) of the device, pixels.
    near, far : clipping distances along the optical axis, board units, ``0 < near < far``.

    Returns
    -------
    (4, 4) float64, to be used as ``P @ v`` (column vectors; ``P.T`` flattened is OpenGL's
    column-major ``glUniformMatrix4fv(..., GL_FALSE, ...)`` layout).
    """
    near, far = check_clip(near, far)
    K = np.asarray(K, float)
    W, H = (float(v) for v in image_size)
    fx, s, cx, fy, cy = K[0, 0], K[0, 1], K[0, 2], K[1, 1], K[1, 2]
    P = np.zeros((4, 4))
    # x_ndc = 2 (u + 0.5) / W - 1 with u = (fx X + s Y) / Z + cx, X_gl = X, Y_gl = -Y, Z_gl = -Z
    P[0] = [2 * fx / W, -2 * s / W, 1 - 2 * (cx + 0.5) / W, 0]
    # y up: y_ndc = 1 - 2 (v + 0.5) / H with v = fy Y / Z + cy
    P[1] = [0, 2 * fy / H, 2 * (cy + 0.5) / H - 1, 0]
    if not y_up:
        P[1] = -P[1]
    if zero_to_one:
        P[2] = [0, 0, -far / (far - near), -far * near / (far - near)]
    else:
        P[2] = [0, 0, -(far + near) / (far - near), -2 * far * near / (far - near)]
    P[3] = [0, 0, -1, 0]
    return P


def view_matrices(calib: Calibration, world: str = "camera") -> dict:
    """4x4 OpenGL view matrices (world -> eye) of the camera and the projector.

    ``world="camera"``: world coordinates are the procam camera frame (OpenCV axes, board units), so
    ``V_camera = GL_FROM_CV`` and ``V_projector = GL_FROM_CV @ [R | T]``; ``world="projector"``: the
    projector frame, ``V_projector = GL_FROM_CV`` and ``V_camera = GL_FROM_CV @ [R | T]^-1``.
    ``clip = P_dev @ V_dev @ [X_world, 1]``.

    Returns ``{"camera": (4, 4), "projector": (4, 4)}``.
    """
    check_world(world)
    return {name: GL_FROM_CV @ rt4(*pose) for name, pose in device_poses(calib, world).items()}


def clip_to_pixels(clip, image_size, *, y_up: bool = True, zero_to_one: bool = False):
    """Clip coordinates (N, 4) -> procam pixels (N, 2) and depth in [0, 1] (N,) (the default
    ``glDepthRange(0, 1)`` window depth), the inverse of :func:`opengl_projection`'s conventions."""
    c = np.asarray(clip, float).reshape(-1, 4)
    ndc = c[:, :3] / c[:, 3:4]
    W, H = (float(v) for v in image_size)
    xw = (ndc[:, 0] + 1) * 0.5 * W
    yw = (ndc[:, 1] + 1) * 0.5 * H
    x = xw - 0.5
    y = (H - yw - 0.5) if y_up else (yw - 0.5)
    depth = ndc[:, 2] if zero_to_one else 0.5 * (ndc[:, 2] + 1)
    return np.column_stack([x, y]), depth


def opengl_document(calib: Calibration, near: float, far: float, *, world: str = "camera", y_up: bool = True,
                    zero_to_one: bool = False) -> dict:
    """A JSON-able document with both devices' projection and view matrices (row-major nested lists
    and OpenGL column-major flat lists), their image sizes, K, distortion and the conventions."""
    near, far = check_clip(near, far)
    V = view_matrices(calib, world)
    out = {"format": OPENGL_FORMAT, "version": 1,
           "conventions": {
               "eye": "OpenGL: x right, y up, looking down -z; eye = diag(1, -1, -1) @ (OpenCV device frame)",
               "world": f"the procam {world} frame (OpenCV axes: x right, y down, z forward), board units",
               "clip": "clip = projection @ view @ [X_world, 1]; ndc = clip.xyz / clip.w",
               "ndc_x": "-1 left edge, +1 right edge of the image",
               "ndc_y": ("+1 top edge, -1 bottom edge (window origin at the bottom-left corner)" if y_up
                         else "-1 top edge, +1 bottom edge (window origin at the top-left corner)"),
               "ndc_z": "0 at near, 1 at far" if zero_to_one else "-1 at near, +1 at far",
               "pixel": "procam pixel (x, y) (origin: centre of the top-left pixel) = window "
                        + ("(x + 0.5, H - y - 0.5)" if y_up else "(x + 0.5, y + 0.5)"),
               "row_major": "matrices as nested rows, for column vectors (M @ v)",
               "column_major": "the same matrices flattened column by column "
                               "(glUniformMatrix4fv with transpose=GL_FALSE)",
               "touchdesigner": "a Camera COMP takes these OpenGL matrices as they are (its projection and its "
                                "transform = inverse(view))",
               "unity": "use procam export --format unity (physical camera and transform in Unity's frame, metres)",
               "distortion": "not included: the matrices render the undistorted (pinhole) image",
           },
           "near": near, "far": far}
    for name, dev in (("camera", calib.camera), ("projector", calib.projector)):
        P = opengl_projection(dev.K, dev.image_size, near, far, y_up=y_up, zero_to_one=zero_to_one)
        out[name] = {"image_size": [int(v) for v in dev.image_size], "K": np.asarray(dev.K, float).tolist(),
                     "projection": P.tolist(), "view": V[name].tolist(),
                     "projection_column_major": P.T.ravel().tolist(), "view_column_major": V[name].T.ravel().tolist(),
                     "distortion": dev.distortion.to_dict()}
    return out


