"""A whole capture session as one call: the devices opened, the poses captured, advice before and a verdict
after each pose -- what ``procam capture`` does between parsing its options and printing.

:func:`capture_session`

1. checks the pose folders before any device opens (:func:`procam.capture.check_out_dir`);
2. opens the projector: a :class:`~procam.acquire.projector.VirtualProjector` for a virtual rig (1920x1080
   unless told), else the full-screen :class:`~procam.acquire.projector.ProjectorWindow` on the chosen display
   (the display's size unless told);
3. opens the camera the ``--camera`` spec names at its first use and shares it between the poses; the
   simulator instead gets one :class:`~procam.acquire.cameras.VirtualCamera` per pose, the board at the
   pose's angles (:data:`~procam.acquire.cameras.VIRTUAL_POSES`, in turn), its sequence rendered once, and
   its ground truth written into the pose folder as ``truth.json``;
4. before each pose, lights the board white while it is placed: the live advice
   (:class:`~procam.acquire.live.LiveAdvice`) ends that (Esc in its window stops the session), or, between
   the poses of a real rig without advice, the user says so (:meth:`Hooks.place_board`);
5. captures the pose (:func:`~procam.acquire.session.capture_pose`, or
   :func:`~procam.acquire.session.capture_poses` for ``pose01``, ``pose02`` ...);
6. after each pose, with a board, judges it at once (:func:`procam.check.check_pose`, on the advice's board
   when there is advice, whose calibration then teaches the advice: :meth:`~procam.acquire.live.LiveAdvice.learn`).

Nothing is printed: a :class:`Hooks` object is told what happens and asked to wait for the user; its methods
do nothing here (the command line's print).  A failure stops the session with its one-line
:class:`~procam.errors.ProcamError`; poses already captured stay, and every device is closed.
"""

from __future__ import annotations

import contextlib
import json
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..capture import check_out_dir
from ..errors import ProcamError
from .session import CaptureOptions, CaptureResult, capture_pose, capture_poses, pose_folders


@dataclass(frozen=True)
class Devices:
    """The devices of a capture session.

    camera : a ``--camera`` spec (:func:`~procam.acquire.cameras.parse_camera_spec`).
    proj_size : (width, height) of the patterns; None = the display's size (1920x1080 when virtual).
    display : the projector's display (:func:`~procam.acquire.projector.choose_display`); None = the one
        that is not the primary.
    virtual : a virtual projector, and the simulator as the camera.
    cam_size, exposure_ms, gain, timeout_s : the camera's settings
        (:func:`~procam.acquire.cameras.open_camera`; the simulator takes the gain only).
    seed : the simulator's noise seed (pose ``i`` is rendered with ``seed + i``).
    scene : virtual: the :class:`procam.simulate.Scene` every pose renders (its ``proj_size`` the patterns'),
        e.g. one pair of a simulated rig (:mod:`procam.acquire.rig`); None = the demo scene at the poses'
        angles.
    """

    camera: str = "opencv:0"
    proj_size: tuple | None = None
    display: int | None = None
    virtual: bool = False
    cam_size: tuple | None = None
    exposure_ms: float | None = None
    gain: float | None = None
    timeout_s: float = 60.0
    seed: int = 0
    scene: object = None

    @property
    def camera_kind(self) -> str:
        """``"opencv"``, ``"genicam"``, ``"folder"`` or ``"virtual"``."""
        from .cameras import parse_camera_spec

        return parse_camera_spec("virtual" if self.virtual else self.camera)[0]


class Hooks:
    """What a capture session tells its user and asks of them (every method does nothing here)."""

    def projector(self, projector) -> None:
        """The projector is open."""

    def camera(self, camera) -> None:
        """The camera the poses share is open."""

    def busy(self, text: str):
        """A context manager around something slow that says nothing meanwhile (the simulator rendering a pose)."""
        return contextlib.nullcontext()

    def pose(self, i: int, poses: int, camera_kind: str) -> None:
        """Pose ``i`` (0-based) of ``poses`` comes next, with a camera of ``camera_kind``."""

    def place_board(self, i: int) -> None:
        """Return when the user has placed the board for pose ``i`` in the projector's (white) light."""

    def progress(self, i: int, event) -> None:
        """An :class:`~procam.acquire.session.Event` of pose ``i``'s capture."""

    def captured(self, result: CaptureResult) -> None:
        """A pose's folder is written."""

    def verdict(self, result: CaptureResult, check, png: Path) -> None:
        """The pose's instant verdict (:class:`procam.check.PoseCheck`) and the path for its overlay picture; a
        :class:`ProcamError` raised here counts as the verdict's failure."""

    def verdict_failed(self, result: CaptureResult, error: ProcamError) -> None:
        """The pose has no verdict: ``error`` stopped it."""


