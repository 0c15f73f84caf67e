"""File plumbing (the bottom floor): which files of a folder are images and their natural order, JSON side files,
atomic writes, the manifest of the files procam wrote into a folder, and whether an existing file is procam's.
Reading the images themselves is :mod:`procam.io.images`'s.

File names are sorted naturally (``img2`` before ``img10``); files that are not images by extension
(``truth.json``, ``patterns.json``, notes) are ignored.

Every output is written under a hidden temporary name ``.NAME.tmpPID.EXT`` and renamed
(:func:`atomic_path`); temporary files of dead processes (a kill mid-write) are removed the next time
procam writes into that folder.  A folder procam creates for its outputs carries a manifest,
``.procam-manifest.json`` (:data:`MANIFEST`), that lists every file procam wrote there and its role
(``frame`` of a sequence, ``captured`` frame of a camera, ``sidecar`` JSON, ``output``).  Writers
refuse a non-empty folder without it, never overwrite a file it does not list, and delete only files it
lists (:mod:`procam.io.folders`); readers ignore the outputs it lists.
A file no manifest lists is procam's when it carries procam's mark (:func:`procam_wrote`, the marks in
:mod:`procam.io.formats`).
"""

from __future__ import annotations

import json
import os
import re
import zlib
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ..errors import CaptureError, OutputError
from . import formats
from . import jsonfile as _jsonfile
from .image_marks import PNG_SIGNATURE, jpeg_comment, jpeg_with_comment, png_texts, png_with_text

