"""Chessboard geometry and corner detection.

Board frame: corner ``k = j * cols + i`` (``i`` along the ``cols``
direction, ``j`` along ``rows``) sits at ``(i s, j s, 0) - centroid``; with the canonical
image order (corner 0 top-left in the image, ``i`` running to the right) the board's z axis
points away from the devices, so a fronto-parallel board has ``R = I``.

Corner detection (:func:`detect_corners`) finds the board on a copy of the image downscaled to at
most :data:`DETECT_MAX_WIDTH` pixels wide (OpenCV's detector takes a few ms there, against 0.1-0.4 s
at full size; Moreno & Taubin downscale too), falls back to the full-size image (classic, then SB),
then refines the corners at full size.  The default refinement (``refine="fit"``, :func:`fit_corners`)
fits a model of a blurred, unevenly lit chessboard corner to the pixels around each corner:
0.014 px RMS on renders where ``cornerSubPix`` (``"subpix"``, kept as an option) has 0.064, and
0.157 px instead of 0.245 px calibrateCamera RMS on OpenCV's sample photographs.
:func:`find_corners` tries several frames of a pose and, when a board of another size is in view,
gives up at once with that size (:func:`size_hint`).  ``benchmarks/correspond.py`` measures all of it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .errors import ProcamError

#: Inner corners per side that a board may have (OpenCV's detectors need at least 3; 500 is far beyond
#: any printed calibration board and keeps every array small).
CORNERS_PER_SIDE = (3, 500)
#: Square sizes accepted, in the user's length unit (1e-6 .. 1e6: microns to kilometres in mm).
SQUARE_RANGE = (1e-6, 1e6)


@dataclass(frozen=True)
class Board:
    """A printed chessboard: ``cols`` x ``rows`` **inner** corners (OpenCV's ``pattern_size``; a board of
    11 x 7 squares has 10 x 6 inner corners) and the side ``square`` of a square, which is the length
    unit of every output (say mm).

    Raises :class:`~procam.errors.ProcamError` for counts outside :data:`CORNERS_PER_SIDE` or a square
    size that is not a finite number in :data:`SQUARE_RANGE`.

    >>> Board(10, 6, 24.0).object_points().shape
    (60, 3)
    """

    cols: int
    rows: int
    square: float

    def __post_init__(self):
        lo, hi = CORNERS_PER_SIDE
        for what, v in (("columns", self.cols), ("rows", self.rows)):
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not lo <= v <= hi:
                raise ProcamError(f"board {self.cols}x{self.rows}: {what} of inner corners must be an integer "
                                  f"from {lo} to {hi}, got {v!r} (count inner corners, not squares)")
        sq = self.square
        if isinstance(sq, bool) or not isinstance(sq, (int, float, np.integer, np.floating)) \
                or not math.isfinite(sq) or not SQUARE_RANGE[0] <= sq <= SQUARE_RANGE[1]:
            raise ProcamError(f"board square size must be a finite length from {SQUARE_RANGE[0]:g} to "
                              f"{SQUARE_RANGE[1]:g} (the square's side in your length unit, e.g. 24 for mm), "
                              f"got {sq!r}")
        object.__setattr__(self, "cols", int(self.cols))
        object.__setattr__(self, "rows", int(self.rows))
        object.__setattr__(self, "square", float(sq))

    @property
    def pattern_size(self) -> tuple[int, int]:
        """``(cols, rows)``, OpenCV's ``pattern_size``."""
        return self.cols, self.rows

    @property
    def n_corners(self) -> int:
        return self.cols * self.rows

    def object_points(self) -> np.ndarray:
        """(cols*rows, 3) board corners (:func:`object_points`)."""
        return object_points(self.cols, self.rows, self.square)

    def to_dict(self) -> dict:
        return {"cols": self.cols, "rows": self.rows, "square": self.square}


