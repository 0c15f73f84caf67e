"""Live advice while the board is placed: a virtual live camera and the advising loop.

:class:`VirtualLiveCamera`
    The simulator as a live camera for the advisor: every grab renders the frame the camera sees under
    the projector's **white** pattern at the board's current pose (one :class:`procam.simulate.Renderer`
    per pose, about 20 ms per frame at 1280x800 after ~0.3 s per new pose with ``supersample=1``); the board
    is moved with :meth:`~VirtualLiveCamera.set_board` / :meth:`~VirtualLiveCamera.move` (a test, or a
    script, plays the user).
:func:`advise`
    The loop: grab a frame, :meth:`procam.advisor.Advisor.update`, hand the advice to a callback (the
    preview window, the JSON lines), until a key asks for the capture, ``auto`` finds the pose ready, or
    ``max_frames`` frames were seen.  Nothing is printed.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..errors import ProcamError
from .cameras.base import Frame, _Camera, to_gray


class VirtualLiveCamera(_Camera):
    """The simulator as a live camera that sees the board under the projector's white light.

    Parameters
    ----------
    scene : :class:`procam.simulate.Scene` (its board pose is the starting pose).
    seed : noise seed (one generator for all frames).
    supersample : the renderer's rays per pixel and axis (default 1: fast; the scene's own value for
        ``None``).
    order : pattern order (only fixes which image is the white one).
    """

    def __init__(self, scene, *, seed: int = 0, supersample: int | None = 1, order: str = "opencv"):
        self.name = "virtual-live"
        self.order = order
        self.supersample = supersample
        self._rng = np.random.default_rng(seed)
        self.seed = int(seed)
        self._renderer = None
        self.grabs = 0
        self.scene = None
        self.set_scene(scene)

    def set_scene(self, scene) -> None:
        """Replace the whole scene (the next grab renders it)."""
        if self.supersample is not None and scene.supersample != self.supersample:
            scene = scene.replace(supersample=int(self.supersample))
        if scene is not self.scene:
            self.scene = scene
            self._renderer = None

    def set_board(self, R_board, t_board) -> None:
        """Put the board at pose ``(R_board, t_board)`` (board -> camera)."""
        self.set_scene(self.scene.replace(R_board=np.asarray(R_board, float), t_board=np.asarray(t_board, float)))

    def move(self, turn_deg: float = 0.0, tilt_deg: float = 0.0, shift=(0.0, 0.0, 0.0)) -> None:
        """Turn and tilt the board about its centre as :func:`procam.advisor.apply_move` defines them, then
        shift its centre by ``shift`` (camera frame, board units)."""
        from ..advisor import apply_move

        R, t = apply_move(self.scene.R_board, self.scene.t_board, turn_deg, tilt_deg)
        self.set_board(R, t + np.asarray(shift, float).reshape(3))

    def grab(self) -> Frame:
        from .. import simulate

        if self._renderer is None:
            self._renderer = simulate.Renderer(self.scene, self.order)
        r = self._renderer
        img = r.frame(r.pattern_set.white, self._rng)
        self.grabs += 1
        return Frame(img, time.monotonic(), {"source": self.name})

    def describe(self) -> dict:
        s = self.scene
        return {"backend": "virtual-live", "scene": s.name, "size": list(s.cam_size),
                "projector_size": list(s.proj_size), "seed": self.seed, "supersample": s.supersample,
                "settings": {}, "notes": ["white frames rendered by procam.simulate at the board's current pose"]}


@dataclass(frozen=True)
class AdviseResult:
    """How :func:`advise` ended: ``reason`` (``"key"``, ``"auto"``, ``"max-frames"``, ``"quit"``), the last
    :class:`~procam.advisor.Advice` (None if no frame was seen) and the number of ``frames``."""

    reason: str
    advice: object
    frames: int


def advise(camera, advisor, *, on_advice: Callable | None = None, poll: Callable | None = None,
           auto: bool = False, max_frames: int | None = None, clock: Callable[[], float] = time.monotonic,
           use_camera_time: bool = True) -> AdviseResult:
    """Run the advisor on the camera's live frames until the capture should start (or the loop ends).

    Parameters
    ----------
    camera : an open camera (``grab() -> Frame``).
    advisor : :class:`procam.advisor.Advisor` for the camera's frame size.
    on_advice : called with ``(frame image, advice)`` after each frame (draw the preview, print JSON).
    poll : called after each frame; returns None to go on, ``"capture"`` (a key asked for the capture)
        or ``"quit"``.
    auto : end as soon as the advice is ``ready`` (good, and the board still).
    max_frames : end after this many frames (scripts, tests).
    clock : time source when the camera's time stamps are not used.
    use_camera_time : use each frame's own time stamp (``Frame.timestamp``) for the stillness test.

    Returns
    -------
    :class:`AdviseResult`.
    """
    if max_frames is not None and max_frames < 1:
        raise ProcamError(f"--max-frames must be >= 1, got {max_frames}")
    n, last = 0, None
    while True:
        frame = camera.grab()
        img = to_gray(frame.image)
        t = frame.timestamp if use_camera_time and frame.timestamp is not None else clock()
        last = advisor.update(img, t)
        n += 1
        if on_advice is not None:
            on_advice(img, last)
        what = poll() if poll is not None else None
        if what in ("capture", "quit"):
            return AdviseResult("key" if what == "capture" else "quit", last, n)
        if auto and last.ready:
            return AdviseResult("auto", last, n)
        if max_frames is not None and n >= max_frames:
            return AdviseResult("max-frames", last, n)
