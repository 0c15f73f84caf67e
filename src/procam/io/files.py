"""File plumbing (the bottom floor): image reads, natural sort, JSON side files, atomic writes, and the
manifest of the files procam wrote into a folder.

Images are read with OpenCV (PNG, JPEG, TIFF, BMP, PGM/PPM, WebP), 8- or 16-bit.
Colour images are converted to grey with OpenCV's ``COLOR_BGR2GRAY`` (ITU-R BT.601 luma,
``0.299 R + 0.587 G + 0.114 B``); an alpha channel is dropped.  File names are sorted
naturally (``img2`` before ``img10``); files that are not images by extension
(``truth.json``, ``patterns.json``, notes) are ignored.  PNG and JPEG files are checked for
truncation and damage before OpenCV decodes them (so a broken file is named in one line, and
libpng prints nothing).

Every output is written under a hidden temporary name ``.NAME.tmpPID.EXT`` and renamed
(:func:`atomic_path`); temporary files of dead processes (a kill mid-write) are removed the next time
procam writes into that folder.  A folder procam creates for its outputs carries a manifest,
``.procam-manifest.json`` (:data:`MANIFEST`), that lists every file procam wrote there and its role
(``frame`` of a sequence, ``captured`` frame of a camera, ``sidecar`` JSON, ``output``).  Writers
refuse a non-empty folder without it (:func:`prepare_output_dir`), never overwrite a file it does not
list, and delete only files it lists; readers ignore the outputs it lists.
"""

from __future__ import annotations

import errno
import json
import os
import re
import zlib
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ..errors import CaptureError, OutputError

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
    files = []
    for p in folder.iterdir():
        if p.name.startswith(".") or p.suffix.lower() not in IMAGE_EXTS:
            continue
        if not p.is_file():
            raise CaptureError(f"{p}: {_not_a_file(p)}; move it out of the pose folder")
        files.append(p)
    if not files:
        others = sorted(p.name for p in folder.iterdir())
        hint = f" (it holds: {', '.join(others[:5])}{', ...' if len(others) > 5 else ''})" if others else " (it is empty)"
        raise CaptureError(f"{folder}: no images found{hint}; expected PNG/JPEG/TIFF/BMP captures of the pattern sequence")
    return sorted(files, key=lambda p: natural_key(p.name))


def _not_a_file(p: Path) -> str:
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


_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _png_with_text(data: bytes, key: str, text: str) -> bytes:
    """A PNG with a ``tEXt`` chunk ``key = text`` after its header chunk."""
    body = b"tEXt" + key.encode("latin-1") + b"\x00" + text.encode("latin-1")
    chunk = (len(body) - 4).to_bytes(4, "big") + body + (zlib.crc32(body) & 0xFFFFFFFF).to_bytes(4, "big")
    end = 8 + 12 + int.from_bytes(data[8:12], "big")  # signature + IHDR
    return data[:end] + chunk + data[end:]


def _png_texts(data: bytes) -> dict:
    """The ``tEXt`` chunks of a PNG's first 64 KiB: ``{key: text}``."""
    out, pos = {}, 8
    while pos + 12 <= len(data):
        n = int.from_bytes(data[pos:pos + 4], "big")
        kind = data[pos + 4:pos + 8]
        if kind == b"tEXt":
            key, _, val = data[pos + 8:pos + 8 + n].partition(b"\x00")
            out[key.decode("latin-1")] = val.decode("latin-1")
        if kind in (b"IDAT", b"IEND"):
            break
        pos += 12 + n
    return out


