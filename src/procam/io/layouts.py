"""Other tools' camera-projector result files: their OpenCV FileStorage layouts (YAML, XML, JSON), as data.

One table, :data:`RESULT_LAYOUTS`, says for each layout which keys hold the camera's ``K`` and distortion, the
projector's, ``R`` and ``T``, where the image sizes are, and what ``R, T`` mean.  The one reader
(:func:`procam.io.load_calibration`, and :func:`procam.io.load_camera_intrinsics` for the camera) reads every
layout of the table with the same code (:func:`procam.io.opencv.read_layout`), and the one validator set
(:mod:`procam.io.validate`) checks what it reads.  A new layout is a new row, never a new reader.

Every layout here holds ``R, T`` as OpenCV ``stereoCalibrate`` returns them with the camera as the first
device: ``x_projector = R x_camera + T``, ``T`` in the unit of the chessboard's square (procam's convention), so
none is converted.  The key names are those the tools write:

* the structured-light tool whose ``CCalibration::Result`` writes ``CamMat, ProMat, R, T``
  (``stereoCalibrate(object, camera points, projector points)``); it writes no distortion, so ``CamDist``,
  ``ProDist`` (or its variables' names ``CamDisCoeffs``, ``ProDisCoeffs``) are read when present;
* SLStudio's ``calibration.xml`` (``CalibrationData::saveXML``): ``Kc, kc, Kp, kp, Rp, Tp`` (``Rp, Tp`` from
  ``stereoCalibrate(Q, qc, qp)``: camera -> projector), ``cam_error, proj_error, stereo_error``, the camera's
  ``frameWidth, frameHeight`` and the projector's ``screenResX, screenResY`` (0 when unset: read as not stored);
* OpenCV's stereo layout, device 1 the camera and 2 the projector: ``K1, D1, K2, D2, R, T`` as scripts save
  ``cv2.stereoCalibrate``'s results, ``cameraMatrix1, distCoeffs1, ...`` (its argument names) and ``M1, D1,
  M2, D2`` (OpenCV's stereo_calib sample); MATLAB's ``stereoParameters`` exported as OpenCV YAML is this layout
  (the common export scripts write ``K1 = IntrinsicMatrix'``, ``R = RotationOfCamera2'``,
  ``T = TranslationOfCamera2'``: OpenCV's convention, MATLAB's own matrices being the transposes).  A file
  written with MATLAB's ``RotationOfCamera2`` untransposed holds ``R^T``; nothing in the file tells the two
  apart (both are rotations), so procam reads OpenCV's convention, as the docs say.  The camera's size is
  ``image_width, image_height``, ``width, height``, or a pair ``image_size`` / ``imageSize``, which is
  ``[width, height]`` from OpenCV and ``[height, width]`` from MATLAB: the principal point decides, and a pair
  it cannot decide is refused.

Nothing here reads a file; this module imports nothing.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class SizeKeys:
    """Where a layout stores one device's image size: two numbers (keys ``width`` and ``height``), or one pair
    (``height`` None; key ``width``) in the order ``order``: ``"wh"``, or ``"either"`` (``[width, height]`` or
    ``[height, width]``, told apart by the principal point)."""

    width: str
    height: str | None = None
    order: str = "wh"

    def keys(self) -> tuple[str, ...]:
        return (self.width,) if self.height is None else (self.width, self.height)


@dataclass(frozen=True)
class ResultLayout:
    """One tool's FileStorage result file.  Each field lists the key names that may hold it (one file holds one
    of them; two at once are refused).  ``R, T``: ``x_projector = R x_camera + T``, ``T`` in the chessboard's unit
    (:data:`EXTRINSICS`).  ``rms``: the keys of the camera, projector and stereo RMS errors (pixels) or None."""

    name: str
    cam_K: tuple[str, ...]
    cam_dist: tuple[str, ...]
    proj_K: tuple[str, ...]
    proj_dist: tuple[str, ...]
    R: tuple[str, ...]
    T: tuple[str, ...]
    cam_size: tuple[SizeKeys, ...] = ()
    proj_size: tuple[SizeKeys, ...] = ()
    rms: tuple[str | None, str | None, str | None] = (None, None, None)
    method: str = "imported"

    def keys(self) -> str:
        """The layout's keys as the docs and errors say them: ``CamMat, CamDist?, ...``."""
        opt = [self.cam_dist, self.proj_dist]
        return ", ".join("/".join(k) + ("?" if k in opt else "")
                         for k in (self.cam_K, self.cam_dist, self.proj_K, self.proj_dist, self.R, self.T))


#: What ``R, T`` mean in every layout of :data:`RESULT_LAYOUTS`.
EXTRINSICS = "x_projector = R x_camera + T (OpenCV stereoCalibrate, camera first); T in the chessboard's unit"

STRUCTURED_LIGHT = ResultLayout(
    "structured-light CamMat/ProMat", ("CamMat",), ("CamDist", "CamDisCoeffs"), ("ProMat",),
    ("ProDist", "ProDisCoeffs"), ("R",), ("T",), method="cammat-promat")
SLSTUDIO = ResultLayout(
    "SLStudio calibration.xml", ("Kc",), ("kc",), ("Kp",), ("kp",), ("Rp",), ("Tp",),
    cam_size=(SizeKeys("frameWidth", "frameHeight"),), proj_size=(SizeKeys("screenResX", "screenResY"),),
    rms=("cam_error", "proj_error", "stereo_error"), method="slstudio")
OPENCV_STEREO = ResultLayout(
    "OpenCV stereo / MATLAB stereoParameters export", ("K1", "cameraMatrix1", "M1"),
    ("D1", "distCoeffs1"), ("K2", "cameraMatrix2", "M2"), ("D2", "distCoeffs2"), ("R",), ("T",),
    cam_size=(SizeKeys("image_width", "image_height"), SizeKeys("width", "height"),
              SizeKeys("image_size", order="either"), SizeKeys("imageSize", order="either")),
    method="opencv-stereo")

#: Other tools' result files read by :func:`procam.io.load_calibration`, in the order the docs list them.
RESULT_LAYOUTS = (STRUCTURED_LIGHT, SLSTUDIO, OPENCV_STEREO)