def object_points(cols: int, rows: int, square: float) -> np.ndarray:
    """(cols*rows, 3) board corners, row-major (``cols`` per row), centred at their centroid."""
    i, j = np.meshgrid(np.arange(cols, dtype=float), np.arange(rows, dtype=float))
    pts = np.column_stack([i.ravel() * square, j.ravel() * square, np.zeros(cols * rows)])
    pts[:, :2] -= pts[:, :2].mean(axis=0)
    return pts


DETECTORS = ("auto", "classic", "sb")
REFINERS = ("fit", "subpix", "none")

#: Images wider than this are searched for the board on a downscaled copy first (pixels).
DETECT_MAX_WIDTH = 640

#: Default refinement half-window (pixels) per method, the measured best within ~0.1 s per pose
#: (``benchmarks/correspond.py``): the fit gains up to 20 px, ``cornerSubPix`` is best at 11 (OpenCV's
#: usual ``winSize=(11, 11)``) and worse above.
REFINE_WINDOW = {"fit": 15, "subpix": 11, "none": 0}



def _gray(image: np.ndarray) -> np.ndarray:
    """(H, W) grey image in its own dtype when OpenCV takes it (uint8, uint16, float32), else float32."""
    import cv2

    img = np.asarray(image)
    if img.dtype not in (np.uint8, np.uint16, np.float32):
        img = img.astype(np.float32)
    if img.ndim == 3:
        img = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY if img.shape[2] == 3 else cv2.COLOR_BGRA2GRAY)
    return img


def gray_float(image: np.ndarray) -> np.ndarray:
    """(H, W) float32 grey copy of an image (uint8/uint16/float, grey, BGR or BGRA), values unscaled."""
    return _gray(image).astype(np.float32, copy=False)


def _stretch8(img: np.ndarray) -> np.ndarray:
    """Contrast-stretch a grey image to uint8 between its 0.5 and 99.5 percentiles."""
    import cv2

    step = max(1, int(np.sqrt(img.size / 250_000)))  # percentiles of a ~250k-pixel sample
    lo, hi = np.percentile(img[::step, ::step], [0.5, 99.5])
    if hi <= lo:
        return np.zeros(img.shape, np.uint8)
    a = 255.0 / (hi - lo)
    if img.dtype == np.uint8:
        return cv2.LUT(img, np.clip((np.arange(256) - lo) * a, 0, 255).astype(np.uint8))
    if img.dtype == np.uint16:
        return np.clip((np.arange(65536, dtype=np.float32) - lo) * a, 0, 255).astype(np.uint8)[img]
    return np.clip((img.astype(np.float32) - lo) * a, 0, 255).astype(np.uint8)


def to_gray8(image: np.ndarray) -> np.ndarray:
    """8-bit grey copy of an image (uint8/uint16, grey or BGR), contrast-stretched to the
    0.5–99.5 percentiles so dim or 16-bit frames detect like well-exposed ones."""
    return _stretch8(gray_float(image))


def canonical_order(corners: np.ndarray, cols: int, rows: int) -> np.ndarray:
    """Reorder detected corners (cols*rows, 2) into procam's canonical order.

    The grid keeps ``cols`` corners per row.  The order is made right-handed in the image
    (the ``i`` direction turned clockwise gives the ``j`` direction, so the board's z axis points
    away from the camera), and of the two right-handed orders the one whose corner 0 is nearest
    the image's top-left corner is kept.  For a square grid (cols == rows) the four rotations
    are considered.
    """
    g = np.asarray(corners, float).reshape(rows, cols, 2)
    cands = []
    variants = [g, g[::-1, ::-1], g[::-1, :], g[:, ::-1]]
    if cols == rows:
        variants += [np.transpose(v, (1, 0, 2)) for v in variants]
    for v in variants:
        di = v[:, -1].mean(0) - v[:, 0].mean(0)
        dj = v[-1, :].mean(0) - v[0, :].mean(0)
        if di[0] * dj[1] - di[1] * dj[0] > 0:  # right-handed with y down
            cands.append(v)
    best = min(cands, key=lambda v: v[0, 0].sum())
    return best.reshape(-1, 2).copy()


# --------------------------------------------------------------------------------------------
# detection
# --------------------------------------------------------------------------------------------

