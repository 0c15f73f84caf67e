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

Submodules load on first use (PEP 562), so ``import procam.export`` imports no scipy or OpenCV.
"""

from __future__ import annotations

import importlib

from .. import choices

#: The formats ``procam export --format`` writes.
FORMATS = choices.EXPORT_FORMATS
#: The world frames of the engine exports (``world=``).
WORLDS = choices.WORLDS

_SUBMODULES = ("frames", "opengl", "blender", "blender_cameras", "unity", "maps", "rectify", "projector_view")
_EXPORTS = {
    "GL_FROM_CV": "opengl", "opengl_projection": "opengl", "view_matrices": "opengl", "clip_to_pixels": "opengl",
    "opengl_document": "opengl",
    "BLENDER_FROM_CV": "blender", "blender_document": "blender", "blender_camera": "blender",
    "UNITY_FROM_CV": "unity", "unity_document": "unity", "physical_camera": "unity", "unity_projection": "unity",
    "unity_transform": "unity",
    "undistort_maps": "maps", "predistort_maps": "maps", "st_map": "maps", "st_map_lookup": "maps",
    "stereo_rectify": "rectify", "rectifying_rotations": "rectify",
    "projector_view": "projector_view", "ProjectorView": "projector_view",
    "device_poses": "frames", "LENGTH_UNITS": "frames",
}

__all__ = ["FORMATS", "WORLDS", *_SUBMODULES, *_EXPORTS]


def __getattr__(name: str):
    if name in _SUBMODULES:
        return importlib.import_module(f"{__name__}.{name}")
    if name in _EXPORTS:
        return getattr(importlib.import_module(f"{__name__}.{_EXPORTS[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
