"""A ZIP archive of deflated members, compressed in parallel threads: the container of procam's ``.npz`` files.

:mod:`zipfile` compresses one member after the other on the calling thread; a camera's decoded maps (a dozen
members, 20 MB at 1.3 MP) took a tenth of a second that way, most of ``procam decode``'s writing. zlib lets the
interpreter lock go while it compresses, so the members are compressed in threads at once and written in their
order. The archive is the one :mod:`zipfile` writes for the same members: the date fixed at 1980-01-01 00:00, no
data descriptors, the file mode ``rw-------`` (zipfile's for a member written from bytes), and the creating system
zipfile names (3, Unix; 0 on Windows); with the deflater ``"zlib"`` byte for byte, each member deflated by
``zlib.compressobj(level, DEFLATED, -15)`` as zipfile does it. With ``"isal"`` (ISA-L's deflate, the ``isal``
package, levels 0-3) the members' deflate streams are ISA-L's: any ZIP reader inflates them to the same bytes,
and the same members give the same archive on one machine (as zlib's streams, they can differ with the library's
version and the CPU's instruction set). ISA-L's level 2 deflates a camera's decoded maps 5-6 times faster than
zlib's level 1, to files as small or smaller (:data:`FAST`).

An archive that could need ZIP64 records (members of over 2 GB in all, or 65535 members or more: zipfile's limits)
is left to :mod:`zipfile` (:func:`write` says so by returning False).
"""

from __future__ import annotations

import operator
import os
import struct
import zlib
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import BinaryIO

try:  # ISA-L's deflate and checksum (procam.io.png inflates with it too)
    from isal import isal_zlib as _isal
except ImportError:  # pragma: no cover - isal is a dependency where it has wheels
    _isal = None

#: ``(deflater, level)`` for writing a camera's maps fast: ISA-L's level 2 where the ``isal`` package is installed
#: (a 1.3 MP phase decode's 18 MB of maps: 0.03 CPU-s against zlib level 1's 0.18, 3.80 MB against 3.81), else
#: zlib's level 1
FAST = ("isal", 2) if _isal is not None else ("zlib", 1)

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


def _deflated(data, level: int, lib=zlib) -> tuple[bytes, int]:
    """(raw deflate stream, CRC-32) of ``data`` by ``lib`` (zlib, or ISA-L's ``isal_zlib``), as zipfile deflates a
    member written in one piece."""
    c = lib.compressobj(level, lib.DEFLATED, -15)
    return c.compress(data) + c.flush(), lib.crc32(data)


def write(f: BinaryIO, members: Sequence[tuple[str, object]], level: int, threads: int | None = None,
          deflater: str = "zlib") -> bool:
    """Write the archive of ``members`` (``(name, data)``: a name, and bytes or any contiguous buffer) to the
    binary file ``f`` (at its start), each deflated at ``level`` by ``deflater`` (``"zlib"``: 0-9, zipfile's bytes;
    ``"isal"``: ISA-L, 0-3), ``threads`` at once (default: the CPUs, at most 4).  Returns False, having written
    nothing, when the members are too large for an archive without ZIP64 records (:data:`LIMIT`,
    :data:`COUNT_LIMIT`): write those with :mod:`zipfile`.  Raises ValueError for a deflater that is not installed
    or a level it does not have."""
    lib = {"zlib": zlib, "isal": _isal}.get(deflater)
    try:  # any integer (NumPy's too), not a bool or a float
        good = not isinstance(level, bool) and 0 <= operator.index(level) <= (9 if lib is zlib else 3)
    except TypeError:
        good = False
    if lib is None or not good:
        raise ValueError(f"no deflater {deflater!r} with level {level!r} (zlib: 0-9; isal, where installed: 0-3)")
    level = operator.index(level)
    views = [(name, memoryview(data).cast("B")) for name, data in members]
    if len(views) >= COUNT_LIMIT or sum(v.nbytes + 2 * len(n) for n, v in views) * 1.05 + 1024 * (len(views) + 1) > LIMIT:
        return False
    n = max(1, min(len(views), threads if threads is not None else min(4, os.cpu_count() or 1)))
    if n > 1:  # the largest first: the threads end together
        with ThreadPoolExecutor(n) as ex:
            started = {k: ex.submit(_deflated, views[k][1], level, lib)
                       for k in sorted(range(len(views)), key=lambda k: -views[k][1].nbytes)}
            done = [started[k].result() for k in range(len(views))]
    else:
        done = [_deflated(v, level, lib) for _, v in views]
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