class _Pyramid:
    """The grey image at full size (native dtype, and stretched to uint8 when needed) and, when it
    is wider than ``max_width``, a stretched uint8 copy downscaled to that width."""

    def __init__(self, image, max_width):
        import cv2

        self.gray = _gray(image)
        h, w = self.gray.shape
        self._g8 = None
        self.scale = 1.0
        self.small = None
        if max_width and w > max_width:
            # stretch, then downscale: findChessboardCorners finds the board in 1-3 ms in that image
            # against 20-40 ms when the downscaled image is stretched (16 renders, 640-1024 px wide)
            self.scale = max_width / w
            size = (int(max_width), max(1, round(h * self.scale)))
            self.small = cv2.resize(self.g8, size, interpolation=cv2.INTER_AREA)

    @property
    def g8(self):
        if self._g8 is None:
            self._g8 = _stretch8(self.gray)
        return self._g8

    def level(self, small: bool):
        return (self.small, self.scale) if small else (self.g8, 1.0)


def _find(g8, size, kind):
    """One OpenCV detector call; (cols*rows, 2) float64 corners in OpenCV's order or None."""
    import cv2

    cols, rows = size
    if kind == "sb":
        flags = cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY
        ok, c = cv2.findChessboardCornersSB(g8, (cols, rows), flags=flags)
    else:
        flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
        ok, c = cv2.findChessboardCorners(g8, (cols, rows), flags=flags)
    if not ok or c is None or len(c) != cols * rows:
        return None
    return c.reshape(-1, 2).astype(np.float64)


def _attempts(detector, downscaled):
    """(kind, on the downscaled copy?) in the order tried."""
    if detector == "classic":
        return [("classic", True), ("classic", False)] if downscaled else [("classic", False)]
    if detector == "sb":
        return [("sb", True), ("sb", False)] if downscaled else [("sb", False)]
    # auto: the old chain (classic, then SB, at full size), preceded by classic on the small copy
    return ([("classic", True)] if downscaled else []) + [("classic", False), ("sb", False)]


def _search(pyr, size, attempts):
    """The first detection among ``attempts`` (see :func:`_attempts`), full-size pixels, canonical order."""
    cols, rows = size
    for kind, small in attempts:
        g8, s = pyr.level(small)
        c = _find(g8, (cols, rows), kind)
        if c is not None:
            c = (c + 0.5) / s - 0.5 if s != 1.0 else c  # pixel centres at integers at both scales
            return canonical_order(c, cols, rows)
    return None


def _check(pattern_size, detector, refine):
    if detector not in DETECTORS:
        raise ValueError(f"detector must be one of {DETECTORS}, got {detector!r}")
    if refine not in REFINERS:
        raise ValueError(f"refine must be one of {REFINERS}, got {refine!r}")
    return int(pattern_size[0]), int(pattern_size[1])


def find_grid(image: np.ndarray, pattern_size, *, detector: str = "auto",
              max_width: int | None = DETECT_MAX_WIDTH) -> np.ndarray | None:
    """Detect a chessboard (no sub-pixel refinement beyond the detector's own).

    Parameters
    ----------
    image : (H, W) or (H, W, 3) uint8/uint16.
    pattern_size : (cols, rows) inner corners.
    detector : ``"classic"`` (``findChessboardCorners``, adaptive threshold + normalisation; on the
        downscaled copy, then at full size), ``"sb"`` (``findChessboardCornersSB``, exhaustive +
        accuracy; likewise) or ``"auto"`` (classic on the downscaled copy, then procam's earlier
        chain: classic at full size, SB at full size).
    max_width : images wider than this are searched on a copy downscaled to this width first
        (None or 0: full size only).

    Returns
    -------
    (cols*rows, 2) float64 corners in full-size pixels, canonical order, or None.
    """
    size = _check(pattern_size, detector, "none")
    pyr = _Pyramid(image, max_width)
    return _search(pyr, size, _attempts(detector, pyr.small is not None))


