"""Calibration outputs for the tools users feed next: rendering matrices and remap tables.

* :func:`opengl_projection`, :func:`view_matrices`, :func:`clip_to_pixels`, :func:`opengl_document` --
  OpenGL / Unity-style 4x4 projection and view matrices of the camera and the projector.
* :func:`undistort_maps` -- ``cv2.initUndistortRectifyMap``-compatible ``(map_x, map_y)`` for any
  procam device (OpenCV model: OpenCV's own function; division model: computed here);
  :func:`predistort_maps` -- the opposite table, for showing a pinhole-rendered image through a
  projector's (or display's) real lens; :func:`stereo_rectify` -- ``cv2.stereoRectify`` of the pair.

The files live in :mod:`procam.io`: remap tables as ``.npz`` (:func:`procam.io.save_maps`), kamino410's
``calibration_result.xml`` (:func:`procam.io.save_kamino410`), one camera's intrinsics from the files people
have (:func:`procam.io.load_camera_intrinsics`).

Conventions (docs/exports.md has the tables): procam pixels ``(x, y)`` have their origin at the
centre of the top-left pixel (as OpenCV's); camera frames are OpenCV's (x right, y down, z forward);
``x_p = R x_c + T`` maps camera to projector coordinates, board units.
"""

from __future__ import annotations

import numpy as np

from .calibration import Calibration, Device
from .errors import CalibrationError
from .io.formats import OPENGL_FORMAT
from . import choices

#: The formats ``procam export --format`` writes.
FORMATS = choices.EXPORT_FORMATS
#: The world frames of the OpenGL export (``world=``).
WORLDS = choices.WORLDS

#: OpenCV camera frame (x right, y down, z forward) -> OpenGL eye frame (x right, y up, z backward).
GL_FROM_CV = np.diag([1.0, -1.0, -1.0, 1.0])

#: OpenCV camera frame -> Unity's left-handed frame (x right, y up, z forward).
UNITY_FROM_CV = np.diag([1.0, -1.0, 1.0])


# --------------------------------------------------------------------------------------------------
# OpenGL / Unity
# --------------------------------------------------------------------------------------------------

def _check_near_far(near, far):
    near, far = float(near), float(far)
    if not (np.isfinite(near) and np.isfinite(far) and 0 < near < far):
        raise CalibrationError(f"near and far must be finite with 0 < near < far (board units), got near={near}, "
                               f"far={far}")
    return near, far


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
    near, far = _check_near_far(near, far)
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


def _rt4(R, t) -> np.ndarray:
    M = np.eye(4)
    M[:3, :3] = np.asarray(R, float)
    M[:3, 3] = np.asarray(t, float).reshape(3)
    return M


def view_matrices(calib: Calibration, world: str = "camera") -> dict:
    """4x4 OpenGL view matrices (world -> eye) of the camera and the projector.

    ``world="camera"``: world coordinates are the procam camera frame (OpenCV axes, board units), so
    ``V_camera = GL_FROM_CV`` and ``V_projector = GL_FROM_CV @ [R | T]``; ``world="projector"``: the
    projector frame, ``V_projector = GL_FROM_CV`` and ``V_camera = GL_FROM_CV @ [R | T]^-1``.
    ``clip = P_dev @ V_dev @ [X_world, 1]``.

    Returns ``{"camera": (4, 4), "projector": (4, 4)}``.
    """
    if calib.projector is None or calib.R is None or calib.T is None:
        raise CalibrationError("the calibration has no projector or no camera->projector extrinsics")
    E = _rt4(calib.R, calib.T)                 # camera -> projector
    if world == "camera":
        return {"camera": GL_FROM_CV.copy(), "projector": GL_FROM_CV @ E}
    if world == "projector":
        return {"camera": GL_FROM_CV @ np.linalg.inv(E), "projector": GL_FROM_CV.copy()}
    raise ValueError(f"world must be 'camera' or 'projector', got {world!r}")


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


def _unity_pose(R_cv_world_to_dev, t_cv_world_to_dev) -> dict:
    """Unity transform (position, rotation) of a device whose OpenCV pose maps the world (a procam
    device frame, OpenCV axes) to the device; Unity world = that frame with y flipped (left-handed)."""
    from scipy.spatial.transform import Rotation

    S = UNITY_FROM_CV
    R = np.asarray(R_cv_world_to_dev, float)
    t = np.asarray(t_cv_world_to_dev, float).reshape(3)
    M = S @ R.T @ S                      # device local -> Unity world rotation
    pos = S @ (-R.T @ t)
    return {"position": pos.tolist(), "rotation_matrix": M.tolist(),
            "quaternion_xyzw": Rotation.from_matrix(M).as_quat().tolist()}


