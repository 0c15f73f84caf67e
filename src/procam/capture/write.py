"""The one writer of a capture folder: a sequence of frames -> zero-padded PNGs in sequence order
(``{prefix}00.png`` ..., :func:`sequence_names`), ``patterns.json`` (the pattern set plus the frames' names),
side files, and the folder's manifest (:func:`procam.io.files.record_files`).

:class:`SequenceWriter` writes frame by frame (the capture loop); :func:`write_sequence` writes a whole stack
(``procam patterns``, the simulator).  Two kinds of frames, placed two ways, so that nothing of the user's is
ever overwritten and no half-written folder looks complete:

pattern images and simulator renders (manifest role ``"frame"``)
    into ``out_dir`` as :func:`procam.io.folders.prepare_output_dir` allows it: new, empty, the same writer's
    earlier output, or with ``force`` any folder -- but never over a file procam did not write
    (:func:`check_sequence_dir`).  The manifest lists the names before any file is written; each file is
    written under a hidden temporary name and renamed (:func:`procam.io.files.write_image`), so an interrupted run
    leaves no half-written image; frames of an earlier, longer sequence are deleted (:func:`remove_stale`). When
    done, the manifest records each file's digest: a rerun refuses to overwrite or delete a file the user edited
    since (:func:`procam.io.files.changed_since_written`); each file's old digest is dropped just before it is
    replaced, so an interrupted run leaves the files it replaced replaceable and the others protected.
a camera's frames (manifest role ``"captured"``, which no procam writer replaces or deletes)
    ``out_dir`` must not exist or be empty (:func:`check_out_dir`).  Everything is written into a hidden
    sibling folder ``.NAME.partial-PID``, which gets its manifest last and is renamed to ``NAME`` only when
    complete: an interrupted or failed capture leaves no folder that looks complete (the partial one is
    removed, or kept hidden and without JSON for inspection).

Side files (``patterns.json`` and e.g. ``truth.json``, ``capture.json``) have the role ``"sidecar"``.
"""

from __future__ import annotations

import json
import os
import re
import shutil
from pathlib import Path

import numpy as np

from .. import patterns
from ..io import files as _files
from ..io import folders
from ..errors import ProcamError


def remove_stale(out_dir, keep, prefix: str = "") -> list[Path]:
    """Delete the frames of an earlier, longer sequence in ``out_dir`` that are not in ``keep``.

    An earlier run with a longer sequence (e.g. a 1920x1200 projector after a 1024x768 one)
    leaves ``pattern_44.png`` ... behind, which a loader would read as part of the new
    sequence.  Only files the folder's manifest lists as procam's frames are touched (never a file
    procam did not write, nor a camera's frames), and of those only names made of ``prefix``,
    decimal digits and ``.png``.

    Parameters
    ----------
    out_dir : the folder.
    keep : paths (or names) just written.
    prefix : file-name prefix of the sequence (``""`` for a capture folder of ``00.png`` ...).

    Returns
    -------
    list of the deleted paths.
    """
    out = Path(out_dir)
    keep = {Path(p).name for p in keep}
    return folders.remove_listed(out, sorted(n for n in _own_frames(out, prefix) if n not in keep))


def _own_frames(out: Path, prefix: str) -> set[str]:
    """The frames of a sequence of ``prefix`` the folder's manifest lists as procam's (role ``"frame"``; names of
    ``prefix``, decimal digits and ``.png``): what a new sequence of that prefix may replace or remove."""
    pat = re.compile(re.escape(prefix) + r"\d+\.png")
    man = _files.read_manifest(out)
    return {n for n, r in man["files"].items() if r == "frame" and pat.fullmatch(n)} if man is not None else set()


def sequence_names(ps: patterns.PatternSet, prefix: str = "") -> list[str]:
    """The image names :func:`write_sequence` gives a sequence: ``{prefix}00.png`` ... (zero-padded)."""
    digits = max(2, len(str(ps.count - 1)))
    return [f"{prefix}{i:0{digits}d}.png" for i in range(ps.count)]


def check_out_dir(out_dir) -> Path:
    """A capture's folder must not exist, or be an empty folder (procam never writes into a capture)."""
    out = Path(out_dir)
    if out.exists():
        if not out.is_dir():
            raise ProcamError(f"{out}: exists and is not a folder; give a new folder for the capture")
        if any(out.iterdir()):
            raise ProcamError(f"{out}: exists and is not empty; give a new folder (procam never writes into an "
                              "existing capture)")
    return out


