"""Point clouds from a decoded capture: triangulate every decoded camera pixel, fit the board's plane.

* :func:`reconstruct` -- decoded maps (:class:`procam.decode.DecodeResult`) + calibration (+ the white
  frame for colour) -> :class:`PointCloud` (camera frame, board units), by
  :func:`procam.triangulate.triangulate_dense`.
* :func:`fit_plane` -- robust plane (least median of squares, then a least-squares refit on the
  inliers); :func:`residual_map` -- the signed distances as an image, the visual check of a
  calibration (a correct one leaves noise; wrong intrinsics bend or tilt the board).
* the cloud is written as binary PLY by :func:`procam.io.write_ply` (``procam.io.ply``).

Coordinates: camera frame (origin at the camera centre, x right, y down, z forward), the unit of
the calibration's ``T`` (the board's square unit, e.g. mm).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from .errors import ModelErrorWarning, ProcamError
from .io.files import full_scale_of
from .stats import rms as _rms
from .stats import robust_sigma, tls_plane
from .triangulate import triangulate_dense


@dataclass(frozen=True)
class PointCloud:
    """Triangulated camera pixels.

    Attributes
    ----------
    points : (N, 3) float64, camera frame, board units.
    colours : (N, 3) uint8 RGB (grey replicated for grey captures), or None.
    pixels : (N, 2) int64 camera pixel ``(x, y)`` of each point.
    both : (N,) bool -- projector column and row both used (else one of them).
    residual_px : (N,) projector reprojection error where both were used (pixels), else 0.
    image_size : (width, height) of the camera image.
    accounting : what :func:`reconstruct` did with the decoded pixels (:func:`dropped_lines` says it in words):
        ``decoded`` (camera pixels with a decoded column or row), ``not_in_front`` (no point in front of both
        devices), ``disagree`` (dropped: column and row disagree by more than ``max_residual_px``), ``kept``,
        ``max_residual_px``, and over the pixels with both coordinates ``median_disagreement_px`` and
        ``p90_disagreement_px`` (before dropping; with ``use`` col or row from a sample of them triangulated with
        both); empty for a subset.
    """

    points: np.ndarray
    colours: np.ndarray | None
    pixels: np.ndarray
    both: np.ndarray
    residual_px: np.ndarray
    image_size: tuple
    accounting: dict = field(default_factory=dict, compare=False)

    def __len__(self) -> int:
        return len(self.points)

    def subset(self, mask) -> "PointCloud":
        """The points where ``mask`` (N,) is True."""
        m = np.asarray(mask, bool)
        return PointCloud(self.points[m], None if self.colours is None else self.colours[m], self.pixels[m],
                          self.both[m], self.residual_px[m], self.image_size)  # no accounting: a subset

    def image_mask(self, region) -> np.ndarray:
        """(N,) bool: points whose camera pixel is True in the (H, W) bool image ``region``."""
        region = np.asarray(region, bool)
        return region[self.pixels[:, 1], self.pixels[:, 0]]


def to_rgb8(image) -> np.ndarray:
    """An image as (H, W, 3) uint8 RGB: grey replicated, OpenCV BGR(A) reordered, 16 bit scaled by
    its full scale (:func:`procam.io.files.full_scale_of`)."""
    img = np.asarray(image)
    if img.dtype == np.uint16:
        img = np.clip(np.rint(img.astype(np.float64) * (255.0 / full_scale_of(img))), 0, 255).astype(np.uint8)
    elif img.dtype != np.uint8:
        raise ValueError(f"colour image must be uint8 or uint16, got {img.dtype}")
    if img.ndim == 2:
        return np.repeat(img[:, :, None], 3, axis=2)
    if img.ndim == 3 and img.shape[2] == 1:
        return np.repeat(img, 3, axis=2)
    if img.ndim == 3 and img.shape[2] in (3, 4):
        return np.ascontiguousarray(img[:, :, 2::-1])
    raise ValueError(f"colour image must be (H, W), (H, W, 3) or (H, W, 4), got {img.shape}")


def reconstruct(calib, maps, colour=None, *, use: str = "both", max_residual_px: float | None = 2.0,
                region=None) -> PointCloud:
    """Triangulate every decoded camera pixel of one pose.

    Parameters
    ----------
    calib : :class:`procam.calibration.Calibration` with a projector and ``(R, T)``.
    maps : :class:`procam.decode.DecodeResult` of the pose (``col``, ``row``, ``valid_col``,
        ``valid_row``), or any object with those (H, W) attributes.
    colour : optional (H, W[, 3|4]) uint8/uint16 image for the points' colour (the white frame;
        BGR as OpenCV reads it).
    use : ``"both"`` (column and row where both are decoded, one of them elsewhere), ``"col"`` or
        ``"row"`` (see :func:`procam.triangulate.triangulate_dense`).
    max_residual_px : drop points whose column and row disagree by more than this (projector pixels,
        the reprojection error of the least-squares point): decoding errors. None keeps all.
    region : optional (H, W) bool: only these camera pixels.

    Returns
    -------
    :class:`PointCloud`

    Warns
    -----
    ModelErrorWarning
        Most decoded pixels were dropped because the calibration does not describe the capture's rig (or the
        maps are wrong): :attr:`Dropped.misfit` of :func:`dropped_lines`, the cloud is not to be trusted.

    Raises
    ------
    ProcamError
        The maps' size differs from the calibration's camera image size.
    """
    H, W = np.asarray(maps.col).shape
    cw, ch = (int(v) for v in calib.camera.image_size)
    if (W, H) != (cw, ch):
        raise ProcamError(f"the decoded maps are {W}x{H} but the calibration's camera is {cw}x{ch}; "
                          "reconstruct captures of the calibrated camera at its calibrated resolution")
    vc = np.asarray(maps.valid_col, bool)
    vr = np.asarray(maps.valid_row, bool)
    if region is not None:
        region = np.asarray(region, bool)
        vc, vr = vc & region, vr & region
    out = triangulate_dense(calib, maps.col, maps.row, vc, vr, use=use)
    keep = np.ones(len(out["points"]), bool)
    if max_residual_px is not None:
        keep = out["residual_px"] <= float(max_residual_px)
    decoded = int(np.count_nonzero((vc & (use != "row")) | (vr & (use != "col"))))  # as triangulate_dense reads them
    if use == "both":
        both_res = out["residual_px"][out["both"]]
    else:  # one coordinate triangulates, yet both were decoded: their disagreement still tests the fit
        ys, xs = np.nonzero(vc & vr)
        step = max(1, len(xs) // 20000)  # a sample is enough for a median
        sample = np.column_stack([xs[::step], ys[::step]])
        both_res = triangulate_dense(calib, maps.col, maps.row, vc, vr, use="both", pixels=sample)["residual_px"]
    accounting = {"decoded": decoded, "not_in_front": decoded - len(out["points"]),
                  "disagree": int(np.count_nonzero(~keep)), "kept": int(np.count_nonzero(keep)),
                  "max_residual_px": None if max_residual_px is None else float(max_residual_px),
                  "median_disagreement_px": float(np.median(both_res)) if both_res.size else float("nan"),
                  "p90_disagreement_px": float(np.percentile(both_res, 90)) if both_res.size else float("nan")}
    pix = out["pixels"][keep]
    cols = None
    if colour is not None:
        rgb = to_rgb8(colour)
        if rgb.shape[:2] != (H, W):
            raise ProcamError(f"the colour image is {rgb.shape[1]}x{rgb.shape[0]}, the maps {W}x{H}")
        cols = rgb[pix[:, 1], pix[:, 0]]
    cloud = PointCloud(out["points"][keep], cols, pix, out["both"][keep], out["residual_px"][keep], (W, H),
                       accounting)
    misfit = dropped_lines(cloud).misfit
    if misfit:
        warnings.warn(f"the point cloud must not be trusted: {misfit}", ModelErrorWarning, stacklevel=2)
    return cloud


#: The median column/row disagreement (projector px) above which the calibration does not fit the capture: decoding
#: noise is well under a pixel, a calibration of this rig leaves it there.
MISFIT_PX = 2.0


class Dropped(NamedTuple):
    """What :func:`reconstruct` dropped, in words (:func:`dropped_lines`).

    lines : the accounting, one line per quantity; warnings : at most one, when many pixels were dropped;
    misfit : why the cloud must not be trusted (the calibration does not describe the capture's rig, or the
    decoded maps are wrong), else ``""``.
    """

    lines: list
    warnings: list
    misfit: str


def dropped_lines(cloud: PointCloud, warn_fraction: float = 0.1) -> Dropped:
    """What :func:`reconstruct` dropped, and why, in words (:class:`Dropped`).

    The lines account for every decoded camera pixel (kept; dropped because its projector column and row
    disagree; no point in front of both devices) and give the median column/row disagreement. A pixel's
    disagreement is the distance (projector pixels) between its decoded (column, row) and the projection of its
    least-squares point: with a right calibration and a right decode it is the decoding noise (well under a
    pixel).  A misfit -- the cloud is not to be trusted -- when the median is above :data:`MISFIT_PX` (measured on
    the pixels with both coordinates whatever ``use`` and ``max_residual_px`` were) or most pixels triangulate
    behind a device: the calibration does not describe this rig or the decoded maps are wrong (swapped pattern
    pairs, another capture's patterns).  Else a warning when more than ``warn_fraction`` of the decoded pixels
    were dropped: the noisy ones, at edges and in shadow.
    """
    a = cloud.accounting
    if not a:
        return Dropped([], [], "")
    n = max(a["decoded"], 1)
    thr = a["max_residual_px"]
    lines = [f"decoded camera pixels: {a['decoded']}; kept {a['kept']} ({a['kept'] / n:.0%})"]
    if thr is not None:
        lines.append(f"dropped, projector column and row disagree by more than {thr:g} px: {a['disagree']} "
                     f"({a['disagree'] / n:.0%})")
    lines.append(f"dropped, no point in front of both devices: {a['not_in_front']} ({a['not_in_front'] / n:.0%})")
    med, p90 = a["median_disagreement_px"], a["p90_disagreement_px"]
    if np.isfinite(med):
        lines.append(f"column/row disagreement (pixels with both): median {med:.2f} px, 90th percentile {p90:.2f} px")
    dropped = a["disagree"] + a["not_in_front"]
    head = f"{dropped} of {a['decoded']} decoded pixels ({dropped / n:.0%}) were dropped: "
    if np.isfinite(med) and med > MISFIT_PX:
        why = (f"the median column/row disagreement ({med:.1f} px) is above {MISFIT_PX:g} px: for most pixels the "
               "decoded column and row do not meet on one point -- the calibration does not describe this camera "
               "and projector (another rig, a moved projector, a wrong --projector size), or the decoded maps are "
               "wrong (swapped pattern pairs, patterns from another capture: procam decode --png shows them)")
        return Dropped(lines, [head + why], head + why)
    if a["not_in_front"] > 0.5 * n:
        why = ("most of them triangulate behind a device: the calibration's R, T do not describe this rig (or the "
               "capture is of another one)")
        return Dropped(lines, [head + why], head + why)
    if dropped <= warn_fraction * n:
        return Dropped(lines, [], "")
    return Dropped(lines, [head + f"the median disagreement ({med:.2f} px) is small: the dropped pixels are the noisy "
                           "ones (edges, shadows, dark or glossy surfaces); --max-residual keeps more of them"], "")


@dataclass(frozen=True)
class Plane:
    """A plane ``normal . X + offset = 0`` (unit ``normal`` pointing to the camera side, so signed
    distances are positive in front of the plane).

    Attributes
    ----------
    normal : (3,); offset : float (board units; the camera centre's distance to the plane).
    inliers : (N,) bool over the fitted points.
    residuals : (N,) signed distances of all fitted points, board units.
    rms : RMS distance of the inliers; sigma : robust (MAD) scale of the inliers' residuals, board units.
    """

    normal: np.ndarray
    offset: float
    inliers: np.ndarray
    residuals: np.ndarray
    rms: float
    sigma: float

    def distance(self, X) -> np.ndarray:
        """Signed distances (N,) of points X (N, 3)."""
        return np.asarray(X, float).reshape(-1, 3) @ self.normal + self.offset


def _tls_plane(X):
    """:func:`procam.stats.tls_plane` as ``(normal, offset)`` with ``normal . x + offset = 0``, offset >= 0."""
    n, c = tls_plane(X)
    d = -float(n @ c)
    if d < 0:
        n, d = -n, -d
    return n, d


def fit_plane(points, *, robust: bool = True, k: float = 3.0, trials: int = 300, max_sample: int = 20000,
              seed: int = 0) -> Plane:
    """Plane through 3-D points, robust to a minority of outliers.

    ``robust=True``: least median of squares over ``trials`` random point triples (scored on at
    most ``max_sample`` points, seeded), then three rounds of: total-least-squares refit on the
    inliers, ``sigma = 1.4826 median |r|`` over the inliers, inliers ``|r| <= k sigma``.
    ``robust=False``: total least squares on all points (all inliers).

    Parameters
    ----------
    points : (N, 3), N >= 3, board units.

    Returns
    -------
    :class:`Plane`.  Raises ValueError for fewer than 3 finite points.
    """
    X = np.asarray(points, float).reshape(-1, 3)
    fin = np.isfinite(X).all(1)
    if fin.sum() < 3:
        raise ValueError(f"a plane needs at least 3 finite points, got {int(fin.sum())}")
    Xf = X[fin]
    if not robust:
        n, d = _tls_plane(Xf)
        inl = np.ones(len(Xf), bool)
    else:
        rng = np.random.default_rng(seed)
        S = Xf if len(Xf) <= max_sample else Xf[rng.choice(len(Xf), max_sample, replace=False)]
        best = (np.inf, None, None)
        for _ in range(int(trials)):
            a, b, c = S[rng.choice(len(S), 3, replace=False)]
            n = np.cross(b - a, c - a)
            nn = np.linalg.norm(n)
            if not nn > 0:
                continue
            n = n / nn
            med = float(np.median(np.abs((S - a) @ n)))
            if med < best[0]:
                best = (med, n, -float(n @ a))
        if best[1] is None:
            n, d = _tls_plane(Xf)
        else:
            n, d = best[1], best[2]
        r = Xf @ n + d
        inl = np.abs(r) <= max(2.5 * robust_sigma(r, about=0.0), 1e-12)
        for _ in range(3):
            if inl.sum() < 3:
                break
            n, d = _tls_plane(Xf[inl])
            r = Xf @ n + d
            sig = robust_sigma(r[inl], about=0.0)
            inl = np.abs(r) <= max(k * sig, 1e-12)
    if d < 0:
        n, d = -n, -d
    r = Xf @ n + d
    sig = robust_sigma(r[inl], about=0.0)
    r_all = np.full(len(X), np.nan)
    r_all[fin] = r
    inliers = np.zeros(len(X), bool)
    inliers[fin] = inl
    rms = _rms(r[inl], dim=1)
    return Plane(np.asarray(n, float), float(d), inliers, r_all, rms, sig)


def residual_map(cloud: PointCloud, plane: Plane, mask=None) -> np.ndarray:
    """(H, W) float32 image of the signed distances of ``cloud``'s points to ``plane`` (board units),
    NaN where there is no point (or outside ``mask`` (N,) bool over the cloud)."""
    W, H = cloud.image_size
    out = np.full((H, W), np.nan, np.float32)
    m = np.ones(len(cloud), bool) if mask is None else np.asarray(mask, bool)
    px = cloud.pixels[m]
    out[px[:, 1], px[:, 0]] = plane.distance(cloud.points[m]).astype(np.float32)
    return out


def residual_image(res_map: np.ndarray, scale: float | None = None) -> np.ndarray:
    """A (H, W, 3) uint8 BGR picture of a residual map: blue (below) - green (0) - red (above) over
    ``[-scale, scale]`` (default 3 x the robust sigma of the map), black where NaN."""
    import cv2

    r = np.asarray(res_map, float)
    fin = np.isfinite(r)
    if scale is None:
        scale = 3.0 * robust_sigma(r[fin], about=0.0) if fin.any() else 1.0
    scale = scale if scale > 0 else 1.0
    u = np.clip((np.where(fin, r, 0.0) / scale + 1.0) * 127.5, 0, 255).astype(np.uint8)
    img = cv2.applyColorMap(u, cv2.COLORMAP_JET)
    img[~fin] = 0
    return img
