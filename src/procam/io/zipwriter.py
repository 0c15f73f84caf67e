"""A ZIP archive of deflated members, compressed in parallel threads: the container of procam's ``.npz`` files.

:mod:`zipfile` compresses one member after the other on the calling thread; a camera's decoded maps (a dozen
members, 20 MB at 1.3 MP) took a tenth of a second that way, most of ``procam decode``'s writing. zlib lets the
interpreter lock go while it compresses, so the members are compressed in threads at once and written in their
order. The archive is the one :mod:`zipfile` writes for the same members, byte for byte: each member deflated by
``zlib.compressobj(level, DEFLATED, -15)`` as zipfile does it, the date fixed at 1980-01-01 00:00, no data
descriptors, the file mode ``rw-------`` (zipfile's for a member written from bytes), and the creating system
zipfile names (3, Unix; 0 on Windows).

An archive that could need ZIP64 records (members of over 2 GB in all, or 65535 members or more: zipfile's limits)
is left to :mod:`zipfile` (:func:`write` says so by returning False).
"""

from __future__ import annotations

import os
import struct
import zlib
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import BinaryIO

#: zipfile's limits past which it writes ZIP64 records: bytes, and members; an archive that might reach either is
#: left to zipfile
LIMIT = (1 << 31) - 1
COUNT_LIMIT = 0xFFFF

_LOCAL = struct.Struct("<4s2B4HL2L2H")
_CENTRAL = struct.Struct("<4s4B4HL2L5H2L")
_END = struct.Struct("<4s4H2LH")
_VERSION = 20                     # "deflate": the version zipfile writes as made by and as needed to extract
_SYSTEM = 0 if os.name == "nt" else 3
_DOS_DATE = (0 << 9) | (1 << 5) | 1  # 1980-01-01
_DOS_TIME = 0                     # 00:00:00
_MODE = 0o600 << 16               # the external attributes: rw------- in the high bytes, as zipfile's writestr


def _deflated(data, level: int) -> tuple[bytes, int]:
    """(raw deflate stream, CRC-32) of ``data``, as zipfile deflates a member written in one piece."""
    c = zlib.compressobj(level, zlib.DEFLATED, -15)
    return c.compress(data) + c.flush(), zlib.crc32(data)


def write(f: BinaryIO, members: Sequence[tuple[str, object]], level: int, threads: int | None = None) -> bool:
    """Write the archive of ``members`` (``(name, data)``: a name, and bytes or any contiguous buffer) to the
    binary file ``f`` (at its start), each deflated at zlib ``level``, ``threads`` at once (default: the CPUs, at
    most 4).  Returns False, having written nothing, when the members are too large for an archive without ZIP64
    records (:data:`LIMIT`, :data:`COUNT_LIMIT`): write those with :mod:`zipfile`."""
    views = [(name, memoryview(data).cast("B")) for name, data in members]
    if len(views) >= COUNT_LIMIT or sum(v.nbytes + 2 * len(n) for n, v in views) * 1.05 + 1024 * (len(views) + 1) > LIMIT:
        return False
    n = max(1, min(len(views), threads if threads is not None else min(4, os.cpu_count() or 1)))
    if n > 1:  # the largest first: the threads end together
        with ThreadPoolExecutor(n) as ex:
            started = {k: ex.submit(_deflated, views[k][1], level)
                       for k in sorted(range(len(views)), key=lambda k: -views[k][1].nbytes)}
            done = [started[k].result() for k in range(len(views))]
    else:
        done = [_deflated(v, level) for _, v in views]
    central, offset = [], 0
    for (name, view), (packed, crc) in zip(views, done):
        encoded, flags = (name.encode("ascii"), 0) if name.isascii() else (name.encode("utf-8"), 0x800)
        local = _LOCAL.pack(b"PK\x03\x04", _VERSION, 0, flags, zlib.DEFLATED, _DOS_TIME, _DOS_DATE, crc, len(packed),
                            view.nbytes, len(encoded), 0)
        f.write(local + encoded)
        f.write(packed)
        central.append(_CENTRAL.pack(b"PK\x01\x02", _VERSION, _SYSTEM, _VERSION, 0, flags, zlib.DEFLATED, _DOS_TIME,
                                     _DOS_DATE, crc, len(packed), view.nbytes, len(encoded), 0, 0, 0, 0, _MODE, offset)
                       + encoded)
        offset += len(local) + len(encoded) + len(packed)
    directory = b"".join(central)
    f.write(directory)
    f.write(_END.pack(b"PK\x05\x06", 0, 0, len(central), len(central), len(directory), offset, 0))
    return True