IMAGE_EXTS = {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp", ".pgm", ".ppm", ".pnm", ".webp", ".jp2"}


def natural_key(name: str):
    """Sort key that orders embedded numbers numerically (``img2`` < ``img10``): the runs of decimal digits (any
    script's, as ``int`` reads them) are numbers and the text between them is compared without case; other
    characters that only look like digits (superscripts, circled numbers) are text."""
    return [int(t) if k % 2 else t.lower() for k, t in enumerate(re.split(r"(\d+)", str(name)))]


def list_images(folder) -> list[Path]:
    """Image files in ``folder`` in natural order.

    Raises :class:`CaptureError` if the folder does not exist, is not a folder, or holds no images.
    """
    folder = Path(folder)
    if not folder.exists():
        raise CaptureError(f"{folder}: no such folder; give the folder that holds one pose's captured images")
    if not folder.is_dir():
        raise CaptureError(f"{folder}: not a folder; give the folder that holds one pose's captured images")
    files = []
    for p in folder.iterdir():
        if p.name.startswith(".") or p.suffix.lower() not in IMAGE_EXTS:
            continue
        if not p.is_file():
            raise CaptureError(f"{p}: {not_a_file(p)}; move it out of the pose folder")
        files.append(p)
    if not files:
        others = sorted(p.name for p in folder.iterdir())
        hint = f" (it holds: {', '.join(others[:5])}{', ...' if len(others) > 5 else ''})" if others else " (it is empty)"
        raise CaptureError(f"{folder}: no images found{hint}; expected PNG/JPEG/TIFF/BMP captures of the pattern sequence")
    return sorted(files, key=lambda p: natural_key(p.name))


def not_a_file(p: Path) -> str:
    """Why ``p`` (named like an image) is not a readable file: a folder, a symlink loop, a dangling link ..."""
    if p.is_symlink():
        try:
            p.resolve(strict=True)
        except RuntimeError:
            return "is a symbolic link that loops"
        except OSError:
            return f"is a symbolic link to {os.readlink(p)}, which does not exist"
    if p.is_dir():
        return "is a folder, not an image file"
    if p.exists():
        return "is not a regular file (a device, socket or pipe)"
    return "no such file"


def is_frame(path) -> bool:
    """Is ``path`` a PNG frame procam wrote (a pattern image, a render, a capture's frame): marked
    :data:`~procam.io.formats.FRAME_MARK`?"""
    try:
        with open(path, "rb") as f:
            head = f.read(1 << 12)
    except OSError:
        return False
    return head[:8] == PNG_SIGNATURE and png_texts(head).get(formats.PNG_TEXT_KEY) == formats.FRAME_MARK


def kept_because(path) -> str:
    """Why procam does not write over the existing file ``path`` (:func:`procam_wrote` says no), and what to do, in
    words for a message after the file's name."""
    if changed_since_written(path):
        return ("the file was changed since procam wrote it, or cannot be read to tell (an edit is the user's); give "
                "another name, or move it away first (procam never overwrites a user's edit)")
    if is_frame(path):
        return ("the file is a frame of a capture (data procam wrote, not an output); give another name, or move it "
                "away first (procam never overwrites a capture's frames)")
    return ("the file exists and procam did not write it; give another name, or move it away first (procam never "
            "overwrites a file it did not write)")


def procam_wrote(path) -> bool:
    """Does the existing file ``path`` look like procam wrote it (so writing over it loses nothing of the user's)?

    Not when its folder's manifest holds the digest of what procam wrote and the file's differs (the user edited
    it: :func:`changed_since_written`).  Yes when the manifest lists it (not as a camera frame), or by its content
    (the marks of
    :mod:`procam.io.formats`): procam's JSON (``"format": "procam-..."``), a FileStorage file or ``.npz`` whose
    ``procam_format`` names one of procam's formats, a PLY with procam's header comment, a PNG/JPEG/PDF/SVG
    marked ``procam`` (every figure and image procam writes is; not a sequence's frame, marked ``procam frame``,
    which only its folder's manifest lists as replaceable), an HTML page whose head names procam its
    generator (the report), a script whose first line is procam's mark with the digest of the rest, or an empty
    file.
    """
    path = Path(path)
    man = read_manifest(path.parent)
    if man is not None and man["files"].get(path.name) in ("output", "frame", "sidecar"):
        return not changed_since_written(path, man)  # an edited file is the user's, whatever its marks say
    try:
        with open(path, "rb") as f:
            head = f.read(1 << 16)
    except OSError:
        return False
    if not head:
        return True
    suffix = path.suffix.lower()
    if suffix == ".json":
        try:
            doc = _jsonfile.load_json(path, finite=False)
        except (OSError, ValueError, UnicodeDecodeError):
            return False
        return isinstance(doc, dict) and str(doc.get("format", "")).startswith(formats.JSON_PREFIX)
    if suffix in (".yml", ".yaml", ".xml"):
        return _storage_format(head) in formats.FILESTORAGE_FORMATS.values()
    if suffix == ".npz":
        return _npz_format(path) in formats.NPZ_FORMATS
    if suffix == ".ply":
        end = head.find(b"\nend_header")
        return head.startswith(b"ply") and end > 0 and re.search(
            rb"\ncomment " + re.escape(formats.PLY_COMMENT.encode()) + rb"\r?\n", head[:end + 1]) is not None
    if suffix == ".png":
        return head[:8] == PNG_SIGNATURE and png_texts(head).get(formats.PNG_TEXT_KEY) == formats.SOFTWARE
    if suffix == ".pdf":  # the document information (its Creator) comes last
        try:
            with open(path, "rb") as f:
                f.seek(max(0, f.seek(0, 2) - (1 << 16)))
                tail = f.read()
        except OSError:
            return False
        return head.startswith(b"%PDF") and f"/Creator ({formats.SOFTWARE})".encode() in tail + head
    if suffix in (".svg", ".ps", ".eps"):
        return formats.SOFTWARE.encode() in head
    if suffix in (".jpg", ".jpeg"):
        return jpeg_comment(head) == formats.SOFTWARE.encode()
    if suffix in (".html", ".htm"):
        low = head.lower()
        end = low.find(b"</head>")
        return end > 0 and formats.HTML_GENERATOR.encode() in low[:end]
    if suffix == ".py":
        if not head.startswith(formats.SCRIPT_MARK.encode()):
            return False
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError):
            return False
        first, _, body = text.partition("\n")
        return first + "\n" == formats.script_mark(body)
    return False


def _storage_format(head: bytes) -> str | None:
    """The format an OpenCV FileStorage file (YAML or XML, its first bytes ``head``) names under procam's key
    :data:`~procam.io.formats.FILESTORAGE_KEY`, or None."""
    key = re.escape(formats.FILESTORAGE_KEY.encode())
    if head.startswith(b"%YAML"):
        m = re.search(rb"(?m)^" + key + rb':[ \t]*"?([\w.-]+)"?[ \t]*\r?$', head)
    elif b"<opencv_storage>" in head:
        m = re.search(rb"<" + key + rb'>[ \t]*"?([\w.-]+)"?[ \t]*</' + key + rb">", head)
    else:
        return None
    return m.group(1).decode("ascii") if m else None


def _npz_format(path) -> str | None:
    """The format an ``.npz`` names in its member :data:`~procam.io.formats.NPZ_KEY` (a string array), or None."""
    import zipfile

    try:
        with zipfile.ZipFile(path) as z, z.open(f"{formats.NPZ_KEY}.npy") as f:
            value = np.lib.format.read_array(f, allow_pickle=False)
    except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile):
        return None
    return str(value) if value.dtype.kind == "U" and value.ndim == 0 else None


