"""Maps as NumPy ``.npz`` files: the decoded maps of a pose (``procam decode -o``) and remap tables
(``procam export --format maps``).

* :func:`save_decoded_maps` / :func:`load_decoded_maps` -- per camera pixel, the projector column and row, their
  validity, reasons, confidence and dropped bits, with the projector's size and the sequence order
  (members :data:`procam.io.formats.DECODED_MAPS_KEYS`; the table is in ``docs/file-formats.md``).
* :func:`save_maps` -- ``map_x``, ``map_y`` (float32) for ``cv2.remap`` plus metadata arrays.

Files are written atomically and byte for byte the same for the same arrays (:func:`procam.io.files.write_npz`).
The reader checks the members, their common (H, W) shape and the projector size (:mod:`procam.io.validate`) and
raises :class:`~procam.errors.CaptureError` naming the file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import CaptureError
from .files import write_npz
from .formats import DECODED_MAPS_FORMAT, DECODED_MAPS_KEYS, REMAP_FORMAT, REMAP_MARK
from .validate import bad, check_size

_FIX = "re-run 'procam decode -o'"
#: The members of a decoded-maps file that are not (H, W) maps.
_META = ("projector_size", "order")
#: Each map's numpy dtype kinds and what they are in words (procam writes float32, bool and uint8).
_KINDS = {**dict.fromkeys(("col", "row", "confidence"), ("f", "real numbers")),
          **dict.fromkeys(("valid_col", "valid_row"), ("b", "true/false values")),
          **dict.fromkeys(("reason_col", "reason_row", "dropped_col", "dropped_row"), ("u", "unsigned integers"))}


def save_decoded_maps(path, result, source: str | None = None) -> Path:
    """Write a pose's decoded maps (a :class:`procam.decode.DecodeResult`) as ``.npz``, atomically; ``source`` the
    capture's :attr:`procam.capture.Capture.fingerprint` (member ``source``: a reader of the maps with the capture
    can tell they are its)."""
    ps = result.pattern_set
    arrays = {"col": result.col, "row": result.row, "valid_col": result.valid_col, "valid_row": result.valid_row,
              "reason_col": result.reason_col, "reason_row": result.reason_row, "confidence": result.confidence,
              "dropped_col": result.dropped_col, "dropped_row": result.dropped_row,
              "projector_size": np.array([ps.width, ps.height]), "order": np.array(ps.order)}
    extra = {} if source is None else {"source": np.array(str(source))}
    return write_npz(path, DECODED_MAPS_FORMAT, **{k: arrays[k] for k in DECODED_MAPS_KEYS}, **extra)


def load_decoded_maps(path) -> dict:
    """Read a decoded-maps file: ``{member: (H, W) array}`` for the maps, ``projector_size`` as ``(width,
    height)``, ``order`` as a string and ``source`` the fingerprint of the capture they were decoded from (``""``
    in a file without one: written before procam recorded it).

    Raises :class:`~procam.errors.CaptureError` naming the file: missing, not an ``.npz``, a member missing, a map
    that is not 2-D or not of the others' shape or of another kind of value (real numbers for the coordinates and
    the confidence, true/false for the validity, unsigned integers for the reasons and dropped bits), a projector
    size that is not one, or a decoded coordinate outside the projector (or not a number).
    """
    import zipfile

    path = Path(path)
    how = {"fix": _FIX, "error": CaptureError}
    if not path.is_file():
        raise CaptureError(f"{path}: no such file; {_FIX}")
    try:
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as e:
        raise CaptureError(f"{path}: not a decoded-maps .npz file ({e}); {_FIX}") from None
    missing = [k for k in DECODED_MAPS_KEYS if k not in data]
    if missing:
        raise CaptureError(f"{path}: has no {', '.join(missing)} (not procam's decoded maps); {_FIX}")
    maps = [k for k in DECODED_MAPS_KEYS if k not in _META]
    shape = data[maps[0]].shape
    for k in maps:
        a = data[k]
        if a.ndim != 2:
            bad(path, k, f"is {'x'.join(map(str, a.shape)) or 'a single value'}, not a map (camera rows x columns)",
                **how)
        if a.shape != shape:
            bad(path, k, f"is {'x'.join(map(str, a.shape))}, the maps are {'x'.join(map(str, shape))}", **how)
        kind, what = _KINDS[k]
        if a.dtype.kind not in kind:
            bad(path, k, f"holds {a.dtype} values, not {what}", **how)
    out = {k: data[k] for k in maps}
    out["projector_size"] = check_size(path, "projector_size", data["projector_size"], **how)
    for key, valid, extent in (("col", "valid_col", out["projector_size"][0]), ("row", "valid_row",
                                                                                 out["projector_size"][1])):
        v = out[key][out[valid]]
        if v.size and not (np.isfinite(v).all() and v.min() >= -1.0 and v.max() <= extent):
            bad(path, key, f"holds decoded values outside the projector's 0 to {extent} px (or not numbers) where "
                           f"{valid} says decoded", **how)
    out["order"] = str(data["order"])
    out["source"] = str(data["source"]) if "source" in data and data["source"].ndim == 0 else ""
    return out


def save_maps(path, map_x, map_y, **meta) -> Path:
    """Write remap tables as ``.npz`` (``map_x``, ``map_y`` float32 plus ``meta`` arrays), atomically (the same
    tables give the same bytes)."""
    x, y = REMAP_MARK
    return write_npz(path, REMAP_FORMAT, **{x: np.asarray(map_x, np.float32), y: np.asarray(map_y, np.float32)},
                     **{k: np.asarray(v) for k, v in meta.items()})
