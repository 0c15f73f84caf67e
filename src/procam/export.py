"""Calibration outputs for the tools users feed next: rendering matrices, remap tables, other tools' files.

* :func:`opengl_projection`, :func:`view_matrices`, :func:`clip_to_pixels`, :func:`opengl_document` --
  OpenGL / Unity-style 4x4 projection and view matrices of the camera and the projector.
* :func:`undistort_maps` -- ``cv2.initUndistortRectifyMap``-compatible ``(map_x, map_y)`` for any
  procam device (OpenCV model: OpenCV's own function; division model: computed here);
  :func:`predistort_maps` -- the opposite table, for showing a pinhole-rendered image through a
  projector's (or display's) real lens; :func:`stereo_rectify` -- ``cv2.stereoRectify`` of the pair.
* :func:`save_kamino410` / :func:`load_kamino410` -- kamino410/procam-calibration's
  ``calibration_result.xml``; :func:`load_camera_intrinsics` -- one camera's intrinsics from procam
  JSON, procam / Moreno-Taubin YAML, an OpenCV calibration YAML or kamino410's files.

Conventions (docs/exports.md has the tables): procam pixels ``(x, y)`` have their origin at the
centre of the top-left pixel (as OpenCV's); camera frames are OpenCV's (x right, y down, z forward);
``x_p = R x_c + T`` maps camera to projector coordinates, board units.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .calibration import Calibration, Device, Distortion
from .errors import CalibrationError, CalibrationFileError
from .io.files import atomic_path

#: OpenCV camera frame (x right, y down, z forward) -> OpenGL eye frame (x right, y up, z backward).
#: The formats ``procam export --format`` writes.
FORMATS = ("opengl", "maps", "kamino410")
#: The world frames of the OpenGL export (``world=``).
WORLDS = ("camera", "projector")

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
    out = {"format": "procam-opengl", "version": 1,
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


def _opencv_coeffs(device: Device) -> np.ndarray:
    """OpenCV distortion coefficients of a device (division model: the OpenCV fit), (1, n)."""
    d = device.distortion
    if d.model == "opencv":
        return np.asarray(d.coeffs, float).reshape(1, -1)
    if d.model == "division":
        from .distortion import opencv_from_division

        coeffs, _ = opencv_from_division(device.K, d.center, d.k1, d.k2, device.image_size)
        return np.asarray(coeffs, float).reshape(1, -1)
    return np.zeros((1, 5))


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


def save_maps(path, map_x, map_y, **meta) -> Path:
    """Write remap tables as ``.npz`` (``map_x``, ``map_y`` float32 plus ``meta`` arrays), atomically (the same
    tables give the same bytes)."""
    from .io.files import write_npz

    return write_npz(path, map_x=np.asarray(map_x, np.float32), map_y=np.asarray(map_y, np.float32),
                     **{k: np.asarray(v) for k, v in meta.items()})


# --------------------------------------------------------------------------------------------------
# kamino410/procam-calibration
# --------------------------------------------------------------------------------------------------

#: kamino410/procam-calibration's ``calibration_result.xml`` keys -> meaning (procam's name).
KAMINO410_KEYS = {
    "img_shape": "camera image shape (height, width), 2x1 double",
    "rms": "stereoCalibrate RMS, px (procam: stereo_rms)",
    "cam_int": "camera K, 3x3 (procam: camera.K)",
    "cam_dist": "camera OpenCV distortion, 1x5 (procam: camera distortion; division -> OpenCV fit)",
    "proj_int": "projector K, 3x3 (procam: projector.K)",
    "proj_dist": "projector OpenCV distortion, 1x5",
    "rotation": "camera -> projector R, 3x3 (older files: 'roration')",
    "translation": "camera -> projector T, 3x1, chessboard units (procam: T)",
}


def save_kamino410(calib: Calibration, path) -> Path:
    """Write kamino410/procam-calibration's ``calibration_result.xml`` (``cv2.FileStorage``), atomically.

    Keys as theirs (:data:`KAMINO410_KEYS`): ``img_shape`` (camera ``[height, width]``, 2x1 double),
    ``rms``, ``cam_int``, ``cam_dist`` (1x5), ``proj_int``, ``proj_dist`` (1x5), ``rotation``,
    ``translation`` (3x1), with their meaning: ``x_proj = rotation x_cam + translation`` (OpenCV
    ``stereoCalibrate`` with the camera first, exactly procam's ``R, T``), ``translation`` in the
    chessboard's unit.  A division-model camera is written as its OpenCV ``(k1, k2, p1, p2, k3)`` fit
    (as procam's YAML).  procam adds ``proj_shape`` (projector ``[height, width]``), which their
    reader ignores and :func:`load_kamino410` uses.  ``.xml`` (theirs), ``.yml`` or ``.yaml``.
    """
    import cv2

    path = Path(path)
    if path.suffix.lower() not in (".xml", ".yml", ".yaml"):
        raise CalibrationFileError(f"{path}: kamino410's format is an OpenCV FileStorage file; name it .xml "
                                   "(as theirs), .yml or .yaml")
    if calib.projector is None or calib.R is None or calib.T is None:
        raise CalibrationFileError(f"{path}: a camera-only calibration has no projector, so no kamino410 file")
    W, H = (int(v) for v in calib.camera.image_size)
    Wp, Hp = (int(v) for v in calib.projector.image_size)
    with atomic_path(path) as tmp:
        fs = cv2.FileStorage(str(tmp), cv2.FILE_STORAGE_WRITE)
        fs.write("img_shape", np.array([[H], [W]], float))
        fs.write("rms", float(calib.stereo_rms))
        fs.write("cam_int", np.asarray(calib.camera.K, float))
        fs.write("cam_dist", _opencv_coeffs(calib.camera))
        fs.write("proj_int", np.asarray(calib.projector.K, float))
        fs.write("proj_dist", _opencv_coeffs(calib.projector))
        fs.write("rotation", np.asarray(calib.R, float))
        fs.write("translation", np.asarray(calib.T, float).reshape(3, 1))
        fs.write("proj_shape", np.array([[Hp], [Wp]], float))
        fs.release()
    return path


def _open_fs(path):
    import cv2

    try:
        fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    except (cv2.error, SystemError) as e:   # a parse error surfaces as SystemError in some OpenCV builds
        e = e.__cause__ or e
        msg = str(e).strip().splitlines()[-1] if str(e).strip() else "parse error"
        raise CalibrationFileError(f"{path}: not a readable OpenCV FileStorage file ({msg})") from None
    if not fs.isOpened():
        raise CalibrationFileError(f"{path}: cannot be opened as an OpenCV FileStorage file")
    return fs


def _fs_mat(fs, key):
    n = fs.getNode(key)
    if n.empty():
        return None
    m = n.mat()
    if m is None and n.isSeq():
        m = np.array([n.at(i).real() for i in range(n.size())], float)
    return None if m is None else np.asarray(m, float)


def _fs_real(fs, key):
    n = fs.getNode(key)
    return None if n.empty() else float(n.real())


def _check_K(K, path, field) -> np.ndarray:
    K = None if K is None else np.asarray(K, float)
    if K is None or K.size != 9:
        raise CalibrationFileError(f"{path}: {field} must be a 3x3 camera matrix, got "
                                   f"{'nothing' if K is None else f'{K.size} values'}")
    K = K.reshape(3, 3)
    if not np.isfinite(K).all():
        raise CalibrationFileError(f"{path}: {field} has non-finite values; re-export the calibration")
    if not (K[0, 0] > 0 and K[1, 1] > 0) or not np.allclose(K[2], [0, 0, 1], atol=1e-9) or K[1, 0] != 0:
        raise CalibrationFileError(f"{path}: {field} is not a camera matrix [[fx, s, cx], [0, fy, cy], [0, 0, 1]] "
                                   "with fx, fy > 0")
    return K


def _check_dist(d, path, field) -> tuple:
    if d is None:
        return ()
    d = np.asarray(d, float).ravel()
    if d.size not in (0, 4, 5, 8, 12, 14):
        raise CalibrationFileError(f"{path}: {field} has {d.size} coefficients; OpenCV distortion has 4, 5, 8, 12 "
                                   "or 14")
    if not np.isfinite(d).all():
        raise CalibrationFileError(f"{path}: {field} has non-finite values; re-export the calibration")
    return tuple(float(v) for v in d)


def _check_size(size, path, field) -> tuple[int, int]:
    try:
        w, h = (float(v) for v in np.asarray(size, float).ravel())
    except (TypeError, ValueError):
        raise CalibrationFileError(f"{path}: {field} must be two numbers (width, height)") from None
    if not (np.isfinite(w) and np.isfinite(h) and w == int(w) and h == int(h)
            and 2 <= w <= 100000 and 2 <= h <= 100000):
        raise CalibrationFileError(f"{path}: {field} = ({w:g}, {h:g}) is not an image size in pixels")
    return int(w), int(h)


def _opencv_distortion(coeffs) -> Distortion:
    return Distortion("opencv", coeffs=coeffs) if coeffs and any(coeffs) else Distortion()


def load_kamino410(path, proj_size=None) -> Calibration:
    """Read kamino410/procam-calibration's ``calibration_result.xml`` (or a file :func:`save_kamino410` wrote).

    ``proj_size`` (width, height) is needed for files from their tool, which do not store the
    projector's size; without it procam's ``proj_shape`` is used, else ``(2 u0, 2 v0)`` is assumed and
    a warning added.  Accepts their old misspelt ``roration`` key.
    """
    path = Path(path)
    if not path.is_file():
        raise CalibrationFileError(f"{path}: no such file")
    fs = _open_fs(path)
    try:
        missing = [k for k in ("cam_int", "proj_int", "translation") if fs.getNode(k).empty()]
        rot_key = "rotation" if not fs.getNode("rotation").empty() else "roration"
        if fs.getNode(rot_key).empty():
            missing.append("rotation")
        if missing:
            raise CalibrationFileError(f"{path}: missing {', '.join(missing)}; expected kamino410's keys "
                                       "cam_int, cam_dist, proj_int, proj_dist, rotation, translation, img_shape")
        Kc = _check_K(_fs_mat(fs, "cam_int"), path, "cam_int")
        Kp = _check_K(_fs_mat(fs, "proj_int"), path, "proj_int")
        dc = _check_dist(_fs_mat(fs, "cam_dist"), path, "cam_dist")
        dp = _check_dist(_fs_mat(fs, "proj_dist"), path, "proj_dist")
        R = _fs_mat(fs, rot_key)
        T = _fs_mat(fs, "translation")
        if R is None or R.size != 9 or not np.isfinite(R).all():
            raise CalibrationFileError(f"{path}: {rot_key} must be a finite 3x3 rotation")
        R = R.reshape(3, 3)
        if not np.allclose(R @ R.T, np.eye(3), atol=1e-6) or np.linalg.det(R) <= 0:
            raise CalibrationFileError(f"{path}: {rot_key} is not a rotation matrix")
        if T is None or T.size != 3 or not np.isfinite(T).all():
            raise CalibrationFileError(f"{path}: translation must be 3 finite numbers")
        shape = _fs_mat(fs, "img_shape")
        if shape is None:
            raise CalibrationFileError(f"{path}: missing img_shape (the camera's height, width)")
        cam_size = _check_size(shape.ravel()[::-1], path, "img_shape")
        warnings = []
        if proj_size is not None:
            proj_size = _check_size(proj_size, path, "the projector size")
        elif _fs_mat(fs, "proj_shape") is not None:
            proj_size = _check_size(_fs_mat(fs, "proj_shape").ravel()[::-1], path, "proj_shape")
        else:
            proj_size = (int(round(2 * Kp[0, 2])), int(round(2 * Kp[1, 2])))
            warnings.append(f"{path.name} does not store the projector size; assumed {proj_size[0]}x{proj_size[1]} "
                            "from its principal point: give the real size")
        rms = _fs_real(fs, "rms")
    finally:
        fs.release()
    return Calibration(Device(Kc, cam_size, _opencv_distortion(dc)), Device(Kp, proj_size, _opencv_distortion(dp)),
                       R, T.reshape(3), "kamino410", stereo_rms=float("nan") if rms is None else rms,
                       warnings=tuple(warnings), info={"source": str(path)})


# --------------------------------------------------------------------------------------------------
# one camera's intrinsics from any of the usual files
# --------------------------------------------------------------------------------------------------

#: FileStorage key sets read by :func:`load_camera_intrinsics`: (K key, distortion key, size reader).
_FS_LAYOUTS = (
    ("cam_K", "cam_kc", "procam / Moreno-Taubin YAML"),
    ("camera_matrix", "distortion_coefficients", "OpenCV calibration sample"),
    ("cam_int", "cam_dist", "kamino410/procam-calibration"),
    ("M1", "D1", "OpenCV stereo_calib sample (first camera)"),
)


def _fs_size(fs, K_key, path):
    if K_key == "cam_K":
        m = _fs_mat(fs, "cam_size")
        return None if m is None else _check_size(m, path, "cam_size")
    if K_key == "camera_matrix":
        w, h = _fs_real(fs, "image_width"), _fs_real(fs, "image_height")
        return None if w is None or h is None else _check_size((w, h), path, "image_width/image_height")
    if K_key == "cam_int":
        m = _fs_mat(fs, "img_shape")
        return None if m is None else _check_size(m.ravel()[::-1], path, "img_shape")
    return None


def load_camera_intrinsics(path, image_size=None) -> Device:
    """One camera's intrinsics (K, distortion, image size) from the files people have.

    Reads, by content:

    * procam calibration JSON (``procam calibrate``, also camera-only): the ``camera`` block, any
      distortion model;
    * kamino410's camera JSON (``{"camera": {"P": [9 numbers], "distortion": [...], "width", "height"}}``);
    * ``cv2.FileStorage`` YAML/XML/JSON with ``cam_K``/``cam_kc`` (procam, Moreno-Taubin's
      scan3d-capture; size from ``cam_size``), ``camera_matrix``/``distortion_coefficients`` (OpenCV's
      calibration sample; size from ``image_width``/``image_height``), ``cam_int``/``cam_dist``
      (kamino410; size from ``img_shape``) or ``M1``/``D1`` (OpenCV's stereo sample: the first camera).

    Parameters
    ----------
    path : the file.
    image_size : (width, height) of the images the intrinsics will be used with.  Required when the
        file has no size; when it has one they must agree.

    Raises
    ------
    CalibrationFileError
        Missing file, unknown layout, a malformed matrix (naming the field), no image size, or a
        size that differs from ``image_size``.
    """
    path = Path(path)
    if not path.is_file():
        raise CalibrationFileError(f"{path}: no such file; give a camera calibration file")
    K = size = dist = None
    suffix = path.suffix.lower()
    doc = None
    if suffix == ".json":
        try:
            doc = json.loads(path.read_text())
        except (OSError, UnicodeDecodeError, ValueError) as e:
            raise CalibrationFileError(f"{path}: not valid JSON ({e})") from None
    if isinstance(doc, dict) and doc.get("format") == "procam-calibration":
        cam = doc.get("camera")
        if not isinstance(cam, dict):
            raise CalibrationFileError(f"{path}: the procam calibration has no camera block")
        K = _check_K(cam.get("K"), path, "camera.K")
        size = _check_size(cam.get("image_size"), path, "camera.image_size") if cam.get("image_size") else None
        try:
            dist = Distortion.from_dict(cam.get("distortion") or {})
        except (KeyError, TypeError, ValueError) as e:
            raise CalibrationFileError(f"{path}: camera.distortion is malformed ({e})") from None
        if dist.model == "division":
            vals = [*dist.center, dist.k1, dist.k2]
            if not np.isfinite(vals).all():
                raise CalibrationFileError(f"{path}: camera.distortion has non-finite values")
        elif dist.model == "opencv":
            dist = _opencv_distortion(_check_dist(dist.coeffs, path, "camera.distortion.coeffs"))
    elif isinstance(doc, dict) and isinstance(doc.get("camera"), dict) and "P" in doc["camera"]:
        cam = doc["camera"]
        K = _check_K(cam.get("P"), path, "camera.P")
        dist = _opencv_distortion(_check_dist(cam.get("distortion"), path, "camera.distortion"))
        if cam.get("width") is not None and cam.get("height") is not None:
            size = _check_size((cam["width"], cam["height"]), path, "camera.width/height")
    elif suffix in (".yml", ".yaml", ".xml", ".json"):
        fs = _open_fs(path)
        try:
            for K_key, d_key, _ in _FS_LAYOUTS:
                if not fs.getNode(K_key).empty():
                    K = _check_K(_fs_mat(fs, K_key), path, K_key)
                    dist = _opencv_distortion(_check_dist(_fs_mat(fs, d_key), path, d_key))
                    size = _fs_size(fs, K_key, path)
                    break
        finally:
            fs.release()
        if K is None:
            keys = ", ".join(f"{k}/{d} ({what})" for k, d, what in _FS_LAYOUTS)
            raise CalibrationFileError(f"{path}: no camera matrix found; expected one of {keys}")
    else:
        raise CalibrationFileError(f"{path}: unknown file type {path.suffix!r}; give a procam .json or an OpenCV "
                                   ".yml/.yaml/.xml calibration")
    if image_size is not None:
        want = _check_size(image_size, path, "the image size")
        if size is not None and size != want:
            raise CalibrationFileError(f"{path}: the intrinsics are for {size[0]}x{size[1]} images, the images are "
                                       f"{want[0]}x{want[1]}; use the calibration of this camera at this resolution")
        size = want
    if size is None:
        raise CalibrationFileError(f"{path}: the file does not say the image size the intrinsics belong to; "
                                   "give it (width x height)")
    return Device(K, size, dist if dist is not None else Distortion())
