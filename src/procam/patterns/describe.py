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
from the phase block of its axis.  Unknown keys are errors (a misspelt ``shfit`` must not be ignored).
"""

from __future__ import annotations

import math

from .gray import ORDERS, pattern_set
from .phase import AXES, KINDS, PHASE_FAMILIES, Block, Fringe, PhaseSet

_FRINGE_KEYS = ("sign", "origin", "pixel_center", "shift", "start", "levels", "gamma")
_TOP_KEYS = ("format", "version", "family", "width", "height", "order", "count", "white", "black", "sequence",
             "fringe", "files", "note", "notes", "description")
_BLOCK_KEYS = {"phase": ("kind", "axis", "steps", "period", "periods", *_FRINGE_KEYS),
               "gray": ("kind", "axis", "bits", "inverse", "complementary", "period"),
               "white": ("kind",), "black": ("kind",)}


def family_of(meta: dict | None) -> str:
    """The family a ``patterns.json`` dict describes: its ``family``, else ``"gray"`` (procam's Gray-code files
    carry none)."""
    if not isinstance(meta, dict):
        return "gray"
    return str(meta.get("family", "gray"))


def _number(v, what: str, lo: float = -math.inf, hi: float = math.inf, integer: bool = False):
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise ValueError(f"{what} must be a finite number, got {v!r}")
    if integer and v != int(v):
        raise ValueError(f"{what} must be a whole number, got {v!r}")
    if not lo <= v <= hi:
        raise ValueError(f"{what} must be from {lo:g} to {hi:g}, got {v!r}")
    return int(v) if integer else float(v)


def _fringe(d: dict, base: Fringe, where: str) -> Fringe:
    kw = {}
    for key in _FRINGE_KEYS:
        if key not in d:
            continue
        v = d[key]
        if key == "levels":
            if not (isinstance(v, (list, tuple)) and len(v) == 2):
                raise ValueError(f"{where}.levels must be [lo, hi], got {v!r}")
            kw[key] = tuple(_number(x, f"{where}.levels", 0, 255) for x in v)
        elif key in ("sign", "shift"):
            kw[key] = _number(v, f"{where}.{key}", -1, 1, integer=True)
        else:
            kw[key] = _number(v, f"{where}.{key}")
    try:
        return Fringe(**{**base.__dict__, **kw})
    except ValueError as e:
        raise ValueError(f"{where}: {e}") from None


def _flag(d: dict, key: str, default: bool, where: str) -> bool:
    v = d.get(key, default)
    if not isinstance(v, bool):
        raise ValueError(f"{where}.{key} must be true or false, got {v!r}")
    return v


def from_dict(meta: dict, width: int | None = None, height: int | None = None):
    """The sequence ``meta`` (a ``patterns.json`` dict) describes: a :class:`PatternSet` for Gray codes (only
    ``width``, ``height``, ``order``, ``step`` are read) or a :class:`PhaseSet`.  ``width``, ``height`` override the
    file's projector size.  Raises ValueError naming the field and what is wrong."""
    if not isinstance(meta, dict):
        raise ValueError("not a JSON object")
    family = family_of(meta)
    try:
        w = _number(meta["width"] if width is None else width, "width", 2, 32768, integer=True)
        h = _number(meta["height"] if height is None else height, "height", 2, 32768, integer=True)
    except KeyError as e:
        raise ValueError(f"no {e.args[0]} (the projector's size in pixels)") from None
    if family == "gray":
        order = meta.get("order", "opencv")
        if order not in ORDERS:
            raise ValueError(f"unknown order {order!r} (one of {', '.join(ORDERS)})")
        return pattern_set(w, h, order, _number(meta.get("step", 1), "step", 1, 64, integer=True))
    if family not in PHASE_FAMILIES:
        raise ValueError(f"unknown family {family!r} (one of gray, {', '.join(PHASE_FAMILIES)})")
    unknown = [k for k in meta if k not in _TOP_KEYS]
    if unknown:
        raise ValueError(f"unknown key {unknown[0]!r} (the keys of a {family} description are "
                         f"{', '.join(_TOP_KEYS[2:10])} and fringe)")
    base = Fringe()
    if "fringe" in meta:
        if not isinstance(meta["fringe"], dict):
            raise ValueError(f"fringe must be an object of {', '.join(_FRINGE_KEYS)}")
        bad = [k for k in meta["fringe"] if k not in _FRINGE_KEYS]
        if bad:
            raise ValueError(f"fringe: unknown key {bad[0]!r} (one of {', '.join(_FRINGE_KEYS)})")
        base = _fringe(meta["fringe"], base, "fringe")
    seq = meta.get("sequence")
    if not isinstance(seq, list) or not seq:
        raise ValueError("no sequence: a list of blocks (phase, gray, white, black) in frame order")
    raw = []
    for i, d in enumerate(seq):
        where = f"sequence[{i}]"
        if not isinstance(d, dict) or d.get("kind") not in KINDS:
            raise ValueError(f"{where} must be an object whose kind is one of {', '.join(KINDS)}, got {d!r}")
        bad = [k for k in d if k not in _BLOCK_KEYS[d["kind"]]]
        if bad:
            raise ValueError(f"{where}: unknown key {bad[0]!r} for a {d['kind']} block (one of "
                             f"{', '.join(_BLOCK_KEYS[d['kind']])})")
        if d["kind"] in ("phase", "gray") and d.get("axis") not in AXES:
            raise ValueError(f"{where}.axis must be 'col' or 'row', got {d.get('axis')!r}")
        raw.append(d)
    phase_of = {}
    for i, d in enumerate(raw):
        if d["kind"] == "phase":
            phase_of.setdefault(d["axis"], []).append(i)
    blocks, first = [], 0
    for i, d in enumerate(raw):
        where = f"sequence[{i}]"
        kind = d["kind"]
        if kind == "phase":
            n = w if d["axis"] == "col" else h
            if ("period" in d) == ("periods" in d):
                raise ValueError(f"{where}: give the fringe period either in pixels (period) or as a count across the "
                                 "panel (periods)")
            period = (_number(d["period"], f"{where}.period", 2, 1e7) if "period" in d
                      else n / _number(d["periods"], f"{where}.periods", 1e-6, n / 2))
            b = Block("phase", d["axis"], first, _number(d.get("steps"), f"{where}.steps", 3, 64, integer=True),
                      period, fringe=_fringe(d, base, where))
        elif kind == "gray":
            own = phase_of.get(d["axis"], [])
            if len(own) != 1:
                raise ValueError(f"{where}: a Gray block orders the periods of the one phase block of its axis; "
                                 f"axis {d['axis']} has {len(own)}")
            ph = raw[own[0]]
            ref = _fringe(ph, base, f"sequence[{own[0]}]")
            n = w if d["axis"] == "col" else h
            period = (float(ph["period"]) if "period" in ph else n / float(ph["periods"]))
            if "period" in d and abs(_number(d["period"], f"{where}.period", 2, 1e7) - period) > 1e-9:
                raise ValueError(f"{where}.period {d['period']} differs from the phase block's {period:g}")
            b = Block("gray", d["axis"], first, bits=_number(d.get("bits"), f"{where}.bits", 1, 20, integer=True),
                      period=period, inverse=_flag(d, "inverse", True, where),
                      complementary=_flag(d, "complementary", False, where), fringe=ref)
        else:
            b = Block(kind, first=first)
        blocks.append(b)
        first += b.count
    ps = PhaseSet(w, h, family, tuple(blocks), str(meta.get("order", "custom")))
    if "count" in meta and meta["count"] != ps.count:
        raise ValueError(f"count is {meta['count']!r} but the sequence's blocks have {ps.count} frames")
    return ps
