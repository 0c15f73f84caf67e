"""Targets on the wall behind the board: what the check in the world can measure where the calibration does not
know the surface.

The calibration knows the board's plane (its corners give the board's pose by PnP) but not the wall's.  A spot
shown at projector pixel ``q`` lights the point of the wall on ``q``'s projector ray, wherever the wall is, and
the camera must see it on the image of that ray: ``q``'s **epipolar curve** (a line bent by the camera's lens).
How far the found spot lies from that curve is measurable without knowing the wall, and is what the wall's
targets check (camera px; with the gap between the spot's camera ray and ``q``'s projector ray, in the
calibration's length unit).  Where along the curve the spot lies is the wall's depth, which only the calibration
itself could predict (by triangulation): it is reported (:attr:`WallCheck.points`), not checked.  So an error
that slides the spots along their epipolar curves -- the baseline's length, a turn of the projector about the
normal of the epipolar planes -- is invisible on the wall; the board's targets see it.

Spots whose epipolar curves pass near each other are shown in different frames (:func:`frames`), so each is
searched for only in a band around its own curve (:func:`band_peak`); spots that would land on the board or its
shadow, or be cut by the panel's border, are not shown (:func:`grid`), and spots found next to the board in the camera image or at its border are
set aside (status ``"board"``, ``"edge"``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Depths searched along a projector ray, as multiples of the board's depth in the projector frame.
DEPTHS = (0.5, 20.0)


@dataclass(frozen=True)
class WallCheck:
    """The wall's targets of :func:`procam.world_check.world_check` (M spots; pixels ``(x, y)``).

    proj_pts : (M, 2) the spots' projector pixels (a grid over the panel, the board's footprint left out).
    frame : (M,) the frame each spot was shown in (spots with nearby epipolar curves in different frames).
    found : (M, 2) the spots' centroids, camera px (NaN unless ``status`` is ``"found"``).
    status : (M,) ``"found"``, ``"faint"`` (nothing above the noise near the spot's epipolar curve: the wall is
        hidden, too dark or out of view), ``"board"`` (found on or beside the board, not on the wall) or ``"edge"``
        (found within 4 sigma of the image's border, which would pull its centroid inwards); only ``"found"`` spots
        are measured.
    miss_px : (M, 2) found - the nearest point of the spot's epipolar curve, camera px (across the curve).
    gap : (M,) the distance between the found spot's camera ray and the spot's projector ray at their closest,
        in the calibration's length unit.
    points : (M, 3) the point of the projector ray nearest the found spot's camera ray, camera frame (the wall,
        as the calibration triangulates it; not checked).
    sd_px : (M,) the centroids' standard deviation from the image noise, camera px.
    rms_px, max_px : RMS and largest ``|miss_px|`` over the found spots; rms_gap : RMS ``gap``.
    noise_px : median ``sd_px``.
    """

    proj_pts: np.ndarray
    frame: np.ndarray
    found: np.ndarray
    status: tuple
    miss_px: np.ndarray
    gap: np.ndarray
    points: np.ndarray
    sd_px: np.ndarray
    rms_px: float
    max_px: float
    rms_gap: float
    noise_px: float

    @property
    def n_found(self) -> int:
        return int(sum(s == "found" for s in self.status))

    def to_dict(self, num, arr) -> dict:
        """JSON-ready numbers (``num``/``arr`` the caller's rounding of a number / a (N, k) array)."""
        return {"rms_px": num(self.rms_px), "max_px": num(self.max_px), "rms_gap": num(self.rms_gap),
                "noise_px": num(self.noise_px), "found": self.n_found, "targets": len(self.status),
                "markers": [{"projector": arr([q])[0], "frame": int(f), "status": s, "found": arr([c])[0],
                             "miss_px": arr([m])[0], "gap": num(g), "point": arr([X])[0]}
                            for q, f, s, c, m, g, X in zip(self.proj_pts, self.frame, self.status, self.found,
                                                           self.miss_px, self.gap, self.points)]}


#: How far beyond the outer inner corners the board's footprint reaches, in squares: the outer squares (1), a
#: printed white border of up to a square (1), and half a square to spare.
GROW = 2.5


def footprint(device, R, t, board, grow: float = GROW) -> np.ndarray:
    """(4, 2) ``device`` pixels of the board's outer corners' rectangle grown by ``grow`` squares on every side
    (the printed board with its border, generously), board at pose ``(R, t)`` (board -> device)."""
    obj = board.object_points()
    lo, hi = obj[:, :2].min(0) - grow * board.square, obj[:, :2].max(0) + grow * board.square
    rect = np.array([[lo[0], lo[1], 0], [hi[0], lo[1], 0], [hi[0], hi[1], 0], [lo[0], hi[1], 0]])
    return device.project(R, t, rect)


def inside(poly: np.ndarray, pts: np.ndarray, margin: float = 0.0) -> np.ndarray:
    """(N,) bool: ``pts`` (N, 2) within ``margin`` px of the polygon ``poly`` (K, 2) or inside it."""
    import cv2

    c = np.asarray(poly, np.float32).reshape(-1, 1, 2)
    return np.array([np.isfinite(p).all() and cv2.pointPolygonTest(c, (float(p[0]), float(p[1])), True) > -margin
                     for p in np.asarray(pts, float)], bool)


def grid(proj_size, shape, keep_out: np.ndarray, edge: float = 0.0) -> np.ndarray:
    """(M, 2) projector pixels: the centres of a ``shape = (cols, rows)`` grid of cells over the panel
    ``proj_size = (W, H)``, those inside the polygon ``keep_out`` (the board's footprint) or within ``edge`` px of
    the panel's border (a spot cut by it would be shown off centre) left out."""
    W, H = proj_size
    cols, rows = shape
    x = (np.arange(cols) + 0.5) * W / cols - 0.5
    y = (np.arange(rows) + 0.5) * H / rows - 0.5
    q = np.stack(np.meshgrid(x, y), -1).reshape(-1, 2)
    on_panel = (q[:, 0] >= edge) & (q[:, 0] <= W - 1 - edge) & (q[:, 1] >= edge) & (q[:, 1] <= H - 1 - edge)
    return q[on_panel & ~inside(keep_out, q)]


def curves(calib, q: np.ndarray, depth: float, n: int = 128) -> np.ndarray:
    """(M, n, 2) the epipolar curves of projector pixels ``q`` (M, 2): the camera pixels (distorted) of each
    projector ray at ``n`` depths (projector frame) from ``DEPTHS[0]`` to ``DEPTHS[1]`` times ``depth``, even in
    inverse depth; NaN where the point is behind the camera or outside its image."""
    from ..triangulate import rays

    R, T = np.asarray(calib.R, float), np.asarray(calib.T, float).reshape(3)
    d = rays(calib.projector, q)
    z = 1.0 / np.linspace(1.0 / (DEPTHS[0] * depth), 1.0 / (DEPTHS[1] * depth), n)
    Xc = ((d[:, None, :] * z[None, :, None]) - T) @ R          # R^T (X_p - T), row-wise
    with np.errstate(divide="ignore", invalid="ignore"):
        pix = calib.camera.project(np.eye(3), np.zeros(3), Xc.reshape(-1, 3)).reshape(len(q), n, 2)
    W, H = calib.camera.image_size
    bad = (Xc[..., 2] <= 0) | ~np.isfinite(pix).all(-1) | (pix[..., 0] < -0.5) | (pix[..., 0] > W - 0.5) | (
        pix[..., 1] < -0.5) | (pix[..., 1] > H - 0.5)
    pix[bad] = np.nan
    return pix


def frames(curves_px: np.ndarray, separation: float) -> np.ndarray:
    """(M,) frame index per spot: spots whose curves come closer than ``separation`` px are in different frames
    (greedy colouring, spots in their order)."""
    M = len(curves_px)
    pts = [c[np.isfinite(c).all(1)] for c in curves_px]
    out = np.full(M, -1)
    for k in range(M):
        taken = set()
        for j in range(k):
            if len(pts[k]) and len(pts[j]) and np.min(
                    np.linalg.norm(pts[k][:, None] - pts[j][None], axis=2)) < separation:
                taken.add(out[j])
        out[k] = next(f for f in range(M + 1) if f not in taken)
    return out


def band_peak(smooth: np.ndarray, curve: np.ndarray, band: float):
    """The brightest pixel (x, y) of ``smooth`` within ``band`` px of the polyline ``curve`` (n, 2; NaN rows
    break it) and its value; None when the curve has no point in the image."""
    import cv2

    mask = np.zeros(smooth.shape, np.uint8)
    ok = np.isfinite(curve).all(1)
    runs = np.split(np.arange(len(curve)), np.flatnonzero(np.diff(ok.astype(int))) + 1)
    for run in runs:
        if ok[run[0]]:
            seg = np.round(curve[run] * 16).astype(np.int32).reshape(-1, 1, 2)
            cv2.polylines(mask, [seg], False, 1, thickness=max(1, round(2 * band + 1)), lineType=cv2.LINE_8,
                          shift=4)
    if not mask.any():
        return None
    win = np.where(mask > 0, smooth, -np.inf)
    k = int(np.argmax(win))
    y, x = divmod(k, smooth.shape[1])
    return np.array([x, y], float), float(win.flat[k])


def on_ray(calib, q: np.ndarray, found: np.ndarray, iterations: int = 8):
    """For each projector pixel ``q`` (M, 2) and camera pixel ``found`` (M, 2): the point of ``q``'s projector ray
    whose camera image is nearest ``found`` (Gauss-Newton on the depth along the ray, from the rays' closest
    approach).  Returns (nearest (M, 2) distorted camera px on the epipolar curve, points (M, 3) camera frame,
    gap (M,) the rays' distance at their closest, length unit); NaN rows where ``found`` is NaN."""
    from ..triangulate import rays

    R, T = np.asarray(calib.R, float), np.asarray(calib.T, float).reshape(3)
    o = -R.T @ T                                    # the projector's centre, camera frame
    a = rays(calib.projector, q) @ R                # its rays' directions (R^T d), camera frame
    r = rays(calib.camera, found)
    n = np.cross(r, a)
    with np.errstate(divide="ignore", invalid="ignore"):
        gap = np.abs(n @ o) / np.linalg.norm(n, axis=1)
        # closest approach: t r = o + z a (least squares in t, z) -> z
        rr, aa, ra = (r * r).sum(1), (a * a).sum(1), (r * a).sum(1)
        ro, ao = r @ o, a @ o
        z = (ra * ro - rr * ao) / (rr * aa - ra ** 2)

    def image(z):
        with np.errstate(divide="ignore", invalid="ignore"):
            return calib.camera.project(np.eye(3), np.zeros(3), o + z[:, None] * a)

    for _ in range(iterations):
        f = image(z) - found
        h = 1e-6 * np.abs(z) + 1e-9
        J = (image(z + h) - image(z)) / h[:, None]
        with np.errstate(divide="ignore", invalid="ignore"):
            z = z - (J * f).sum(1) / (J * J).sum(1)
    return image(z), o + z[:, None] * a, gap