def detect_corners(image: np.ndarray, pattern_size: tuple[int, int], *, detector: str = "auto",
                   refine_window: int | None = None, refine: str = "fit",
                   max_width: int | None = DETECT_MAX_WIDTH) -> np.ndarray | None:
    """Find the inner corners of a chessboard in one image.

    Parameters
    ----------
    image : (H, W) or (H, W, 3) uint8/uint16
    pattern_size : (cols, rows) of inner corners (OpenCV's ``pattern_size``).
    detector : ``"classic"`` (``findChessboardCorners`` with adaptive threshold and normalisation),
        ``"sb"`` (``findChessboardCornersSB``, exhaustive + accuracy flags: slower, more tolerant of
        blur and uneven light) or ``"auto"`` (classic, then SB if classic fails).  See
        :func:`find_grid`.
    refine_window : half-size in pixels of the refinement window (0 = no refinement; None = the
        method's :data:`REFINE_WINDOW`); clamped per corner so the window stays clear of the
        neighbouring corners.
    refine : ``"fit"`` (default, :func:`fit_corners`), ``"subpix"`` (``cornerSubPix`` only) or ``"none"``.
    max_width : detect on a copy downscaled to this width when the image is wider (None/0: never);
        the corners are refined at full size either way.

    Returns
    -------
    (cols*rows, 2) float64 corners in canonical order (see :func:`canonical_order`), or None.
    """
    size = _check(pattern_size, detector, refine)
    pyr = _Pyramid(image, max_width)
    c = _search(pyr, size, _attempts(detector, pyr.small is not None))
    return None if c is None else _refine(pyr, c, size, refine, refine_window)


def _refine(pyr, c, size, refine, window):
    return refine_corners(pyr.gray, c, size, method=refine, window=window, start_error=1.0 / pyr.scale)


def find_corners(images, pattern_size, *, detector: str = "auto", refine_window: int | None = None,
                 refine: str = "fit", max_width: int | None = DETECT_MAX_WIDTH):
    """Corners of the board in the first of several images of it that shows it; fails fast.

    For a pose's white, white - black and black frames.  Order: the quick attempt (the first of
    :func:`find_grid`'s, on the downscaled copy) on the first image; if it fails, :func:`size_hint`
    on that image, and if a board of another size is in view, give up at once (a wrong ``--board``
    would otherwise cost every slow full-size attempt on every image); then the remaining attempts,
    then :func:`detect_corners` on each further image.

    Parameters
    ----------
    images : sequence of images, or of zero-argument callables returning one (called only when
        reached, so a fallback image is built only when needed).
    pattern_size, detector, refine_window, refine, max_width : as :func:`detect_corners`.

    Returns
    -------
    (corners, hint) : ``corners`` (cols*rows, 2) float64 in canonical order, or None; ``hint`` the
    (cols, rows) of a board found instead (see :func:`size_hint_text`), else None.
    """
    size = _check(pattern_size, detector, refine)
    images = [im if callable(im) else (lambda im=im: im) for im in images]
    if not images:
        return None, None
    pyr = _Pyramid(images[0](), max_width)
    attempts = _attempts(detector, pyr.small is not None)
    c = _search(pyr, size, attempts[:1])
    if c is None:
        hint = size_hint(None, size, _pyr=pyr)
        if hint is not None:
            return None, hint
        c = _search(pyr, size, attempts[1:])
    if c is not None:
        return _refine(pyr, c, size, refine, refine_window), None
    for image in images[1:]:
        c = detect_corners(image(), size, detector=detector, refine_window=refine_window, refine=refine,
                           max_width=max_width)
        if c is not None:
            return c, None
    return None, None


# --------------------------------------------------------------------------------------------
# refinement
# --------------------------------------------------------------------------------------------

