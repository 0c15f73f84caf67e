"""Reading capture images (the bottom floor): one file as OpenCV reads it, a pose's files into one stack, a PNG's
size from its header.

Images are read with OpenCV (PNG, JPEG, TIFF, BMP, PGM/PPM, WebP), 8- or 16-bit; the PNGs capture scripts write
(OpenCV's ``imwrite``: grey or colour, rows under one filter) are decoded by :mod:`procam.io.png`, to the same
array in about half the time.  Colour images are converted to grey with OpenCV's ``COLOR_BGR2GRAY`` (ITU-R BT.601
luma, ``0.299 R + 0.587 G + 0.114 B``); an alpha channel is dropped.  PNG and JPEG files are checked for truncation
and damage before they are decoded (so a broken file is named in one line, and libpng prints nothing).  Which files
of a folder are images, and their order, is :mod:`procam.io.files`'s.
"""

from __future__ import annotations

import os
import re
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from ..errors import CaptureError
from .files import not_a_file
from .image_marks import PNG_SIGNATURE


def check_image_bytes(path, data: bytes) -> list | None:
    """Raise :class:`CaptureError` naming ``path`` when a PNG or JPEG is truncated or damaged.

    PNG: the signature, every chunk's length and CRC, and the final IEND chunk (:func:`procam.io.png.chunks`,
    whose list of the chunks is returned for a PNG; None for another format).  JPEG: the start (FFD8) and end
    (FFD9) markers.  Other formats are left to the decoder.
    """
    what = parts = None
    if data[:8] == PNG_SIGNATURE:
        from . import png

        parts, what = png.chunks(data)
    elif data[:2] == b"\xff\xd8" and b"\xff\xd9" not in data[-4096:]:
        what = "is truncated (no JPEG end marker: the file was not written completely)"
    if what is not None:
        raise CaptureError(f"{path}: {what}; re-save or re-capture it, or remove it from the folder")
    return parts


def read_image(path, gray: bool = True, into: np.ndarray | None = None) -> np.ndarray:
    """Read one image as ``uint8`` or ``uint16``, (H, W) when ``gray`` else as stored.

    ``into``: an (H, W) ``uint8`` array (a frame of a stack) that an 8-bit grey PNG of that size is decoded into
    and returned (``into`` itself), saving a copy; any other image comes back as a new array.

    Raises :class:`CaptureError` naming the file when it cannot be read or has an unsupported type.
    """
    import cv2

    path = Path(path)
    raw = _file_bytes(path)
    parts = check_image_bytes(path, raw)
    img = None
    if parts:  # the common PNG, decoded faster than OpenCV does and to the same array (procam.io.png)
        from . import png

        try:
            img = png.decode(raw, parts, into)
        except png.Damaged as e:
            raise CaptureError(f"{path}: is damaged ({e}); re-save or re-capture it, or remove it from the folder") \
                from None
    if img is None and raw:
        try:
            img = cv2.imdecode(np.frombuffer(raw, dtype=np.uint8), cv2.IMREAD_UNCHANGED)
        except cv2.error as e:  # OpenCV refuses a header over its limits by an assertion, not None
            raise CaptureError(f"{path}: cannot be read as an image ({_opencv_says(e)}); remove it from the folder "
                               "or re-save it as PNG") from None
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


def _opencv_says(e) -> str:
    """What an OpenCV error says is wrong, without its source file, line and function: ``OpenCV: pixels <=
    CV_IO_MAX_IMAGE_PIXELS (assertion failed)``."""
    text = " ".join(str(e).split())
    m = re.search(r"error: \(-?\d+:([^)]*)\)\s*(.*?)(?:\s+in function\b.*)?$", text)
    return f"OpenCV: {m.group(2)} ({m.group(1).lower()})" if m else f"OpenCV: {text}"


#: ``os.open`` flags of an image read: not blocking, so a named pipe given as an image is refused, not waited on
_READ_FLAGS = os.O_RDONLY | getattr(os, "O_BINARY", 0) | getattr(os, "O_NONBLOCK", 0)


