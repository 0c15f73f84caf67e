"""Output folders: which files of a folder procam may overwrite or delete, and a folder made ready for a
writer's outputs.

A folder procam creates for its outputs carries a manifest (:data:`procam.io.files.MANIFEST`) listing every
file procam wrote there and its role.  Writers refuse a non-empty folder without it
(:func:`prepare_output_dir`), never overwrite a file it does not list (:func:`check_overwrite`), and delete
only files it lists (:func:`remove_listed`); camera frames (role ``captured``) are never replaced or deleted.
A folder an older procam wrote (before manifests) is known by its ``patterns.json``.  Before any work, a
folder is checked to take a new file at all (:func:`why_not_writable`: read-only, no permission, disk full).
"""

from __future__ import annotations

import errno
import os
from pathlib import Path

from ..errors import OutputError
from . import formats
from .files import (IMAGE_EXTS, MANIFEST, changed_since_written, fmt_bytes, is_frame, natural_key, plain_name,
                    read_manifest, record_files, remove_stale_temps, unlist_files, write_manifest)
from .jsonfile import JSONError, load_json


def _visible(folder: Path) -> list[str]:
    """Names in ``folder`` a user put there or can see: everything but hidden entries."""
    return sorted((e.name for e in os.scandir(folder) if not e.name.startswith(".")), key=natural_key)


def _legacy_files(folder: Path) -> set[str]:
    """Files an older procam (before manifests) wrote: a sequence folder's ``patterns.json`` lists its
    frames, each marked as procam's (a camera's frames copied beside a copied patterns.json are not); ``truth.json``
    is the simulator's.  A camera capture (``capture.json``) is not counted."""
    try:
        meta = load_json(folder / "patterns.json")
    except (OSError, JSONError):  # none, or not one procam wrote: nothing in the folder counts as procam's
        return set()
    if not (isinstance(meta, dict) and meta.get("format") == formats.GRAYCODE_FORMAT
            and isinstance(meta.get("files"), list)):
        return set()
    if (folder / "capture.json").exists():
        return set()
    # a listed frame is procam's only with procam's mark: a user's camera frames can share its name
    frames = {str(f) for f in meta["files"]
              if plain_name(str(f)) and (not (folder / str(f)).exists() or is_frame(folder / str(f)))}
    return frames | {"patterns.json", "truth.json"}


def _listing(names: list[str], n: int = 4) -> str:
    return ", ".join(names[:n]) + (f", ... ({len(names)} in all)" if len(names) > n else "")


def replaceable(folder, names=None) -> set[str]:
    """Names in ``folder`` (of ``names``, default all) procam may overwrite or delete: listed in its manifest (or an
    older procam's patterns.json), except camera frames (role ``captured``) and files changed since procam wrote
    them (their recorded digest is not theirs: :func:`procam.io.files.changed_since_written`, which reads the
    file: give ``names`` to judge only those)."""
    folder = Path(folder)
    man = read_manifest(folder)
    if man is None:
        own = _legacy_files(folder)
        return own if names is None else own & set(names)
    listed = man["files"] if names is None else {n: man["files"][n] for n in names if n in man["files"]}
    return {n for n, r in listed.items() if r != "captured" and not changed_since_written(folder / n, man)}


