"""From a pose's images to a :class:`~procam.view.View`: decode, detect corners, correspond.

The thin glue the CLI, the benchmarks and the experiment share; each stage lives in its own
module (``capture``, ``decode``, ``board``, ``correspond``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import board as _board
from . import capture as _capture
from . import correspond as _corr
from . import decode as _decode
from .errors import BoardNotFoundError, CorrespondenceError
from .patterns import PatternSet
from .view import View


@dataclass(frozen=True)
class PoseOptions:
    """Options of :func:`view_from_stack` (see the stage modules for their meaning and units)."""

    decode_method: str = "robust"
    shadow_threshold: float = 10.0
    contrast_threshold: float = 3.0
    detector: str = "auto"
    refine_window: int | None = None  # None: procam.board.REFINE_WINDOW of the method
    refine: str = "fit"
    corners: _corr.CornerOptions = field(default_factory=_corr.CornerOptions)
    min_corners: int = 10


def find_board(stack: np.ndarray, ps: PatternSet, pattern_size, detector="auto", refine_window=None, name="pose",
               refine="fit"):
    """Camera corners (N, 2) from the white frame; falls back to white - black, then the black frame.

    Raises :class:`BoardNotFoundError` with what to check (at once, naming the right ``--board``,
    when a board of another size is in view).
    """
    white = stack[ps.white]
    black = stack[ps.black]
    candidates = (white,  # the white - black image is only built when the white frame fails
                  lambda: np.clip(white.astype(np.float32) - black.astype(np.float32), 0, None),
                  black)
    c, hint = _board.find_corners(candidates, pattern_size, detector=detector, refine_window=refine_window,
                                  refine=refine)
    if c is not None:
        return c
    cols, rows = pattern_size
    if hint is not None:
        raise BoardNotFoundError(f"{name}: chessboard with {cols}x{rows} inner corners not found in the white frame "
                                 f"(#{ps.white}); {_board.size_hint_text(pattern_size, hint)}")
    raise BoardNotFoundError(
        f"{name}: chessboard with {cols}x{rows} inner corners not found in the white frame "
        f"(#{ps.white}); check --board (inner corners, not squares: {cols + 1}x{rows + 1} squares have "
        f"{cols}x{rows} inner corners), the exposure of the white frame, and that the whole board is in view")


def view_from_stack(stack: np.ndarray, pattern_set: PatternSet, board, square: float, *, name: str = "pose",
                    options: PoseOptions = PoseOptions(), cam_pts: np.ndarray | None = None, warnings=()):
    """Decode a stack and build the pose's View.

    Parameters
    ----------
    stack : (K, H, W) uint8/uint16 in ``pattern_set``'s order.
    board : (cols, rows) inner corners; ``square`` the square size (the length unit of all outputs).
    cam_pts : optional (N, 2) camera corners to use instead of detecting them.
    warnings : notes about the capture, kept in ``view.diagnostics["warnings"]``.

    Returns
    -------
    (View, DecodeResult).  Raises :class:`BoardNotFoundError` or :class:`CorrespondenceError`.
    """
    cols, rows = int(board[0]), int(board[1])
    maps = _decode.decode(stack, pattern_set, options.decode_method, shadow_threshold=options.shadow_threshold,
                          contrast_threshold=options.contrast_threshold)
    if cam_pts is None:
        cam_pts = find_board(stack, pattern_set, (cols, rows), options.detector, options.refine_window, name,
                             options.refine)
    proj, diag = _corr.projector_corners(cam_pts, maps, options.corners)
    obj = _board.object_points(cols, rows, square)
    H, W = stack.shape[1:]
    view = View(obj, cam_pts, proj, name, (W, H), (pattern_set.width, pattern_set.height),
                {**diag, "warnings": list(warnings)})
    n_ok = int(view.valid.sum())
    if n_ok < options.min_corners:
        raise CorrespondenceError(
            f"{name}: only {n_ok} of {cols * rows} corners have projector coordinates (need "
            f"{options.min_corners}); failed: {_corr.reason_summary(diag['reason'])} — check that the projector "
            "lights the whole board and that the decode picture (procam decode --png) shows it decoded")
    return view, maps


def view_from_folder(folder, board, square: float, projector=None, order=None, *,
                     options: PoseOptions = PoseOptions(), step=None):
    """Load, validate and process one pose folder; returns (View, DecodeResult).

    The capture's exposure warnings are in ``view.diagnostics["warnings"]``.
    """
    cap = _capture.load_capture(folder, projector, order, step=step)
    return view_from_stack(cap.stack, cap.pattern_set, board, square, name=str(Path(folder)), options=options,
                           warnings=cap.warnings)