def opengl_document(calib: Calibration, near: float, far: float, *, world: str = "camera", y_up: bool = True,
                    zero_to_one: bool = False) -> dict:
    """A JSON-able document with both devices' projection and view matrices (row-major nested lists
    and OpenGL column-major flat lists), their image sizes, the Unity transforms and the conventions."""
    near, far = _check_near_far(near, far)
    V = view_matrices(calib, world)
    E = _rt4(calib.R, calib.T)
    poses = {"camera": (np.eye(3), np.zeros(3)), "projector": (E[:3, :3], E[:3, 3])}
    if world == "projector":
        Ei = np.linalg.inv(E)
        poses = {"camera": (Ei[:3, :3], Ei[:3, 3]), "projector": (np.eye(3), np.zeros(3))}
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
               "unity": "Unity world = the procam world frame with y flipped (x right, y up, z forward, left-handed); "
                        "set Camera.projectionMatrix = projection and the transform's position/rotation below "
                        "(lengths in board units: scale to metres yourself)",
               "distortion": "not included: the matrices render the undistorted (pinhole) image",
           },
           "near": near, "far": far}
    for name, dev in (("camera", calib.camera), ("projector", calib.projector)):
        P = opengl_projection(dev.K, dev.image_size, near, far, y_up=y_up, zero_to_one=zero_to_one)
        out[name] = {"image_size": [int(v) for v in dev.image_size], "K": np.asarray(dev.K, float).tolist(),
                     "projection": P.tolist(), "view": V[name].tolist(),
                     "projection_column_major": P.T.ravel().tolist(), "view_column_major": V[name].T.ravel().tolist(),
                     "unity": _unity_pose(*poses[name]),
                     "distortion": dev.distortion.to_dict()}
    return out


# --------------------------------------------------------------------------------------------------
# remap tables
# --------------------------------------------------------------------------------------------------

def _grid(size):
    W, H = (int(v) for v in size)
    xs, ys = np.meshgrid(np.arange(W, dtype=np.float64), np.arange(H, dtype=np.float64))
    return xs, ys


def _as_map(pts, size):
    W, H = (int(v) for v in size)
    p = np.asarray(pts, float).reshape(H, W, 2)
    bad = ~np.isfinite(p).all(axis=2)
    p[bad] = -1.0e6                   # far outside: cv2.remap gives the border value there
    return p[..., 0].astype(np.float32), p[..., 1].astype(np.float32)


def undistort_maps(device: Device, *, new_K=None, R=None, size=None):
    """``(map_x, map_y)`` for ``cv2.remap`` that undistort (and optionally rectify) the device's images.

    Same contract as ``cv2.initUndistortRectifyMap(K, dist, R, new_K, size, cv2.CV_32FC1)``: for every
    pixel ``p`` of the output image, the source location in the device's (distorted) image of the
    ray ``R^-1 new_K^-1 p``.  OpenCV-model devices use that very function; division-model devices are
    computed here (:func:`procam.models.distort_division`); where the division model has no
    distorted pixel the map points far outside the image (``cv2.remap`` fills the border value).

    Parameters
    ----------
    device : :class:`procam.calibration.Device`.
    new_K : (3, 3) camera matrix of the output (default: the device's ``K``).
    R : (3, 3) rectifying rotation (default: identity), as ``cv2.stereoRectify``'s ``R1`` / ``R2``.
    size : (width, height) of the output (default: the device's image size).

    Returns
    -------
    map_x, map_y : (H, W) float32 source pixel coordinates.
    """
    import cv2

    K = np.asarray(device.K, float)
    new_K = K if new_K is None else np.asarray(new_K, float)
    Rm = np.eye(3) if R is None else np.asarray(R, float)
    size = tuple(int(v) for v in (device.image_size if size is None else size))
    dist = device.distortion
    if dist.model in ("opencv", "none"):
        coeffs = np.asarray(dist.coeffs, float) if dist.model == "opencv" else None
        mx, my = cv2.initUndistortRectifyMap(K, coeffs, Rm, new_K, size, cv2.CV_32FC1)
        return mx, my
    xs, ys = _grid(size)
    p = np.stack([xs.ravel(), ys.ravel(), np.ones(xs.size)], axis=1)
    rays = p @ np.linalg.inv(new_K).T @ Rm      # rows: R^T new_K^-1 p  (R^-1 = R^T)
    with np.errstate(divide="ignore", invalid="ignore"):
        und = rays @ K.T
        und = und[:, :2] / und[:, 2:3]
    und[rays[:, 2] <= 0] = np.nan
    src = dist.distort(und, K)
    return _as_map(src, size)


