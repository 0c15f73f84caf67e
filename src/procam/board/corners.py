"""Chessboard corner detection and refinement: the one place that calls OpenCV's chessboard detectors.

Detection (:func:`detect_corners`) finds the board on a copy of the image downscaled to at most
:data:`DETECT_MAX_WIDTH` pixels wide (OpenCV's detector takes a few ms there, against 0.1-0.4 s at full
size; Moreno & Taubin downscale too), falls back to the full-size image (classic, then SB), then refines the
corners at full size.  The default refinement (``refine="fit"``, :func:`fit_corners`) fits a model of a
blurred, unevenly lit chessboard corner to the pixels around each corner: 0.014 px RMS on renders where
``cornerSubPix`` (``"subpix"``, kept as an option) has 0.064, and 0.157 px instead of 0.245 px
calibrateCamera RMS on OpenCV's sample photographs.  :func:`find_corners` tries several frames of a pose
and, when a board of another size is in view, gives up at once with that size (:func:`size_hint`).
``benchmarks/correspond.py`` measures all of it.

How a board is searched and refined is a :class:`DetectOptions`; :data:`LIVE` is the setting for live
camera frames (the advisor's, ``benchmarks/advisor.py``): the classic detector on the downscaled copy only,
with OpenCV's fast check (a frame without the board costs a few ms), the 8-bit frame as it is (no contrast
stretch), ``cornerSubPix`` with a short termination at full size.  It fails more often than the default on
a dim, blurred or small board, where the default's full-size attempts would find it.

Corner order: :func:`canonical_order` (corner 0 top-left in the image, ``cols`` corners per row, the
order right-handed in the image), the order of :func:`procam.board.object_points`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ._xjunction import level_and_contrast, levenberg_marquardt, window_samples
from .. import choices

DETECTORS = choices.DETECTORS
REFINERS = choices.REFINERS

#: Images wider than this are searched for the board on a downscaled copy first (pixels).
DETECT_MAX_WIDTH = 640

#: Default refinement half-window (pixels) per method, the measured best within ~0.1 s per pose
#: (``benchmarks/correspond.py``): the fit gains up to 20 px, ``cornerSubPix`` is best at 11 (OpenCV's
#: usual ``winSize=(11, 11)``) and worse above.
REFINE_WINDOW = {"fit": 15, "subpix": 11, "none": 0}

#: How ``cornerSubPix``'s window is clamped by the corner spacing (:func:`subpix_window`).
CLAMPS = ("rows", "grid")


@dataclass(frozen=True)
class DetectOptions:
    """How :func:`detect_corners` finds and refines a board (checked at construction: ``ValueError``).

    Attributes
    ----------
    detector : ``"classic"`` (``findChessboardCorners``, adaptive threshold + normalisation; on the
        downscaled copy, then at full size), ``"sb"`` (``findChessboardCornersSB``, exhaustive + accuracy:
        slower, more tolerant of blur and uneven light; likewise) or ``"auto"`` (every attempt of both: classic on
        the downscaled copy and at full size, then SB likewise, so it finds whatever either finds).  See
        :func:`find_grid`.
    refine : ``"fit"`` (:func:`fit_corners`), ``"subpix"`` (``cornerSubPix`` only) or ``"none"``.
    refine_window : half-size in pixels of the refinement window (0 = no refinement; None = the method's
        :data:`REFINE_WINDOW`); clamped per corner so the window stays clear of the neighbouring corners.
    max_width : search a copy downscaled to this width first when the image is wider (None/0: never); the
        corners are refined at full size either way.
    fallback : when the first attempt fails, go on with the detector's others (full size; SB for
        ``"auto"``); False: the first attempt only.
    fast_check : ``findChessboardCorners``' ``CALIB_CB_FAST_CHECK``: an image without a board is rejected
        quickly (it may miss a board the full search finds).
    stretch_8bit : contrast-stretch an 8-bit image too before the search (between its 0.5 and 99.5
        percentiles, then downscaled); False: an 8-bit image is searched as it is, any other is downscaled,
        then stretched.
    subpix_iterations, subpix_eps : ``cornerSubPix``'s termination (iterations, px) in the ``"subpix"``
        refinement.
    subpix_clamp : ``"rows"`` (the window clamped by the corner spacing along the rows, procam's
        calibration) or ``"grid"`` (along both board directions); see :func:`subpix_window`.
    """

    detector: str = "auto"
    refine: str = "fit"
    refine_window: int | None = None
    max_width: int | None = DETECT_MAX_WIDTH
    fallback: bool = True
    fast_check: bool = False
    stretch_8bit: bool = True
    subpix_iterations: int = 50
    subpix_eps: float = 0.001
    subpix_clamp: str = "rows"

    def __post_init__(self):
        if self.detector not in DETECTORS:
            raise ValueError(f"detector must be one of {DETECTORS}, got {self.detector!r}")
        if self.refine not in REFINERS:
            raise ValueError(f"refine must be one of {REFINERS}, got {self.refine!r}")
        if self.subpix_clamp not in CLAMPS:
            raise ValueError(f"subpix_clamp must be one of {CLAMPS}, got {self.subpix_clamp!r}")
        if not (int(self.subpix_iterations) >= 1 and float(self.subpix_eps) > 0):
            raise ValueError(f"cornerSubPix needs iterations >= 1 and eps > 0, got {self.subpix_iterations!r} "
                             f"and {self.subpix_eps!r}")


#: Detection for calibration (every attempt, the fitted corners).
DEFAULT = DetectOptions()

#: Detection for live camera frames (the advisor's): see the module docstring.
LIVE = DetectOptions(detector="classic", refine="subpix", refine_window=11, max_width=640, fallback=False,
                     fast_check=True, stretch_8bit=False, subpix_iterations=30, subpix_eps=0.01,
                     subpix_clamp="grid")


def _options(options: DetectOptions | None, fields: dict) -> DetectOptions:
    """``options`` (default :data:`DEFAULT`) with ``fields`` (names of :class:`DetectOptions`) replaced."""
    o = DEFAULT if options is None else options
    return replace(o, **fields) if fields else o


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
    """The grey image at full size (native dtype, and as the 8-bit image the detector searches) and,
    when it is wider than ``max_width``, an 8-bit copy downscaled to that width.

    ``stretch_8bit`` (:class:`DetectOptions`): the 8-bit images are contrast-stretched (:func:`to_gray8`),
    then downscaled; without it an 8-bit image is taken as it is and any other is downscaled, then
    stretched (a live frame: no full-size stretch)."""

    def __init__(self, image, max_width, stretch_8bit: bool = True):
        import cv2

        self.gray = _gray(image)
        self.stretch_8bit = stretch_8bit
        h, w = self.gray.shape
        self._g8 = None
        self.scale = 1.0
        self.small = None
        if max_width and w > max_width:
            self.scale = max_width / w
            size = (int(max_width), max(1, round(h * self.scale)))
            if stretch_8bit:
                # stretch, then downscale: findChessboardCorners finds the board in 1-3 ms in that image
                # against 20-40 ms when the downscaled image is stretched (16 renders, 640-1024 px wide)
                self.small = cv2.resize(self.g8, size, interpolation=cv2.INTER_AREA)
            else:
                self.small = self._to8(cv2.resize(self.gray, size, interpolation=cv2.INTER_AREA))

    def _to8(self, img):
        if self.stretch_8bit:
            return _stretch8(img)
        return img if img.dtype == np.uint8 else to_gray8(img)

    @property
    def g8(self):
        if self._g8 is None:
            self._g8 = self._to8(self.gray)
        return self._g8

    def level(self, small: bool):
        return (self.small, self.scale) if small else (self.g8, 1.0)


def _find(g8, size, kind, fast_check: bool = False):
    """One OpenCV detector call; (cols*rows, 2) float64 corners in OpenCV's order or None."""
    import cv2

    cols, rows = size
    if kind == "sb":
        flags = cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY
        ok, c = cv2.findChessboardCornersSB(g8, (cols, rows), flags=flags)
    else:
        flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
        if fast_check:
            flags |= cv2.CALIB_CB_FAST_CHECK
        ok, c = cv2.findChessboardCorners(g8, (cols, rows), flags=flags)
    if not ok or c is None or len(c) != cols * rows:
        return None
    return c.reshape(-1, 2).astype(np.float64)