def capture_session(out_dir, poses: int, rig: Devices, options: CaptureOptions, *, board=None, live=None,
                    hooks: Hooks | None = None) -> list[CaptureResult]:
    """Run a capture session (see the module docstring).

    Parameters
    ----------
    out_dir : the pose folder to create, or with ``poses`` > 1 the folder that gets ``pose01`` ... (each must
        not exist, or be empty).
    poses : number of poses.
    rig : the devices (:class:`Devices`).
    options : the capture loop's :class:`~procam.acquire.session.CaptureOptions`.
    board : :class:`procam.board.Board` for each pose's instant verdict, or None (no verdict).
    live : :class:`~procam.acquire.live.LiveAdvice` to run before each pose (closed at the end), or None.
    hooks : :class:`Hooks`.

    Returns
    -------
    list of :class:`~procam.acquire.session.CaptureResult`, one per pose.
    """
    hooks = hooks or Hooks()
    if poses == 1:
        check_out_dir(out_dir)
    else:
        pose_folders(out_dir, poses)
    with ExitStack() as stack:
        proj, size = _open_projector(rig)
        stack.enter_context(proj)
        hooks.projector(proj)
        run = _Session(rig, proj, size, stack, options, poses, board, live, hooks)
        if live is not None:
            stack.callback(live.close)
        if poses == 1:
            run.before_pose(0)
            result = capture_pose(out_dir, proj, run.camera_for(0), options, progress=run.progress_of(0),
                                  extra_files=run.extra_files(0))
            run.after_pose(0, result)
            return [result]
        return capture_poses(out_dir, poses, proj, run.camera_for, options, before_pose=run.before_pose,
                             after_pose=run.after_pose, progress=hooks.progress, extra_files_for=run.extra_files)


def _open_projector(rig: Devices):
    """The (not yet open) projector of ``rig`` and its pattern size."""
    from .projector import ProjectorWindow, VirtualProjector

    size = rig.proj_size
    if rig.virtual:
        size = size or (1920, 1080)
        return VirtualProjector(size), size
    if size is None:
        from .projector import choose_display, list_displays

        size = choose_display(list_displays(), rig.display).size
    return ProjectorWindow(size, rig.display), size


class _Session:
    """One session's devices and the steps around each pose (kept out of the public API)."""

    def __init__(self, rig: Devices, projector, size, stack: ExitStack, options: CaptureOptions, poses: int,
                 board, live, hooks: Hooks):
        self.rig, self.projector, self.size, self.stack = rig, projector, size, stack
        self.order, self.poses, self.board, self.live, self.hooks = options.order, poses, board, live, hooks
        self.options = options
        self.kind = rig.camera_kind
        self._scenes: dict = {}
        self._virtual: dict = {}
        self._shared = None

    def progress_of(self, i: int):
        return lambda event: self.hooks.progress(i, event)

    def _scene(self, i: int):
        if self.rig.scene is not None:
            return self.rig.scene
        if i not in self._scenes:
            from .cameras import VIRTUAL_POSES, demo_scene

            self._scenes[i] = demo_scene(self.size, VIRTUAL_POSES[i % len(VIRTUAL_POSES)])
        return self._scenes[i]

    def camera_for(self, i: int):
        """The open camera of pose ``i``."""
        rig = self.rig
        if self.kind == "virtual":
            if i not in self._virtual:
                from .. import simulate
                from .cameras import VirtualCamera

                gray = self.options.family == "gray"
                try:
                    sequence = None if gray else self.options.sequence(*self.size)
                except ValueError as e:
                    raise ProcamError(f"pattern sequence: {e}") from None
                cam = VirtualCamera(self.projector, self._scene(i), order=self.order, seed=rig.seed + i,
                                    gain=1.0 if rig.gain is None else rig.gain, sequence=sequence)
                with self.hooks.busy(f"rendering the simulator's view of pose {i + 1}"):
                    cam.stack, _ = simulate.render(cam.scene, order=self.order if gray else sequence,
                                                   seed=rig.seed + i)
                self._virtual[i] = self.stack.enter_context(cam)
            return self._virtual[i]
        if self._shared is None:
            from .cameras import open_camera

            self._shared = self.stack.enter_context(open_camera(rig.camera, size=rig.cam_size,
                                                                exposure_ms=rig.exposure_ms, gain=rig.gain,
                                                                timeout_s=rig.timeout_s))
            self.hooks.camera(self._shared)
        return self._shared

    def extra_files(self, i: int) -> dict | None:
        """The simulator's ground truth of pose ``i`` (``truth.json``); None for a real camera."""
        if self.kind != "virtual":
            return None
        from .. import simulate
        from ..io.files import to_jsonable

        return {"truth.json": json.dumps(to_jsonable(simulate.truth(self._scene(i))), indent=1)}

    def _light(self) -> None:
        """Light the board while it is placed."""
        self.projector.show(np.full((self.size[1], self.size[0]), 255, np.uint8))

    def before_pose(self, i: int) -> None:
        self.hooks.pose(i, self.poses, self.kind)
        if self.live is not None:
            from .projector import CaptureAborted

            self._light()
            res = self.live.run(self.camera_for(i), f"pose {i + 1}/{self.poses}")
            if res.reason == "quit":
                raise CaptureAborted("capture stopped: Esc was pressed in the preview window, or it was closed")
        elif self.poses > 1 and not self.rig.virtual:
            self._light()
            self.hooks.place_board(i)

    def after_pose(self, i: int, result: CaptureResult) -> None:
        """Report the pose; its instant verdict (a PoseCheck, or the error that stopped it) with a board; the
        advice learns from it."""
        self.hooks.captured(result)
        checked = None
        if self.board is not None:
            from ..check import check_pose

            png = result.folder.with_name(result.folder.name + ".check.png")
            try:  # with advice, on the advisor's board: its calibration (T in that unit) teaches the advisor
                checked = check_pose(result.folder, self.board if self.live is None else self.live.board)
                self.hooks.verdict(result, checked, png)
            except ProcamError as e:
                self.hooks.verdict_failed(result, e)
                checked = e
        if self.live is not None:
            self.live.learn(result.folder, checked=checked)