def prepare_output_dir(folder, writer: str, *, force: bool = False, option: str | None = None,
                       create: bool = True) -> Path:
    """Make ``folder`` ready for ``writer``'s outputs (``"simulate"``, ``"patterns"``, ``"study"`` ...).

    A missing or empty folder is created and gets a manifest.  A folder this writer wrote before (its
    manifest, or an older procam's patterns.json, lists everything in it) is reused.  Anything else --
    files procam did not write, or another command's output -- is refused with one line naming the folder
    and what it holds, unless ``force``; even then nothing procam did not write is overwritten or deleted
    (:func:`check_overwrite`).  Temporary files of dead processes are removed.  Without ``create`` the
    folder is only checked (a missing one: that it can be created), not created.

    Raises :class:`OutputError`.
    """
    folder = Path(folder)
    label = f"{option} {folder}" if option else str(folder)
    if folder.exists() and not folder.is_dir():
        raise OutputError(f"{label}: exists and is not a folder; give a folder for the outputs")
    if not folder.exists() and not create:
        parent = folder.parent
        while not parent.exists() and parent != parent.parent:
            parent = parent.parent
        if not parent.is_dir():
            raise OutputError(f"{label}: cannot create the folder ({parent} is not a folder)")
        check_writable_dir(parent, label)
        return folder
    new = not folder.exists()
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise OutputError(f"{label}: cannot create the folder ({e.strerror or e}); check the path and its "
                          "permissions") from None
    if new and read_manifest(folder.parent) is not None:  # a folder inside procam's output folder is procam's
        record_files(folder.parent, {folder.name: "output"})
    check_writable_dir(folder, label)
    remove_stale_temps(folder)
    visible = _visible(folder)
    man = read_manifest(folder)
    listed = set(man["files"]) if man is not None else _legacy_files(folder)
    foreign = [n for n in visible if n not in listed]
    legacy = "simulate" if (folder / "truth.json").exists() else "patterns"
    if man is not None:
        other = man.get("writer") != writer
        captured = any(r == "captured" for r in man["files"].values())
    else:
        other = bool(listed) and writer != legacy
        captured = False
    if captured:
        raise OutputError(f"{label}: the folder holds a camera capture; give a new or empty folder (procam never "
                          "writes into a capture)")
    if visible and not force:
        if foreign:
            raise OutputError(
                f"{label}: the folder holds {len(foreign)} file(s) procam did not write ({_listing(foreign)}); give "
                "a new or empty folder, or add --force to write next to them (procam never overwrites or deletes "
                "files it did not write)")
        if other:
            what = man.get("writer") if man is not None else legacy
            raise OutputError(f"{label}: the folder holds the output of 'procam {what}'; give a new or empty folder, "
                              "or add --force to write into it")
    if man is None and create:
        doc = {"format": formats.MANIFEST_FORMAT, "version": 1, "writer": legacy if listed else writer,
               "files": {n: ("frame" if Path(n).suffix.lower() in IMAGE_EXTS and n not in ("patterns.json",)
                             else "sidecar") for n in sorted(listed & set(visible))}}
        write_manifest(folder, doc)
    return folder


def check_overwrite(folder, names, option: str | None = None) -> None:
    """Raise :class:`OutputError` when writing ``names`` into ``folder`` would overwrite a file procam did
    not write (or a camera frame)."""
    folder = Path(folder)
    names = [n for n in names if (folder / n).exists()]
    ok = replaceable(folder, names)
    clash = [n for n in names if n not in ok]
    if clash:
        label = f"{option} {folder}" if option else str(folder)
        man = read_manifest(folder)
        edited = [n for n in clash if changed_since_written(folder / n, man)]
        if edited:
            raise OutputError(f"{label}: writing here would overwrite {len(edited)} file(s) changed since procam "
                              f"wrote them ({_listing(sorted(edited, key=natural_key))}: an edit is the user's); "
                              "move them away first, or give a new or empty folder")
        raise OutputError(f"{label}: writing here would overwrite {len(clash)} file(s) procam did not write "
                          f"({_listing(sorted(clash, key=natural_key))}); give a new or empty folder")


def remove_listed(folder, names) -> list[Path]:
    """Delete ``names`` from ``folder`` if its manifest lists them as procam's (and not as camera frames),
    and unlist them; anything else is left alone.  Returns the deleted paths."""
    folder = Path(folder)
    ok = replaceable(folder, names)
    gone = []
    for n in names:
        if n in ok and (folder / n).is_file() and not (folder / n).is_symlink():
            (folder / n).unlink()
            gone.append(folder / n)
    if gone:
        unlist_files(folder, [p.name for p in gone])
    return gone