def _open_image(path: Path) -> tuple[int, int]:
    """``(descriptor, size in bytes)`` of the image file ``path``, opened without blocking (a named pipe named like an
    image is refused, not waited on); the caller closes it.  Raises :class:`CaptureError` naming the file when it is
    not a readable regular file."""
    import stat

    try:
        fd = os.open(path, _READ_FLAGS)
    except OSError as e:
        if not path.is_file():
            raise CaptureError(f"{path}: {not_a_file(path)}") from None
        raise CaptureError(f"{path}: cannot be read ({e.strerror or e}); check its permissions") from None
    st = os.fstat(fd)
    if not stat.S_ISREG(st.st_mode):
        os.close(fd)
        raise CaptureError(f"{path}: {not_a_file(path)}")
    return fd, st.st_size


def _file_bytes(path: Path) -> bytes:
    """The contents of the image file ``path``, read in four system calls (open, size, read, close).  Each lets the
    interpreter lock go, and a reader thread then waits up to Python's switch interval to get it back while another
    thread runs Python: ``Path.read_bytes`` (with the check that it is a file) made eight.  Raises
    :class:`CaptureError` naming the file when it is not a readable regular file."""
    fd, size = _open_image(path)
    try:
        data = os.read(fd, size)  # a file still being written is read as it was: a truncated PNG says so
        while len(data) < size:  # a short read (over 2 GB, or a file that shrank)
            more = os.read(fd, size - len(data))
            if not more:
                break
            data += more
        return data
    except OSError as e:
        raise CaptureError(f"{path}: cannot be read ({e.strerror or e}); check its permissions") from None
    finally:
        os.close(fd)


def png_header(path) -> tuple[int, int, int] | None:
    """``(height, width, bytes per sample)`` of a PNG file from its IHDR chunk, without decoding it; None for
    another format or a header that cannot be read (:func:`read_image` then says what is wrong)."""
    try:
        fd, _ = _open_image(Path(path))
    except CaptureError:
        return None
    try:
        head = os.read(fd, 26)
    except OSError:
        return None
    finally:
        os.close(fd)
    if len(head) < 26 or head[:8] != b"\x89PNG\r\n\x1a\n" or head[12:16] != b"IHDR":
        return None
    w, h = int.from_bytes(head[16:20], "big"), int.from_bytes(head[20:24], "big")
    return (h, w, 2 if head[24] == 16 else 1) if w > 0 and h > 0 else None


def read_images(files, gray: bool = True, threads: int | None = None, out: np.ndarray | None = None) -> np.ndarray:
    """Read ``files`` into one array (K, H, W) of a single dtype.

    Images are read in parallel threads (OpenCV releases the GIL).  All images must have the
    same size and bit depth: otherwise :class:`CaptureError` names the first one that differs.  ``out``: a
    (K, H, W) array to read into and return (e.g. shared memory), whose frame size and type every image must have.
    """
    files = [Path(f) for f in files]
    if not files:
        raise CaptureError("no image files given")
    if out is None:
        first = read_image(files[0], gray)
        stack = np.empty((len(files),) + first.shape, dtype=first.dtype)
        stack[0] = first
        start = 1
    else:
        if len(out) != len(files):
            raise ValueError(f"out holds {len(out)} frames, {len(files)} files given")
        stack, start = out, 0
    shape, dtype = stack.shape[1:], stack.dtype
    like = files[0].name if out is None else "the stack read into"  # what every frame must match

    def load(i):
        slot = stack[i]
        img = read_image(files[i], gray, slot)
        if img is slot:  # decoded in place
            return
        if img.shape != shape:
            raise CaptureError(f"{files[i]}: size {img.shape[1]}x{img.shape[0]} differs from {like} "
                               f"({shape[1]}x{shape[0]}); all images of a pose must come from one "
                               "camera at one resolution")
        if img.dtype != dtype:
            raise CaptureError(f"{files[i]}: {img.dtype.itemsize * 8}-bit image among "
                               f"{dtype.itemsize * 8}-bit ones ({like}); capture all frames at one bit depth")
        stack[i] = img

    n = threads if threads is not None else min(4, os.cpu_count() or 1)
    if n > 1 and len(files) - start > 1:
        with ThreadPoolExecutor(n) as ex:
            list(ex.map(load, range(start, len(files))))
    else:
        for i in range(start, len(files)):
            load(i)
    return stack
