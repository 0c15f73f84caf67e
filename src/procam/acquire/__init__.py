"""Driving the devices: show the Gray-code sequence on the projector, grab and check camera frames.

Modules (each with one job):

``projector``
    :class:`~procam.acquire.projector.ProjectorWindow` (a full-screen SDL2 window on one display,
    pixel-exact; ``pip install 'procam[capture]'``), :class:`~procam.acquire.projector.VirtualProjector`,
    :func:`~procam.acquire.projector.list_displays`.
``cameras``
    The :class:`~procam.acquire.cameras.Camera` interface and its backends: OpenCV ``VideoCapture``,
    GenICam through ``harvesters``, a folder watch, and the simulator (``VirtualCamera``).
``checks``
    Pre-flight exposure check and per-frame / per-pair verification, plain functions on arrays.
``session``
    The capture loop (:func:`~procam.acquire.session.capture_pose`): writes a pose folder that
    ``procam decode``/``calibrate`` read as is, plus ``capture.json``.
``live``
    Live advice while the board is placed: the advising loop (:func:`~procam.acquire.live.advise`, over
    :class:`procam.advisor.Advisor`) and :class:`~procam.acquire.live.VirtualLiveCamera` (the simulator's
    view of the board under the projector's white light, at a pose a test or script moves).
``preview``
    The advisor's preview window on the operator's screen (:class:`~procam.acquire.preview.PreviewWindow`,
    pygame-ce) and the overlay drawing (:func:`~procam.acquire.preview.draw_advice`).

The capture-folder *format* (reading and validating a pose folder) stays in :mod:`procam.capture`.
Nothing here imports pygame, screeninfo, harvesters or the simulator until it is used.
"""

from .cameras import (Camera, FolderWatchCamera, Frame, HarvestersCamera, OpenCVCamera,  # noqa: F401
                      VirtualCamera, open_camera, parse_camera_spec)
from .projector import CaptureAborted, Display, ProjectorWindow, VirtualProjector, list_displays  # noqa: F401
from .session import CaptureFailed, CaptureOptions, CaptureResult, Event, capture_pose, capture_poses  # noqa: F401