def check_sequence_dir(out_dir, ps: patterns.PatternSet, prefix: str = "", *, writer: str = "patterns",
                       force: bool = False, extra=None, option: str | None = None) -> tuple[list[str], list[str]]:
    """Check, before any work and without writing anything, that :func:`write_sequence` may write ``ps`` into
    ``out_dir`` (:func:`procam.io.folders.prepare_output_dir` without creating it, and no file procam did not write
    would be overwritten).  Returns (image names, side-file names); raises
    :class:`~procam.errors.OutputError`."""
    folders.prepare_output_dir(out_dir, writer, force=force, option=option, create=False)
    names = sequence_names(ps, prefix)
    sidecars = ["patterns.json", *(extra or {})]
    folders.check_overwrite(out_dir, names + sidecars, option)
    man = _files.read_manifest(out_dir)
    edited = sorted(n for n in _own_frames(Path(out_dir), prefix) - set(names)
                    if _files.changed_since_written(Path(out_dir) / n, man))
    if edited:
        from ..errors import OutputError

        where = f"{option} {out_dir}" if option else str(out_dir)
        raise OutputError(f"{where}: writing {names[0]} ... here would remove {len(edited)} frame(s) of the "
                          f"sequence before, changed since procam wrote them ({', '.join(edited[:3])}"
                          f"{' ...' if len(edited) > 3 else ''}: an edit is the user's); move them away first, or "
                          "write into another folder")
    orphans = _other_sequence(Path(out_dir), names, prefix)
    if orphans:
        from ..errors import OutputError

        where = f"{option} {out_dir}" if option else str(out_dir)
        raise OutputError(f"{where}: holds another sequence ({len(orphans)} frames {orphans[0]} ... that its "
                          f"patterns.json describes); writing {names[0]} ... here would replace that description "
                          "and leave its frames beside the new ones (even with --force); write into another folder")
    return names, sidecars


def _other_sequence(out: Path, names, prefix: str) -> list[str]:
    """The frames of the sequence ``out/patterns.json`` describes that writing ``names`` would neither replace nor
    remove as stale (:func:`remove_stale`): another sequence (a capture, a simulator render), whose description the
    new ``patterns.json`` would replace."""
    from ..io.jsonfile import JSONError, load_json

    try:
        listed = load_json(out / "patterns.json").get("files")
    except (OSError, JSONError, ValueError, AttributeError):
        return []  # no sequence's description (check_overwrite has judged the file itself)
    if not isinstance(listed, list):
        return []
    replaced = set(names) | _own_frames(out, prefix)
    return [n for n in listed if isinstance(n, str) and n not in replaced and (out / n).is_file()]