def _attempts(o: DetectOptions, downscaled: bool):
    """(kind, on the downscaled copy?) in the order tried."""
    if o.detector in ("classic", "sb"):
        out = [(o.detector, True), (o.detector, False)] if downscaled else [(o.detector, False)]
    else:  # auto: every attempt of both detectors, the quick ones first: classic on the small copy and at full
        # size, then SB likewise (SB on the small copy finds boards SB at full size misses: what --detector sb does)
        out = ([("classic", True)] if downscaled else []) + [("classic", False)] + (
            [("sb", True)] if downscaled else []) + [("sb", False)]
    return out if o.fallback else out[:1]


def _search(pyr, size, attempts, fast_check: bool = False):
    """The first detection among ``attempts`` (see :func:`_attempts`), full-size pixels, canonical order."""
    cols, rows = size
    for kind, small in attempts:
        g8, s = pyr.level(small)
        c = _find(g8, (cols, rows), kind, fast_check)
        if c is not None:
            c = (c + 0.5) / s - 0.5 if s != 1.0 else c  # pixel centres at integers at both scales
            return canonical_order(c, cols, rows)
    return None


def _size(pattern_size) -> tuple[int, int]:
    return int(pattern_size[0]), int(pattern_size[1])


def find_grid(image: np.ndarray, pattern_size, options: DetectOptions | None = None,
              **fields) -> np.ndarray | None:
    """Detect a chessboard (no sub-pixel refinement beyond the detector's own).

    Parameters
    ----------
    image : (H, W) or (H, W, 3) uint8/uint16.
    pattern_size : (cols, rows) inner corners.
    options : :class:`DetectOptions` (default :data:`DEFAULT`); its ``detector``, ``max_width``,
        ``fallback``, ``fast_check`` and ``stretch_8bit`` apply.
    **fields : fields of :class:`DetectOptions` to replace (``detector="classic"``, ``max_width=0`` ...).

    Returns
    -------
    (cols*rows, 2) float64 corners in full-size pixels, canonical order, or None.
    """
    o = _options(options, fields)
    pyr = _Pyramid(image, o.max_width, o.stretch_8bit)
    return _search(pyr, _size(pattern_size), _attempts(o, pyr.small is not None), o.fast_check)


