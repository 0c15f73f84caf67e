"""The capture-folder layout of a rig: several projectors (or cameras) seeing one board pose.

A **rig pose folder** holds one sub-folder per (camera, projector) pair, each an ordinary pose folder (the
projector's whole sequence as that camera recorded it, :func:`procam.capture.load_capture` reads it), and
``rig.json`` naming the devices::

    pose1/
      rig.json       {"format": "procam-rig-pose", "version": 1, "reference": "cam",
                      "cameras": ["cam"], "projectors": ["left", "right"],
                      "pairs": {"left": ["cam", "left"], "right": ["cam", "right"]}}
      left/          00.png ... 45.png, patterns.json     (camera cam, projector left)
      right/         00.png ... 45.png, patterns.json     (camera cam, projector right)

A sub-folder is named after the projector when the rig has one camera, after the camera when it has one
projector, and ``<camera>_<projector>`` otherwise (:func:`pair_folder_name`).  The reference camera (the
frame every device's pose is given in) is the first camera.  A folder without ``rig.json`` whose
sub-folders are pose folders (each with ``patterns.json``) and that holds no images itself is read as one
camera called ``camera`` and one projector per sub-folder, named after it.

Device names are identifiers (a letter, then letters, digits or ``_``): they become keys of the OpenCV
YAML file of a rig calibration.

Failure modes: a missing sub-folder, two pairs that are one capture (one folder once links are resolved, or the
same frames: :mod:`procam.capture.distinct`), a device named twice, a pair naming an unknown device, or a manifest
that is not procam's are :class:`~procam.errors.CaptureError` with one line naming the file.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from ..errors import CaptureError
from ..io.formats import RIG_POSE_FORMAT

__all__ = ["RIG_MANIFEST", "RigPair", "RigPose", "is_rig_pose", "read_rig_pose", "rig_manifest", "pair_folder_name",
           "check_device_name", "prepare_rig_dir", "write_rig_file"]

#: The manifest of a rig pose folder.
RIG_MANIFEST = "rig.json"
_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,31}$")
_IMAGES = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp", ".pgm")


def check_device_name(name: str, where: str = "device name") -> str:
    """``name`` if it is a device name (a letter, then up to 31 letters, digits or ``_``), else ``ValueError``."""
    if not isinstance(name, str) or not _NAME.match(name):
        raise ValueError(f"{where} {name!r}: a device name is a letter then letters, digits or '_' (at most 32)")
    return name


def pair_folder_name(camera: str, projector: str, n_cameras: int, n_projectors: int) -> str:
    """The sub-folder of the pair (``camera``, ``projector``) in a rig of ``n_cameras`` and ``n_projectors``."""
    if n_cameras == 1:
        return projector
    if n_projectors == 1:
        return camera
    return f"{camera}_{projector}"


@dataclass(frozen=True)
class RigPair:
    """One pair of a rig pose: its pose ``folder``, the ``camera`` and the ``projector`` (names)."""

    folder: Path
    camera: str
    projector: str

    @property
    def key(self) -> str:
        """``"camera/projector"``: the pair's name in a rig calibration."""
        return f"{self.camera}/{self.projector}"


@dataclass(frozen=True)
class RigPose:
    """A rig pose folder (:func:`read_rig_pose`): ``cameras`` and ``projectors`` (names, the reference camera
    first) and the ``pairs`` (:class:`RigPair`) captured at this board pose."""

    folder: Path
    cameras: tuple
    projectors: tuple
    pairs: tuple

    @property
    def reference(self) -> str:
        return self.cameras[0]

    @property
    def name(self) -> str:
        return str(self.folder)


def rig_manifest(cameras, projectors, pairs=None) -> dict:
    """The ``rig.json`` document of a rig pose: ``cameras``, ``projectors`` (names; the first camera is the
    reference) and ``pairs`` (sub-folder -> [camera, projector]; default every pair, named by
    :func:`pair_folder_name`)."""
    cameras, projectors = [check_device_name(c) for c in cameras], [check_device_name(p) for p in projectors]
    if not cameras or not projectors:
        raise ValueError("a rig needs at least one camera and one projector")
    if len(set(cameras + projectors)) != len(cameras + projectors):
        raise ValueError(f"device names must be unique, got {cameras + projectors}")
    if pairs is None:
        pairs = {pair_folder_name(c, p, len(cameras), len(projectors)): [c, p] for c in cameras for p in projectors}
    return {"format": RIG_POSE_FORMAT, "version": 1, "reference": cameras[0], "cameras": cameras,
            "projectors": projectors, "pairs": {k: list(v) for k, v in pairs.items()},
            "layout": "one sub-folder per (camera, projector) pair, each an ordinary pose folder"}


def write_rig_file(out_dir, name: str, text: str) -> Path:
    """Write one of a rig pose folder's own files (``rig.json``, ``truth.json``) into ``out_dir``, listed in its
    manifest as a ``sidecar``: a file its readers need, so no command's output ever replaces it (an ``output`` is
    what a later command may write over)."""
    from ..io.files import write_text

    return write_text(Path(out_dir) / name, text, role="sidecar")


def prepare_rig_dir(out_dir, writer: str, *, force: bool = False, option: str | None = None):
    """Make ``out_dir`` ready to take a rig pose (:func:`procam.io.folders.prepare_output_dir`: new, empty or this
    writer's earlier output; ``force`` as there).  Returns its path; raises :class:`~procam.errors.OutputError`."""
    from ..io.folders import prepare_output_dir

    return prepare_output_dir(out_dir, writer, force=force, option=option)


def _pose_like(d: Path) -> bool:
    return d.is_dir() and (d / "patterns.json").is_file()


