"""The spots of the check in the world: the projector image that shows them and finding them in the camera's
difference image (shown - black)."""

from __future__ import annotations

import numpy as np


def spots_image(size, pts: np.ndarray, sigma: float) -> np.ndarray:
    """(H, W) uint8 projector image: a Gaussian spot of ``sigma`` px, peak 255, at each of ``pts`` (N, 2)."""
    W, H = size
    img = np.zeros((H, W), np.float32)
    r = int(np.ceil(4 * sigma))
    for x, y in pts:
        x0, x1 = max(0, int(np.floor(x)) - r), min(W, int(np.floor(x)) + r + 2)
        y0, y1 = max(0, int(np.floor(y)) - r), min(H, int(np.floor(y)) + r + 2)
        if x0 >= x1 or y0 >= y1:
            continue
        gx = np.exp(-0.5 * ((np.arange(x0, x1) - x) / sigma) ** 2)
        gy = np.exp(-0.5 * ((np.arange(y0, y1) - y) / sigma) ** 2)
        np.maximum(img[y0:y1, x0:x1], np.outer(gy, gx).astype(np.float32), out=img[y0:y1, x0:x1])
    return np.rint(img * 255).astype(np.uint8)


def robust_sigma(a: np.ndarray) -> float:
    a = a[np.isfinite(a)]
    return float(1.4826 * np.median(np.abs(a - np.median(a)))) if a.size else float("nan")


def centroid(diff, smooth, p, search, sigma_cam, floor, noise):
    """The spot near ``p``: (centroid (2,), its sd px) or None when nothing stands above ``floor`` in ``smooth``."""
    h, w = diff.shape
    x0, x1 = int(max(0, np.floor(p[0] - search))), int(min(w, np.ceil(p[0] + search) + 1))
    y0, y1 = int(max(0, np.floor(p[1] - search))), int(min(h, np.ceil(p[1] + search) + 1))
    if x1 - x0 < 3 or y1 - y0 < 3:
        return None
    yy, xx = np.mgrid[y0:y1, x0:x1]
    win = np.where((xx - p[0]) ** 2 + (yy - p[1]) ** 2 <= search ** 2, smooth[y0:y1, x0:x1], -np.inf)
    k = int(np.argmax(win))
    amp = float(win.flat[k])
    if not amp > floor:
        return None
    c = np.array([xx.flat[k], yy.flat[k]], float)
    rw = 3.0 * sigma_cam
    for _ in range(5):  # a window that follows the spot, so its edge does not pull the centroid
        x0, x1 = int(max(0, np.floor(c[0] - rw))), int(min(w, np.ceil(c[0] + rw) + 1))
        y0, y1 = int(max(0, np.floor(c[1] - rw))), int(min(h, np.ceil(c[1] + rw) + 1))
        yy, xx = np.mgrid[y0:y1, x0:x1]
        inside = (xx - c[0]) ** 2 + (yy - c[1]) ** 2 <= rw ** 2
        wgt = np.where(inside, np.maximum(diff[y0:y1, x0:x1] - 0.1 * amp, 0.0), 0.0)
        tot = wgt.sum()
        if not tot > 0:
            return None
        new = np.array([(wgt * xx).sum(), (wgt * yy).sum()]) / tot
        done = np.hypot(*(new - c)) < 1e-3
        c = new
        if done:
            break
    # the centroid's sd: each pixel of the window carries the image noise
    var = noise ** 2 * (((xx - c[0]) ** 2 + (yy - c[1]) ** 2) * (wgt > 0)).sum() / tot ** 2
    return c, float(np.sqrt(var / 2.0))


def spot_levels(lit: np.ndarray, dark: np.ndarray, sigma_cam: float, min_snr: float):
    """The difference image of a frame with spots and the black frame, and what finding its spots needs:
    (diff (H, W) float32, smooth: diff blurred to the spots' size ``sigma_cam`` camera px, noise: diff's robust
    sigma (at least half a level), floor: ``min_snr`` times smooth's noise, the least peak that is a spot)."""
    import cv2

    diff = lit.astype(np.float32) - dark.astype(np.float32)
    noise = max(robust_sigma(diff[::2, ::2]), 0.5)       # at least the quantisation of one level
    smooth = cv2.GaussianBlur(diff, (0, 0), sigmaX=max(sigma_cam, 0.5))
    floor = min_snr * max(robust_sigma(smooth[::2, ::2]), 0.5 / (2 * np.sqrt(np.pi) * max(sigma_cam, 0.5)))
    return diff, smooth, noise, floor


def count_spots(smooth: np.ndarray, floor: float, sigma_cam: float) -> int:
    """How many spots stand above ``floor`` anywhere in ``smooth`` (:func:`spot_levels`): its local maxima at least
    about two spot widths apart, a plateau counted once -- the spots the camera saw wherever they landed."""
    import cv2

    r = max(1, int(np.ceil(2 * sigma_cam)))
    peak = cv2.dilate(smooth, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1)))
    mask = ((smooth >= peak) & (smooth > floor)).astype(np.uint8)
    return int(cv2.connectedComponents(mask, connectivity=8)[0]) - 1
