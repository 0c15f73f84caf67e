"""procam's mark inside an image file's bytes: a PNG ``tEXt`` chunk, a JPEG comment segment (written by
:func:`procam.io.files.write_image`, read by :func:`procam.io.files.procam_wrote`; the marks themselves are in
:mod:`procam.io.formats`).  Plain bytes in, bytes out; nothing here touches a file."""

from __future__ import annotations

import zlib

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def png_with_text(data: bytes, key: str, text: str) -> bytes:
    """A PNG with a ``tEXt`` chunk ``key = text`` after its header chunk."""
    body = b"tEXt" + key.encode("latin-1") + b"\x00" + text.encode("latin-1")
    chunk = (len(body) - 4).to_bytes(4, "big") + body + (zlib.crc32(body) & 0xFFFFFFFF).to_bytes(4, "big")
    end = 8 + 12 + int.from_bytes(data[8:12], "big")  # signature + IHDR
    return data[:end] + chunk + data[end:]


def png_texts(data: bytes) -> dict:
    """The ``tEXt`` chunks of a PNG's first bytes ``data`` (a whole file or its head; the chunks up to the first
    one cut off or failing its checksum, walked by :func:`procam.io.png.chunks`): ``{key: text}``."""
    from .png import chunks

    out = {}
    for kind, start, end in chunks(data)[0]:
        if kind == b"tEXt":
            key, _, val = data[start:end].partition(b"\x00")
            out[key.decode("latin-1")] = val.decode("latin-1")
    return out


def jpeg_comment(data: bytes) -> bytes | None:
    """The first comment (``COM`` segment) of the JPEG ``data`` before its image data, or None."""
    if data[:2] != b"\xff\xd8":
        return None
    pos = 2
    while pos + 4 <= len(data) and data[pos] == 0xFF:
        marker, n = data[pos + 1], int.from_bytes(data[pos + 2:pos + 4], "big")
        if marker == 0xFE:
            return data[pos + 4:pos + 2 + n]
        if marker == 0xDA:  # start of scan: the image data follows
            return None
        pos += 2 + n
    return None


def jpeg_with_comment(data: bytes, text: bytes) -> bytes:
    """The JPEG ``data`` with a comment segment ``text`` after its JFIF header (or its start marker)."""
    pos = 2
    if data[2:4] == b"\xff\xe0":  # APP0 (JFIF) must stay first
        pos = 4 + int.from_bytes(data[4:6], "big")
    return data[:pos] + b"\xff\xfe" + (len(text) + 2).to_bytes(2, "big") + text + data[pos:]
