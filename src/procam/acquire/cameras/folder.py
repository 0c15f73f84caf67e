"""Cameras whose own software saves each shot into a folder (DSLR tethering, vendor apps): the folder watch
(:class:`FolderWatchCamera`).
"""

from __future__ import annotations

import time
from pathlib import Path

from ...errors import ProcamError
from .base import Frame, _Camera, to_gray


_PARTIAL_SUFFIXES = {".part", ".partial", ".tmp", ".crdownload", ".download", ".filepart"}


class FolderWatchCamera(_Camera):
    """A camera whose own software saves each shot into a folder.

    After each pattern is shown (:meth:`arm`) every file already in the folder is old; :meth:`grab`
    waits for the next new image file (extensions as :data:`procam.io.IMAGE_EXTS`), lets it grow
    until its size stays the same for ``stable_s`` and it decodes, and returns it.  Hidden files,
    ``~`` files and download/partial suffixes are ignored.  The files are left where they are.

    Parameters
    ----------
    folder : the folder the camera software saves into (must exist).
    timeout_s : how long :meth:`grab` waits for a new file.
    poll_s : polling period.
    stable_s : the time a file's size must stay unchanged before it is read.
    """

    def __init__(self, folder, timeout_s: float = 60.0, poll_s: float = 0.05, stable_s: float = 0.2):
        self.folder = Path(folder)
        self.timeout_s = float(timeout_s)
        self.poll_s = float(poll_s)
        self.stable_s = float(stable_s)
        self.name = f"folder:{self.folder}"
        self.streaming = False
        self._seen: set[str] = set()
        self._taken: list[str] = []

    def _candidates(self) -> list[Path]:
        from ...io.files import IMAGE_EXTS

        try:
            entries = list(self.folder.iterdir())
        except OSError as e:
            raise ProcamError(f"{self.name}: cannot read the folder ({e.strerror or e})") from None
        out = []
        for p in entries:
            n = p.name
            if n.startswith((".", "~")) or p.suffix.lower() in _PARTIAL_SUFFIXES or p.suffix.lower() not in IMAGE_EXTS:
                continue
            out.append(p)
        return out

    def open(self):
        if not self.folder.is_dir():
            raise ProcamError(f"{self.name}: no such folder; give the folder your camera software saves into")
        self.arm()
        return self

    def arm(self):
        self._seen = {p.name for p in self._candidates()}

    def grab(self) -> Frame:
        from ...io.images import read_image

        deadline = time.monotonic() + self.timeout_s
        sizes: dict[str, tuple[int, float]] = {}
        while True:
            now = time.monotonic()
            new = []
            for p in self._candidates():
                if p.name in self._seen:
                    continue
                try:
                    st = p.stat()
                except OSError:
                    continue
                new.append((st.st_mtime, p, st.st_size))
            for _, p, size in sorted(new, key=lambda t: (t[0], t[1].name)):
                prev = sizes.get(p.name)
                if prev is None or prev[0] != size:
                    sizes[p.name] = (size, now)
                    continue
                if size == 0 or now - prev[1] < self.stable_s:
                    continue
                try:
                    img = read_image(p)
                except ProcamError:
                    continue  # still being written, or not an image: wait for the next poll
                self._seen.add(p.name)
                self._taken.append(p.name)
                return Frame(to_gray(img), now, {"source": self.name, "file": str(p)})
            if now >= deadline:
                raise ProcamError(f"{self.name}: no new image within {self.timeout_s:g} s; check that the camera "
                                  "software saves every shot into this folder as JPEG/PNG/TIFF (files already there "
                                  "are ignored)")
            time.sleep(self.poll_s)

    def describe(self) -> dict:
        return {"backend": "folder", "folder": str(self.folder), "timeout_s": self.timeout_s,
                "files": list(self._taken), "settings": {},
                "notes": ["exposure and gain are set in the camera's own software"]}
