"""Camera input behind one small interface (:mod:`~procam.acquire.cameras.base`), one backend per module:

``opencv``   :class:`OpenCVCamera`, UVC/V4L2 webcams through ``cv2.VideoCapture``;
``genicam``  :class:`HarvestersCamera`, GenICam machine-vision cameras through a GenTL producer (``harvesters``);
``folder``   :class:`FolderWatchCamera`, cameras whose own software saves files (DSLRs, vendor apps);
``virtual``  :class:`VirtualCamera` and :class:`VirtualLiveCamera`, the simulator as the camera (of the patterns, of
             the board under white light);
``specs``    :func:`open_camera` builds one from a ``--camera`` spec (:func:`parse_camera_spec`).
"""

from .base import Camera, Frame, to_gray  # noqa: F401
from .folder import FolderWatchCamera  # noqa: F401
from .genicam import HarvestersCamera, list_genicam_cameras  # noqa: F401
from .opencv import OpenCVCamera, list_opencv_cameras  # noqa: F401
from .specs import CAMERA_SPECS, open_camera, parse_camera_spec  # noqa: F401
from .virtual import VIRTUAL_POSES, VirtualCamera, VirtualLiveCamera, demo_scene  # noqa: F401