def corner_spacing(corners: np.ndarray, cols: int, rows: int) -> np.ndarray:
    """(N,) distance from each corner to the nearest grid line not through it (pixels).

    The distance to its nearest neighbour along either board direction, times the sine of the
    angle between the two directions: a window of this radius around the corner holds only the
    two edges that cross there.
    """
    g = np.asarray(corners, float).reshape(rows, cols, 2)
    big = np.full((rows, cols), np.inf)
    di, dj = big.copy(), big.copy()
    if cols > 1:
        d = np.linalg.norm(np.diff(g, axis=1), axis=2)
        di[:, :-1] = d
        di[:, 1:] = np.minimum(di[:, 1:], d)
    if rows > 1:
        d = np.linalg.norm(np.diff(g, axis=0), axis=2)
        dj[:-1] = d
        dj[1:] = np.minimum(dj[1:], d)
    ui, uj = _directions(g)
    sin = np.abs(ui[..., 0] * uj[..., 1] - ui[..., 1] * uj[..., 0])
    out = np.minimum(di, dj) * np.where(np.isfinite(sin), sin, 1.0)
    return np.where(np.isfinite(out), out, 1e9).ravel()


def _directions(g):
    """Unit vectors (rows, cols, 2) along the board's i and j directions at every corner."""
    gi = np.gradient(g, axis=1) if g.shape[1] > 1 else np.zeros_like(g) + [1.0, 0.0]
    gj = np.gradient(g, axis=0) if g.shape[0] > 1 else np.zeros_like(g) + [0.0, 1.0]
    with np.errstate(invalid="ignore", divide="ignore"):
        ui = gi / np.linalg.norm(gi, axis=2, keepdims=True)
        uj = gj / np.linalg.norm(gj, axis=2, keepdims=True)
    return ui, uj


def _subpix(img, corners, half, eps=0.001, iters=50):
    import cv2

    c = np.asarray(corners, np.float32).reshape(-1, 1, 2).copy()
    crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_MAX_ITER, iters, eps)
    return cv2.cornerSubPix(img, c, (int(half), int(half)), (-1, -1), crit).reshape(-1, 2).astype(np.float64)


def subpix_window(corners, cols, rows, window):
    """procam's ``cornerSubPix`` half-window: ``window`` clamped to half the smallest corner spacing
    along the rows minus one (so the window cannot reach a neighbouring corner), at least 2."""
    g = np.asarray(corners, float).reshape(rows, cols, 2)
    spacing = np.min(np.linalg.norm(np.diff(g, axis=1), axis=2)) if cols > 1 else 1e9
    return int(max(2, min(window, spacing / 2 - 1)))


def refine_corners(image: np.ndarray, corners: np.ndarray, pattern_size, *, method: str = "fit",
                   window: int | None = None, start_error: float = 1.0) -> np.ndarray:
    """Sub-pixel corners from approximate ones.

    Parameters
    ----------
    image : (H, W) grey (any dtype) or colour image the corners were found in, at full size.
    corners : (cols*rows, 2) approximate corners, canonical (row-major grid) order.
    pattern_size : (cols, rows).
    method : ``"fit"`` — ``cornerSubPix`` with a small window, then :func:`fit_corners` (a corner it
        cannot fit gets the ``"subpix"`` refinement); ``"subpix"`` — ``cornerSubPix`` with
        :func:`subpix_window` (procam's earlier refinement); ``"none"``.
    window : half-size of the window in pixels (see :func:`subpix_window` and :func:`fit_corners`);
        None = :data:`REFINE_WINDOW`.
    start_error : rough error of ``corners`` in pixels (the detector's pixel size); widens the first
        ``cornerSubPix`` pass of ``"fit"`` when the board was found on a downscaled image.

    Returns
    -------
    (cols*rows, 2) float64 refined corners.
    """
    if method not in REFINERS:
        raise ValueError(f"refine method must be one of {REFINERS}, got {method!r}")
    c = np.asarray(corners, float).reshape(-1, 2)
    if window is None:
        window = REFINE_WINDOW[method]
    if method == "none" or window <= 0:
        return c.copy()
    cols, rows = int(pattern_size[0]), int(pattern_size[1])
    img = np.asarray(image)
    if img.ndim != 2 or img.dtype not in (np.uint8, np.float32):  # what cornerSubPix takes
        img = gray_float(img)
    if method == "subpix":
        return _subpix(img, c, subpix_window(c, cols, rows, window))
    coarse = int(np.clip(np.ceil(2 * start_error) + 2, 3, 8))
    c = _subpix(img, c, subpix_window(c, cols, rows, min(window, coarse)), eps=0.01)
    out, ok = fit_corners(img, c, (cols, rows), window=window)
    if not ok.all():  # the few corners the model does not fit get the "subpix" refinement
        out[~ok] = _subpix(img, c[~ok], subpix_window(c, cols, rows, min(window, REFINE_WINDOW["subpix"])))
    return out


