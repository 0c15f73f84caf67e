"""The app's devices: the projector and the camera the steps share, and the camera's live view.

``virtual``: the simulator, as ``procam capture --virtual`` has it -- a virtual projector of ``projector_size`` and
the camera of :func:`procam.acquire.cameras.demo_scene`'s rig, the board at one of
:data:`~procam.acquire.cameras.VIRTUAL_POSES` (the user turns it with :meth:`Devices.set_pose` /
:meth:`Devices.move`, as a person turns the printed board); the live view is a
:class:`~procam.acquire.cameras.VirtualLiveCamera` of the same scene.  Otherwise a projector window on
``display`` and the camera of the ``camera`` spec (:func:`procam.acquire.cameras.open_camera`), opened at first use.
"""

from __future__ import annotations

import threading

import numpy as np

from ..errors import ProcamError


class Devices:
    """The projector and camera of the app (see the module docstring)."""

    def __init__(self, virtual: bool, *, camera: str = "opencv:0", display: int | None = None, seed: int = 0,
                 projector_size=(1920, 1080)):
        self.virtual, self.camera_spec, self.display, self.seed = virtual, camera, display, int(seed)
        self.lock = threading.RLock()  # the live view and a job never use the camera at once
        self._pose_lock = threading.Lock()  # the virtual board's pose (short: a click waits for no frame)
        self._live = None
        self._shown = None  # the scene the live camera shows
        self._camera = None
        self._listing = None
        self.pose_index = 0
        self.projector_size = tuple(int(v) for v in projector_size)
        self.scene = None
        if virtual:
            self.set_projector_size(self.projector_size)

    # ---- the virtual rig -------------------------------------------------------------------
    def set_projector_size(self, size) -> None:
        """Virtual: the projector's pattern size (width, height), 320x200 to 3840x2160."""
        w, h = (int(v) for v in size)
        if not (320 <= w <= 3840 and 200 <= h <= 2160):
            raise ProcamError(f"projector size {w}x{h}: give 320x200 to 3840x2160 pixels")
        self.projector_size = (w, h)
        if self.virtual:
            self.set_pose(self.pose_index)

    def set_pose(self, index: int) -> None:
        """Virtual: put the board at :data:`~procam.acquire.cameras.VIRTUAL_POSES` ``[index]``."""
        from ..acquire.cameras import VIRTUAL_POSES, VirtualLiveCamera, demo_scene

        self._virtual_only("set the board's pose")
        if not (isinstance(index, int) and 0 <= index < len(VIRTUAL_POSES)):
            raise ProcamError(f"board pose: give 0 to {len(VIRTUAL_POSES) - 1}, got {index!r}")
        scene = demo_scene(self.projector_size, VIRTUAL_POSES[index])
        with self._pose_lock:  # the live camera takes the new scene at its next frame: a click never waits for one
            self.pose_index, self.scene = index, scene
            if self._live is None:
                self._live = VirtualLiveCamera(scene, seed=self.seed)

    def move(self, turn_deg: float = 0.0, tilt_deg: float = 0.0) -> None:
        """Virtual: turn / tilt the board about its centre (:func:`procam.advisor.apply_move`), degrees."""
        from ..advisor import apply_move

        self._virtual_only("move the board")
        for name, v in (("turn", turn_deg), ("tilt", tilt_deg)):
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not -45 <= v <= 45:
                raise ProcamError(f"board {name}: give degrees from -45 to 45, got {v!r}")
        with self._pose_lock:
            R, t = apply_move(self.scene.R_board, self.scene.t_board, float(turn_deg), float(tilt_deg))
            self.scene = self.scene.replace(R_board=R, t_board=t)

    def _live_camera(self):
        """The virtual live camera, showing the board where it is now (call with :attr:`lock` held)."""
        with self._pose_lock:
            scene = self.scene
        if scene is not self._shown:
            self._live.set_scene(scene)
            self._shown = scene
        return self._live

    def _virtual_only(self, what: str) -> None:
        if not self.virtual:
            raise ProcamError(f"only the virtual rig lets the app {what}; move the printed board by hand")

    # ---- what the steps use ----------------------------------------------------------------------
    def describe(self) -> dict:
        """The displays and cameras (what ``procam capture --list-devices`` lists), and which are used."""
        if self.virtual:
            from ..acquire.cameras import VIRTUAL_POSES

            w, h = self.projector_size
            cw, ch = self.scene.cam_size
            return {"virtual": True, "projector": f"virtual projector {w}x{h}", "projector_size": [w, h],
                    "camera": f"the simulator's camera {cw}x{ch}", "poses": [list(p) for p in VIRTUAL_POSES],
                    "pose_index": self.pose_index, "displays": [], "cameras": []}
        if self._listing is not None:  # probing the cameras takes a while: once per session
            return self._listing
        from ..acquire import cameras as cams
        from ..acquire.projector import choose_display, list_displays

        try:
            displays = list_displays()
            chosen = choose_display(displays, self.display)
            shown = [{"index": d.index, "label": d.label(), "projector": d.index == chosen.index} for d in displays]
            projector, size = chosen.label(), list(chosen.size)
        except ProcamError as e:
            shown, projector, size = [], f"none: {e}", None
        self._listing = {"virtual": False, "projector": projector, "projector_size": size, "camera": self.camera_spec,
                         "displays": shown, "cameras": cams.list_opencv_cameras(), "poses": [], "pose_index": None}
        return self._listing

    def grab(self) -> np.ndarray:
        """One grey camera frame, (H, W) uint8/uint16 (the board in the projector's white light, virtual)."""
        from ..acquire.cameras.base import to_gray

        with self.lock:
            if self.virtual:
                return to_gray(self._live_camera().grab().image)
            if self._camera is None:
                from ..acquire.cameras import open_camera

                self._camera = open_camera(self.camera_spec).__enter__()
            return to_gray(self._camera.grab().image)

    def release(self) -> None:
        """Close the live camera (before a capture opens the devices, and at the end)."""
        with self.lock:
            if self._camera is not None:
                self._camera.__exit__(None, None, None)
                self._camera = None

    def capture_devices(self):
        """The :class:`procam.acquire.orchestrate.Devices` of a capture."""
        from ..acquire.orchestrate import Devices as CaptureDevices

        if self.virtual:
            return CaptureDevices(virtual=True, proj_size=self.projector_size, seed=self.seed, scene=self.scene)
        return CaptureDevices(camera=self.camera_spec, display=self.display)

    def lit_grab(self, stack, size):
        """``show_and_grab`` of the exposure check: virtual, the live camera under the projector image (its
        renderer and noise, :meth:`~procam.acquire.cameras.VirtualLiveCamera.grab`); else :meth:`show_and_grab`."""
        if not self.virtual:
            return self.show_and_grab(stack, size)
        from ..acquire.cameras.base import to_gray

        return lambda image: to_gray(self._live_camera().grab(image).image)

    def show_and_grab(self, stack, size):
        """``show_and_grab`` of the world check (:func:`procam.world_check.virtual_device` or
        :func:`~procam.world_check.capture_device`), entered on ``stack`` (an ExitStack)."""
        from .. import world_check

        if self.virtual:
            return world_check.virtual_device(self.scene, self.seed)
        from ..acquire.cameras import open_camera
        from ..acquire.projector import ProjectorWindow

        self.release()
        proj = stack.enter_context(ProjectorWindow(tuple(size), self.display, title="procam app"))
        cam = stack.enter_context(open_camera(self.camera_spec))
        return world_check.capture_device(proj, cam)
