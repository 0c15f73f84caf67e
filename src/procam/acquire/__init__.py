"""Driving the devices: show the Gray-code sequence on the projector, grab and check camera frames.

Modules (each with one job):

``projector``
    :class:`~procam.acquire.projector.ProjectorWindow` (a full-screen SDL2 window on one display,
    pixel-exact; ``pip install 'procam[capture]'``), :class:`~procam.acquire.projector.VirtualProjector`,
    :func:`~procam.acquire.projector.list_displays`.
``cameras``
    The :class:`~procam.acquire.cameras.Camera` interface and its backends, one module each: OpenCV
    ``VideoCapture``, GenICam through ``harvesters``, a folder watch, and the simulator (``VirtualCamera``,
    ``VirtualLiveCamera``); :func:`~procam.acquire.cameras.open_camera` builds one from a ``--camera`` spec.
``checks``
    Pre-flight exposure check and per-frame / per-pair verification, plain functions on arrays.
``session``
    The capture loop (:func:`~procam.acquire.session.capture_pose`): a pose folder that ``procam
    decode``/``calibrate`` read as is, plus ``capture.json``, written by :class:`procam.capture.SequenceWriter`.
``live``
    Live advice while the board is placed: the advising loop (:func:`~procam.acquire.live.advise`, over
    :class:`procam.advisor.Advisor`) and the advising session over a capture's poses
    (:class:`~procam.acquire.live.LiveAdvice`: the preview window, a quick calibration of each captured pose).
``orchestrate``
    A whole capture session as one call (:func:`~procam.acquire.orchestrate.capture_session`): the devices of
    a :class:`~procam.acquire.orchestrate.Devices` opened, advice before and a verdict after each pose, told to
    :class:`~procam.acquire.orchestrate.Hooks` (what ``procam capture`` prints).
``preview``
    The advisor's preview window on the operator's screen (:class:`~procam.acquire.preview.PreviewWindow`,
    pygame-ce) and the overlay drawing (:func:`~procam.acquire.preview.draw_advice`).
``_window``, ``_device``
    The one SDL window start-up both windows use; the context-manager base of every device.

The capture-folder *format* (reading, validating and writing a pose folder, the frames' names) is
:mod:`procam.capture`.  Nothing here imports pygame, screeninfo, harvesters or the simulator until it is used.
"""

from .cameras import (  # noqa: F401
                      Camera,
                      FolderWatchCamera,
                      Frame,
                      HarvestersCamera,
                      OpenCVCamera,
                      VirtualCamera,
                      open_camera,
                      parse_camera_spec,
)
from .live import LiveAdvice  # noqa: F401
from .orchestrate import Devices, Hooks, capture_session  # noqa: F401
from .projector import CaptureAborted, Display, ProjectorWindow, VirtualProjector, list_displays  # noqa: F401
from .session import CaptureFailed, CaptureOptions, CaptureResult, Event, capture_pose, capture_poses  # noqa: F401
