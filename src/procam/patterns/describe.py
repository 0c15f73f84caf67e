"""A sequence described in words: ``patterns.json`` -> :class:`~procam.patterns.PatternSet` (Gray codes) or
:class:`~procam.patterns.phase.PhaseSet` (the phase families), with a one-line error for anything that does not
describe a sequence (the schema and worked examples are in ``docs/patterns.md``).

A phase-family description::

    {"family": "phase", "width": 1920, "height": 1080,
     "fringe": {"sign": 1, "origin": 0, "shift": -1},               # optional: the conventions of every block
     "sequence": [{"kind": "phase", "axis": "col", "steps": 3, "period": 32},
                  {"kind": "phase", "axis": "col", "steps": 3, "periods": 1},   # one period across the panel
                  {"kind": "phase", "axis": "row", "steps": 3, "period": 32},
                  {"kind": "phase", "axis": "row", "steps": 3, "periods": 1}]}

A block may override any key of ``fringe``.  A Gray block (family ``gray-phase``) takes its period and origin
from the phase block of its axis; its ``bit_order`` (``"msb-first"``, the default, or ``"lsb-first"``) says in
which order its bits come, as the same key does for a Gray-family description.  Unknown keys are errors naming the
key and the closest known one (a misspelt ``shfit`` or ``famliy`` must not be ignored), and every number is
bounded before use.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import fields

from .gray import BIT_ORDERS, ORDERS, PatternSet, pattern_set
from .phase import AXES, KINDS, PHASE_FAMILIES, Block, Fringe, PhaseSet

_FRINGE_KEYS = ("sign", "origin", "pixel_center", "shift", "start", "levels", "gamma")
_TOP_KEYS = ("format", "version", "family", "width", "height", "order", "count", "white", "black", "sequence",
             "fringe", "upside_down", "files", "note", "notes", "description")
#: The keys of a Gray-family patterns.json: procam's own (:meth:`PatternSet.to_dict` and the frames' names) and
#: ``bit_order``; only ``width``, ``height``, ``order``, ``step`` and ``bit_order`` are read.
_GRAY_KEYS = (*(f.name for f in fields(PatternSet)), "format", "version", "family", "col_pairs", "row_pairs",
              "bit_rule", "files", "note", "notes", "description")
_BLOCK_KEYS = {"phase": ("kind", "axis", "steps", "period", "periods", *_FRINGE_KEYS),
               "gray": ("kind", "axis", "bits", "inverse", "complementary", "period", "bit_order"),
               "white": ("kind",), "black": ("kind",)}


def family_of(meta: dict | None) -> str:
    """The family a ``patterns.json`` dict describes: its ``family``, else ``"gray"`` (procam's Gray-code files
    carry none)."""
    if not isinstance(meta, dict):
        return "gray"
    return str(meta.get("family", "gray"))


def _unknown(keys, known, where: str, what: str) -> None:
    """Raise ValueError naming the first of ``keys`` not among ``known``, with the closest known key."""
    bad = [k for k in keys if k not in known]
    if not bad:
        return
    key = bad[0]
    close = difflib.get_close_matches(str(key), [str(k) for k in known], n=1, cutoff=0.6)
    guess = f"did you mean {close[0]!r}? " if close else ""
    listing = ", ".join(known) if len(known) <= 12 else "in docs/patterns.md"
    raise ValueError(f"{where}unknown key {_short(key)} ({guess}the keys of {what} are {listing})")


def check_keys(meta: dict) -> None:
    """Raise ValueError naming a key of the ``patterns.json`` dict ``meta`` that no description has (a misspelt
    ``famliy`` must not turn a phase description into a Gray one), with the closest known key."""
    known = tuple(dict.fromkeys((*_TOP_KEYS, *_GRAY_KEYS)))
    _unknown(meta, known, "", "a patterns.json")
    family = family_of(meta)
    if family == "gray":
        phase_only = [k for k in meta if k not in _GRAY_KEYS]
        if phase_only and "family" not in meta:
            raise ValueError(f"{phase_only[0]!r} belongs to a phase family's description, but the file names no "
                             f"family (without one it is a Gray-code file): add \"family\" ("
                             f"{', '.join(PHASE_FAMILIES)})")
        _unknown(meta, _GRAY_KEYS, "", "a Gray-code description (no family, or family gray)")
    elif family in PHASE_FAMILIES:
        _unknown(meta, _TOP_KEYS, "", f"a {family} description")


def _number(v, what: str, lo: float = -math.inf, hi: float = math.inf, integer: bool = False):
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ValueError(f"{what} must be a number, got {_short(v)}")
    if isinstance(v, int):  # compared as a whole number: a 400-digit one must not overflow a float
        if not lo <= v <= hi:
            raise ValueError(f"{what} must be from {lo:g} to {hi:g}, got {_short(v)}")
        return v if integer else float(v)
    if not math.isfinite(v):
        raise ValueError(f"{what} must be a finite number, got {v!r}")
    if integer and v != int(v):
        raise ValueError(f"{what} must be a whole number, got {v!r}")
    if not lo <= v <= hi:
        raise ValueError(f"{what} must be from {lo:g} to {hi:g}, got {v!r}")
    return int(v) if integer else float(v)


def _short(v) -> str:
    """``repr(v)`` cut to 40 characters (a message quotes a value, never a whole document)."""
    text = repr(v)
    return text if len(text) <= 40 else text[:37] + "..."


def _fringe(d: dict, base: Fringe, where: str) -> Fringe:
    kw = {}
    for key in _FRINGE_KEYS:
        if key not in d:
            continue
        v = d[key]
        if key == "levels":
            if not (isinstance(v, (list, tuple)) and len(v) == 2):
                raise ValueError(f"{where}.levels must be [lo, hi], got {_short(v)}")
            kw[key] = tuple(_number(x, f"{where}.levels", 0, 255) for x in v)
        elif key in ("sign", "shift"):
            kw[key] = _number(v, f"{where}.{key}", -1, 1, integer=True)
        elif key == "start":
            kw[key] = _number(v, f"{where}.start", -100.0, 100.0)
        else:
            kw[key] = _number(v, f"{where}.{key}", -1e7, 1e7)
    try:
        return Fringe(**{**base.__dict__, **kw})
    except ValueError as e:
        raise ValueError(f"{where}: {e}") from None


def _flag(d: dict, key: str, default: bool, where: str) -> bool:
    v = d.get(key, default)
    if not isinstance(v, bool):
        raise ValueError(f"{where + '.' if where else ''}{key} must be true or false, got {_short(v)}")
    return v


def from_dict(meta: dict, width: int | None = None, height: int | None = None):
    """The sequence ``meta`` (a ``patterns.json`` dict) describes: a :class:`PatternSet` for Gray codes
    (:func:`gray_from_dict`) or a :class:`PhaseSet`.  ``width``, ``height`` override the
    file's projector size.  Raises ValueError naming the field and what is wrong."""
    if not isinstance(meta, dict):
        raise ValueError("not a JSON object")
    family = family_of(meta)
    if family == "gray":
        return gray_from_dict(meta, width, height)
    if family not in PHASE_FAMILIES:
        raise ValueError(f"unknown family {_short(meta.get('family'))} (one of gray, {', '.join(PHASE_FAMILIES)})")
    check_keys(meta)
    w, h = _size(meta, width, height)
    base = Fringe()
    if "fringe" in meta:
        if not isinstance(meta["fringe"], dict):
            raise ValueError(f"fringe must be an object of {', '.join(_FRINGE_KEYS)}")
        _unknown(meta["fringe"], _FRINGE_KEYS, "fringe: ", "fringe")
        base = _fringe(meta["fringe"], base, "fringe")
    seq = meta.get("sequence")
    if not isinstance(seq, list) or not seq:
        raise ValueError("no sequence: a list of blocks (phase, gray, white, black) in frame order")
    raw = []
    for i, d in enumerate(seq):
        where = f"sequence[{i}]"
        if not isinstance(d, dict) or not isinstance(d.get("kind"), str) or d["kind"] not in KINDS:
            raise ValueError(f"{where} must be an object whose kind is one of {', '.join(KINDS)}, got {_short(d)}")
        _unknown(d, _BLOCK_KEYS[d["kind"]], f"{where}: ", f"a {d['kind']} block")
        if d["kind"] in ("phase", "gray") and d.get("axis") not in AXES:
            raise ValueError(f"{where}.axis must be 'col' or 'row', got {_short(d.get('axis'))}")
        raw.append(d)
    phase_of, periods = {}, {}
    for i, d in enumerate(raw):  # every phase block's period first: a Gray block before its phase block uses it
        if d["kind"] == "phase":
            phase_of.setdefault(d["axis"], []).append(i)
            periods[i] = _period(d, w if d["axis"] == "col" else h, f"sequence[{i}]")
    blocks, first = [], 0
    for i, d in enumerate(raw):
        where = f"sequence[{i}]"
        kind = d["kind"]
        if kind == "phase":
            b = Block("phase", d["axis"], first, _number(d.get("steps"), f"{where}.steps", 3, 64, integer=True),
                      periods[i], fringe=_fringe(d, base, where))
        elif kind == "gray":
            own = phase_of.get(d["axis"], [])
            if len(own) != 1:
                raise ValueError(f"{where}: a Gray block orders the periods of the one phase block of its axis; "
                                 f"axis {d['axis']} has {len(own)}")
            ref = _fringe(raw[own[0]], base, f"sequence[{own[0]}]")
            period = periods[own[0]]
            if "period" in d and abs(_number(d["period"], f"{where}.period", 2, 1e7) - period) > 1e-9:
                raise ValueError(f"{where}.period {d['period']} differs from the phase block's {period:g}")
            b = Block("gray", d["axis"], first, bits=_number(d.get("bits"), f"{where}.bits", 1, 20, integer=True),
                      period=period, inverse=_flag(d, "inverse", True, where),
                      complementary=_flag(d, "complementary", False, where), fringe=ref,
                      bit_order=bit_order_of(d, where + "."))
        else:
            b = Block(kind, first=first)
        blocks.append(b)
        first += b.count
    order = meta.get("order", "custom")
    if not isinstance(order, str) or len(order) > 64:
        raise ValueError(f"order must be a short text (procam's own sequences say 'procam'), got {_short(order)}")
    upside_down = _flag(meta, "upside_down", False, "")
    if upside_down and any(b.kind == "gray" for b in blocks):
        raise ValueError("upside_down applies to a sequence without a Gray code (a Gray code is absolute: its "
                         "projector's image decodes the way it is shown); drop it")
    ps = PhaseSet(w, h, family, tuple(blocks), order, upside_down)
    if "count" in meta and meta["count"] != ps.count:
        raise ValueError(f"count is {_short(meta['count'])} but the sequence's blocks have {ps.count} frames")
    return ps


