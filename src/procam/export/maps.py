"""Distortion maps: what an engine camera cannot hold (lens distortion), as tables for ``cv2.remap`` and as
ST maps for engines.

* :func:`undistort_maps` -- ``cv2.initUndistortRectifyMap``-compatible ``(map_x, map_y)`` for any procam device
  (OpenCV model: OpenCV's own function; division model: computed here), optionally rectifying;
* :func:`predistort_maps` -- the opposite table: an image rendered with the pinhole device (an engine camera, the
  OpenGL matrices) warped by it is what the real projector (or display) must show through its lens;
* :func:`st_map` -- a remap table as an **ST map** (16-bit RGB image of normalised source coordinates: the form
  Nuke's STMap, TouchDesigner's Remap TOP, Blender's compositor Map UV node and a one-line shader read).

ST map convention: output pixel ``(i, j)`` (column, row from the top) holds in red ``s = (x_src + 0.5) / W_src``
and in green ``t = 1 - (y_src + 0.5) / H_src`` -- texture coordinates with the origin at the **bottom-left
corner** of the source image (OpenGL's) -- and in blue 1 where the source point lies in the source image, 0
where there is none (the output pixel then shows nothing); each channel as ``round(value * 65535)``.  Sixteen bits
resolve 1/65535 of the source's side (0.03 px of a 1920-px image).

Where a map has no source point (the division model has no distorted pixel, a ray turned behind the device), the
tables point far outside the image, so ``cv2.remap`` fills the border value.
"""

from __future__ import annotations

import numpy as np

from ..calibration import Device

#: The full scale of an ST map's 16-bit channels.
ST_SCALE = 65535


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


def st_map(map_x, map_y, source_size) -> np.ndarray:
    """The ST map (H, W, 3) uint16 **RGB** of a remap table ``(map_x, map_y)`` (H, W) into a source image of
    ``source_size`` = (width, height) (module docstring); write it with :func:`procam.io.files.write_image`
    after turning it to BGR (``[..., ::-1]``)."""
    W, H = (float(v) for v in source_size)
    mx, my = np.asarray(map_x, float), np.asarray(map_y, float)
    inside = np.isfinite(mx) & np.isfinite(my) & (mx >= -0.5) & (mx <= W - 0.5) & (my >= -0.5) & (my <= H - 0.5)
    s = np.where(inside, (mx + 0.5) / W, 0.0)
    t = np.where(inside, 1.0 - (my + 0.5) / H, 0.0)
    out = np.stack([s, t, inside.astype(float)], axis=-1)
    return np.round(np.clip(out, 0.0, 1.0) * ST_SCALE).astype(np.uint16)


def distortion_maps(calib) -> dict:
    """What no engine camera holds, per device with lens distortion: the camera's undistortion and the projector's
    pre-distortion, ``{device: {"what", "map_x", "map_y", "st_map", "K", "size"}}`` (:func:`undistort_maps`,
    :func:`predistort_maps`, :func:`st_map`); written by :func:`procam.io.engines.save_distortion_maps`."""
    out = {}
    for name, what in (("camera", "undistort"), ("projector", "predistort")):
        dev = getattr(calib, name)
        if dev is None or dev.distortion.model == "none":
            continue
        mx, my = undistort_maps(dev) if what == "undistort" else predistort_maps(dev)
        out[name] = {"what": what, "map_x": mx, "map_y": my, "st_map": st_map(mx, my, dev.image_size), "K": dev.K,
                     "size": tuple(dev.image_size)}
    return out


def st_map_lookup(st, source_size):
    """The source pixels ``(map_x, map_y)`` (H, W) float64 and the validity (H, W) bool of an ST map of
    :func:`st_map` (RGB order): the inverse of its convention, to check one or to use one with ``cv2.remap``."""
    W, H = (float(v) for v in source_size)
    st = np.asarray(st, float) / ST_SCALE
    return st[..., 0] * W - 0.5, (1.0 - st[..., 1]) * H - 0.5, st[..., 2] > 0.5
