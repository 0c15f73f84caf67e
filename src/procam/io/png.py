"""PNG files read faster than OpenCV reads them: the common kind decoded here, everything else left to OpenCV.

A PNG's pixels are one zlib stream of rows, each row filtered (stored as its difference from a prediction; the
first byte of a row names the filter).  OpenCV's ``imdecode`` hands that to libpng, which inflates the stream
with the zlib OpenCV was built with and undoes the filters byte by byte: about 8 ms for a 1280x1024 grey frame,
so that reading a capture's PNGs is most of a calibration's time.  :func:`decode` does the same work in two
steps that each run several times faster:

* the stream is inflated by ISA-L (the ``isal`` package: about twice zlib's speed) where it is installed, else
  by Python's zlib;
* the filter is undone for the whole image at once.  ``Sub`` (each byte plus the byte one pixel to its left,
  modulo 256) is a running sum along each row, ``Up`` (plus the byte above) a running sum down each column,
  and the low byte of a running sum is the running sum modulo 256: both are the low bytes of differences of
  one ``cv2.integral`` image.

It takes what cameras' capture scripts write (OpenCV's ``imwrite`` filters every row with ``Sub``): 8- or 16-bit
grey or colour, not interlaced, every row under one filter of ``None``, ``Sub`` or ``Up``, and no chunks but
those OpenCV's reader ignores (:data:`IGNORED`).  For anything else (palette, alpha, a transparency chunk, rows
under ``Average`` or ``Paeth`` as Pillow's and most image editors' adaptive filters write, a stream that does
inflates to more than the image's size, image data split by another chunk, a size over libpng's or OpenCV's
limits) :func:`decode` returns None and the caller decodes with OpenCV, so the result is always OpenCV's: the same
array, bit for bit (``tests/test_png.py`` compares every filter, depth and channel count with ``cv2.imdecode``,
and files with bytes changed and chunks moved: whatever decodes here, OpenCV decodes to the same array).  A file
no PNG reader decodes (a zero size, image data that does not inflate or ends early, its checksums right) is
:class:`Damaged`: said in one line, where OpenCV would have let libpng print its own first.
"""

from __future__ import annotations

import struct
import zlib

import numpy as np

try:  # ISA-L's inflate and checksum: the same results as zlib's, in about half the time and less
    from isal import isal_zlib as _inflater
except ImportError:  # pragma: no cover - isal is a dependency where it has wheels
    _inflater = zlib


#: Ancillary chunks OpenCV's PNG reader does not apply to the pixels (``IMREAD_UNCHANGED``): text, time,
#: physical size, colour-space notes.  A chunk not listed here (``tRNS`` adds an alpha channel, ``PLTE``...)
#: leaves the file to OpenCV.
IGNORED = frozenset({b"tEXt", b"zTXt", b"iTXt", b"tIME", b"pHYs", b"gAMA", b"cHRM", b"sRGB", b"iCCP", b"sBIT",
                     b"bKGD"})

#: The largest image (bytes of its filtered rows) decoded here: a header asking for more goes to OpenCV, which
#: has its own limit (a damaged or hostile file must not make this allocate gigabytes).
MAX_BYTES = 1 << 30

_CHANNELS = {0: 1, 2: 3}  # colour type -> channels: grey, RGB
#: Bytes per call of the chunk checksum: zlib's and ISA-L's ``crc32`` keep the interpreter lock up to 5 KB and let
#: it go above.  A PNG writer's image data comes in 8 KB chunks, ~70 a camera frame, and a reader thread that lets
#: the lock go ~70 times a frame waits up to Python's switch interval (5 ms) to get it back each time another
#: thread runs Python (an import, a fit): reading slowed 25-fold beside one busy thread.  Held, the checksums of a
#: frame take 0.08 ms with ISA-L's (0.2 ms with zlib's).
_CRC_PIECE = 4096
_BAD_STREAM = (zlib.error, getattr(_inflater, "error", zlib.error), ValueError, MemoryError)
_NOT_INFLATED = (zlib.error, getattr(_inflater, "error", zlib.error))


class Damaged(ValueError):
    """A PNG whose chunks are whole but whose contents no PNG reader decodes (libpng refuses it too, after printing
    its own lines): the message says what is wrong, after the file's name."""