def _period(d: dict, n: int, where: str) -> float:
    """The fringe period (projector pixels) of the phase block ``d`` along an axis of ``n`` pixels."""
    if ("period" in d) == ("periods" in d):
        raise ValueError(f"{where}: give the fringe period either in pixels (period) or as a count across the "
                         "panel (periods)")
    if "period" in d:
        return _number(d["period"], f"{where}.period", 2, 1e7)
    return n / _number(d["periods"], f"{where}.periods", 1e-6, n / 2)


def bit_order_of(d: dict, where: str = "") -> str:
    """The ``bit_order`` of a Gray-code description or Gray block ``d`` (default ``"msb-first"``)."""
    v = d.get("bit_order", "msb-first")
    if v not in BIT_ORDERS:
        raise ValueError(f"{where}bit_order must be \"msb-first\" (most significant bit first, the default) or "
                         f"\"lsb-first\" (least significant first), got {_short(v)}")
    return v


def _size(meta: dict, width=None, height=None) -> tuple[int, int]:
    """The projector's ``(width, height)`` of a description (the arguments, when given, override the file's),
    bounded; ValueError naming the field."""
    try:
        w = _number(meta["width"] if width is None else width, "width", 2, 32768, integer=True)
        h = _number(meta["height"] if height is None else height, "height", 2, 32768, integer=True)
    except KeyError as e:
        raise ValueError(f"no {e.args[0]} (the projector's size in pixels)") from None
    return w, h