def read_sidecar(folder, name: str = "patterns.json") -> dict | None:
    """The JSON file ``name`` in ``folder`` (e.g. written by ``procam patterns``/``simulate``), or None."""
    path = Path(folder) / name
    if not path.is_file():
        return None
    try:
        return _jsonfile.load_json(path, finite=False)
    except (OSError, ValueError) as e:
        raise CaptureError(f"{path}: not valid JSON ({e}); fix or delete it") from None


_TEMP = re.compile(r"^\..+\.tmp(\d+)(\.[^.]*)?$")


def temp_path(path) -> Path:
    """The hidden temporary name :func:`atomic_path` writes ``path`` under: ``.STEM.tmpPID.SUFFIX``."""
    path = Path(path)
    stem = path.stem
    if len(path.name) > 200:  # a name near the file system's limit: keep the temporary name within it
        stem = f"{stem[:100]}~{zlib.crc32(path.name.encode()):08x}"
    return path.with_name(f".{stem}.tmp{os.getpid()}{path.suffix[:20]}")


def _pid_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # EPERM: alive, someone else's
        return True
    return True


def remove_stale_temps(folder) -> list[Path]:
    """Delete the temporary files of :func:`atomic_path` that a dead process left in ``folder`` (a kill
    mid-write); files of running processes, and everything else, are left alone.  Returns the deleted paths."""
    removed = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    for e in entries:
        m = _TEMP.match(e.name)
        if m is None or not e.is_file(follow_symlinks=False) or _pid_alive(int(m.group(1))):
            continue
        try:
            os.unlink(e.path)
            removed.append(Path(e.path))
        except OSError:
            pass
    return removed


def _named(e: OSError, path: Path) -> OSError:
    """``e`` naming the user's ``path`` instead of a hidden temporary name."""
    return OSError(e.errno, e.strerror or str(e), str(path))


@contextmanager
def atomic_path(path, record: bool = True, role: str = "output"):
    """Yield a temporary path next to ``path``; on success rename it to ``path``.  An existing ``path`` procam did not
    write (:func:`procam_wrote`) is never replaced: :class:`~procam.errors.OutputError` before anything is written,
    whatever a command checked before (its ``--force`` included).

    On error the temporary file is removed, so no half-written output is left behind; an OS error
    (disk full, read-only, permission denied) names ``path``, not the temporary file.  Temporary files
    of dead processes in the folder are removed first (:func:`remove_stale_temps`).  With ``record``,
    a folder that has a manifest gets ``path`` listed in it (role ``output`` unless it is listed already)
    before the file is written, so a kill never leaves a file of procam's that its manifest does not list; ``role``
    ``sidecar`` (a file the folder's readers need) also replaces an ``output`` listing; and once written, the
    file's digest (:func:`changed_since_written` then tells a user's edit).  The digest recorded for ``path`` is
    dropped just before it is replaced (``record`` or not), so a kill in between leaves a file procam may replace.
    """
    path = Path(path)
    if path.name != MANIFEST and path.exists() and not procam_wrote(path):  # the last line of defence
        raise OutputError(f"{path}: {kept_because(path)}")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise _named(e, path.parent) from None
    remove_stale_temps(path.parent)
    man = read_manifest(path.parent) if path.name != MANIFEST else None
    if record and man is not None:
        listed = man["files"].get(path.name)
        if listed is None or (listed == "output" and role != "output"):
            man = record_files(path.parent, {path.name: role})
    tmp = temp_path(path)
    try:
        yield tmp
        digest = file_digest(tmp) if record and man is not None else None
        if man is not None and path.name in man["digests"]:  # procam replaces it: the old digest goes first
            set_digest(path.parent, path.name, None)
        os.replace(tmp, path)
        if digest is not None:
            set_digest(path.parent, path.name, digest)
    except OSError as e:
        raise _named(e, path) from None
    finally:
        try:
            if tmp.exists():
                tmp.unlink()
        except OSError:
            pass


def write_text(path, text: str, record: bool = True, role: str = "output") -> Path:
    """Write ``text`` to ``path`` atomically as UTF-8 (``record``, ``role``: see :func:`atomic_path`); the lone
    surrogates that stand for a file name's undecodable bytes are written as Python's escapes (``\\udcff``)."""
    with atomic_path(path, record, role) as tmp:
        Path(tmp).write_text(text, encoding="utf-8", errors="backslashreplace")
    return Path(path)


