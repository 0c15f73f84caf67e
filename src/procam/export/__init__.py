"""Calibration outputs for the tools users feed next: engine cameras, rendering matrices, remap tables, the
projector's view.

One module per engine or job:

    frames          each device's pose in the chosen world frame (the upright device), length units
    opengl          OpenGL / TouchDesigner projection and view matrices of both devices
    blender         Blender's own camera and render properties per device, its world transform, and the script
                    that creates the cameras in a scene (:mod:`.blender_cameras`)
    unity           Unity Physical Cameras (focal length, sensor size, lens shift, gate fit) and transforms in
                    Unity's left-handed, y-up world
    maps            what no engine camera holds (lens distortion): remap tables and ST maps
    rectify         stereo rectification for any rig orientation
    projector_view  the camera's view of the scene remapped into projector pixels (the template mapping tools
                    draw on), with the decoded-valid mask

The files live in :mod:`procam.io`; ``procam export`` writes them.  Conventions (docs/exports.md has the tables
and figures): procam pixels ``(x, y)`` have their origin at the centre of the top-left pixel (OpenCV's); device
frames are OpenCV's (x right, y down, z forward); ``x_p = R x_c + T`` maps camera to projector coordinates, board
units.  Every engine camera is a pinhole: each export says what it leaves out (lens distortion, skew) and the
distortion maps carry it.

Importing the package imports numpy only (OpenCV and scipy load inside the functions that use them), and the
command line imports it only inside ``procam export``.
"""

from __future__ import annotations

from .. import choices
from . import blender_cameras  # noqa: F401  (the script, as a module: importable without Blender)
from .blender import BLENDER_FROM_CV, blender_camera, blender_document
from .frames import LENGTH_UNITS, device_poses
from .maps import distortion_maps, predistort_maps, st_map, st_map_lookup, undistort_maps
from .opengl import GL_FROM_CV, clip_to_pixels, opengl_document, opengl_projection, view_matrices
from .projector_view import ProjectorView, projector_view
from .rectify import rectifying_rotations, stereo_rectify
from .unity import UNITY_FROM_CV, physical_camera, unity_document, unity_projection, unity_transform

#: The formats ``procam export --format`` writes.
FORMATS = choices.EXPORT_FORMATS
#: The world frames of the engine exports (``world=``).
WORLDS = choices.WORLDS

__all__ = ["FORMATS", "WORLDS", "BLENDER_FROM_CV", "GL_FROM_CV", "LENGTH_UNITS", "UNITY_FROM_CV", "ProjectorView",
           "blender_camera", "blender_document", "clip_to_pixels", "device_poses", "distortion_maps",
           "opengl_document", "opengl_projection", "physical_camera", "predistort_maps", "projector_view",
           "rectifying_rotations", "st_map", "st_map_lookup", "stereo_rectify", "undistort_maps", "unity_document",
           "unity_projection", "unity_transform", "view_matrices"]