def procam_wrote(path) -> bool:
    """Does the existing file ``path`` look like procam wrote it (so writing over it loses nothing of the user's)?

    Yes when its folder's manifest lists it (not as a camera frame), or by its content: procam's JSON
    (``"format": "procam-..."``), a calibration FileStorage file (``cam_K``/``cam_int`` ...), procam's
    ``.npz`` maps, a PLY with procam's header comment, a PNG/PDF/SVG marked ``procam`` (every figure and
    image procam writes is), or an empty file.
    """
    path = Path(path)
    man = read_manifest(path.parent)
    if man is not None and man["files"].get(path.name) in ("output", "frame", "sidecar"):
        return True
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
            doc = json.loads(path.read_text())
        except (OSError, ValueError, UnicodeDecodeError):
            return False
        return isinstance(doc, dict) and str(doc.get("format", "")).startswith("procam")
    if suffix in (".yml", ".yaml", ".xml"):
        return (head.startswith(b"%YAML") or b"<opencv_storage>" in head) and any(
            k in head for k in (b"cam_K", b"proj_K", b"cam_int", b"proj_int"))
    if suffix == ".npz":
        import zipfile

        try:
            with zipfile.ZipFile(path) as z:
                names = set(z.namelist())
        except (OSError, zipfile.BadZipFile):
            return False
        return {"col.npy", "valid_col.npy"} <= names or {"map_x.npy", "map_y.npy"} <= names
    if suffix == ".ply":
        return b"\ncomment procam" in head[:4096]
    if suffix == ".png":
        return head[:8] == _PNG_SIGNATURE and _png_texts(head).get("Software") == "procam"
    if suffix in (".pdf", ".svg", ".ps", ".eps"):
        return b"procam" in head
    return False


def check_image_bytes(path, data: bytes) -> None:
    """Raise :class:`CaptureError` naming ``path`` when a PNG or JPEG is truncated or damaged.

    PNG: the signature, every chunk's length and CRC, and the final IEND chunk.  JPEG: the start
    (FFD8) and end (FFD9) markers.  Other formats are left to the decoder.
    """
    head = data[:8]
    what = None
    if head == _PNG_SIGNATURE:
        pos, n = 8, len(data)
        mv = memoryview(data)
        last = b""
        while pos + 12 <= n:
            length = int.from_bytes(data[pos:pos + 4], "big")
            kind = bytes(data[pos + 4:pos + 8])
            name = kind.decode("latin-1") + " chunk" if kind.isalpha() else "a chunk"
            end = pos + 12 + length
            if end > n:
                what = f"is truncated ({name} ends after the end of the file)"
                break
            crc = int.from_bytes(data[end - 4:end], "big")
            if zlib.crc32(mv[pos + 4:end - 4]) & 0xFFFFFFFF != crc:
                what = f"is damaged ({name} fails its checksum)"
                break
            last = kind
            pos = end
            if kind == b"IEND":
                break
        if what is None and last != b"IEND":
            what = "is truncated (no end marker: the file was not written completely)"
    elif head[:2] == b"\xff\xd8" and b"\xff\xd9" not in data[-4096:]:
        what = "is truncated (no JPEG end marker: the file was not written completely)"
    if what is not None:
        raise CaptureError(f"{path}: {what}; re-save or re-capture it, or remove it from the folder")


def read_image(path, gray: bool = True) -> np.ndarray:
    """Read one image as ``uint8`` or ``uint16``, (H, W) when ``gray`` else as stored.

    Raises :class:`CaptureError` naming the file when it cannot be read or has an unsupported type.
    """
    import cv2

    path = Path(path)
    if not path.is_file():
        raise CaptureError(f"{path}: {_not_a_file(path)}")
    try:
        raw = path.read_bytes()
    except OSError as e:
        raise CaptureError(f"{path}: cannot be read ({e.strerror or e}); check its permissions") from None
    check_image_bytes(path, raw)
    data = np.frombuffer(raw, dtype=np.uint8)
    img = cv2.imdecode(data, cv2.IMREAD_UNCHANGED) if data.size else None
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


