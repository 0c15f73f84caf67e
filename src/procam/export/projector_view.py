"""The projector's view: the camera's picture of the scene remapped into projector pixels, with the decoded-valid
mask -- the template projection-mapping tools draw content on (each pixel of it is what that projector pixel
lights).

Method.  The decoded maps give, at every camera pixel that decoded both codes, the projector pixel that lit it
(:mod:`procam.decode`).  The inverse map -- for every projector pixel, where the camera saw it -- is built in
two steps:

1. **binning**: the camera pixels that decoded to the same projector pixel are averaged (their mean camera
   position is where the camera saw that projector pixel's centre; a camera denser than the projector gives
   several per projector pixel);
2. **interpolation**: at every projector pixel the camera position is a local linear fit to the binned samples
   around it, weighted by a Gaussian of the sampling spacing ``r`` (first-order normalised convolution: a few
   image filters and a 3x3 solve per pixel).  It fills the gaps a projector denser than the camera leaves
   between samples and is exact for a map that is locally affine (a smooth surface's), without the bias a
   plain weighted mean has where the samples lie on one side (an edge).

The **mask** says which projector pixels the capture decoded: the binned pixels, closed (dilated then eroded) by
the sampling spacing ``r`` (the median projector pixels per camera pixel along a side, from the decoded maps'
gradients; at least :data:`MIN_CLOSE_PX`), so gaps between samples are filled but the decoded area does not
grow.  Outside it the view is black: the projector lights something the camera did not see there (beyond the
camera's view, in a shadow, on a dark or shiny surface), or nothing.  The image is ``cv2.remap`` of the camera's
white frame (colour if it is colour) through the inverse map, bilinear.

Assumptions and failure modes: one projector pixel is seen at one camera position (interreflections and
translucent surfaces decode to several: their mean is taken); a code decoded wrongly puts a camera pixel at a
wrong projector pixel (an isolated speck, left as it is); the decoded coordinates are pixel centres (or block
centres with ``--step``), so the view has the capture's resolution, not more.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: The smallest closing radius of the mask (projector px).
MIN_CLOSE_PX = 2


@dataclass(frozen=True)
class ProjectorView:
    """The projector's view (module docstring).

    Attributes
    ----------
    image : (Hp, Wp) or (Hp, Wp, 3) of the camera image's dtype: the camera's picture in projector pixels, black
        outside ``mask``.
    mask : (Hp, Wp) bool, the decoded-valid mask.
    map_x, map_y : (Hp, Wp) float32: the camera pixel each projector pixel was taken from (NaN outside ``mask``).
    close_px : the closing radius used (projector px).
    """

    image: np.ndarray
    mask: np.ndarray
    map_x: np.ndarray
    map_y: np.ndarray
    close_px: int

    @property
    def coverage(self) -> float:
        """Fraction of the projector's pixels in the mask."""
        return float(self.mask.mean())


def _spacing(col, row, ok) -> float:
    """Median projector pixels per camera pixel along a side (sqrt of the decoded map's Jacobian determinant)."""
    dcol_dy, dcol_dx = np.gradient(np.where(ok, col, np.nan))     # np.gradient: along rows (y) first
    drow_dy, drow_dx = np.gradient(np.where(ok, row, np.nan))
    det = np.abs(dcol_dx * drow_dy - dcol_dy * drow_dx)
    det = det[np.isfinite(det) & (det > 0)]
    return float(np.sqrt(np.median(det))) if det.size else 1.0