def detect_corners(image: np.ndarray, pattern_size: tuple[int, int], options: DetectOptions | None = None,
                   **fields) -> np.ndarray | None:
    """Find the inner corners of a chessboard in one image.

    Parameters
    ----------
    image : (H, W) or (H, W, 3) uint8/uint16
    pattern_size : (cols, rows) of inner corners (OpenCV's ``pattern_size``).
    options : :class:`DetectOptions` (default :data:`DEFAULT`: every attempt, the fitted corners;
        :data:`LIVE` for live frames).
    **fields : fields of :class:`DetectOptions` to replace: ``detector``, ``refine``, ``refine_window``,
        ``max_width`` ... (e.g. ``refine="subpix"``).

    Returns
    -------
    (cols*rows, 2) float64 corners in canonical order (see :func:`canonical_order`), or None.
    """
    o = _options(options, fields)
    size = _size(pattern_size)
    pyr = _Pyramid(image, o.max_width, o.stretch_8bit)
    c = _search(pyr, size, _attempts(o, pyr.small is not None), o.fast_check)
    return None if c is None else _refine(pyr, c, size, o)


def _refine(pyr, c, size, o: DetectOptions):
    return refine_corners(pyr.gray, c, size, method=o.refine, window=o.refine_window, start_error=1.0 / pyr.scale,
                          subpix_iterations=o.subpix_iterations, subpix_eps=o.subpix_eps, clamp=o.subpix_clamp)


