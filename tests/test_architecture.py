"""The house: every room (a top-level module or package of procam) imports only rooms on floors below its own,
the rooms are the ones docs/architecture.md describes, there are few flat modules, and files are parsed in io/
only. Read from the source's own import statements (no import is run)."""

from __future__ import annotations

import ast
import re
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "procam"
DOC = Path(__file__).resolve().parents[1] / "docs" / "architecture.md"

#: The floors, bottom first (docs/architecture.md): a room may import the rooms of lower floors only.
FLOORS = (
    ("errors", "choices", "style", "parameters", "stats", "uncertainty", "_dual", "_threads", "datasheet",
     "mounting"),
    ("models", "verdict", "triangulate"),
    ("board", "calibration", "crlb", "distortion", "residuals", "summary"),
    ("view",),
    ("io", "evaluate"),
    ("patterns", "export", "reconstruct"),
    ("decode",),
    ("capture", "correspond", "plots"),
    ("single_pose", "simulate", "stream"),
    ("multi_pose", "advisor", "pipeline"),
    ("method", "verify", "check", "paper"),
    ("rig", "acquire"),
    ("report", "world_check"),
    ("app",),
    ("cli",),
)
FLOOR = {room: k for k, rooms in enumerate(FLOORS) for room in rooms}


def _imports():
    """``[(file, importing room, imported room)]`` of every procam import in the source (lazy ones too)."""
    out = []
    for f in SRC.rglob("*.py"):
        parts = list(f.relative_to(SRC.parent).with_suffix("").parts)
        is_pkg = parts[-1] == "__init__"
        mod = parts[:-1] if is_pkg else parts
        pkg = mod if is_pkg else mod[:-1]
        room = mod[1] if len(mod) > 1 else None
        for node in ast.walk(ast.parse(f.read_text())):
            if not isinstance(node, ast.ImportFrom):
                continue
            if node.level:
                base = pkg[:len(pkg) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if not target.startswith("procam"):
                continue
            names = [f"procam.{a.name}" for a in node.names] if target == "procam" else [target]
            for t in names:
                t_room = t.split(".")[1] if "." in t else None
                if room is not None and t_room not in (None, room, "__version__"):
                    out.append((f.relative_to(SRC.parent), room, t_room))
    return out


def test_every_room_is_on_a_floor_and_imports_only_rooms_below():
    rooms = {p.stem if p.is_file() else p.name for p in SRC.iterdir()
             if (p.suffix == ".py" and p.stem != "__init__") or (p.is_dir() and (p / "__init__.py").exists())}
    assert rooms == set(FLOOR), (sorted(rooms - set(FLOOR)), sorted(set(FLOOR) - rooms))
    upward = [(str(f), a, b) for f, a, b in _imports() if FLOOR[b] >= FLOOR[a]]
    assert not upward, upward


def test_at_most_28_flat_modules():
    flat = [p.name for p in SRC.glob("*.py") if p.name != "__init__.py"]
    assert len(flat) <= 28, sorted(flat)


def test_every_room_has_its_paragraph_in_docs_architecture():
    text = DOC.read_text()
    described = set(re.findall(r"\*\*`([a-z_]+)`\*\*", text))
    assert described == set(FLOOR), (sorted(set(FLOOR) - described), sorted(described - set(FLOOR)))


def test_files_are_parsed_in_io_only():
    """JSON, FileStorage and NumPy files are read by procam.io alone (the Blender-side loader runs inside Blender,
    without procam)."""
    readers = re.compile(r"\bjson\.loads?\(|FileStorage\(|\bnp\.load\(")
    found = [str(f.relative_to(SRC)) for f in SRC.rglob("*.py")
             if readers.search(f.read_text()) and f.relative_to(SRC).parts[0] != "io"]
    assert found == ["export/blender_cameras.py"], found