def _local_linear_fit(w, values, sigma):
    """First-order normalised convolution: at every pixel the value at that pixel of the weighted least-squares
    plane through ``values`` (list of (H, W)) with weights ``w`` (H, W) times a Gaussian of ``sigma`` px.
    Returns the fitted (H, W) arrays and the total weight (H, W); NaN where the window's samples do not
    determine a plane."""
    import cv2

    r = max(1, int(np.ceil(2.5 * sigma)))
    d = np.arange(-r, r + 1, dtype=np.float64)
    dx, dy = np.meshgrid(d, d)
    g = np.exp(-(dx ** 2 + dy ** 2) / (2 * sigma ** 2))

    def corr(img, kernel):
        return cv2.filter2D(img, cv2.CV_64F, kernel, borderType=cv2.BORDER_CONSTANT)

    kernels = (g, g * dx, g * dy)
    s0, sx, sy = (corr(w, k) for k in kernels)
    sxx, sxy, syy = corr(w, g * dx * dx), corr(w, g * dx * dy), corr(w, g * dy * dy)
    # the first row of the inverse of [[s0, sx, sy], [sx, sxx, sxy], [sy, sxy, syy]] (cofactors): the plane's value
    c0, c1, c2 = sxx * syy - sxy * sxy, sy * sxy - sx * syy, sx * sxy - sy * sxx
    det = s0 * c0 + sx * c1 + sy * c2
    good = det > 1e-9 * np.maximum(s0, 1e-300) ** 3
    det = np.where(good, det, 1.0)
    out = []
    for v in values:
        b0, bx, by = (corr(w * v, k) for k in kernels)
        out.append(np.where(good, (c0 * b0 + c1 * bx + c2 * by) / det, np.nan))
    return out, s0


def projector_view(col, row, valid, image, proj_size, *, close_px: int | None = None) -> ProjectorView:
    """The camera's ``image`` seen from the projector (module docstring).

    Parameters
    ----------
    col, row : (H, W) decoded projector column / row of each camera pixel (NaN where not decoded).
    valid : (H, W) bool, both decoded (``valid_col & valid_row``).
    image : (H, W) or (H, W, 3) camera image (the white frame).
    proj_size : (width, height) of the projector.
    close_px : the mask's closing radius (projector px); default from the sampling (module docstring).
    """
    import cv2

    Wp, Hp = (int(v) for v in proj_size)
    col, row = np.asarray(col, float), np.asarray(row, float)
    ok = np.asarray(valid, bool) & np.isfinite(col) & np.isfinite(row)
    ok &= (col > -0.5) & (col < Wp - 0.5) & (row > -0.5) & (row < Hp - 0.5)
    ys, xs = np.nonzero(ok)
    empty = np.zeros((Hp, Wp), bool)
    nan = np.full((Hp, Wp), np.nan, np.float32)
    img = np.asarray(image)
    if xs.size < 3:
        return ProjectorView(np.zeros((Hp, Wp) + img.shape[2:], img.dtype), empty, nan, nan, MIN_CLOSE_PX)
    idx = np.rint(row[ok]).astype(np.int64) * Wp + np.rint(col[ok]).astype(np.int64)
    n = np.bincount(idx, minlength=Wp * Hp)
    sx = np.bincount(idx, xs, minlength=Wp * Hp)
    sy = np.bincount(idx, ys, minlength=Wp * Hp)
    hit = n > 0
    if close_px is None:
        close_px = max(MIN_CLOSE_PX, int(np.ceil(_spacing(col, row, ok))) + 1)
    k = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * close_px + 1, 2 * close_px + 1))
    mask = cv2.morphologyEx(hit.reshape(Hp, Wp).astype(np.uint8), cv2.MORPH_CLOSE, k).astype(bool)
    w = hit.reshape(Hp, Wp).astype(np.float64)
    mean_x = np.where(hit, sx / np.maximum(n, 1), 0.0).reshape(Hp, Wp)
    mean_y = np.where(hit, sy / np.maximum(n, 1), 0.0).reshape(Hp, Wp)
    (fx, fy), _ = _local_linear_fit(w, [mean_x, mean_y], max(1.0, close_px / 2.0))
    map_x = np.where(mask, fx, np.nan).astype(np.float32)
    map_y = np.where(mask, fy, np.nan).astype(np.float32)
    mask &= np.isfinite(map_x) & np.isfinite(map_y)
    out = cv2.remap(img, np.where(mask, map_x, -1e6).astype(np.float32), np.where(mask, map_y, -1e6).astype(np.float32),
                    cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    out[~mask] = 0
    map_x[~mask] = np.nan
    map_y[~mask] = np.nan
    return ProjectorView(out, mask, map_x, map_y, int(close_px))
