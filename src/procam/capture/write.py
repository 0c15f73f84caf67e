"""Writing a capture folder: a pattern or capture sequence -> zero-padded PNGs plus ``patterns.json``
(:func:`write_sequence`).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np

from .. import _files, patterns


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
    pat = re.compile(re.escape(prefix) + r"\d+\.png")
    man = _files.read_manifest(out)
    listed = {n for n, r in man["files"].items() if r == "frame"} if man is not None else set()
    stale = sorted(n for n in listed if pat.fullmatch(n) and n not in keep)
    return _files.remove_listed(out, stale)


def sequence_names(ps: patterns.PatternSet, prefix: str = "") -> list[str]:
    """The image names :func:`write_sequence` gives a sequence: ``{prefix}00.png`` ... (zero-padded)."""
    digits = max(2, len(str(ps.count - 1)))
    return [f"{prefix}{i:0{digits}d}.png" for i in range(ps.count)]


def check_sequence_dir(out_dir, ps: patterns.PatternSet, prefix: str = "", *, writer: str = "patterns",
                       force: bool = False, extra=None, option: str | None = None) -> tuple[list[str], list[str]]:
    """Check, before any work and without writing anything, that :func:`write_sequence` may write ``ps`` into
    ``out_dir`` (:func:`procam._files.prepare_output_dir` without creating it, and no file procam did not write
    would be overwritten).  Returns (image names, side-file names); raises
    :class:`~procam.errors.OutputError`."""
    _files.prepare_output_dir(out_dir, writer, force=force, option=option, create=False)
    names = sequence_names(ps, prefix)
    sidecars = ["patterns.json", *(extra or {})]
    _files.check_overwrite(out_dir, names + sidecars, option)
    return names, sidecars


def write_sequence(out_dir, stack, ps: patterns.PatternSet, prefix: str = "", *, writer: str = "patterns",
                   force: bool = False, extra_files: dict | None = None) -> list[Path]:
    """Write ``stack`` as zero-padded PNGs plus ``patterns.json`` into ``out_dir``.

    ``out_dir`` must be new, empty, or ``writer``'s own earlier output (its manifest lists everything in
    it); ``force`` writes into another folder, but never over a file procam did not write
    (:func:`procam._files.prepare_output_dir`).  The names are listed in the folder's manifest before the
    files are written; each file is written under a hidden temporary name and renamed
    (:func:`procam._files.write_image`), so an interrupted run leaves no half-written image.
    ``{prefix}NN.png`` frames of an earlier, longer sequence that the manifest lists are deleted
    (:func:`remove_stale`).

    Parameters
    ----------
    out_dir : the folder (created if missing).
    stack : (K, H, W) uint8/uint16 images, or any sequence of K such (H, W) images (e.g. a generator,
        so a large sequence is never in memory at once).
    ps : the pattern set (K = ``ps.count``).
    prefix : file-name prefix of the images.
    writer : the command writing (recorded in the manifest).
    force : write into a folder that holds other files (see above).
    extra_files : ``{name: text}`` written with patterns.json (e.g. the simulator's truth.json).

    Returns
    -------
    The image paths.  Raises :class:`~procam.errors.OutputError` (one line) when the folder is refused.
    """
    names, sidecars = check_sequence_dir(out_dir, ps, prefix, writer=writer, force=force, extra=extra_files)
    out = _files.prepare_output_dir(out_dir, writer, force=force)
    _files.record_files(out, {**{n: "frame" for n in names}, **{n: "sidecar" for n in sidecars}}, writer)
    paths = []
    for name, img in zip(names, stack):
        paths.append(_files.write_image(out / name, np.asarray(img), record=False))
    if len(paths) != ps.count:
        raise ValueError(f"the sequence has {ps.count} images, got {len(paths)}")
    remove_stale(out, paths, prefix)
    meta = ps.to_dict()
    meta["files"] = [p.name for p in paths]
    _files.write_text(out / "patterns.json", json.dumps(meta, indent=2), record=False)
    for name, text in (extra_files or {}).items():
        _files.write_text(out / name, text, record=False)
    return paths
