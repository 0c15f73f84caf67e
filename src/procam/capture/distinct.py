"""One capture seen twice: a pose folder, a rig's pair folder or a device's frames given again under another name.

A link (``right/`` a symlink of ``left/``), a copy, or one folder named twice on the command line would make procam
calibrate a device against itself: two projectors 0.00 mm apart, a multi-pose calibration that counts one pose
twice, each with a verdict of good.  Two folders are the same capture when they are **the same folder** once links
are resolved, or when they hold **the same frames**: the image files, in their natural order, byte for byte (their
sizes are compared first, so frames are read and hashed only when the sizes of two folders agree).

Failure mode: :class:`~procam.errors.CaptureError` with one line naming both folders and why they are one capture.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

from ..errors import CaptureError
from ..io.files import IMAGE_EXTS, natural_key

__all__ = ["refuse_repeats"]


def _frames(folder: Path) -> list[Path]:
    """The image files of ``folder`` (its frames) in natural order; [] when it has none or cannot be listed."""
    try:
        files = [p for p in folder.iterdir() if p.suffix.lower() in IMAGE_EXTS and not p.name.startswith(".")
                 and p.is_file()]
    except OSError:
        return []
    return sorted(files, key=lambda p: natural_key(p.name))


def _digest(files) -> str:
    h = hashlib.blake2b(digest_size=32)
    for p in files:
        with open(p, "rb") as f:
            while chunk := f.read(1 << 22):
                h.update(chunk)
        h.update(b"\0frame\0")
    return h.hexdigest()


def refuse_repeats(folders, what: str = "pose folder", fix: str = "give each pose once") -> None:
    """Refuse two of ``folders`` that are one capture (module docstring): a :class:`CaptureError` naming both,
    ``what`` they are (``"pose folder"``, ``"pair folder"``) and ``fix``.  Folders that hold no frames are compared
    by their resolved path only (the reader then says what is missing)."""
    seen: dict = {}
    by_sizes: dict = {}
    for folder in folders:
        f = Path(folder)
        try:
            key = f.resolve()
        except OSError:
            key = f.absolute()
        if key in seen:
            raise CaptureError(f"{f}: this {what} is given twice (also as {seen[key]}: one folder once links are "
                               f"resolved); {fix}")
        seen[key] = f
        frames = _frames(f)
        if not frames:
            continue
        try:
            sizes = tuple(p.stat().st_size for p in frames)
        except OSError:
            continue
        by_sizes.setdefault(sizes, []).append((f, frames))
    for group in by_sizes.values():
        if len(group) < 2:
            continue
        digests: dict = {}
        for f, frames in group:
            d = _digest(frames)
            if d in digests:
                raise CaptureError(f"{f}: this {what} is given twice (also as {digests[d]}: the same {len(frames)} "
                                   f"frames, byte for byte, a copy or a link); {fix}")
            digests[d] = f
