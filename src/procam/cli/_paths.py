"""What a command reads and writes, checked before any work: its inputs are distinct captures, and every output
is a new file or procam's own (never a user's, never one of the command's inputs or the files they need).
"""

from __future__ import annotations

import os
from pathlib import Path

from ..errors import OutputError
from ._app import fail, warn
from ._options import optional_size, value

FIGURE_SUFFIXES = (".png", ".pdf", ".svg", ".jpg", ".jpeg")


def _capture_folder(folder: Path, inputs) -> bool:
    """Does ``folder`` hold a capture sequence (a pose folder given to this command, or a sequence folder)?"""
    from ..io import files as _files

    try:
        folder = folder.resolve()
    except OSError:
        return False
    for p in inputs:
        try:
            if Path(p).resolve() == folder:
                return True
        except OSError:
            continue
    man = _files.read_manifest(folder)
    if man is not None:
        return any(r in ("frame", "captured") for r in man["files"].values())
    return (folder / "patterns.json").is_file() or (folder / "capture.json").is_file()


def distinct_poses(poses) -> None:
    """Refuse a pose folder given twice: the same folder once links are resolved, or the same frames (it would
    count as two poses of the board; :func:`procam.capture.distinct.refuse_repeats`)."""
    from ..capture.distinct import refuse_repeats
    from ..errors import CaptureError

    try:
        refuse_repeats(poses, "pose folder", "give each pose once")
    except CaptureError as e:
        fail(str(e))


def load_pose(pose_dir, projector, calib, order=None, step=None):
    """The capture of one pose folder for a command that has a calibration, and the calibration with the sizes its
    file did not store taken from the pose: ``(capture, calib)``.  The projector size from ``--projector``, else the
    folder's ``patterns.json``, else the calibration's; the capture's warnings printed; a pose of another camera or
    projector size than the calibration's is a one-line error."""
    from .. import capture, io

    size = optional_size(projector)
    if size is None and not (Path(pose_dir) / "patterns.json").exists():
        size = tuple(calib.projector.image_size)
    cap = capture.load_capture(pose_dir, size, value(order), step=step)
    for w in cap.warnings:
        warn(w)
    ps = cap.pattern_set
    H, W = cap.stack.shape[1:]
    calib = io.complete_sizes(calib, (W, H), (ps.width, ps.height))   # sizes the calibration file did not store
    if (W, H) != tuple(calib.camera.image_size):
        fail(f"{pose_dir}: camera images are {W}x{H} but the calibration is for "
             f"{calib.camera.image_size[0]}x{calib.camera.image_size[1]}"
             + (assumed_size(calib, "cam_size") or "; use captures of the calibrated camera"))
    if (ps.width, ps.height) != tuple(calib.projector.image_size):
        fail(f"{pose_dir}: the sequence is for a {ps.width}x{ps.height} projector but the calibration's projector is "
             f"{calib.projector.image_size[0]}x{calib.projector.image_size[1]}"
             + (assumed_size(calib, "proj_size") or "; check --projector"))
    return cap, calib


def pose_sizes(calib, path, cam_size, proj_size):
    """``calib`` with the image sizes its file did not store (``info["image_size_assumed"]``) taken from the pose
    (:func:`procam.io.complete_sizes`), each said in a warning (never a silent choice): other tools' result files
    store no size, or only the camera's."""
    from .. import io

    before = set((calib.info or {}).get("image_size_assumed", ()))
    calib = io.complete_sizes(calib, cam_size, proj_size)
    taken = before - set((calib.info or {}).get("image_size_assumed", ()))
    for key, name, size in (("cam_size", "camera", cam_size), ("proj_size", "projector", proj_size)):
        if key in taken:
            warn(f"{Path(path).name} does not store the {name} size; the pose's {size[0]}x{size[1]} is used")
    return calib