#: zlib level of :func:`write_npz` where ISA-L is not installed (and of an archive too large for
#: :mod:`procam.io.zipwriter`): level 1 writes a camera's decoded maps 1.5-2 times faster than the default 6, to the
#: same size for a phase decode's noisy sub-pixel floats and 25 % larger for a Gray decode's. Where it is, ISA-L's
#: level 2 deflates them 5-6 times faster still (:data:`procam.io.zipwriter.FAST`).
NPZ_LEVEL = 1


def write_npz(path, fmt: str | None = None, compress: bool = True, **arrays) -> Path:
    """Write ``arrays`` as a NumPy ``.npz`` atomically, byte for byte the same for the same arrays (the zip
    entries carry a fixed date, unlike ``np.savez``'s; when ``compress``, deflated by ISA-L (or zlib at
    :data:`NPZ_LEVEL` where it is not installed), the members in parallel threads:
    :data:`procam.io.zipwriter.FAST`).  ``compress=False`` stores the members.  With ``fmt`` (one of
    :data:`~procam.io.formats.NPZ_FORMATS`) the file carries procam's mark, the member
    :data:`~procam.io.formats.NPZ_KEY` holding ``fmt``; without, only its folder's manifest says it is procam's."""
    import io
    import zipfile

    from . import zipwriter

    if fmt is not None:
        if fmt not in formats.NPZ_FORMATS:
            raise ValueError(f"fmt must be one of {formats.NPZ_FORMATS}, got {fmt!r}")
        arrays = {**arrays, formats.NPZ_KEY: np.array(fmt)}
    members = []
    for name, a in arrays.items():
        buf = io.BytesIO()
        np.lib.format.write_array(buf, np.asanyarray(a), allow_pickle=False)
        members.append((f"{name}.npy", buf.getbuffer()))
    path = Path(path)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as f:
            deflater, level = zipwriter.FAST
            if compress and zipwriter.write(f, members, level, deflater=deflater):
                return path
        mode = zipfile.ZIP_DEFLATED if compress else zipfile.ZIP_STORED
        with zipfile.ZipFile(tmp, "w", mode, allowZip64=True) as zf:
            for name, data in members:
                info = zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0))
                zf.writestr(info, data, compress_type=mode, compresslevel=NPZ_LEVEL if compress else None)
    return path


def write_image(path, img: np.ndarray, record: bool = True, frame: bool = False) -> Path:
    """Write an image atomically with OpenCV (format from the extension; ``record``: see :func:`atomic_path`); a PNG
    or JPEG carries procam's mark (:mod:`procam.io.formats`), a PNG ``frame`` of a sequence the frame's mark
    (:data:`~procam.io.formats.FRAME_MARK`: :func:`procam_wrote` does not offer it to outputs)."""
    import cv2

    path = Path(path)
    with atomic_path(path, record) as tmp:
        ok, buf = cv2.imencode(path.suffix, img)
        if not ok:
            raise CaptureError(f"{path}: could not encode image")
        data = buf.tobytes()
        if data[:8] == PNG_SIGNATURE:
            data = png_with_text(data, formats.PNG_TEXT_KEY, formats.FRAME_MARK if frame else formats.SOFTWARE)
        elif data[:2] == b"\xff\xd8":
            data = jpeg_with_comment(data, formats.SOFTWARE.encode())
        Path(tmp).write_bytes(data)
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

def portable_path(text, base) -> str:
    """``text`` as a path relative to the folder ``base`` (``/`` separators) when it names an existing file or
    folder (absolute, or relative to the working directory), else unchanged: what a file procam writes stores
    for the inputs it names, so that it does not hold the user's absolute paths and stays right when the folder
    that holds both is moved."""
    import os

    s = str(text)
    try:
        if not s or not os.path.exists(s):
            return s
        return Path(os.path.relpath(os.path.abspath(s), os.path.abspath(base))).as_posix()
    except (OSError, ValueError):          # another drive (Windows), an unreadable path
        return s


