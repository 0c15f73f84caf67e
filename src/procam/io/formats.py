"""Which files are procam's: the marks procam's writers leave in a file, each defined once.

:func:`procam.io.files.procam_wrote` recognises an existing file as procam's by these marks (so an output may
overwrite it without losing anything of the user's); the writer that leaves a mark takes it from here, so the
writer and the recogniser cannot drift apart.  Nothing here reads or writes a file, and this module imports
nothing heavy (``procam.io.files`` imports it, and must stay cheap).

==================  ===========================================================================================
file                mark
==================  ===========================================================================================
JSON                a top-level ``"format"`` that starts with :data:`JSON_PREFIX` (``procam-calibration``, ...)
FileStorage         YAML (``%YAML``) or XML (``<opencv_storage>``) whose key :data:`FILESTORAGE_KEY` names a format of
                    :data:`FILESTORAGE_FORMATS` (procam's layout :data:`OPENCV`, kamino410's :data:`KAMINO410`)
``.npz``            a member :data:`NPZ_KEY` naming a format of :data:`NPZ_FORMATS` (decoded maps, a remap table)
PLY                 a header comment line :data:`PLY_COMMENT` (the key and a format, as in FileStorage)
PNG                 a ``tEXt`` chunk :data:`PNG_TEXT_KEY` = :data:`SOFTWARE`; a frame of a sequence (a pattern, a
                    rendered or a camera's frame) :data:`FRAME_MARK` instead: data, never replaced by an output
Python script       a first line :data:`SCRIPT_MARK` and the SHA-256 of the rest of the file (:func:`script_mark`)
JPEG                a comment (``COM``) segment :data:`SOFTWARE` (a figure written as ``.jpg``)
PDF, SVG, PS, EPS   :data:`SOFTWARE` as the figure's Creator
HTML                ``<meta name="generator" content="procam">`` (:data:`HTML_GENERATOR`) in the page's head
==================  ===========================================================================================

A mark is something a user's own file does not carry by accident: a key or member named after procam holding one of
procam's format names (never the mere presence of keys other tools write too, such as ``cam_K`` or ``map_x``), or,
for a script, a digest of its own text (a copy the user edited is theirs).  A file an older procam wrote without
these marks counts as the user's: it is refused, never overwritten.
"""

from __future__ import annotations

from dataclasses import dataclass

#: The name procam signs its files with (PNG ``Software``, a figure's ``Creator``).
SOFTWARE = "procam"

# ------------------------------------------------------------------------------------------------
# JSON: every document procam writes names its format, "procam-..."
JSON_PREFIX = "procam"
CALIBRATION_FORMAT = "procam-calibration"
CORRESPONDENCES_FORMAT = "procam-correspondences"
OPENGL_FORMAT = "procam-opengl"
#: ``procam export --format blender`` / ``unity``: the engine cameras of a calibration.
BLENDER_FORMAT = "procam-blender"
UNITY_FORMAT = "procam-unity"
MANIFEST_FORMAT = "procam-manifest"
#: ``patterns.json`` of a written Gray-code sequence (an older procam's folders are known by it).
GRAYCODE_FORMAT = "procam-graycode"
#: ``patterns.json`` of a written phase-family sequence (phase, heterodyne, gray-phase).
PATTERNS_FORMAT = "procam-patterns"
#: ``capture.json`` of a pose a camera captured (``procam capture``).
CAPTURE_FORMAT = "procam-capture"
#: ``procam evaluate -o``.
EVALUATION_FORMAT = "procam-evaluation"
#: ``procam world-check --json`` (:meth:`procam.world_check.WorldCheck.to_dict`).
WORLD_CHECK_FORMAT = "procam-world-check"
#: ``procam-app.json``: what ``procam app`` keeps of a project that its files cannot say (:mod:`procam.app.project`).
APP_PROJECT_FORMAT = "procam-app-project"
#: The simulator's ``truth.json`` of one scene, and of a rig.
SIM_TRUTH_FORMAT = "procam-sim-truth"
SIM_RIG_TRUTH_FORMAT = "procam-sim-rig-truth"
#: ``rig.json`` of a rig pose folder (:mod:`procam.capture.rig`) and a rig's calibration (:mod:`procam.rig`).
RIG_POSE_FORMAT = "procam-rig-pose"
RIG_CALIBRATION_FORMAT = "procam-rig-calibration"


