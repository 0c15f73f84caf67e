"""The correspondences of one pose: board, camera and projector points, and, optionally, the dense decoded
samples on the board and on the scene behind it (:mod:`procam.correspond.samples`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .board import Board

#: Per-corner reason codes of a view (``View.diagnostics["reason"]``, uint8): why a corner has no projector point.
#: :mod:`procam.correspond` sets them; the correspondence files write them as these words.
CORNER_REASONS = {
    0: "ok",
    1: "corner not detected in the camera image",
    2: "too few decoded pixels in the window (unlit, shadowed or low contrast)",
    3: "window leaves the image",
    4: "poor local homography fit (residual above max_residual)",
    5: "homography estimation failed",
    6: "the local fit of the sub-pixel map and the local homography disagree (phase families)",
}


@dataclass(frozen=True)
class Samples:
    """Dense decoded correspondences: camera pixels and the projector coordinates decoded there.

    Attributes
    ----------
    cam_pts : (M, 2) float64 distorted camera pixels (x, y).
    proj_pts : (M, 2) float64 projector pixels (x, y) (column and row).
    sigma : (M,) float64 noise of each sample's projector coordinate (px, per axis; a relative weight), or None
        (equal weights: raw decoded pixels).
    window : side (camera px) of the window each sample averages (:mod:`procam.correspond.samples`); 1 for raw pixels.
    """

    cam_pts: np.ndarray
    proj_pts: np.ndarray
    sigma: np.ndarray | None = None
    window: int = 1

    def __post_init__(self):
        cam = np.asarray(self.cam_pts, dtype=np.float64).reshape(-1, 2)
        proj = np.asarray(self.proj_pts, dtype=np.float64).reshape(-1, 2)
        if len(cam) != len(proj):
            raise ValueError(f"sample camera/projector point counts differ: {len(cam)}, {len(proj)}")
        arrays = [cam, proj]
        if self.sigma is not None:
            sig = np.asarray(self.sigma, dtype=np.float64).reshape(-1)
            if len(sig) != len(cam):
                raise ValueError(f"sample sigma has {len(sig)} values for {len(cam)} samples")
            object.__setattr__(self, "sigma", sig)
            arrays.append(sig)
        for arr in arrays:
            arr.setflags(write=False)
        object.__setattr__(self, "cam_pts", cam)
        object.__setattr__(self, "proj_pts", proj)

    def __len__(self) -> int:
        return len(self.cam_pts)


#: The samples of the scene behind the board (the name the single-pose background check knows them by).
Background = Samples


@dataclass(frozen=True)
class View:
    """One pose of the board seen by the camera and the projector.

    Attributes
    ----------
    obj_pts : (N, 3) float64
        Board corners in board coordinates (square-size units, z = 0), canonical order.
    cam_pts : (N, 2) float64
        Distorted camera pixels (x, y) of the corners; NaN where a corner was not found.
    proj_pts : (N, 2) float64
        Projector pixels (x, y) of the corners; NaN where a corner failed (see ``diagnostics``).
    name : str
        The pose's name (usually its capture folder).
    cam_size, proj_size : (width, height) in pixels, or None when unknown.
    diagnostics : dict
        Per-corner diagnostics (arrays of length N) and free-form notes.
    board : :class:`procam.board.Board` the points were made for, or None when unknown.
    background : :class:`Samples` or None -- decoded samples off the board, the scene behind it (filled by
        :mod:`procam.pipeline` from the decoded maps, :func:`procam.correspond.samples.dense_samples`; None when unknown,
        e.g. a view read from a file).
    board_samples : :class:`Samples` or None -- decoded samples on the board (the same; the single-pose
        projector's dense constraints).
    """

    obj_pts: np.ndarray
    cam_pts: np.ndarray
    proj_pts: np.ndarray
    name: str = "view"
    cam_size: tuple[int, int] | None = None
    proj_size: tuple[int, int] | None = None
    diagnostics: dict = field(default_factory=dict, compare=False)
    board: Board | None = None
    background: Samples | None = field(default=None, compare=False)
    board_samples: Samples | None = field(default=None, compare=False)

    def __post_init__(self):
        obj = np.asarray(self.obj_pts, dtype=np.float64)
        if obj.ndim != 2 or obj.shape[1] not in (2, 3):
            raise ValueError(f"obj_pts must be (N, 3), got {obj.shape}")
        if obj.shape[1] == 2:
            obj = np.column_stack([obj, np.zeros(len(obj))])
        cam = np.asarray(self.cam_pts, dtype=np.float64).reshape(-1, 2)
        proj = np.asarray(self.proj_pts, dtype=np.float64).reshape(-1, 2)
        if not (len(obj) == len(cam) == len(proj)):
            raise ValueError(f"obj/cam/proj point counts differ: {len(obj)}, {len(cam)}, {len(proj)}")
        for arr in (obj, cam, proj):
            arr.setflags(write=False)
        object.__setattr__(self, "obj_pts", obj)
        object.__setattr__(self, "cam_pts", cam)
        object.__setattr__(self, "proj_pts", proj)

    @property
    def valid(self) -> np.ndarray:
        """(N,) bool: corners with finite camera and projector points."""
        return np.isfinite(self.cam_pts).all(1) & np.isfinite(self.proj_pts).all(1)

    def subset(self, mask: np.ndarray) -> "View":
        """The view restricted to ``mask`` (N,) bool (diagnostics arrays are subset too)."""
        mask = np.asarray(mask, dtype=bool)
        diag = {k: (np.asarray(v)[mask] if isinstance(v, np.ndarray) and len(v) == len(mask) else v)
                for k, v in self.diagnostics.items()}
        return View(self.obj_pts[mask], self.cam_pts[mask], self.proj_pts[mask], self.name,
                    self.cam_size, self.proj_size, diag, self.board, self.background, self.board_samples)
