"""From captures to :class:`~procam.view.View` s: decode, detect corners, correspond -- for one pose folder,
several, a stack already in memory, or a single photo (camera-only).

The glue the CLI, the benchmarks and the experiment share; each stage lives in its own module
(``capture``, ``decode``, ``board``, ``correspond``).
"""

from __future__ import annotations

import contextlib
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from .io import images as _images
from . import capture as _capture
from .board import corners as _corners
from . import correspond as _corr
from . import decode as _decode
from .decode import plausibility as _plausible
from .board import Board
from .errors import BoardNotFoundError, CorrespondenceError, ProcamError
from .patterns import PatternSet
from .correspond.samples import WINDOW, dense_samples
from .view import View


@dataclass(frozen=True)
class PoseOptions:
    """How a pose's captures become a View (see the stage modules for the meaning and units).

    Attributes
    ----------
    decode : :class:`procam.decode.DecodeOptions` (classifier and thresholds).
    detector : chessboard detector, one of :data:`procam.board.corners.DETECTORS`.
    refine_window : half-window of the corner refinement in camera pixels (0 = none; None = the method's
        default, :data:`procam.board.corners.REFINE_WINDOW`).
    refine : corner refinement, one of :data:`procam.board.corners.REFINERS`.
    corners : :class:`procam.correspond.CornerOptions` (local homographies).
    min_corners : a pose with fewer corners that have projector coordinates is an error.
    background : keep the dense decoded samples (:func:`procam.correspond.samples.dense_samples`) on the board in
        ``view.board_samples`` and off it in ``view.background``: the single-pose projector's dense constraints
        and its background (:mod:`procam.single_pose`).
    window : the samples' window side, camera pixels (odd).
    """

    decode: _decode.DecodeOptions = field(default_factory=_decode.DecodeOptions)
    detector: str = "auto"
    refine_window: int | None = None  # None: procam.board.corners.REFINE_WINDOW of the method
    refine: str = "fit"
    corners: _corr.CornerOptions = field(default_factory=_corr.CornerOptions)
    min_corners: int = 10
    background: bool = True
    window: int = WINDOW

    def __post_init__(self):
        if self.detector not in _corners.DETECTORS:
            raise ValueError(f"detector must be one of {', '.join(_corners.DETECTORS)}, got {self.detector!r}")
        if self.refine_window is not None and not 0 <= int(self.refine_window) <= 100:
            raise ValueError(f"refine window must be from 0 to 100 px, got {self.refine_window!r}")
        if self.refine not in _corners.REFINERS:
            raise ValueError(f"refine must be one of {', '.join(_corners.REFINERS)}, got {self.refine!r}")
        if not (isinstance(self.window, (int, np.integer)) and 3 <= self.window <= 101 and self.window % 2 == 1):
            raise ValueError(f"the samples' window must be an odd number of camera pixels from 3 to 101, "
                             f"got {self.window!r}")


def as_board(board) -> Board:
    """``board`` as a :class:`~procam.board.Board`: a Board, or a ``(cols, rows, square)`` tuple.

    Raises :class:`~procam.errors.ProcamError` (one line) for anything else, e.g. ``(cols, rows)`` without
    the square size (the length unit of every output), or counts the Board refuses.
    """
    if isinstance(board, Board):
        return board
    if isinstance(board, (tuple, list)) and len(board) == 3:
        return Board(*board)
    raise ProcamError(f"board must be a procam.Board(cols, rows, square) of inner corners and the square size "
                      f"(or a (cols, rows, square) tuple), got {board!r}")