def distrust(calib, path) -> str:
    """Why the calibration file ``path`` must not be trusted (its verdict degenerate or failed: written with
    ``procam calibrate --force``), or ""; a command that uses it says so in its output and exits 3."""
    from ..verdict import LEVELS

    if calib.trusted or calib.verdict not in LEVELS:  # good, weak, or another tool's file (no verdict of procam's)
        return ""
    why = "; ".join(calib.verdict_reasons) or "see its verdict_reasons"
    return (f"{path}: its verdict is {calib.verdict} ({why}); procam calibrate wrote it only because of --force: "
            "its numbers may be anything, and so is what is made from them")


def assumed_size(calib, key: str) -> str:
    """A note for a size mismatch when the calibration file had no ``key`` (``cam_size``/``proj_size``) and
    its size was assumed from the principal point; '' otherwise."""
    if key in (calib.info or {}).get("image_size_assumed", ()):
        return f" (the file has no {key}, so 2 (u0, v0) was assumed; add {key}: [width, height] to it)"
    return ""


def output_path(path, option: str, suffixes: tuple[str, ...], inputs=()):
    """Check an output file before any work is done (one-line errors): a known suffix; a folder that can be
    created and written; not an input of the command nor a file an input folder needs, symbolic links resolved
    (``inputs``: files and pose or rig folders; :func:`procam.io.folders.input_clash`),
    not a file procam did not write in a capture folder, not an image added to a capture folder that
    has no manifest (it would be read as a frame of the sequence)."""
    if path is None:
        return None
    from ..io import files as _files
    from ..io import folders

    path = Path(path)
    if path.is_dir():
        fail(f"{option} {path}: is a folder; give a file name")
    if path.suffix.lower() not in suffixes:
        fail(f"{option} {path}: the file name must end in {' or '.join(suffixes)}")
    # the folder is created when the file is written (an early failure leaves no empty folder behind)
    parent = path.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir():
        fail(f"{option} {path}: cannot create the folder {path.parent} ({parent} is not a folder)")
    why = folders.why_not_writable(parent)
    if why is not None:
        where = f"write into {parent}" if parent == path.parent else f"create the folder {path.parent}"
        fail(f"{option} {path}: cannot {where} ({why}); choose another place")
    if path.is_symlink() and not path.exists():
        fail(f"{option} {path}: is a broken or looping symbolic link; give another name")
    clash = folders.input_clash(path, inputs)
    if clash is not None:
        fail(f"{option} {path}: {clash}; give another name (procam never writes over its inputs)")
    if path.exists():
        if not path.is_file():
            fail(f"{option} {path}: exists and is not a regular file; give another name")
        if not os.access(path, os.W_OK):
            fail(f"{option} {path}: the file is read-only; give another name or make it writable")
        if not _files.procam_wrote(path):
            fail(f"{option} {path}: {_files.kept_because(path)}")
    folder = path.parent
    if _capture_folder(folder, inputs):
        own = folders.replaceable(folder, [path.name])
        man = _files.read_manifest(folder)
        roles = man["files"] if man is not None else {}
        if path.exists() and (path.name not in own or roles.get(path.name) not in (None, "output")):
            fail(f"{option} {path}: would overwrite a file of the capture in {folder}; write it elsewhere")
        if path.suffix.lower() in _files.IMAGE_EXTS and man is None:
            fail(f"{option} {path}: {folder} holds a capture, and an image written there would be read as a frame "
                 "of its sequence; write it elsewhere")
    return path


def output_dir(path, option: str, writer: str, force: bool = False, create: bool = False, inputs=()) -> Path:
    """Check an output folder before any work is done: new, empty, or ``writer``'s own earlier output; with
    ``force`` any folder, where nothing procam did not write is overwritten or deleted
    (:func:`procam.io.folders.prepare_output_dir`).  A new folder is created only with ``create`` (otherwise by
    the writer, so an interrupted run leaves none).  Never an input folder of the command, nor a capture folder
    inside one (``inputs``: :func:`procam.io.folders.folder_clash`)."""
    from ..io import folders

    clash = folders.folder_clash(path, inputs)
    if clash is not None:
        fail(f"{option} {path}: {clash}; give another folder (procam never writes into its inputs)")
    try:
        return folders.prepare_output_dir(path, writer, force=force, option=option, create=create)
    except OutputError as e:
        fail(str(e))