def gray_from_dict(meta: dict, width=None, height=None, order=None, step=None) -> PatternSet:
    """The Gray-code sequence a Gray-family ``patterns.json`` dict describes (its ``width``, ``height``, ``order``,
    ``step``, ``bit_order``; the arguments, when given, override the file's).  Raises ValueError naming the
    field."""
    check_keys(meta)
    w, h = _size(meta, width, height)
    order = meta.get("order", "opencv") if order is None else order
    if order not in ORDERS:
        raise ValueError(f"unknown order {_short(order)} (one of {', '.join(ORDERS)})")
    overridden = order != meta.get("order", "opencv") or step is not None
    step = _number(meta.get("step", 1) if step is None else step, "step", 1, 64, integer=True)
    ps = pattern_set(w, h, order, step, bit_order_of(meta))
    if not overridden:  # what the file states beyond its size, order and step must be that sequence's
        derived = ps.to_dict()
        for key in _DERIVED:
            if key in meta and meta[key] != derived[key]:
                raise ValueError(f"{key} {_short(meta[key])} is not that of the {w}x{h} sequence of order {order}, step "
                                 f"{step} ({_short(derived[key])}): the file describes another sequence than procam's "
                                 "(which width, height, order, step and bit_order determine); remove the key or fix it")
    return ps


#: The keys of a Gray-family description that width, height, order and step determine (the frame pairs and their
#: bit rule are the bit order's: the capture's frames tell a wrong one, procam.capture.bit_order, in better words).
_DERIVED = ("count", "col_bits", "row_bits", "col_offset", "row_offset", "white", "black", "col_start", "row_start")