def predistort_maps(device: Device, *, K_ideal=None, size_ideal=None):
    """``(map_x, map_y)`` that warp a pinhole-rendered image into what the device must show.

    For every pixel of the device (a projector's panel), the location in the ideal pinhole image
    (intrinsics ``K_ideal``, default the device's ``K``) of the ray that device pixel actually sends
    light along: ``cv2.remap(rendered, map_x, map_y, cv2.INTER_LINEAR)`` then shows the rendered
    scene correctly through the real lens.  The inverse table of :func:`undistort_maps`.

    Returns
    -------
    map_x, map_y : (H, W) float32 at the device's image size, coordinates in the ideal image.
    """
    K = np.asarray(device.K, float)
    K_ideal = K if K_ideal is None else np.asarray(K_ideal, float)
    size = tuple(int(v) for v in device.image_size)
    xs, ys = _grid(size)
    und = device.undistort(np.column_stack([xs.ravel(), ys.ravel()]))
    if not np.allclose(K_ideal, K):
        h = np.column_stack([und, np.ones(len(und))]) @ np.linalg.inv(K).T @ K_ideal.T
        und = h[:, :2] / h[:, 2:3]
    return _as_map(und, size)


def _border_rays(device: Device, R_rect, n: int = 64) -> np.ndarray:
    """Normalised rectified coordinates (M, 2) of points along the device image's border."""
    W, H = (int(v) for v in device.image_size)
    t = np.linspace(0.0, 1.0, n)
    xs = np.concatenate([t * (W - 1), np.full(n, W - 1.0), (1 - t) * (W - 1), np.zeros(n)])
    ys = np.concatenate([np.zeros(n), t * (H - 1), np.full(n, H - 1.0), (1 - t) * (H - 1)])
    und = device.undistort(np.column_stack([xs, ys]))
    und = und[np.isfinite(und).all(1)]
    Kinv = np.linalg.inv(np.asarray(device.K, float))
    ray = np.column_stack([und, np.ones(len(und))]) @ Kinv.T @ np.asarray(R_rect).T
    if np.any(ray[:, 2] <= 1e-6):
        raise CalibrationError("the rectifying rotation turns part of the image behind the device; "
                               "rectification is not possible for this camera-projector geometry")
    return ray[:, :2] / ray[:, 2:3]


def stereo_rectify(calib: Calibration, *, scale: float = 1.0, max_size: int = 8192) -> dict:
    """Rectification of camera (first) and projector (second): epipolar lines become image rows.

    The rotations ``R1``, ``R2`` are ``cv2.stereoRectify``'s (Bouguet: half of ``R`` each, then the
    baseline turned onto the x axis; they do not depend on the intrinsics or image sizes).  The
    framing is procam's, because OpenCV frames both devices in one image size, which for a camera
    and a lens-shifted projector of another resolution can give unusable (even negative) focal
    lengths: both rectified images share the focal length ``scale`` x the camera's (mean of fx, fy)
    and the principal row ``cy``, their rows span the rows both devices see, and each device's
    columns span its own image.

    Returns
    -------
    dict with ``R1, R2`` (3, 3), ``P1, P2`` (3, 4) (``P2[0, 3] = f * Tx`` of the rectified
    baseline, board units), ``size1``, ``size2`` ((width, height) of each rectified image);
    the maps are ``undistort_maps(calib.camera, new_K=P1[:, :3], R=R1, size=size1)`` and likewise
    with ``P2, R2, size2`` for the projector.
    """
    import cv2

    if calib.projector is None or calib.R is None or calib.T is None:
        raise CalibrationError("the calibration has no projector or no camera->projector extrinsics")
    if not (np.isfinite(scale) and scale > 0):
        raise CalibrationError(f"scale must be a positive number, got {scale}")
    R = np.asarray(calib.R, float)
    T = np.asarray(calib.T, float).reshape(3)
    R1, R2, *_ = cv2.stereoRectify(np.asarray(calib.camera.K, float), None, np.asarray(calib.projector.K, float),
                                   None, tuple(int(v) for v in calib.camera.image_size), R, T.reshape(3, 1),
                                   flags=0)
    f = scale * 0.5 * float(calib.camera.K[0, 0] + calib.camera.K[1, 1])
    b1, b2 = _border_rays(calib.camera, R1), _border_rays(calib.projector, R2)
    y0 = max(b1[:, 1].min(), b2[:, 1].min())
    y1 = min(b1[:, 1].max(), b2[:, 1].max())
    if not y1 > y0:
        raise CalibrationError("the camera and the projector see no common rows after rectification")
    cy = -f * y0
    height = int(np.ceil(f * (y1 - y0))) + 1
    out = {"R1": R1, "R2": R2}
    for k, b in (("1", b1), ("2", b2)):
        x0, x1 = b[:, 0].min(), b[:, 0].max()
        width = int(np.ceil(f * (x1 - x0))) + 1
        if width > max_size or height > max_size:
            raise CalibrationError(f"the rectified images would be {width}x{height} px (more than {max_size}); "
                                   "lower scale")
        P = np.zeros((3, 4))
        P[:, :3] = [[f, 0, -f * x0], [0, f, cy], [0, 0, 1]]
        out["P" + k] = P
        out["size" + k] = (width, height)
    out["P2"][0, 3] = f * float((R2 @ T)[0])
    return out