# ------------------------------------------------------------------------------------------------
# OpenCV FileStorage (YAML / XML): the keys of a camera-projector calibration
@dataclass(frozen=True)
class FileStorageLayout:
    """The FileStorage keys of one tool's camera-projector calibration file."""

    name: str
    cam_K: str
    cam_dist: str
    proj_K: str
    proj_dist: str
    R: str
    T: str


#: procam's YAML/XML: the keys of Moreno & Taubin's scan3d-capture (``procam calibrate --yaml``).
OPENCV = FileStorageLayout("procam / Moreno-Taubin", "cam_K", "cam_kc", "proj_K", "proj_kc", "R", "T")
#: kamino410/procam-calibration's ``calibration_result.xml`` (``procam export --format kamino410``).
KAMINO410 = FileStorageLayout("kamino410/procam-calibration", "cam_int", "cam_dist", "proj_int", "proj_dist",
                              "rotation", "translation")
#: The FileStorage key of procam's mark, and the formats it names (procam's YAML/XML, kamino410's XML).
FILESTORAGE_KEY = "procam_format"
FILESTORAGE_FORMATS = {OPENCV.name: CALIBRATION_FORMAT, KAMINO410.name: "procam-kamino410"}


# ------------------------------------------------------------------------------------------------
# .npz
#: Members of the decoded-maps file (``procam decode -o maps.npz``), in the order they are written.
DECODED_MAPS_KEYS = ("col", "row", "valid_col", "valid_row", "reason_col", "reason_row", "confidence",
                     "dropped_col", "dropped_row", "projector_size", "order")
#: The two tables of a remap file (``procam export --format maps``); further members are its metadata.
REMAP_MARK = ("map_x", "map_y")
#: The member of procam's mark in an ``.npz`` (a 0-d string array, no pickle) and the formats it names.
NPZ_KEY = "procam_format"
DECODED_MAPS_FORMAT = "procam-decoded-maps"
REMAP_FORMAT = "procam-remap"
NPZ_FORMATS = (DECODED_MAPS_FORMAT, REMAP_FORMAT)


# ------------------------------------------------------------------------------------------------
# PLY, PNG and HTML
#: The first header comment of a PLY procam writes (``procam reconstruct``), a whole line.
PLY_COMMENT = "procam_format procam-point-cloud"
#: The ``<head>`` element of every HTML page procam writes (the report), by which it knows the page is its own.
HTML_GENERATOR = f'<meta name="generator" content="{SOFTWARE}">'

#: The PNG ``tEXt`` key procam's signature stands under (value :data:`SOFTWARE`).
PNG_TEXT_KEY = "Software"
#: The PNG ``Software`` text of a frame of a sequence (:class:`procam.capture.write.SequenceWriter`): procam wrote
#: it, but it is a capture's data, not an output: only its folder's manifest lets its own writer replace it (a
#: frame copied out of its folder, manifest left behind, is never overwritten by a figure).
FRAME_MARK = f"{SOFTWARE} frame"
#: The first line of a script procam writes (``procam export --format blender``): this, then the SHA-256 of the rest.
SCRIPT_MARK = "# procam-script sha256:"


def script_mark(body: str) -> str:
    """The first line (with its newline) of a script procam writes whose text after that line is ``body``."""
    import hashlib

    return f"{SCRIPT_MARK}{hashlib.sha256(body.encode('utf-8')).hexdigest()}\n"