def fit_corners(image: np.ndarray, corners: np.ndarray, pattern_size, *, window: float = 15.0,
                reach: float = 0.4, iterations: int = 12, passes: int = 2):
    """Least-squares fit of a blurred, unevenly lit X-junction to the pixels around each corner.

    Model of the intensity at pixel ``x`` near corner ``p`` (``d = x - p``)::

        I(x) = (1 + g . d) * (a + b * erf(n1 . d / (sqrt(2) s)) * erf(n2 . d / (sqrt(2) s)))

    ``n1``, ``n2`` the normals of the two board edges through the corner (angles free, so
    perspective and distortion are followed), ``s`` the blur (pixels), ``a``, ``b`` the mean level
    and contrast, ``g`` the relative illumination gradient (per pixel).  The gradient term matters:
    ignoring it, fall-off of the projector light and vignetting pull quadratic-saddle and
    gradient-based (``cornerSubPix``) estimates by ~0.05-0.1 px, alternating in sign with the
    colour of the squares.  Fitted by Levenberg-Marquardt, all corners at once, to the pixels within
    ``r = min(window, reach * corner_spacing)`` of the corner with Gaussian weights of width ``r``;
    each pass after the first centres the window on the previous pass's corner, so the result does
    not depend on where the fit started.

    Parameters
    ----------
    image : (H, W) grey image (float or integer; not contrast-stretched), full size.
    corners : (N, 2) starting corners within ~1 px, canonical grid order (N = cols * rows).
    pattern_size : (cols, rows).
    window : largest fit radius in pixels.
    reach : the fit radius of a corner is at most ``reach`` times its :func:`corner_spacing`.
    iterations : Levenberg-Marquardt iterations per pass at most.
    passes : fits, each centred on the previous one's corners.

    Returns
    -------
    corners : (N, 2) float64 fitted corners; where a fit fails (moved more than half its radius,
        blur out of range, non-finite) the starting corner is returned.
    ok : (N,) bool, the fit was used.
    """
    f = np.asarray(image)
    if f.ndim != 2:
        f = gray_float(f)
    cols, rows = int(pattern_size[0]), int(pattern_size[1])
    c = np.asarray(corners, float).reshape(-1, 2)
    n = len(c)
    radius = np.clip(reach * corner_spacing(c, cols, rows), 2.0, max(2.0, float(window)))
    ui, uj = _directions(c.reshape(rows, cols, 2))
    t1 = np.arctan2(ui[..., 1], ui[..., 0]).ravel() + np.pi / 2  # normal of the edge along i
    t2 = np.arctan2(uj[..., 1], uj[..., 0]).ravel() + np.pi / 2
    # parameters: px py t1 t2 s a b gx gy
    P = np.column_stack([c, t1, t2, np.ones(n), np.zeros((n, 4))])
    enough = np.zeros(n, bool)
    for k in range(max(1, int(passes))):
        centre = np.where(np.isfinite(P[:, :2]), P[:, :2], c)
        X, Y, z, w = _window_samples(f, centre, radius)
        enough = (w > 0).sum(1) >= 12  # enough pixels inside the image
        if k == 0:
            P[:, 5:7] = _level_and_contrast(P, X, Y, z, w)
        final = k == max(1, int(passes)) - 1  # earlier passes only need to centre the window
        P = _levenberg_marquardt(P, X, Y, z, w, enough, iterations, tol=1e-4 if final else 1e-2)
    p = P[:, :2]
    ok = (enough & np.all(np.isfinite(P), 1) & (np.linalg.norm(p - c, axis=1) <= np.maximum(0.5 * radius, 1.0))
          & (P[:, 4] > 0.05) & (P[:, 4] < radius) & (np.abs(np.sin(P[:, 2] - P[:, 3])) > 0.2))
    return np.where(ok[:, None], p, c), ok