def find_board(stack: np.ndarray, ps: PatternSet, pattern_size, detector="auto", refine_window=None, name="pose",
               refine="fit"):
    """Camera corners (N, 2) from the white frame; falls back to white - black, then the black frame.

    Raises :class:`BoardNotFoundError` with what to check (at once, naming the right ``--board``,
    when a board of another size is in view).
    """
    white = _capture.board_image(stack, ps)  # the white frame, or the mean of a phase family's fringes
    black = stack[ps.black] if ps.black is not None and ps.white is not None else None
    if ps.white is None:  # no white frame: the fringes' mean, then their maximum (each pixel at its brightest:
        # the board as the projector's full light shows it, with twice the mean's contrast where the fringes are lit)
        frames = list(ps.phase_frames())
        candidates = (white, lambda: stack[frames].max(axis=0))
    elif black is None:
        candidates = (white,)
    else:  # the white - black image is only built when the white fails
        candidates = (white, lambda: np.clip(white.astype(np.float32) - black.astype(np.float32), 0, None), black)
    frame = f"the white frame (#{ps.white})" if ps.white is not None else "the mean or the maximum of the phase frames"
    c, hint = _corners.find_corners(candidates, pattern_size, detector=detector, refine_window=refine_window,
                                    refine=refine)
    if c is not None:
        return c
    cols, rows = pattern_size
    if hint is not None:
        raise BoardNotFoundError(f"{name}: chessboard with {cols}x{rows} inner corners not found in {frame}; "
                                 f"{_corners.size_hint_text(pattern_size, hint)}")
    raise BoardNotFoundError(
        f"{name}: chessboard with {cols}x{rows} inner corners not found in {frame} (OpenCV's classic and SB "
        f"detectors, full size and downscaled); check --board (inner corners, not squares: {cols + 1}x{rows + 1} "
        f"squares have {cols}x{rows} inner corners), the exposure of the white frame, and that the whole board is in "
        "view")


def view_from_stack(stack: np.ndarray, pattern_set: PatternSet, board: Board, *, name: str = "pose",
                    options: PoseOptions = PoseOptions(), cam_pts: np.ndarray | None = None, warnings=(),
                    files=None, keep_maps: bool = True):
    """Decode a stack and build the pose's View.

    Parameters
    ----------
    stack : (K, H, W) uint8/uint16 in ``pattern_set``'s order.
    board : the :class:`~procam.board.Board` (inner corners and square size, the length unit of all outputs).
    cam_pts : optional (N, 2) camera corners to use instead of detecting them.
    warnings : notes about the capture, kept in ``view.diagnostics["warnings"]``.
    files : the stack's file names, to name frames in messages (optional).
    keep_maps : return the decoded maps; False returns None instead and skips what only the maps' users need
        (the confidence, direct and global light: :func:`procam.decode.decode`'s ``extras``).

    Returns
    -------
    (View, DecodeResult or None).  Raises :class:`BoardNotFoundError`, :class:`CorrespondenceError`, or
    :class:`~procam.errors.CaptureError` when the decoded capture is not a plausible picture of the projector
    (:mod:`procam.decode.plausibility`: wrong projector size, a pattern swapped with its inverse, a mirror).
    """
    board = as_board(board)
    d = options.decode
    # the corners are found in a second thread while the stack is decoded (both mostly release the GIL): on two
    # cores a pose takes the longer of the two instead of their sum
    with ThreadPoolExecutor(1) as ex:
        corners = None if cam_pts is not None else ex.submit(
            find_board, stack, pattern_set, board.pattern_size, options.detector, options.refine_window, name,
            options.refine)
        maps = _decode.decode_with(stack, pattern_set, d, extras=keep_maps)  # the family's decoder
        if corners is not None:
            cam_pts = corners.result()
    proj, diag = (_corr.dense_projector_corners if maps.subpixel else _corr.projector_corners)(
        cam_pts, maps, options.corners)
    warnings = list(warnings) + _plausible.check_decoded(maps, name, files)
    _plausible.check_orientation(cam_pts, proj, board.cols, board.rows, name, maps, files)
    H, W = stack.shape[1:]
    on_board, background = (dense_samples(maps, cam_pts, window=options.window) if options.background
                             else (None, None))
    view = View(board.object_points(), cam_pts, proj, name, (W, H), (pattern_set.width, pattern_set.height),
                {**diag, "warnings": warnings}, board, background, on_board)
    n_ok = int(view.valid.sum())
    if board.n_corners < options.min_corners:
        raise CorrespondenceError(
            f"{name}: the board has only {board.n_corners} inner corners ({board.cols}x{board.rows}), fewer than the "
            f"{options.min_corners} a pose needs here (single-pose calibration); use a larger board, or calibrate "
            "from several poses (procam calibrate POSE1 POSE2 ... needs 4 corners per pose)")
    if n_ok < options.min_corners:
        raise CorrespondenceError(
            f"{name}: only {n_ok} of {board.n_corners} corners have projector coordinates (need "
            f"{options.min_corners}); failed: {_corr.reason_summary(diag['reason'])} — check that the projector "
            "lights the whole board and that the decode picture (procam decode --png) shows it decoded")
    return view, (maps if keep_maps else None)