def portable_names(obj, base, keys=("name", "pose", "calibration", "source")):
    """``obj`` (JSON-able dicts and lists) with the strings under ``keys`` that name existing paths made relative
    to ``base`` (:func:`portable_path`); a new object, the input is not modified."""
    if isinstance(obj, dict):
        return {k: (portable_path(v, base) if k in keys and isinstance(v, str) else portable_names(v, base, keys))
                for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [portable_names(v, base, keys) for v in obj]
    return obj


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


def available_memory() -> int | None:
    """Bytes of memory available to a new allocation (Linux ``MemAvailable``), or None when unknown."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


def fmt_bytes(n: float) -> str:
    """``1536`` -> ``'1.5 KiB'``."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if abs(n) < 1024 or unit == "TiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024.0
    return f"{n:.1f} TiB"


# ------------------------------------------------------------------------------------------------
# the manifest: which files of a folder procam wrote
MANIFEST = ".procam-manifest.json"

#: Roles of listed files.  ``captured`` frames are a camera's data: no writer replaces or deletes them.
ROLES = ("frame", "captured", "sidecar", "output")


def read_manifest(folder) -> dict | None:
    """The manifest of ``folder`` (``{"format", "version", "writer", "files": {name: role}}``), or None when it
    has none (or an unreadable one: then the folder counts as not procam's)."""
    path = Path(folder) / MANIFEST
    try:
        doc = _jsonfile.load_json(path, finite=False)
    except (OSError, ValueError, UnicodeDecodeError):
        return None
    if not (isinstance(doc, dict) and doc.get("format") == formats.MANIFEST_FORMAT
            and isinstance(doc.get("files"), dict)):
        return None
    # plain names only: a manifest never points outside its folder
    doc["files"] = {str(k): str(v) for k, v in doc["files"].items() if plain_name(str(k))}
    digests = doc.get("digests")
    doc["digests"] = ({str(k): v for k, v in digests.items() if str(k) in doc["files"] and isinstance(v, str)}
                      if isinstance(digests, dict) else {})
    return doc


def file_digest(path) -> str:
    """The digest procam records of a file it wrote (``blake2b-160:`` and 40 hex digits of its bytes)."""
    import hashlib

    h = hashlib.blake2b(digest_size=20)
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return "blake2b-160:" + h.hexdigest()


def changed_since_written(path, man: dict | None = None) -> bool:
    """Is the existing file ``path`` not what procam wrote?  True when its folder's manifest (``man``, default:
    read) holds the digest of the file as procam wrote it and the file's bytes are others now (an edit); False
    without a recorded digest (an older manifest, an output listed without one) or a missing file; True for a file
    that cannot be read (procam cannot tell it is its own)."""
    path = Path(path)
    man = read_manifest(path.parent) if man is None else man
    want = man["digests"].get(path.name) if man is not None else None
    if want is None or not os.path.lexists(path):
        return False
    try:
        return file_digest(path) != want
    except OSError:
        return True


def plain_name(name: str) -> bool:
    """Is ``name`` a plain file name in its folder (no path, not ``.``/``..``)?  Only such names are listed."""
    return bool(name) and name not in (".", "..") and "/" not in name and "\\" not in name and "\x00" not in name


def write_manifest(folder, doc: dict) -> None:
    """Write ``doc`` as the manifest of ``folder`` (atomically; the manifest does not list itself; no
    ``digests`` member when it records none: such a manifest reads as an older procam's)."""
    if not doc.get("digests", True):
        doc = {k: v for k, v in doc.items() if k != "digests"}
    write_text(Path(folder) / MANIFEST, json.dumps(doc, indent=1, sort_keys=True), record=False)


def set_digest(folder, name: str, digest: str | None) -> None:
    """Record ``digest`` (:func:`file_digest`) for the listed file ``name`` in the manifest of ``folder``, or drop
    its digest (None); nothing without a manifest, for a name it does not list, or when nothing changes."""
    doc = read_manifest(folder)
    if doc is None or name not in doc["files"] or doc["digests"].get(name) == digest:
        return
    if digest is None:
        del doc["digests"][name]
    else:
        doc["digests"][name] = str(digest)
    write_manifest(folder, doc)


def record_files(folder, roles: dict, writer: str | None = None, digests: dict | None = None) -> dict:
    """Add ``roles`` (``{name: role}``) to the manifest of ``folder`` (created when missing, with ``writer``);
    returns the manifest.  ``digests`` (``{name: digest}``, :func:`file_digest` of files of ``roles`` as written)
    records what procam wrote (:func:`changed_since_written` then tells an edit)."""
    doc = read_manifest(folder) or {"format": formats.MANIFEST_FORMAT, "version": 1, "writer": writer or "procam",
                                    "files": {}, "digests": {}}
    for name, role in roles.items():
        if role not in ROLES:
            raise ValueError(f"role must be one of {ROLES}, got {role!r}")
        if doc["files"].get(name) != "captured":
            doc["files"][str(name)] = role
    for name, digest in (digests or {}).items():
        if str(name) in roles:
            doc["digests"][str(name)] = str(digest)
    write_manifest(folder, doc)
    return doc


def unlist_files(folder, names) -> None:
    """Remove ``names`` from the manifest of ``folder`` (after deleting them)."""
    doc = read_manifest(folder)
    if doc is None:
        return
    for n in names:
        doc["files"].pop(str(n), None)
        doc["digests"].pop(str(n), None)
    write_manifest(folder, doc)
