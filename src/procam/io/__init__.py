"""procam's files: one home for every file procam reads or writes.

    formats      which files are procam's: the marks its writers leave, defined once
    files        plumbing: natural sort, image reads, atomic writes, JSON helpers, the manifest of procam's files,
                 whether an existing file is procam's
    folders      output folders: what procam may overwrite or delete; a folder made ready for a writer
    procam       procam's JSON: calibrations and correspondences (views)

Submodules load on first use (PEP 562): ``procam.io.load_calibration`` imports the calibration readers when it
is first named, and ``import procam.io.files`` imports no format code.
"""

from __future__ import annotations

import importlib

_SUBMODULES = ("formats", "files", "folders", "procam")

#: Public names handed on here: name -> submodule.
_EXPORTS = {
    "CONVENTIONS": "procam", "UNCERTAINTY_NOTE": "procam", "VERDICT_MEANING": "procam",
    "calibration_to_dict": "procam", "load_calibration": "procam", "save_calibration": "procam",
    "save_opencv_yaml": "procam", "validate_calibration": "procam", "view_from_dict": "procam",
    "view_to_dict": "procam",
    "IMAGE_EXTS": "files", "read_image": "files", "read_images": "files", "write_image": "files",
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