def png_header(path) -> tuple[int, int, int] | None:
    """``(height, width, bytes per sample)`` of a PNG file from its IHDR chunk, without decoding it; None for
    another format or a header that cannot be read (:func:`read_image` then says what is wrong)."""
    try:
        with open(path, "rb") as f:
            head = f.read(26)
    except OSError:
        return None
    if len(head) < 26 or head[:8] != b"\x89PNG\r\n\x1a\n" or head[12:16] != b"IHDR":
        return None
    w, h = int.from_bytes(head[16:20], "big"), int.from_bytes(head[20:24], "big")
    return (h, w, 2 if head[24] == 16 else 1) if w > 0 and h > 0 else None


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
def atomic_path(path, record: bool = True):
    """Yield a temporary path next to ``path``; on success rename it to ``path``.

    On error the temporary file is removed, so no half-written output is left behind; an OS error
    (disk full, read-only, permission denied) names ``path``, not the temporary file.  Temporary files
    of dead processes in the folder are removed first (:func:`remove_stale_temps`).  With ``record``,
    a folder that has a manifest gets ``path`` listed in it (role ``output`` unless it is listed already)
    before the file is written, so a kill never leaves a file of procam's that its manifest does not list.
    """
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise _named(e, path.parent) from None
    remove_stale_temps(path.parent)
    if record:
        man = read_manifest(path.parent)
        if man is not None and path.name not in man["files"]:
            record_files(path.parent, {path.name: "output"})
    tmp = temp_path(path)
    try:
        yield tmp
        os.replace(tmp, path)
    except OSError as e:
        raise _named(e, path) from None
    finally:
        try:
            if tmp.exists():
                tmp.unlink()
        except OSError:
            pass


def write_text(path, text: str, record: bool = True) -> Path:
    """Write ``text`` to ``path`` atomically (``record``: see :func:`atomic_path`)."""
    with atomic_path(path, record) as tmp:
        Path(tmp).write_text(text)
    return Path(path)