class SequenceWriter:
    """Write one sequence's folder frame by frame (see the module docstring); a context manager.

    Parameters
    ----------
    out_dir : the folder.
    ps : the pattern set (``ps.count`` frames).
    prefix : file-name prefix of the frames.
    writer : the command writing (recorded in the manifest).
    sidecars : names of the side files :meth:`finish` writes besides ``patterns.json``.
    captured : the frames are a camera's (role ``"captured"``: a new folder, written whole or not at all);
        else role ``"frame"``, written into ``out_dir``.
    force : role ``"frame"``: write into a folder that holds other files (never over them).
    keep_failed : role ``"captured"``: keep the partial folder of a failed run, hidden, for inspection.

    Nothing is written before :meth:`open` (``with``), which checks the folder first.  :meth:`add` writes a
    frame, :meth:`finish` the side files (and puts a capture's folder into place).  An error inside the
    ``with`` block removes a capture's partial folder (with ``keep_failed``, a :class:`ProcamError` then
    says where the frames are).
    """

    def __init__(self, out_dir, ps: patterns.PatternSet, prefix: str = "", *, writer: str = "patterns",
                 sidecars=(), captured: bool = False, force: bool = False, keep_failed: bool = False):
        self.out = Path(out_dir)
        self.ps, self.prefix, self.writer = ps, prefix, writer
        self.names = sequence_names(ps, prefix)
        self.sidecars = ["patterns.json", *sidecars]
        self.captured, self.force, self.keep_failed = captured, force, keep_failed
        self.folder: Path | None = None  # where the files go while they are written
        self._paths: list[Path | None] = [None] * ps.count
        self._placed = False  # a capture's folder is complete (renamed into place, or refused the rename)

    def roles(self) -> dict:
        """The manifest's ``{name: role}`` of this sequence's files."""
        frame = "captured" if self.captured else "frame"
        return {**{n: frame for n in self.names}, **{n: "sidecar" for n in self.sidecars}}

    def open(self) -> SequenceWriter:
        if self.captured:
            check_out_dir(self.out)
            self.out.parent.mkdir(parents=True, exist_ok=True)
            self.folder = self.out.parent / f".{self.out.name}.partial-{os.getpid()}"
            self.folder.mkdir()
        else:
            check_sequence_dir(self.out, self.ps, self.prefix, writer=self.writer, force=self.force,
                               extra=self.sidecars[1:])
            self.folder = folders.prepare_output_dir(self.out, self.writer, force=self.force)
            _files.record_files(self.folder, self.roles(), self.writer)
        return self

    def __enter__(self) -> SequenceWriter:
        return self.open()

    def __exit__(self, kind, exc, tb) -> bool:
        if exc is not None:
            self._abandon(exc)
        return False

    def add(self, k: int, image) -> Path:
        """Write frame ``k`` of the sequence, (H, W) uint8/uint16; returns its path (in :attr:`folder`).  Frame
        ``k`` again (a capture's retake) replaces the one this writer wrote."""
        if self._paths[k] is not None:  # its own frame: a frame's mark keeps it from any other writer
            self._paths[k].unlink(missing_ok=True)
            self._paths[k] = None
        path = _files.write_image(self.folder / self.names[k], np.asarray(image), record=False, frame=True)
        self._paths[k] = path
        return path

    def finish(self, texts: dict | None = None) -> list[Path]:
        """Write ``patterns.json`` and the side files ``texts`` (``{name: text}``, the ``sidecars``); a capture's
        folder then gets its manifest and is renamed into place.  Returns the frames' paths in ``out_dir``."""
        written = [p for p in self._paths if p is not None]
        if len(written) != self.ps.count:
            raise ValueError(f"the sequence has {self.ps.count} images, got {len(written)}")
        texts = dict(texts or {})
        if sorted(texts) != sorted(self.sidecars[1:]):
            raise ValueError(f"side files {sorted(texts)} given, {sorted(self.sidecars[1:])} announced")
        if not self.captured:
            remove_stale(self.folder, written, self.prefix)
        meta = self.ps.to_dict()
        meta["files"] = [p.name for p in written]
        _files.write_text(self.folder / "patterns.json", json.dumps(meta, indent=2), record=False)
        for name, text in texts.items():
            _files.write_text(self.folder / name, text, record=False)
        if self.captured:
            _files.record_files(self.folder, self.roles(), writer=self.writer)
            self._place()
        else:  # what procam wrote, so that a rerun tells a user's edit from its own file (each file's old digest
            # went as it was replaced)
            _files.record_files(self.folder, self.roles(), self.writer,
                                digests={n: _files.file_digest(self.folder / n) for n in self.roles()})
        return [self.out / p.name for p in written]

    def _place(self) -> None:
        """Rename a capture's complete partial folder to ``out_dir`` (which must still be missing or empty)."""
        self._placed = True
        if self.out.exists():
            if any(self.out.iterdir()):
                raise ProcamError(f"{self.out}: something was written into it during the capture; the capture is "
                                  f"in {self.folder}")
            self.out.rmdir()
        os.replace(self.folder, self.out)

    def _abandon(self, exc: BaseException) -> None:
        """After an error: remove a capture's partial folder (kept with ``keep_failed``; a complete one always)."""
        if not self.captured or self._placed or self.folder is None or not self.folder.exists():
            return
        if not self.keep_failed:
            shutil.rmtree(self.folder, ignore_errors=True)
        elif isinstance(exc, ProcamError):
            raise type(exc)(f"{exc} — the frames so far are in {self.folder}") from None


def write_sequence(out_dir, stack, ps: patterns.PatternSet, prefix: str = "", *, writer: str = "patterns",
                   force: bool = False, extra_files: dict | None = None) -> list[Path]:
    """Write ``stack`` as zero-padded PNGs plus ``patterns.json`` into ``out_dir`` (role ``"frame"``: see the
    module docstring; :class:`SequenceWriter`).

    Parameters
    ----------
    out_dir : the folder (created if missing).
    stack : (K, H, W) uint8/uint16 images, or any sequence of K such (H, W) images (e.g. a generator,
        so a large sequence is never in memory at once).
    ps : the pattern set (K = ``ps.count``).
    prefix : file-name prefix of the images.
    writer : the command writing (recorded in the manifest).
    force : write into a folder that holds other files (never over a file procam did not write).
    extra_files : ``{name: text}`` written with patterns.json (e.g. the simulator's truth.json).

    Returns
    -------
    The image paths.  Raises :class:`~procam.errors.OutputError` (one line) when the folder is refused.
    """
    with SequenceWriter(out_dir, ps, prefix, writer=writer, sidecars=list(extra_files or {}), force=force) as out:
        for k, img in zip(range(ps.count), stack):
            out.add(k, img)
        return out.finish(extra_files)