def is_rig_pose(folder) -> bool:
    """Is ``folder`` a rig pose folder: it holds ``rig.json``, or no images and at least one sub-folder that is a
    pose folder (holds ``patterns.json``)?"""
    f = Path(folder)
    if not f.is_dir():
        return False
    if (f / RIG_MANIFEST).is_file():
        return True
    if (f / "patterns.json").is_file() or any(p.suffix.lower() in _IMAGES for p in f.iterdir() if p.is_file()):
        return False
    return any(_pose_like(d) for d in f.iterdir())


def rig_without_manifest(folder) -> str | None:
    """Why ``folder`` cannot be read, when it looks like a rig pose folder that is not one: no images of its own,
    no ``rig.json``, and sub-folders that hold images but no ``patterns.json`` (so nothing says they are pose
    folders); the message names what a rig pose folder needs.  None for anything else."""
    f = Path(folder)
    if not f.is_dir() or (f / RIG_MANIFEST).exists() or (f / "patterns.json").exists():
        return None
    try:
        entries = list(f.iterdir())
    except OSError:
        return None
    if any(p.suffix.lower() in _IMAGES for p in entries if not p.name.startswith(".")):
        return None
    subs = sorted(d.name for d in entries if not d.name.startswith(".") and d.is_dir()
                  and any(p.suffix.lower() in _IMAGES for p in d.iterdir()))
    if not subs:
        return None
    listing = ", ".join(subs[:4]) + (", ..." if len(subs) > 4 else "")
    return (f"{f}: holds no images, but its sub-folders {listing} do: a rig pose folder needs a {RIG_MANIFEST} naming "
            "its cameras, projectors and the pair each sub-folder holds (docs/rigs.md), or a patterns.json in every "
            "sub-folder (each is then read as one projector); for a single pose, give the sub-folder itself")


def read_rig_pose(folder) -> RigPose:
    """The :class:`RigPose` of a rig pose folder (module docstring), checked: every pair's sub-folder exists,
    the names are device names, each used once as a camera or a projector.  Raises
    :class:`~procam.errors.CaptureError` with one line naming the folder or file."""
    f = Path(folder)
    man = f / RIG_MANIFEST
    if not man.is_file():
        if not is_rig_pose(f):
            raise CaptureError(rig_without_manifest(f) or f"{f}: not a rig pose folder (no {RIG_MANIFEST}, no "
                               "sub-folders with patterns.json)")
        subs = sorted(d.name for d in f.iterdir() if _pose_like(d))
        try:
            doc = rig_manifest(["camera"], subs)
        except ValueError as e:
            raise CaptureError(f"{f}: {e} (sub-folders are read as projectors; add {RIG_MANIFEST} to name them)") \
                from None
    else:
        from ..io.jsonfile import JSONError, load_json

        try:
            doc = load_json(man)
        except OSError as e:
            raise CaptureError(f"{man}: cannot be read ({e.strerror or e}); check its permissions") from None
        except JSONError as e:
            raise CaptureError(f"{man}: not a readable rig manifest: it {e}") from None
        if not isinstance(doc, dict) or doc.get("format") != RIG_POSE_FORMAT:
            raise CaptureError(f"{man}: not a procam rig manifest (missing format: {RIG_POSE_FORMAT})")
    for key, kind, what in (("cameras", list, "a list of names"), ("projectors", list, "a list of names"),
                            ("pairs", dict, "an object: sub-folder -> [camera, projector]")):
        if key in doc and not isinstance(doc[key], kind):
            raise CaptureError(f"{man}: {key} must be {what}, got {doc[key]!r:.60}")
    try:
        cams, projs = list(doc["cameras"]), list(doc["projectors"])
        pairs_doc = dict(doc["pairs"])
        rig_manifest(cams, projs, pairs_doc)  # the names' checks
    except (KeyError, TypeError, ValueError) as e:
        raise CaptureError(f"{man}: {e if isinstance(e, ValueError) else 'needs cameras, projectors and pairs'}") \
            from None
    ref = doc.get("reference", cams[0])
    if ref not in cams:  # the reference the file names is the reference, or the file is wrong
        raise CaptureError(f"{man}: reference {ref!r} is not one of the cameras {cams}")
    cams = [ref] + [c for c in cams if c != ref]
    if not cams or not projs or not pairs_doc:
        raise CaptureError(f"{man}: a rig needs at least one camera, one projector and one pair")
    pairs = []
    for sub, cp in pairs_doc.items():
        if not (isinstance(cp, list) and len(cp) == 2 and cp[0] in cams and cp[1] in projs):
            raise CaptureError(f"{man}: pair {sub!r} must be [camera, projector] of the rig's devices, got {cp!r}")
        if "/" in sub or "\\" in sub or sub in ("", ".", ".."):
            raise CaptureError(f"{man}: pair folder {sub!r} must be a plain sub-folder name")
        d = f / sub
        if not d.is_dir():
            raise CaptureError(f"{d}: the pair ({cp[0]}, {cp[1]}) has no folder; capture it or remove it from "
                               f"{RIG_MANIFEST}")
        pairs.append(RigPair(d, cp[0], cp[1]))
    keys = [p.key for p in pairs]
    if len(set(keys)) != len(keys):
        raise CaptureError(f"{man}: a (camera, projector) pair is listed twice")
    from .distinct import refuse_repeats

    refuse_repeats([p.folder for p in pairs], "pair folder",
                   "each (camera, projector) pair needs its own capture (a link or a copy of another pair's folder "
                   "would calibrate one device against itself)")
    return RigPose(f, tuple(cams), tuple(projs), tuple(pairs))