def write_npz(path, compress: bool = True, **arrays) -> Path:
    """Write ``arrays`` as a NumPy ``.npz`` atomically, byte for byte the same for the same arrays (the zip
    entries carry a fixed date, unlike ``np.savez``'s)."""
    import zipfile

    path = Path(path)
    mode = zipfile.ZIP_DEFLATED if compress else zipfile.ZIP_STORED
    with atomic_path(path) as tmp, zipfile.ZipFile(tmp, "w", mode) as zf:
        for name, a in arrays.items():
            info = zipfile.ZipInfo(f"{name}.npy", date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = mode
            with zf.open(info, "w", force_zip64=True) as f:
                np.lib.format.write_array(f, np.asanyarray(a), allow_pickle=False)
    return path


def write_image(path, img: np.ndarray, record: bool = True) -> Path:
    """Write an image atomically with OpenCV (format from the extension; ``record``: see :func:`atomic_path`)."""
    import cv2

    path = Path(path)
    with atomic_path(path, record) as tmp:
        ok, buf = cv2.imencode(path.suffix, img)
        if not ok:
            raise CaptureError(f"{path}: could not encode image")
        data = buf.tobytes()
        if data[:8] == _PNG_SIGNATURE:
            data = _png_with_text(data, "Software", "procam")
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
        doc = json.loads(path.read_text())
    except (OSError, ValueError, UnicodeDecodeError):
        return None
    if not (isinstance(doc, dict) and doc.get("format") == "procam-manifest" and isinstance(doc.get("files"), dict)):
        return None
    # plain names only: a manifest never points outside its folder
    doc["files"] = {str(k): str(v) for k, v in doc["files"].items() if _plain_name(str(k))}
    return doc


def _plain_name(name: str) -> bool:
    return bool(name) and name not in (".", "..") and "/" not in name and "\\" not in name and "\x00" not in name


def _write_manifest(folder, doc: dict) -> None:
    write_text(Path(folder) / MANIFEST, json.dumps(doc, indent=1, sort_keys=True), record=False)


def record_files(folder, roles: dict, writer: str | None = None) -> dict:
    """Add ``roles`` (``{name: role}``) to the manifest of ``folder`` (created when missing, with ``writer``);
    returns the manifest."""
    doc = read_manifest(folder) or {"format": "procam-manifest", "version": 1, "writer": writer or "procam",
                                    "files": {}}
    for name, role in roles.items():
        if role not in ROLES:
            raise ValueError(f"role must be one of {ROLES}, got {role!r}")
        if doc["files"].get(name) != "captured":
            doc["files"][str(name)] = role
    _write_manifest(folder, doc)
    return doc


def unlist_files(folder, names) -> None:
    """Remove ``names`` from the manifest of ``folder`` (after deleting them)."""
    doc = read_manifest(folder)
    if doc is None:
        return
    for n in names:
        doc["files"].pop(str(n), None)
    _write_manifest(folder, doc)


def _visible(folder: Path) -> list[str]:
    """Names in ``folder`` a user put there or can see: everything but hidden entries."""
    return sorted((e.name for e in os.scandir(folder) if not e.name.startswith(".")), key=natural_key)


def _legacy_files(folder: Path) -> set[str]:
    """Files an older procam (before manifests) wrote: a sequence folder's ``patterns.json`` lists its
    frames; ``truth.json`` is the simulator's.  A camera capture (``capture.json``) is not counted."""
    meta = read_sidecar_quiet(folder, "patterns.json")
    if not (isinstance(meta, dict) and meta.get("format") == "procam-graycode" and isinstance(meta.get("files"), list)):
        return set()
    if (folder / "capture.json").exists():
        return set()
    return {str(f) for f in meta["files"] if _plain_name(str(f))} | {"patterns.json", "truth.json"}


def read_sidecar_quiet(folder, name: str):
    """:func:`read_sidecar` that returns None for an unreadable file instead of raising."""
    try:
        return json.loads((Path(folder) / name).read_text())
    except (OSError, ValueError, UnicodeDecodeError):
        return None


def _listing(names: list[str], n: int = 4) -> str:
    return ", ".join(names[:n]) + (f", ... ({len(names)} in all)" if len(names) > n else "")


def replaceable(folder) -> set[str]:
    """Names in ``folder`` procam may overwrite or delete: listed in its manifest (or an older procam's
    patterns.json), except camera frames (role ``captured``)."""
    folder = Path(folder)
    man = read_manifest(folder)
    if man is None:
        return _legacy_files(folder)
    return {n for n, r in man["files"].items() if r != "captured"}


def prepare_output_dir(folder, writer: str, *, force: bool = False, option: str | None = None,
                       create: bool = True) -> Path:
    """Make ``folder`` ready for ``writer``'s outputs (``"simulate"``, ``"patterns"``, ``"study"`` ...).

    A missing or empty folder is created and gets a manifest.  A folder this writer wrote before (its
    manifest, or an older procam's patterns.json, lists everything in it) is reused.  Anything else --
    files procam did not write, or another command's output -- is refused with one line naming the folder
    and what it holds, unless ``force``; even then nothing procam did not write is overwritten or deleted
    (:func:`check_overwrite`).  Temporary files of dead processes are removed.  Without ``create`` the
    folder is only checked (a missing one: that it can be created), not created.

    Raises :class:`OutputError`.
    """
    folder = Path(folder)
    label = f"{option} {folder}" if option else str(folder)
    if folder.exists() and not folder.is_dir():
        raise OutputError(f"{label}: exists and is not a folder; give a folder for the outputs")
    if not folder.exists() and not create:
        parent = folder.parent
        while not parent.exists() and parent != parent.parent:
            parent = parent.parent
        if not parent.is_dir():
            raise OutputError(f"{label}: cannot create the folder ({parent} is not a folder)")
        check_writable_dir(parent, label)
        return folder
    new = not folder.exists()
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise OutputError(f"{label}: cannot create the folder ({e.strerror or e}); check the path and its "
                          "permissions") from None
    if new and read_manifest(folder.parent) is not None:  # a folder inside procam's output folder is procam's
        record_files(folder.parent, {folder.name: "output"})
    check_writable_dir(folder, label)
    remove_stale_temps(folder)
    visible = _visible(folder)
    man = read_manifest(folder)
    listed = set(man["files"]) if man is not None else _legacy_files(folder)
    foreign = [n for n in visible if n not in listed]
    legacy = "simulate" if (folder / "truth.json").exists() else "patterns"
    if man is not None:
        other = man.get("writer") != writer
        captured = any(r == "captured" for r in man["files"].values())
    else:
        other = bool(listed) and writer != legacy
        captured = False
    if captured:
        raise OutputError(f"{label}: the folder holds a camera capture; give a new or empty folder (procam never "
                          "writes into a capture)")
    if visible and not force:
        if foreign:
            raise OutputError(
                f"{label}: the folder holds {len(foreign)} file(s) procam did not write ({_listing(foreign)}); give "
                "a new or empty folder, or add --force to write next to them (procam never overwrites or deletes "
                "files it did not write)")
        if other:
            what = man.get("writer") if man is not None else legacy
            raise OutputError(f"{label}: the folder holds the output of 'procam {what}'; give a new or empty folder, "
                              "or add --force to write into it")
    if man is None and create:
        doc = {"format": "procam-manifest", "version": 1, "writer": legacy if listed else writer,
               "files": {n: ("frame" if Path(n).suffix.lower() in IMAGE_EXTS and n not in ("patterns.json",)
                             else "sidecar") for n in sorted(listed & set(visible))}}
        _write_manifest(folder, doc)
    return folder


def check_overwrite(folder, names, option: str | None = None) -> None:
    """Raise :class:`OutputError` when writing ``names`` into ``folder`` would overwrite a file procam did
    not write (or a camera frame)."""
    folder = Path(folder)
    ok = replaceable(folder)
    clash = [n for n in names if n not in ok and (folder / n).exists()]
    if clash:
        label = f"{option} {folder}" if option else str(folder)
        raise OutputError(f"{label}: writing here would overwrite {len(clash)} file(s) procam did not write "
                          f"({_listing(sorted(clash, key=natural_key))}); give a new or empty folder")


def remove_listed(folder, names) -> list[Path]:
    """Delete ``names`` from ``folder`` if its manifest lists them as procam's (and not as camera frames),
    and unlist them; anything else is left alone.  Returns the deleted paths."""
    folder = Path(folder)
    ok = replaceable(folder)
    gone = []
    for n in names:
        if n in ok and (folder / n).is_file() and not (folder / n).is_symlink():
            (folder / n).unlink()
            gone.append(folder / n)
    if gone:
        unlist_files(folder, [p.name for p in gone])
    return gone


def why_not_writable(folder, need_bytes: int = 1 << 20) -> str | None:
    """Why ``folder`` (an existing folder) cannot take a new file -- read-only, no permission, less than
    ``need_bytes`` free -- or None when it can (a probe file is created and removed)."""
    import shutil
    import tempfile

    try:
        fd, probe = tempfile.mkstemp(prefix=".procam-probe-", dir=folder)
        os.close(fd)
        os.unlink(probe)
    except OSError as e:
        return {errno.EROFS: "the file system is read-only", errno.EACCES: "no permission to write there",
                errno.EPERM: "no permission to write there", errno.ENOSPC: "the disk is full",
                errno.EDQUOT: "the disk quota is exhausted"}.get(e.errno, e.strerror or str(e))
    try:
        free = shutil.disk_usage(folder).free
    except OSError:
        return None
    if free < need_bytes:
        return f"only {fmt_bytes(free)} free on the disk, about {fmt_bytes(need_bytes)} needed"
    return None


def check_writable_dir(folder, label: str | None = None, need_bytes: int = 1 << 20) -> None:
    """Raise :class:`OutputError` when ``folder`` (an existing folder) cannot take a new file
    (:func:`why_not_writable`)."""
    why = why_not_writable(folder, need_bytes)
    if why is not None:
        raise OutputError(f"{label or folder}: cannot write into {folder} ({why}); choose another place")