def _window_samples(f, centre, radius):
    """Pixel grids X, Y (N, n) within ``radius`` of each centre, their values z and weights w."""
    R = int(np.ceil(radius.max()))
    u = np.arange(-R, R + 1, dtype=float)
    U, V = np.meshgrid(u, u)
    near = U * U + V * V <= (R + 0.5) ** 2
    c0 = np.round(centre)
    X = c0[:, :1] + U[near]
    Y = c0[:, 1:] + V[near]
    H, W = f.shape
    inside = (X >= 0) & (X <= W - 1) & (Y >= 0) & (Y <= H - 1)
    z = f[np.clip(Y, 0, H - 1).astype(np.intp), np.clip(X, 0, W - 1).astype(np.intp)].astype(float)
    d2 = (X - centre[:, :1]) ** 2 + (Y - centre[:, 1:]) ** 2
    r = radius[:, None]
    w = np.where(inside & (d2 <= (r + 0.5) ** 2), np.exp(-d2 / (2 * r * r)), 0.0)
    return X, Y, z, w


def _xjunction(P, X, Y, jac):
    """:func:`fit_corners`' model at the samples (N, n) and, with ``jac``, its Jacobian (N, n, 9)."""
    from scipy.special import erf

    px, py, a1, a2, s, a, b, gx, gy = (P[:, k:k + 1] for k in range(9))
    x, y = X - px, Y - py
    c1, s1, c2, s2 = np.cos(a1), np.sin(a1), np.cos(a2), np.sin(a2)
    d1, d2 = c1 * x + s1 * y, c2 * x + s2 * y
    E1, E2 = erf(d1 / (np.sqrt(2.0) * s)), erf(d2 / (np.sqrt(2.0) * s))
    Q = E1 * E2
    sh = 1.0 + gx * x + gy * y
    base = a + b * Q
    if not jac:
        return sh * base, Q, None
    k = np.sqrt(2.0 / np.pi) / s
    f1 = k * np.exp(-d1 * d1 / (2 * s * s)) * E2  # dQ/dd1
    f2 = k * np.exp(-d2 * d2 / (2 * s * s)) * E1  # dQ/dd2
    sb = sh * b
    J = np.stack([-sb * (f1 * c1 + f2 * c2) - base * gx, -sb * (f1 * s1 + f2 * s2) - base * gy,
                  sb * f1 * (c1 * y - s1 * x), sb * f2 * (c2 * y - s2 * x), -sb * (f1 * d1 + f2 * d2) / s,
                  sh, sh * Q, x * base, y * base], axis=-1)
    return sh * base, Q, J


def _level_and_contrast(P, X, Y, z, w):
    """(N, 2) weighted least-squares ``a``, ``b`` for the geometry in ``P`` (no illumination gradient)."""
    _, Q, _ = _xjunction(P, X, Y, False)
    sw, swq, swqq = w.sum(1), (w * Q).sum(1), (w * Q * Q).sum(1)
    swz, swqz = (w * z).sum(1), (w * Q * z).sum(1)
    det = sw * swqq - swq * swq
    with np.errstate(divide="ignore", invalid="ignore"):
        ab = np.column_stack([(swqq * swz - swq * swqz) / det, (sw * swqz - swq * swz) / det])
    return np.where(np.isfinite(ab), ab, 0.0)