def why_not_writable(folder, need_bytes: int = 1 << 20) -> str | None:
    """Why ``folder`` (an existing folder) cannot take a new file -- read-only, no permission, less than
    ``need_bytes`` free -- or None when it can (a probe file is created and removed)."""
    import shutil
    import tempfile

    try:
        fd, probe = tempfile.mkstemp(prefix=".procam-probe-", dir=folder)
        os.close(fd)
        os.unlink(probe)
    except OSError as e:
        return {errno.EROFS: "the file system is read-only", errno.EACCES: "no permission to write there",
                errno.EPERM: "no permission to write there", errno.ENOSPC: "the disk is full",
                errno.EDQUOT: "the disk quota is exhausted"}.get(e.errno, e.strerror or str(e))
    try:
        free = shutil.disk_usage(folder).free
    except OSError:
        return None
    if free < need_bytes:
        return f"only {fmt_bytes(free)} free on the disk, about {fmt_bytes(need_bytes)} needed"
    return None


def check_writable_dir(folder, label: str | None = None, need_bytes: int = 1 << 20) -> None:
    """Raise :class:`OutputError` when ``folder`` (an existing folder) cannot take a new file
    (:func:`why_not_writable`)."""
    why = why_not_writable(folder, need_bytes)
    if why is not None:
        raise OutputError(f"{label or folder}: cannot write into {folder} ({why}); choose another place")


#: The files of a capture or rig folder its readers need besides its frames (and the manifest naming them).
INPUT_FILES = ("rig.json", "truth.json", "patterns.json", "capture.json", MANIFEST)


def _clash(path, inputs, inside) -> str | None:
    """The words for the first of ``inputs`` that ``path`` is, after resolving symbolic links, or that
    ``inside(target, input, resolved input)`` names (the loop of :func:`input_clash` and :func:`folder_clash`)."""
    try:
        target = Path(path).resolve()
    except (OSError, RuntimeError):
        return None
    for p in inputs:
        try:
            src = Path(p).resolve()
        except (OSError, RuntimeError):
            continue
        if target == src:
            return ("is also an input of this command" if Path(p) == Path(path) else
                    f"is {p}, an input of this command (symbolic links followed)")
        words = inside(target, p, src)
        if words:
            return words
    return None


def input_clash(path: Path, inputs) -> str | None:
    """Which of the command's ``inputs`` (files and pose or rig folders) writing ``path`` would change (words for a
    message: ``'is rig.json of rig1, an input of this command'``), after
    resolving symbolic links (of the file and of its folders), or None: an input file itself, or inside an input
    folder (at any depth) one of :data:`INPUT_FILES` or a file its folder's manifest lists as a frame, camera
    frame or side file -- whether it exists yet or not."""
    def needed(target, p, src):
        if not (src.is_dir() and src in target.parents):
            return None
        man = read_manifest(target.parent)
        role = man["files"].get(target.name) if man is not None else None
        if target.name in INPUT_FILES or role in ("frame", "captured", "sidecar"):
            what = {"frame": "a frame", "captured": "a captured frame"}.get(role, target.name)
            return f"is {what} of {p}, an input of this command"
        return None

    return _clash(path, inputs, needed)


def folder_clash(folder: Path, inputs) -> str | None:
    """Which of the command's ``inputs`` writing into the output ``folder`` would change (words for a message), after
    resolving symbolic links, or None: ``folder`` is an input folder, or a capture folder inside one (a rig pose's
    pair folder), whose readers would take the files written there for its own."""
    def capture_inside(target, p, src):
        man = read_manifest(target)
        holds_frames = (man is not None and any(r in ("frame", "captured") for r in man["files"].values())) or any(
            (target / n).is_file() for n in ("patterns.json", "capture.json", "rig.json"))
        return f"is a capture folder of {p}, an input of this command" if src in target.parents and holds_frames \
            else None

    return _clash(folder, inputs, capture_inside)