def find_corners(images, pattern_size, options: DetectOptions | None = None, **fields):
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
    pattern_size, options, **fields : as :func:`detect_corners`.

    Returns
    -------
    (corners, hint) : ``corners`` (cols*rows, 2) float64 in canonical order, or None; ``hint`` the
    (cols, rows) of a board found instead (see :func:`size_hint_text`), else None.
    """
    o = _options(options, fields)
    size = _size(pattern_size)
    images = [im if callable(im) else (lambda im=im: im) for im in images]
    if not images:
        return None, None
    pyr = _Pyramid(images[0](), o.max_width, o.stretch_8bit)
    attempts = _attempts(o, pyr.small is not None)
    c = _search(pyr, size, attempts[:1], o.fast_check)
    if c is None:
        hint = size_hint(None, size, _pyr=pyr)
        if hint is not None:
            return None, hint
        c = _search(pyr, size, attempts[1:], o.fast_check)
    if c is not None:
        return _refine(pyr, c, size, o), None
    for image in images[1:]:
        c = detect_corners(image(), size, o)
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


def subpix_window(corners, cols, rows, window, clamp: str = "rows"):
    """procam's ``cornerSubPix`` half-window: ``window`` clamped to half the smallest corner spacing minus one
    (so the window cannot reach a neighbouring corner), at least 2.  ``clamp``: the spacing along the rows
    (``"rows"``, calibration's) or along both board directions (``"grid"``, :data:`LIVE`'s)."""
    g = np.asarray(corners, float).reshape(rows, cols, 2)
    spacing = np.min(np.linalg.norm(np.diff(g, axis=1), axis=2)) if cols > 1 else 1e9
    if clamp == "grid":
        spacing = min(spacing, np.min(np.linalg.norm(np.diff(g, axis=0), axis=2)) if rows > 1 else 1e9)
    return int(max(2, min(window, spacing / 2 - 1)))


def refine_corners(image: np.ndarray, corners: np.ndarray, pattern_size, *, method: str = "fit",
                   window: int | None = None, start_error: float = 1.0, subpix_iterations: int = 50,
                   subpix_eps: float = 0.001, clamp: str = "rows") -> np.ndarray:
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
    subpix_iterations, subpix_eps, clamp : ``"subpix"``'s ``cornerSubPix`` termination and window clamp
        (:class:`DetectOptions`).

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
        return _subpix(img, c, subpix_window(c, cols, rows, window, clamp), eps=subpix_eps, iters=subpix_iterations)
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
        X, Y, z, w = window_samples(f, centre, radius)
        enough = (w > 0).sum(1) >= 12  # enough pixels inside the image
        if k == 0:
            P[:, 5:7] = level_and_contrast(P, X, Y, z, w)
        final = k == max(1, int(passes)) - 1  # earlier passes only need to centre the window
        P = levenberg_marquardt(P, X, Y, z, w, enough, iterations, tol=1e-4 if final else 1e-2)
    p = P[:, :2]
    ok = (enough & np.all(np.isfinite(P), 1) & (np.linalg.norm(p - c, axis=1) <= np.maximum(0.5 * radius, 1.0))
          & (P[:, 4] > 0.05) & (P[:, 4] < radius) & (np.abs(np.sin(P[:, 2] - P[:, 3])) > 0.2))
    return np.where(ok[:, None], p, c), ok


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
        if key in tried or min(size) < 3:
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