def view_from_folder(folder, board: Board, projector=None, order=None, *, options: PoseOptions = PoseOptions(),
                     step=None, reader=None, keep_maps: bool = True):
    """Load, validate and process one pose folder; returns (View, DecodeResult or None: ``keep_maps`` as in
    :func:`view_from_stack`).

    ``projector`` (width, height), ``order`` and ``step`` default to the folder's ``patterns.json``
    (:func:`procam.capture.load_capture`, which also takes the ``reader``). The capture's exposure warnings are
    in ``view.diagnostics["warnings"]``.
    """
    board = as_board(board)
    cap = _capture.load_capture(folder, projector, order, step=step, reader=reader)
    return view_from_stack(cap.stack, cap.pattern_set, board, name=str(Path(folder)), options=options,
                           warnings=cap.warnings, files=cap.files, keep_maps=keep_maps)


def views_from_folders(folders: Sequence, board: Board, projector=None, order=None, *,
                       options: PoseOptions = PoseOptions(), step=None,
                       progress: Callable[[int, int, str], None] | None = None, prefetcher=None,
                       dropped: list | None = None) -> list[View]:
    """One View per pose folder (:func:`view_from_folder`), in order; ``progress(done, total, folder)``
    after each.

    The next pose's images are read in background threads while this one is processed: by ``prefetcher``
    (a :class:`procam.stream.Prefetcher` of ``folders`` the caller started, and closes), else by one made here.
    Only the Views are kept.

    ``dropped``: a list to leave out the poses whose board is not found (:class:`BoardNotFoundError`) instead of
    raising: each is appended as ``(folder, message)`` (a multi-pose set goes on with the poses that show the
    board; the caller says so). Any other error of a pose still raises.
    """
    from .stream import Prefetcher

    board = as_board(board)
    views = []
    with (Prefetcher(folders) if prefetcher is None else contextlib.nullcontext(prefetcher)) as pf:
        for k, folder in enumerate(folders):
            try:
                view, _ = view_from_folder(folder, board, projector, order, options=options, step=step,
                                           reader=pf.read, keep_maps=False)
            except BoardNotFoundError as e:
                if dropped is None:
                    raise
                dropped.append((str(folder), str(e)))
                continue
            views.append(view)
            if progress is not None:
                progress(k + 1, len(folders), str(folder))
    return views


def camera_only_view(image_path, board: Board, *, options: PoseOptions = PoseOptions(), projector=None,
                     order=None, step=None) -> View:
    """The View of one photo of the board, or of a pose folder's board image (no projector: ``proj_pts`` NaN,
    ``proj_size`` None): the camera calibrated once from photos and the captures of earlier poses, mixed.

    ``image_path`` is an image file, or a capture folder (Gray or phase; ``projector``, ``order``, ``step`` as
    for :func:`procam.capture.load_capture` when it has no ``patterns.json``) whose board image is its white frame,
    or without one the mean of its phase frames (:attr:`procam.capture.Capture.white`).

    Raises :class:`BoardNotFoundError` naming the file or folder when the board is not found.
    """
    board = as_board(board)
    if Path(image_path).is_dir():
        img = _capture.load_capture(image_path, projector, order, step=step).white
    else:
        img = _images.read_image(image_path)
    c, hint = _corners.find_corners([img], board.pattern_size, detector=options.detector,
                                    refine_window=options.refine_window, refine=options.refine)
    if hint is not None:
        raise BoardNotFoundError(f"{image_path}: chessboard with {board.cols}x{board.rows} inner corners not found; "
                                 f"{_corners.size_hint_text(board.pattern_size, hint)}")
    if c is None:
        cols, rows = board.pattern_size
        raise BoardNotFoundError(f"{image_path}: chessboard with {cols}x{rows} inner corners not found; check --board "
                                 f"(inner corners, not squares: {cols + 1}x{rows + 1} squares have {cols}x{rows} "
                                 "inner corners), the exposure, and that the whole board is in view")
    h, w = img.shape[:2]
    return View(board.object_points(), c, np.full_like(c, np.nan), str(image_path), (w, h), None, board=board)