def _levenberg_marquardt(P, X, Y, z, w, active, iterations, tol=1e-4):
    """Weighted Levenberg-Marquardt of :func:`_xjunction`, one model + Jacobian evaluation per iteration;
    a corner stops when its position moves less than ``tol`` pixels."""
    P = P.copy()
    active = active.copy()
    sq = np.sqrt(w)
    M, _, J = _xjunction(P, X, Y, True)
    res = (z - M) * sq
    J *= sq[..., None]
    cost = np.sum(res * res, 1)
    lam = np.full(len(P), 1e-3)
    eye = np.eye(P.shape[1])
    for _ in range(iterations):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        full = idx.size == len(P)  # every corner still moving: views instead of copies
        Ji = J if full else J[idx]
        Jt = Ji.transpose(0, 2, 1)
        A = np.matmul(Jt, Ji)
        rhs = np.matmul(Jt, res[idx, :, None])[..., 0]
        diag = np.einsum("nii->ni", A)
        A = A + (lam[idx, None] * diag + 1e-12 * diag.max(1, keepdims=True) + 1e-300)[:, :, None] * eye
        with np.errstate(all="ignore"):
            step = np.linalg.solve(A, rhs[..., None])[..., 0]
            Pn = P[idx] + step
            Pn[:, 4] = np.abs(Pn[:, 4])
            Mn, _, Jn = _xjunction(Pn, X if full else X[idx], Y if full else Y[idx], True)
            rn = (z if full else z[idx]) - Mn
            rn *= sq if full else sq[idx]
            cn = np.sum(rn * rn, 1)
        better = np.isfinite(cn) & (cn <= cost[idx])
        k = idx[better]
        if full and better.all():
            Jn *= sq[..., None]
            P, cost, res, J = Pn, cn, rn, Jn
        else:
            P[k], cost[k], res[k], J[k] = Pn[better], cn[better], rn[better], Jn[better] * sq[k, :, None]
        lam[idx] = np.where(better, lam[idx] * 0.2, lam[idx] * 10.0)
        done = (better & (np.abs(step[:, :2]).max(1) < tol)) | (lam[idx] > 1e6)
        active[idx[done]] = False
    return P


# --------------------------------------------------------------------------------------------
# wrong --board
# --------------------------------------------------------------------------------------------

def size_hint(image: np.ndarray, pattern_size, *, max_width: int = 640, _pyr=None) -> tuple[int, int] | None:
    """The board size actually in view when ``pattern_size`` was not found, or None.

    Quick (a fraction of a second): on a copy downscaled to ``max_width``, tries
    ``(cols - 1, rows - 1)`` (the squares were counted instead of the inner corners), then asks
    ``findChessboardCornersSB`` for any board at least 3x3 and confirms the size it reports with
    ``findChessboardCorners``.
    """
    import cv2

    cols, rows = int(pattern_size[0]), int(pattern_size[1])
    pyr = _pyr if _pyr is not None else _Pyramid(image, max_width)
    g8 = pyr.small if pyr.small is not None else pyr.g8
    tried = set()

    def found(size):
        key = tuple(sorted(size))
        if key in tried or min(size) < 2:
            return False
        tried.add(key)
        return _find(g8, size, "classic") is not None

    tried.add(tuple(sorted((cols, rows))))
    if found((cols - 1, rows - 1)):
        return cols - 1, rows - 1
    flags = cv2.CALIB_CB_LARGER | cv2.CALIB_CB_NORMALIZE_IMAGE
    ok, _, meta = cv2.findChessboardCornersSBWithMeta(g8, (3, 3), flags=flags)
    if ok and meta is not None and meta.ndim == 2:
        r, k = meta.shape  # OpenCV reports the found grid as (rows, cols) of its own orientation
        size = (k, r) if (k >= r) == (cols >= rows) else (r, k)
        if found(size):
            return size
    return None


def size_hint_text(pattern_size, found) -> str:
    """``"if 11x8 counts squares, use --board 10x7"`` style advice for :func:`size_hint`'s result."""
    cols, rows = int(pattern_size[0]), int(pattern_size[1])
    if found is None:
        return ""
    fc, fr = int(found[0]), int(found[1])
    if (fc, fr) == (cols - 1, rows - 1):
        return f"if {cols}x{rows} counts squares, use --board {fc}x{fr} (inner corners)"
    return f"a board with {fc}x{fr} inner corners is in view: use --board {fc}x{fr}"
