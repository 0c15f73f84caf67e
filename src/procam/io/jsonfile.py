"""Reading a JSON file a user may have written: every structure and number bounded before anything uses it.

:func:`load_json` parses like :func:`json.loads` but refuses, with a ValueError whose text says what is wrong and
where (the caller prefixes the file's name):

* a document nested more than :data:`MAX_DEPTH` levels deep (a hand-edited or hostile file must not exhaust the
  interpreter's recursion, nor any code that walks the document);
* a whole number of more than :data:`MAX_INT_DIGITS` digits (no field procam reads needs one; a 400-digit
  ``width`` would overflow every float conversion after it);
* a number that is not finite (``NaN``, ``Infinity``, ``1e400``) unless ``finite=False``;
* a key given twice in one object (JSON allows it and a parser keeps one of the two: procam cannot tell which
  one the writer meant, so it keeps neither).

It is the one JSON reader of procam's files: descriptions (``patterns.json``), rig folders (``rig.json``),
manifests, calibrations (:func:`procam.io.validate.load_json` adds the file's name and what to do).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

#: Deepest nesting of arrays and objects a procam JSON file may have (procam's own go 5 levels deep).
MAX_DEPTH = 64
#: Most digits of a whole number (procam's sizes, counts and indices have at most 6).
MAX_INT_DIGITS = 15


class JSONError(ValueError):
    """A JSON text procam does not read; the message says what is wrong, without the file's name."""


def _regular_file_bytes(path: Path) -> bytes:
    """The contents of ``path``, opened without blocking; OSError when it is not a regular file (a folder: EISDIR; a
    named pipe, a device or a socket: EINVAL) or cannot be read."""
    import errno
    import os
    import stat

    fd = os.open(path, os.O_RDONLY | getattr(os, "O_BINARY", 0) | getattr(os, "O_NONBLOCK", 0))
    try:
        mode = os.fstat(fd).st_mode
        if stat.S_ISDIR(mode):
            raise IsADirectoryError(errno.EISDIR, "is a folder", str(path))
        if not stat.S_ISREG(mode):
            raise OSError(errno.EINVAL, "not a regular file (a named pipe, a device or a socket)", str(path))
        with os.fdopen(os.dup(fd), "rb") as f:
            return f.read()
    finally:
        os.close(fd)


def _path(parts) -> str:
    """``sequence[1].period``-style name of a place in a document."""
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out or "the document"


def _check(doc, finite: bool) -> None:
    """Raise :class:`JSONError` for nesting deeper than :data:`MAX_DEPTH`, a whole number of more than
    :data:`MAX_INT_DIGITS` digits or (``finite``) a number that is not finite, naming the field; walked without
    recursion."""
    big = 10 ** MAX_INT_DIGITS
    todo = [(doc, ())]
    while todo:
        node, where = todo.pop()
        if len(where) >= MAX_DEPTH:
            raise JSONError(f"is nested too deep (more than {MAX_DEPTH} levels of arrays and objects)")
        if isinstance(node, dict):
            todo.extend((v, (*where, str(k))) for k, v in node.items())
        elif isinstance(node, list):
            todo.extend((v, (*where, i)) for i, v in enumerate(node))
        elif isinstance(node, int) and not isinstance(node, bool) and abs(node) >= big:
            raise JSONError(f"{_path(where)} is a whole number of {len(str(abs(node)))} digits; no field takes "
                            f"more than {MAX_INT_DIGITS}")
        elif finite and isinstance(node, float) and not math.isfinite(node):
            raise JSONError(f"{_path(where)} is {node}, not a finite number")


def _unique_keys(pairs):
    """``object_pairs_hook`` of :func:`loads`: an object's keys, each once."""
    out = {}
    for k, v in pairs:
        if k in out:
            raise JSONError(f"key {k!r} is given twice (procam cannot tell which one is meant); keep one")
        out[k] = v
    return out


def loads(text: str, finite: bool = True):
    """The document of the JSON ``text``, bounded (module docstring).  Raises :class:`JSONError` (a ValueError)."""
    try:
        doc = json.loads(text, object_pairs_hook=_unique_keys)
    except JSONError:
        raise
    except RecursionError:
        raise JSONError(f"is nested too deep (more than {MAX_DEPTH} levels of arrays and objects)") from None
    except ValueError as e:  # also a number beyond Python's own limit of digits
        raise JSONError(f"is not valid JSON ({e})") from None
    _check(doc, finite)
    return doc


def load_json(path, finite: bool = True):
    """The bounded document of the JSON file ``path`` (:func:`loads`).  Raises :class:`JSONError` for a text
    procam does not read, OSError when the file cannot be read or is not a regular file (a named pipe named like
    the file is refused, not waited on)."""
    data = _regular_file_bytes(Path(path))
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise JSONError(f"is not UTF-8 text ({e.reason} at byte {e.start})") from None
    return loads(text, finite)
