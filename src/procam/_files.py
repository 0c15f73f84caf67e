"""File plumbing (the bottom floor): image reads, natural sort, JSON side files, atomic writes.

Images are read with OpenCV (PNG, JPEG, TIFF, BMP, PGM/PPM, WebP), 8- or 16-bit.
Colour images are converted to grey with OpenCV's ``COLOR_BGR2GRAY`` (ITU-R BT.601 luma,
``0.299 R + 0.587 G + 0.114 B``); an alpha channel is dropped.  File names are sorted
naturally (``img2`` before ``img10``); files that are not images by extension
(``truth.json``, ``patterns.json``, notes) are ignored.
"""

from __future__ import annotations

import json
import os
import re
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from .errors import CaptureError

IMAGE_EXTS = {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp", ".pgm", ".ppm", ".pnm", ".webp", ".jp2"}


def natural_key(name: str):
    """Sort key that orders embedded numbers numerically (``img2`` < ``img10``)."""
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", str(name))]


def list_images(folder) -> list[Path]:
    """Image files in ``folder`` in natural order.

    Raises :class:`CaptureError` if the folder does not exist, is not a folder, or holds no images.
    """
    folder = Path(folder)
    if not folder.exists():
        raise CaptureError(f"{folder}: no such folder; give the folder that holds one pose's captured images")
    if not folder.is_dir():
        raise CaptureError(f"{folder}: not a folder; give the folder that holds one pose's captured images")
    files = [p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_EXTS
             and not p.name.startswith(".")]
    if not files:
        others = sorted(p.name for p in folder.iterdir())
        hint = f" (it holds: {', '.join(others[:5])}{', ...' if len(others) > 5 else ''})" if others else " (it is empty)"
        raise CaptureError(f"{folder}: no images found{hint}; expected PNG/JPEG/TIFF/BMP captures of the pattern sequence")
    return sorted(files, key=lambda p: natural_key(p.name))


def read_image(path, gray: bool = True) -> np.ndarray:
    """Read one image as ``uint8`` or ``uint16``, (H, W) when ``gray`` else as stored.

    Raises :class:`CaptureError` naming the file when it cannot be read or has an unsupported type.
    """
    import cv2

    path = Path(path)
    if path.is_dir():
        raise CaptureError(f"{path}: is a folder, not an image file")
    if not path.exists():
        raise CaptureError(f"{path}: no such file")
    data = np.fromfile(str(path), dtype=np.uint8)
    img = cv2.imdecode(data, cv2.IMREAD_UNCHANGED) if data is not None and data.size else None
    if img is None:
        raise CaptureError(f"{path}: cannot be read as an image (corrupt, empty or not an image); "
                           "remove it from the folder or re-save it as PNG")
    if img.dtype not in (np.uint8, np.uint16):
        raise CaptureError(f"{path}: pixel type {img.dtype} is not supported; save captures as 8- or 16-bit images")
    if gray and img.ndim == 3:
        ch = img.shape[2]
        if ch == 1:
            img = img[:, :, 0]
        elif ch == 4:
            img = cv2.cvtColor(img, cv2.COLOR_BGRA2GRAY)
        elif ch == 3:
            img = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
        else:
            raise CaptureError(f"{path}: {ch} channels are not supported; save as grey or colour (BGR) images")
    return img


def read_images(files, gray: bool = True, threads: int | None = None) -> np.ndarray:
    """Read ``files`` into one array (K, H, W) of a single dtype.

    Images are read in parallel threads (OpenCV releases the GIL).  All images must have the
    same size and bit depth: otherwise :class:`CaptureError` names the first one that differs.
    """
    files = [Path(f) for f in files]
    if not files:
        raise CaptureError("no image files given")
    first = read_image(files[0], gray)
    stack = np.empty((len(files),) + first.shape, dtype=first.dtype)
    stack[0] = first

    def load(i):
        img = read_image(files[i], gray)
        if img.shape != first.shape:
            raise CaptureError(f"{files[i]}: size {img.shape[1]}x{img.shape[0]} differs from {files[0].name} "
                               f"({first.shape[1]}x{first.shape[0]}); all images of a pose must come from one "
                               "camera at one resolution")
        if img.dtype != first.dtype:
            raise CaptureError(f"{files[i]}: {img.dtype.itemsize * 8}-bit image among "
                               f"{first.dtype.itemsize * 8}-bit ones ({files[0].name}); capture all frames at one bit depth")
        stack[i] = img

    n = threads if threads is not None else min(4, os.cpu_count() or 1)
    if n > 1 and len(files) > 2:
        with ThreadPoolExecutor(n) as ex:
            list(ex.map(load, range(1, len(files))))
    else:
        for i in range(1, len(files)):
            load(i)
    return stack


def read_sidecar(folder, name: str = "patterns.json") -> dict | None:
    """The JSON file ``name`` in ``folder`` (e.g. written by ``procam patterns``/``simulate``), or None."""
    path = Path(folder) / name
    if not path.is_file():
        return None
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError) as e:
        raise CaptureError(f"{path}: not valid JSON ({e}); fix or delete it") from None


@contextmanager
def atomic_path(path):
    """Yield a temporary path next to ``path``; on success rename it to ``path``.

    On error the temporary file is removed, so no half-written output is left behind.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.tmp{os.getpid()}{path.suffix}")
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def write_text(path, text: str) -> Path:
    """Write ``text`` to ``path`` atomically."""
    with atomic_path(path) as tmp:
        Path(tmp).write_text(text)
    return Path(path)


def write_image(path, img: np.ndarray) -> Path:
    """Write an image atomically with OpenCV (format from the extension)."""
    import cv2

    path = Path(path)
    with atomic_path(path) as tmp:
        ok, buf = cv2.imencode(path.suffix, img)
        if not ok:
            raise CaptureError(f"{path}: could not encode image")
        Path(tmp).write_bytes(buf.tobytes())
    return path

def full_scale_of(stack: np.ndarray) -> float:
    """Full-scale value of a stack: 255 for uint8; for uint16 the smallest 2^b - 1 (b in 10, 12, 14, 16)
    that holds its maximum."""
    if stack.dtype == np.uint8:
        return 255.0
    mx = int(stack.max())
    for bits in (10, 12, 14, 16):
        if mx <= 2**bits - 1:
            return float(2**bits - 1)
    return 65535.0

def to_jsonable(obj):
    """JSON-ready copy of ``obj``: numpy arrays/scalars -> lists/numbers, NaN/inf -> None, tuples -> lists,
    other objects -> str."""
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        return v if np.isfinite(v) else None
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    if obj is None or isinstance(obj, (str, int, bool)):
        return obj
    return str(obj)
