"""The simulator as a camera.

:class:`VirtualCamera`
    What the camera sees of the pattern a projector shows (the pose's sequence rendered once), with stale
    frames, a dead projector, saturation and exposure changes injectable: the capture loop's camera.
:class:`VirtualLiveCamera`
    What the camera sees under the projector's **white** pattern at the board's current pose (one
    :class:`procam.simulate.Renderer` per pose, about 20 ms per frame at 1280x800 after ~0.3 s per new pose
    with ``supersample=1``); the board is moved with :meth:`~VirtualLiveCamera.set_board` /
    :meth:`~VirtualLiveCamera.move` (a test, or a script, plays the user): the live advisor's camera.
:func:`demo_scene`, :data:`VIRTUAL_POSES`
    The scenes of ``procam capture --virtual``.
"""

from __future__ import annotations

import hashlib
import time

import numpy as np

from ...errors import ProcamError
from .base import Frame, _Camera, _setting


def _digest(image: np.ndarray) -> bytes:
    return hashlib.blake2b(np.ascontiguousarray(image).tobytes(), digest_size=16).digest()


class VirtualCamera(_Camera):
    """The simulator as a camera: returns the rendered view of the pattern a projector shows.

    The pose's whole sequence is rendered once (:func:`procam.simulate.render`); :meth:`grab`
    identifies the image the projector shows (by its hash among the sequence's patterns) and
    returns the rendered frame of it.

    Parameters
    ----------
    projector : anything with ``current`` (the image shown) and ``shown`` (a counter), e.g.
        :class:`~procam.acquire.projector.VirtualProjector` or a real window.
    scene : :class:`procam.simulate.Scene`; its ``proj_size`` must be the projector's size.
    order, seed : the sequence order and noise seed of the render.
    sequence : the pattern set the projector shows (any family, :mod:`procam.patterns`; it needs a white and a
        black frame, which the pre-flight shows); None = the Gray codes in ``order``.
    stack : the rendered stack of ``scene``'s sequence (skips the render; e.g. shared by tests).
    latency : frames the camera has buffered: the first ``latency`` grabs after a new pattern
        return the frame of the pattern shown before it (stale), unless :meth:`flush` drained them.
    flush_works : whether :meth:`flush` drains the buffered frames.
    stale_grabs : grab numbers (0-based, counting every grab) that return the previous pattern's frame.
    dead_projector : every frame is the black frame (the projector's light never arrives).
    gain : a digital gain on every frame (values clipped at full scale: saturation).
    exposure_change_at, exposure_factor : from grab number ``exposure_change_at`` on, frames are
        multiplied by ``exposure_factor`` (auto exposure kicking in mid-sequence).
    """

    def __init__(self, projector, scene, *, order: str = "opencv", seed: int = 0, stack: np.ndarray | None = None,
                 sequence=None,
                 latency: int = 0, flush_works: bool = True, stale_grabs=(), dead_projector: bool = False,
                 gain: float = 1.0, exposure_change_at: int | None = None, exposure_factor: float = 0.5):
        self.projector = projector
        self.scene = scene
        self.order = order
        self.seed = int(seed)
        self.stack = stack
        self.sequence = sequence
        self.latency = int(latency)
        self.flush_works = flush_works
        self.stale_grabs = frozenset(int(i) for i in stale_grabs)
        self.dead_projector = dead_projector
        self.gain = float(gain)
        self.exposure_change_at = exposure_change_at
        self.exposure_factor = float(exposure_factor)
        self.name = "virtual"
        self.grabs = 0
        self._index: dict[bytes, int] = {}
        self._seen_show = None
        self._cur = self._prev = None
        self._pending = 0
        self._ps = None

    def open(self):
        from ... import patterns

        if self._ps is not None:
            return self
        if tuple(self.projector.size) != tuple(self.scene.proj_size):
            raise ProcamError(f"virtual camera: the scene's projector is {self.scene.proj_size[0]}x"
                              f"{self.scene.proj_size[1]} but the patterns are {self.projector.size[0]}x"
                              f"{self.projector.size[1]}")
        w, h = self.scene.proj_size
        ps = self.sequence if self.sequence is not None else patterns.pattern_set(w, h, self.order)
        if (ps.width, ps.height) != (w, h) or ps.white is None or ps.black is None:
            raise ProcamError(f"virtual camera: the sequence must be {w}x{h} with a white and a black frame")
        self._ps = ps
        if self.stack is None:
            from ... import simulate

            self.stack, _ = simulate.render(self.scene, order=ps if self.sequence is not None else self.order,
                                            seed=self.seed)
        expected = (self._ps.count, self.scene.cam_size[1], self.scene.cam_size[0])
        if self.stack.shape != expected:
            raise ValueError(f"stack must be {expected} for this scene and order, got {self.stack.shape}")
        self._index = {_digest(img): k for k, img in enumerate(patterns.frames(ps))}
        return self

    def _identify(self, image) -> int:
        if image is None:
            return self._ps.black  # nothing shown yet: the projector is dark
        k = self._index.get(_digest(image))
        if k is None:
            raise ProcamError("virtual camera: the projector shows an image that is not one of the sequence's "
                              f"patterns ({self._describe()}); the simulator renders only those")
        return k

    def _describe(self) -> str:
        ps = self._ps if self._ps is not None else self.sequence
        if ps is None or not hasattr(ps, "family"):
            return f"Gray codes, order {self.order}, step 1"
        return ps.describe()

    def _update(self):
        if self.projector.shown != self._seen_show:
            self._seen_show = self.projector.shown
            k = self._identify(self.projector.current)
            if k != self._cur:  # showing the same image again changes nothing on the screen
                self._prev = self._cur if self._cur is not None else self._ps.black
                self._cur = k
                self._pending = self.latency

    def flush(self):
        self._update()
        if self.flush_works:
            self._pending = 0

    def grab(self) -> Frame:
        self._update()
        n = self.grabs
        self.grabs += 1
        stale = self._pending > 0 or n in self.stale_grabs
        if self._pending > 0:
            self._pending -= 1
        k = self._prev if stale else self._cur
        if self.dead_projector:
            k = self._ps.black
        img = self.stack[k]
        factor = self.gain
        if self.exposure_change_at is not None and n >= self.exposure_change_at:
            factor *= self.exposure_factor
        if factor != 1.0:
            top = np.iinfo(img.dtype).max
            img = np.clip(np.rint(img.astype(np.float32) * factor), 0, top).astype(img.dtype)
        else:
            img = img.copy()
        return Frame(img, time.monotonic(), {"source": "virtual", "pattern": int(k), "stale": bool(stale)})

    def describe(self) -> dict:
        s = self.scene
        return {"backend": "virtual", "scene": s.name, "size": list(s.cam_size), "projector_size": list(s.proj_size),
                "order": self.order, "sequence": self._describe(), "seed": self.seed, "latency": self.latency,
                "stale_grabs": sorted(self.stale_grabs), "dead_projector": self.dead_projector,
                "settings": {"gain": _setting(self.gain, self.gain, self.gain, True)},
                "notes": ["frames rendered by procam.simulate"]}


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
        from ...advisor import apply_move

        R, t = apply_move(self.scene.R_board, self.scene.t_board, turn_deg, tilt_deg)
        self.set_board(R, t + np.asarray(shift, float).reshape(3))

    def follow(self, advice) -> None:
        """The simulated user: move the board as the camera mode's advice says (its ``next_move`` turn and tilt,
        then its ``next_shift``; :class:`procam.advisor.CameraAdvice`); nothing without a proposed move."""
        if getattr(advice, "next_move", None) is not None:
            self.move(*advice.next_move, shift=advice.next_shift or (0.0, 0.0, 0.0))

    def grab(self, image: np.ndarray | None = None) -> Frame:
        """A frame of the board under the projector's white light, or under the projector image ``image`` ((H, W)
        uint8 of the projector's size: :meth:`procam.simulate.Renderer.linear_image`, the same noise generator)."""
        from ... import simulate

        if self._renderer is None:
            self._renderer = simulate.Renderer(self.scene, self.order)
        r = self._renderer
        img = r.frame(r.pattern_set.white, self._rng) if image is None else r.finish(r.linear_image(image), self._rng)
        self.grabs += 1
        return Frame(img, time.monotonic(), {"source": self.name})

    def describe(self) -> dict:
        s = self.scene
        return {"backend": "virtual-live", "scene": s.name, "size": list(s.cam_size),
                "projector_size": list(s.proj_size), "seed": self.seed, "supersample": s.supersample,
                "settings": {}, "notes": ["white frames rendered by procam.simulate at the board's current pose"]}


#: Board angles (psi, nu, phi) of the poses ``procam capture --virtual --poses N`` renders, in turn.
VIRTUAL_POSES = ((15.0, 12.0, 0.0), (-12.0, 15.0, 5.0), (14.0, -12.0, -5.0), (-15.0, -11.0, 3.0), (10.0, 16.0, -4.0))


def demo_scene(proj_size=None, pose=None, preset: str = "ideal"):
    """A simulator scene for ``procam capture --virtual``: the ``preset`` rig with its projector
    resized to ``proj_size`` (same horizontal field of view, intrinsics scaled by W / 1920) and
    the board at ``pose`` (psi, nu, phi) degrees in the camera frame (default: the recommended pose)."""
    from ... import simulate

    scene = simulate.preset(preset)
    if proj_size is not None and tuple(proj_size) != tuple(scene.proj_size):
        w, h = int(proj_size[0]), int(proj_size[1])
        s = w / scene.proj_size[0]
        scene = scene.replace(proj_size=(w, h), K_proj=np.diag([s, s, 1.0]) @ scene.K_proj)
    if pose is not None or proj_size is not None:
        scene = simulate.with_board_pose(scene, simulate.RECOMMENDED_POSE if pose is None else pose)
    return scene