def chunks(data: bytes) -> tuple[list[tuple[bytes, int, int]], str | None]:
    """Walk the chunks of the PNG ``data`` (its signature already checked) and check each one's CRC.

    Returns ``(chunks, problem)``: ``chunks`` a list of ``(kind, start, end)`` with ``data[start:end]`` the
    chunk's contents, up to IEND; ``problem`` None, or what is wrong in words (a chunk past the end of the data, a
    chunk failing its checksum, no IEND chunk: the file was not written completely).
    """
    pos, n = 8, len(data)
    mv = memoryview(data)
    out = []
    head, stored, crc32, piece = _HEAD.unpack_from, _STORED.unpack_from, _inflater.crc32, _CRC_PIECE
    while pos + 12 <= n:
        length, kind = head(data, pos)
        end = pos + 12 + length
        if end > n:
            return out, f"is truncated ({_name(kind)} ends after the end of the file)"
        crc, i, stop = 0, pos + 4, end - 4  # over the kind and the contents, in pieces (_CRC_PIECE)
        while i < stop:
            crc = crc32(mv[i:min(i + piece, stop)], crc)
            i += piece
        if crc != stored(data, stop)[0]:
            return out, f"is damaged ({_name(kind)} fails its checksum)"
        out.append((kind, pos + 8, stop))
        pos = end
        if kind == b"IEND":
            return out, None
    return out, "is truncated (no end marker: the file was not written completely)"


_HEAD = struct.Struct(">I4s")    # a chunk's length and kind
_STORED = struct.Struct(">I")    # its CRC


def _name(kind: bytes) -> str:
    """A chunk's kind in words for a message: ``IDAT chunk``, or ``a chunk`` when it is not letters."""
    return kind.decode("latin-1") + " chunk" if kind.isalpha() else "a chunk"


def decode(data: bytes, parts: list[tuple[bytes, int, int]], into: np.ndarray | None = None
           ) -> np.ndarray | None:
    """The image of the PNG ``data`` as ``cv2.imdecode(data, cv2.IMREAD_UNCHANGED)`` gives it, or None when it is
    not of the kind decoded here (the module docstring).  Raises :class:`Damaged` for a file libpng refuses too: a
    width or height of 0 (or over 2^31 - 1), image data that does not inflate or ends early.

    ``parts``: its :func:`chunks`, checked.  Returns (H, W) for grey, (H, W, 3) BGR for colour; ``uint8`` or
    ``uint16`` (native byte order).  ``into``: an 8-bit (H, W) array (a frame of a stack) that an 8-bit grey image
    of its size is decoded into and returned (``into`` itself), instead of a new array (any other image ignores it).
    """
    if not parts or parts[0][0] != b"IHDR" or parts[0][2] - parts[0][1] != 13:
        return None
    s = parts[0][1]
    w, h = int.from_bytes(data[s:s + 4], "big"), int.from_bytes(data[s + 4:s + 8], "big")
    depth, ctype, method, filtering, interlace = data[s + 8:s + 13]
    if not (0 < w < 1 << 31 and 0 < h < 1 << 31):  # the PNG standard's sizes: libpng refuses any other
        raise Damaged(f"its header gives a size of {w} x {h} pixels")
    ch = _CHANNELS.get(ctype)
    if ch is None or depth not in (8, 16) or method or filtering or interlace or not _within_limits(w, h):
        return None
    if any(kind not in IGNORED for kind, _, _ in parts[1:] if kind not in (b"IDAT", b"IEND")):
        return None
    bpp = ch * depth // 8
    stride = w * bpp
    size = h * (stride + 1)
    if size > MAX_BYTES:
        return None
    at = [k for k, (kind, _, _) in enumerate(parts) if kind == b"IDAT"]
    if not at or at[-1] - at[0] != len(at) - 1:  # image data split by another chunk: libpng refuses it
        return None
    mv = memoryview(data)
    idat = [mv[parts[k][1]:parts[k][2]] for k in at]
    if not _uniform_start(idat[0], stride):
        return None
    stream = idat[0] if len(idat) == 1 else b"".join(idat)
    try:
        raw = _inflater.decompress(stream, 15, size)
    except _NOT_INFLATED as e:
        if _rows_before_error(stream, size):  # past the rows (the stream's checksum): libpng may read it
            return None
        raise Damaged(f"its image data does not inflate: {e}") from None  # libpng refuses it too
    except _BAD_STREAM:
        return None
    if len(raw) < size:  # libpng: "Not enough image data"
        raise Damaged(f"its image data ends early: {len(raw)} of the {size} bytes of its rows")
    if len(raw) != size:
        return None
    kinds = raw[::stride + 1]  # each row's filter (bytes, not numpy: no call here lets the interpreter lock go)
    kind = kinds[-1]
    if kind == 2:  # Up: the first row's prediction is a row of zeros, so it may say None
        uniform = kinds.count(2, 1) == h - 1 and kinds[0] in (0, 2)
    else:
        uniform = kind in (0, 1) and kinds.count(kind) == h
    if not uniform:
        return None
    rows = np.frombuffer(raw, np.uint8).reshape(h, stride + 1)[:, 1:]
    if not (bpp == 1 and into is not None and into.shape == (h, w) and into.dtype == np.uint8):
        into = None
    if kind == 0:
        out = np.empty((h, stride), np.uint8) if into is None else into
        out[...] = rows
    elif kind == 1:
        out = _running_sum(rows.reshape(h, w, bpp) if bpp > 1 else rows, True, into).reshape(h, stride)
    else:
        out = _running_sum(rows, False, into)
    if into is not None:
        return into
    if depth == 16:
        out = out.view(">u2").astype(np.uint16)
    if ch == 1:
        return out.reshape(h, w)
    return np.ascontiguousarray(out.reshape(h, w, 3)[:, :, ::-1])  # RGB -> OpenCV's BGR


