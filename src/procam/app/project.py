"""The project folder is the app's state: every capture, camera file, calibration, report and export lands in it in
procam's ordinary formats, under fixed names (:data:`FILES`), so the command line reads the same folder and a
reopened app resumes where its user left.

What the files cannot say (the board, the camera file chosen, the virtual rig's size) is kept in
``procam-app.json`` (format ``procam-app-project``).  Every path a request names is confined to the folder
(:meth:`Project.path`); every write goes through :mod:`procam.io.files` (atomic, and never over a file procam
did not write).
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

from ..errors import ProcamError
from ..io.formats import APP_PROJECT_FORMAT as STATE_FORMAT

#: What lands where in the project folder.
FILES = {"state": "procam-app.json", "board": "board.svg", "photos": "camera", "camera": "camera.json",
         "calibration": "calib.json", "yaml": "calib.yml",
         "residuals": "calib.residuals.png", "report": "calib.html", "world": "world.png",
         "world_json": "world.json", "export": "export",
         "rig_calibration": "rig-calib.json", "rig_yaml": "rig-calib.yml", "rig_figure": "rig-calib.png",
         "rig_report": "rig-calib.html", "blend": "blend"}

#: The defaults of a new project.
DEFAULTS = {"board": {"cols": 10, "rows": 6, "square": 24.0}, "unit": "mm", "camera_file": None,
            "projector_size": [1920, 1080], "pose": None, "calibration": None, "photos": None,
            "rig": None, "rig_calibration": None}


class Project:
    """The project folder ``root`` (created if missing) and its state."""

    def __init__(self, root):
        root = Path(root).expanduser()
        if root.exists() and not root.is_dir():
            raise ProcamError(f"{root}: not a folder; give the project folder (new or one the app made)")
        state = root / FILES["state"]
        if root.is_dir() and not state.exists() and any(not p.name.startswith(".") for p in root.iterdir()):
            what = ("a capture folder" if any((root / n).is_file() for n in ("capture.json", "patterns.json", "rig.json"))
                    else "a folder of other files")
            raise ProcamError(f"{root}: {what}, not a project the app made (no {FILES['state']}); give a new or "
                              "empty folder, or one the app made (procam calibrate and the other commands read "
                              "capture folders)")
        root.mkdir(parents=True, exist_ok=True)
        self.root = root.resolve()
        self.state = dict(DEFAULTS)
        if state.exists():
            self._load()
        else:
            self.save()  # the folder is the app's from now on: reopened, it is recognised

    def hold(self) -> None:
        """Take the project for this process (``.procam-app.lock`` holds its id): a second ``procam app`` on the
        same folder would write the same state file.  A lock whose process no longer runs is taken over; one of a
        running process is a one-line :class:`ProcamError`.  :meth:`release` gives it back."""
        lock = self.root / LOCK
        for _ in range(3):
            try:
                fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                try:
                    pid = int(lock.read_text().strip() or 0)
                except (OSError, ValueError):
                    pid = 0
                if pid and _running(pid):
                    raise ProcamError(f"{self.root}: another procam app (process {pid}) has this project open; stop "
                                      f"it (Ctrl+C there), or give another folder (the lock: {lock})") from None
                lock.unlink(missing_ok=True)  # the lock of a process that no longer runs
                continue
            with os.fdopen(fd, "w") as f:
                f.write(str(os.getpid()))
            return
        raise ProcamError(f"{lock}: cannot take the project's lock; remove the file if no procam app runs on it")

    def release(self) -> None:
        """Give back the lock :meth:`hold` took (only this process's)."""
        lock = self.root / LOCK
        try:
            if lock.read_text().strip() == str(os.getpid()):
                lock.unlink()
        except OSError:
            pass

    def file(self, key: str) -> Path:
        """The project file of ``key`` (:data:`FILES`)."""
        return self.root / FILES[key]

    def path(self, relative: str) -> Path:
        """``relative`` inside the project folder; :class:`ProcamError` for a path that leaves it (``..``, an
        absolute path, a symbolic link out of it)."""
        rel = Path(str(relative))
        if rel.is_absolute() or not str(relative).strip():
            raise ProcamError(f"{relative}: give a path inside the project folder {self.root}")
        p = (self.root / rel).resolve()
        if p != self.root and self.root not in p.parents:
            raise ProcamError(f"{relative}: outside the project folder {self.root}; give a path inside it")
        return p

    def _load(self) -> None:
        f = self.file("state")
        from ..io.jsonfile import load_json

        try:
            doc = load_json(f)
        except (OSError, ValueError) as e:
            raise ProcamError(f"{f}: not readable as the app's project state ({e}); move it away to start over") \
                from None
        if not isinstance(doc, dict) or doc.get("format") != STATE_FORMAT:
            raise ProcamError(f"{f}: not the app's project state (no \"format\": \"{STATE_FORMAT}\"); move it away")
        if doc.get("version", 1) != 1:
            raise ProcamError(f"{f}: version {doc.get('version')!r} of the project state; this procam reads version 1 "
                              "(a newer procam wrote it: use that one, or move the file away to start over)")
        for key in DEFAULTS:  # a state file edited by hand is checked as a request would be
            if key not in doc:
                continue
            v, kind = doc[key], _STATE_KINDS[key]
            if kind == "board":
                b = v if isinstance(v, dict) else {}
                try:
                    v = _checked_board(b.get("cols"), b.get("rows"), b.get("square"))
                except ProcamError as e:
                    raise ProcamError(f"{f}: {e}; fix it, or move the file away to start over") from None
            elif kind == "size":
                if not (isinstance(v, list) and len(v) == 2 and all(type(n) is int and 1 <= n <= 16384 for n in v)):
                    raise ProcamError(f"{f}: {key} must be [width, height] in pixels, got {v!r}; fix it, or move "
                                      "the file away to start over")
            elif not (v is None or isinstance(v, kind)):
                raise ProcamError(f"{f}: {key} must be {_KIND_WORDS[kind]}{'' if key == 'unit' else ' or null'}, got "
                                  f"{str(v)[:40]!r}; fix it, or move the file away to start over")
            self.state[key] = v

    def save(self) -> None:
        from ..io.files import write_text

        write_text(self.file("state"), json.dumps({"format": STATE_FORMAT, "version": 1, **self.state}, indent=1))

    def board(self):
        """The project's :class:`procam.board.Board`."""
        from ..board import Board

        b = self.state["board"]
        return Board(b["cols"], b["rows"], b["square"])

    def set_board(self, cols, rows, square) -> None:
        """Check and keep the board (a one-line :class:`ProcamError` names the wrong field)."""
        self.state["board"] = _checked_board(cols, rows, square)
        self.save()

    def summary(self) -> dict:
        """What the folder holds: the files of each step (names relative to the folder) that exist."""
        have = {k: self.file(k).exists() for k in FILES}
        exports = sorted(str(p.relative_to(self.root)) for p in self.file("export").glob("*") if p.is_file()) \
            if have["export"] else []
        pose = (self.state.get("pose") or {}).get("name")
        check = f"{pose}.check.png" if pose and (self.root / f"{pose}.check.png").is_file() else None
        return {"root": str(self.root), "state": self.state, "files": {k: FILES[k] for k in FILES if have[k]},
                "pose_check": check, "exports": exports}


#: The kind of value each key of the state file holds (null allowed but for the board, the unit and the size).
_STATE_KINDS = {"board": "board", "unit": str, "camera_file": str, "projector_size": "size", "pose": dict,
                "calibration": dict, "photos": dict, "rig": dict, "rig_calibration": dict}
_KIND_WORDS = {str: "a string", dict: "an object"}


def _checked_board(cols, rows, square) -> dict:
    """The state's board entry of ``cols`` x ``rows`` inner corners of ``square`` side, checked (a one-line
    :class:`ProcamError` names the wrong field)."""
    from ..board import Board

    for name, v in (("cols", cols), ("rows", rows)):
        if isinstance(v, bool) or not isinstance(v, int):
            raise ProcamError(f"board {name}: give a whole number of inner corners, got {v!r}")
    if isinstance(square, bool) or not isinstance(square, (int, float)) or not math.isfinite(square):
        raise ProcamError(f"board square: give the square's side as a number (e.g. 24 for mm), got {square!r}")
    Board(cols, rows, float(square))
    return {"cols": cols, "rows": rows, "square": float(square)}


#: The hidden file that says which process has the project open (:meth:`Project.hold`).
LOCK = ".procam-app.lock"


def _running(pid: int) -> bool:
    """Does process ``pid`` run (on Windows, where a signal 0 is Ctrl+C, every lock counts as held)?"""
    if os.name == "nt":
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True
