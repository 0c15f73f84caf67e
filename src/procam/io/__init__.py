"""procam's files: one home for every file procam reads or writes.

    formats           which files are procam's: the marks its writers leave, defined once
    files             plumbing: which files are images, natural sort, atomic writes, JSON helpers, the manifest of
                      procam's files, whether an existing file is procam's
    images            reading capture images: one file as OpenCV reads it, a pose's files into one stack, a PNG's
                      header
    png               the PNGs capture scripts write, decoded faster than OpenCV and to its pixels (the rest:
                      OpenCV's)
    folders           output folders: what procam may overwrite or delete; a folder made ready for a writer
    validate          the one validator set every reader checks what it loads with
    procam            procam's JSON: calibrations and correspondences (views)
    opencv            OpenCV FileStorage YAML/XML: procam's keys written and read, other tools' camera layouts read
    kamino410         kamino410/procam-calibration's calibration_result.xml and camera_config.json
    layouts           other tools' result files (structured-light CamMat/ProMat, SLStudio, OpenCV stereo / MATLAB):
                      their FileStorage layouts as one table, read by opencv.read_layout
    calibration_file  one calibration file, whatever its format: save_calibration (by suffix), load_calibration
                      and load_camera_intrinsics (by content)
    rig               a rig's calibration file (every device, relative pose and pair), written and read back
    maps              decoded maps (procam decode -o) and remap tables as .npz
    engines           the engine exports' files: their JSON, the Blender script, distortion maps, the projector's view
    ply               point clouds as binary PLY

Submodules load on first use (PEP 562): ``procam.io.load_calibration`` imports the calibration readers when it
is first named, and ``import procam.io.files`` imports no format code.
"""

from __future__ import annotations

import importlib

_SUBMODULES = ("formats", "files", "images", "png", "folders", "validate", "procam", "opencv", "kamino410", "layouts",
               "calibration_file", "rig", "maps", "engines", "ply")

#: Public names handed on here: name -> submodule.
_EXPORTS = {
    "IMAGE_EXTS": "files", "read_image": "images", "read_images": "images", "write_image": "files",
    "validate_calibration": "validate",
    "CONVENTIONS": "procam", "UNCERTAINTY_NOTE": "procam", "VERDICT_MEANING": "procam",
    "calibration_to_dict": "procam", "view_from_dict": "procam", "view_to_dict": "procam",
    "save_opencv_yaml": "opencv",
    "KAMINO410_KEYS": "kamino410", "load_kamino410": "kamino410", "save_kamino410": "kamino410",
    "load_calibration": "calibration_file", "load_camera_intrinsics": "calibration_file",
    "load_projector_intrinsics": "calibration_file",
    "save_calibration": "calibration_file", "complete_sizes": "calibration_file",
    "load_rig_calibration": "calibration_file", "save_rig_calibration": "rig", "is_rig_calibration": "rig",
    "load_decoded_maps": "maps", "save_decoded_maps": "maps", "save_maps": "maps",
    "read_ply": "ply", "write_ply": "ply",
}

__all__ = [*_SUBMODULES, *_EXPORTS]


def __getattr__(name: str):
    if name in _SUBMODULES:
        return importlib.import_module(f"{__name__}.{name}")
    if name in _EXPORTS:
        return getattr(importlib.import_module(f"{__name__}.{_EXPORTS[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