def _within_limits(w: int, h: int) -> bool:
    """Whether OpenCV would decode a ``w`` x ``h`` PNG at all: libpng's limit of 1 000 000 pixels a side and
    OpenCV's of 2^30 pixels (each lowered by OpenCV's ``OPENCV_IO_MAX_IMAGE_WIDTH``, ``..._HEIGHT``,
    ``..._PIXELS`` when set)."""
    import os

    def limit(name: str, default: int) -> int:
        try:
            return min(default, int(os.environ.get(f"OPENCV_IO_MAX_IMAGE_{name}", default)))
        except ValueError:
            return default

    return (0 < w <= limit("WIDTH", 1_000_000) and 0 < h <= limit("HEIGHT", 1_000_000)
            and w * h <= limit("PIXELS", 1 << 30))


def _rows_before_error(stream, size: int) -> bool:
    """Whether the zlib ``stream``, which fails to inflate, gives its ``size`` bytes of rows before it fails (the
    error is in what follows them, as its checksum: libpng stops reading once it has the rows).  Inflated in pieces
    of 4 KB, then the failing piece byte by byte, to see how far it gets; only ever called for a damaged file."""
    def inflated(pieces):
        d, got = zlib.decompressobj(), 0
        for k, piece in enumerate(pieces):
            try:
                got += len(d.decompress(piece))
            except zlib.error:
                return got, k
        return got, None

    data = bytes(stream)
    got, failed = inflated(data[i:i + 4096] for i in range(0, len(data), 4096))
    if failed is not None:
        start = failed * 4096
        got, _ = inflated([data[:start]] + [data[i:i + 1] for i in range(start, min(len(data), start + 4096))])
    return got >= size


def _uniform_start(first, stride: int, rows: int = 8) -> bool:
    """Whether the first ``rows`` rows (inflated from the start of the first IDAT chunk) are under None, Sub or Up:
    an adaptive writer's Paeth or Average rows show there, before the whole image is inflated for nothing."""
    d = zlib.decompressobj()
    try:
        head = d.decompress(first[:4 * rows * (stride + 1) + 64], rows * (stride + 1))
    except zlib.error as e:  # not a stream cut short (that raises nothing): one no PNG reader inflates
        raise Damaged(f"its image data does not inflate: {e}") from None
    return all(b in (0, 1, 2) for b in head[::stride + 1])


def _running_sum(a: np.ndarray, along_rows: bool, into: np.ndarray | None = None) -> np.ndarray:
    """The running sum of the bytes ``a`` (H, W) or (H, W, C), modulo 256: along each row (per channel) or down
    each column, written into ``into`` (``a``'s shape, ``uint8``) when given.  From ``cv2.integral`` in blocks of
    rows small enough that its int32 sums cannot overflow (a column's running sum carries over to the next
    block)."""
    import cv2

    h = a.shape[0]
    per_row = a[0].size
    step = max(1, ((1 << 31) - 1) // (255 * per_row + 255))
    out = np.empty(a.shape, np.uint8) if into is None else into
    for r0 in range(0, h, step):
        block = a[r0:r0 + step]
        if not along_rows and r0:
            block = block.copy()
            block[0] += out[r0 - 1]
        # the low bytes, contiguous: numpy's cast of (non-negative) int32 to uint8 keeps the low byte, in one
        # vectorised pass; reading them in place (a view with a stride of 4) made the differences below a byte
        # gather, twice the time of the integral itself
        lo = cv2.integral(block).astype(np.uint8)
        if along_rows:
            np.subtract(lo[1:, 1:], lo[:-1, 1:], out=out[r0:r0 + step])
        else:
            np.subtract(lo[1:, 1:], lo[1:, :-1], out=out[r0:r0 + step])
    return out
