"""The capture loop: show each pattern, grab a frame, check it, write the pose folder.

:func:`capture_pose` runs one pose:

1. pre-flight: white, black and white again -> :func:`procam.acquire.checks.preflight` (refuses to
   start when the projector's light is not visible, the white frame is saturated on the board, the
   board is not found, ...);
2. the sequence (:func:`procam.patterns.generate`: Gray codes in OpenCV's order + white + black by default,
   or a phase family's, :meth:`CaptureOptions.sequence`): per
   pattern show, wait the settle time, flush the camera, grab, check
   (:func:`~procam.acquire.checks.check_frame`; per pattern/inverse pair
   :func:`~procam.acquire.checks.check_pair`) and re-grab up to ``retries`` times, then stop with
   the reason;
3. a white frame after the sequence against the pre-flight's (drift);
4. ``patterns.json`` and ``capture.json`` (devices, settings, pre-flight, every frame's timings,
   attempts and checks).

Frames are written as they come by the capture-folder writer (:class:`procam.capture.SequenceWriter`,
role ``"captured"``): into a hidden sibling folder ``.NAME.partial-PID``, renamed to ``NAME`` only when
everything is written, so an interrupted or failed capture leaves no folder that looks complete (the
partial one is removed unless ``keep_failed``).  Nothing is printed: progress is reported through a
callback of :class:`Event`.

:func:`preflight_check` runs step 1 alone, once (the app's exposure help before a capture).
"""

from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Callable

import numpy as np

from .. import __version__, patterns
from ..errors import ProcamError
from ..io.files import to_jsonable
from ..io.formats import CAPTURE_FORMAT
from ..capture import SequenceWriter, check_out_dir, describe_frame
from . import checks
from .cameras.base import to_gray


class CaptureFailed(ProcamError):
    """The capture stopped: a check failed after all re-grabs, or the pre-flight refused to start."""


@dataclass(frozen=True)
class CaptureOptions:
    """Options of :func:`capture_pose`.

    order, step : the Gray family's sequence (:func:`procam.patterns.pattern_set`).
    family : the pattern family (:data:`procam.patterns.FAMILIES`; default ``"gray"``).
    phase : the phase family's keywords of :func:`procam.patterns.phase_set` (``steps``, ``period``, ``periods``,
        ``inverse``, ``complementary``); its sequence always ends with a white and a black frame.
    settle_s : wait after showing a pattern before flushing and grabbing (s).
    retries : re-grabs allowed per frame (and per pattern/inverse pair) before the capture stops.
    flush : call the camera's ``flush()`` before each grab.
    board : (cols, rows) inner corners: the pre-flight finds the board and measures on it; None =
        on the area the projector lights.
    max_saturated, min_span, level_tol, stale_frac, min_agreement : thresholds of
        :mod:`procam.acquire.checks`.
    postflight : grab a white frame after the sequence and compare it with the pre-flight's.
    keep_failed : keep the partial folder of a failed capture (hidden, no capture.json) for inspection.
    """

    order: str = "opencv"
    step: int = 1
    family: str = "gray"
    phase: dict = field(default_factory=dict)
    settle_s: float = 0.25
    retries: int = 3
    flush: bool = True
    board: tuple | None = None
    max_saturated: float = checks.MAX_SATURATED
    min_span: float = checks.MIN_SPAN_DN
    level_tol: float = 0.25
    stale_frac: float = 0.25
    min_agreement: float = 0.9
    postflight: bool = True
    keep_failed: bool = False

    def sequence(self, width: int, height: int):
        """The pattern set of a ``width`` x ``height`` projector (raises ValueError when the options do not make
        one)."""
        if self.family == "gray":
            return patterns.pattern_set(width, height, self.order, self.step)
        return patterns.pattern_set(width, height, family=self.family, **self.phase)

    def __post_init__(self):
        import math

        if not (isinstance(self.settle_s, (int, float)) and math.isfinite(self.settle_s) and self.settle_s >= 0):
            raise ValueError(f"settle_s must be a finite number >= 0, got {self.settle_s}")
        if int(self.retries) != self.retries or self.retries < 0:
            raise ValueError(f"retries must be an integer >= 0, got {self.retries}")
        if self.order not in patterns.ORDERS:
            raise ValueError(f"order must be one of {patterns.ORDERS}, got {self.order!r}")
        if self.family not in patterns.FAMILIES:
            raise ValueError(f"family must be one of {patterns.FAMILIES}, got {self.family!r}")
        if self.family == "gray" and self.phase:
            raise ValueError(f"the Gray family takes no {', '.join(sorted(self.phase))}")
        if "white_black" in self.phase:
            raise ValueError("a captured sequence always has its white and black frames (white_black)")
        for name in ("max_saturated", "min_span", "level_tol", "stale_frac", "min_agreement"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(f"{name} must be a finite number >= 0, got {v}")


@dataclass(frozen=True)
class Event:
    """Progress of a capture: ``kind`` in ``"preflight"``, ``"frame"`` (a frame accepted),
    ``"retry"`` (a frame rejected, re-grabbing), ``"postflight"``, ``"done"``; ``index`` the
    sequence frame (-1 for the whole pose), ``total`` the sequence length, ``message`` one line,
    ``data`` the numbers (a :class:`~procam.acquire.checks.Preflight` dict, a check ...)."""

    kind: str
    index: int
    total: int
    message: str = ""
    data: dict = field(default_factory=dict)


@dataclass(frozen=True)
class CaptureResult:
    """A finished pose: ``folder`` (complete, renamed into place), ``files`` (image paths in sequence
    order), the ``preflight`` verdict, the number of ``retries`` and the ``record`` written to
    capture.json."""

    folder: Path
    files: tuple
    preflight: checks.Preflight
    retries: int
    record: dict
    warnings: tuple = ()


def _units(ps) -> list[tuple[int, ...]]:
    """The sequence as units in capture order: (pattern, inverse) pairs and the single frames (white, black, the
    phase families' fringes, Gray bits without inverses)."""
    units = [(int(a), int(b)) for axis in ("col", "row") for a, b in ps.pair_indices(axis)]
    paired = {k for u in units for k in u}
    units += [(k,) for k in range(ps.count) if k not in paired]
    return sorted(units, key=lambda u: u[0])


def _jsonable_meta(meta: dict) -> dict:
    out = {}
    for k, v in (meta or {}).items():
        if isinstance(v, (str, int, float, bool)) or v is None:
            out[k] = v
        elif isinstance(v, (np.integer, np.floating, np.bool_)):
            out[k] = v.item()
    return out


class _Run:
    """State of one pose's capture (kept out of the public API)."""

    def __init__(self, projector, camera, opts: CaptureOptions, progress, clock):
        self.projector, self.camera, self.opts = projector, camera, opts
        self.progress = progress or (lambda event: None)
        self.clock = clock
        self.t0 = clock()
        self.retries = 0

    def emit(self, kind, index, total, message="", data=None):
        self.progress(Event(kind, index, total, message, data or {}))

    def shoot(self, image: np.ndarray):
        """Show ``image``, settle, flush, grab: (grey frame, Frame, t_show, t_grab) relative to the start."""
        o = self.opts
        t_show = self.clock() - self.t0
        self.projector.show(image)
        if hasattr(self.camera, "arm"):
            self.camera.arm()
        self.projector.wait(o.settle_s)
        if o.flush and hasattr(self.camera, "flush"):
            self.camera.flush()
        frame = self.camera.grab()
        t_grab = self.clock() - self.t0
        img = to_gray(frame.image)
        if img.dtype not in (np.uint8, np.uint16):
            raise CaptureFailed(f"camera {getattr(self.camera, 'name', '')}: frames of type {img.dtype}; procam "
                                "needs 8- or 16-bit images")
        return img, frame, t_show, t_grab


def capture_pose(out_dir, projector, camera, options: CaptureOptions = CaptureOptions(), *,
                 progress: Callable[[Event], None] | None = None, extra_files: dict | None = None,
                 extra: dict | None = None, clock: Callable[[], float] = time.monotonic) -> CaptureResult:
    """Capture one pose into ``out_dir`` (see the module docstring).

    Parameters
    ----------
    out_dir : the pose folder to create (must not exist, or be empty).
    projector : an open projector (``size``, ``show``, ``wait``, ``describe``):
        :class:`~procam.acquire.projector.ProjectorWindow` or ``VirtualProjector``.
    camera : an open camera (:class:`~procam.acquire.cameras.Camera`).
    options : :class:`CaptureOptions`.
    progress : called with an :class:`Event` for the pre-flight, each accepted or rejected frame,
        the post-flight check and the end.
    extra_files : ``{name: text}`` written into the folder with the JSON (e.g. a simulator's truth.json).
    extra : JSON-able dict stored in capture.json under ``"extra"``.
    clock : time source (seconds).

    Returns
    -------
    CaptureResult (its ``folder`` is the hook for a verdict on the pose).  Raises
    :class:`CaptureFailed` (one line) when a check stops the capture; on
    any error or interruption the partial folder is removed (kept, hidden, with ``keep_failed``).
    """
    o = options
    out = check_out_dir(out_dir)
    W, H = (int(v) for v in projector.size)
    try:
        ps = o.sequence(W, H)
    except ValueError as e:
        raise ProcamError(f"pattern sequence: {e}") from None
    seq = patterns.generate(W, H, o.order, step=o.step) if o.family == "gray" else \
        patterns.generate(W, H, family=o.family, **o.phase)
    white_img = np.full((H, W), 255, np.uint8)
    black_img = np.zeros((H, W), np.uint8)
    writer = SequenceWriter(out, ps, writer="capture", captured=True, keep_failed=o.keep_failed,
                            sidecars=("capture.json", *(extra_files or {})))
    run = _Run(projector, camera, o, progress, clock)
    started = datetime.now(timezone.utc).isoformat(timespec="seconds")
    with writer:
        pre, pre_record = _preflight(run, white_img, black_img, ps)
        ref = pre.reference
        t_seq = clock()
        frames: list[dict | None] = [None] * ps.count
        previous = ("pre-flight white", np.ones(len(ref.idx), np.float32))
        accepted: dict[int, np.ndarray] = {}
        for unit in _units(ps):
            before = previous
            for attempt in range(o.retries + 1):
                previous = before
                for j, k in enumerate(unit):
                    partner = accepted[unit[0]] if j == 1 else None
                    p = _grab_frame(run, k, seq[k], ps, ref, previous, partner, frames, writer)
                    accepted[k] = p
                    previous = (k, p)
                if len(unit) == 1:
                    break
                a, b = unit
                pc = checks.check_pair(accepted[a], accepted[b], a, b, ps, min_agreement=o.min_agreement,
                                       level_tol=o.level_tol)
                frames[b]["pair_check"] = pc.to_dict()
                if pc.ok:
                    break
                if attempt == o.retries:
                    raise CaptureFailed(f"{pc.reason} (still after {o.retries} re-grabs of the pair)")
                run.retries += 1
                run.emit("retry", b, ps.count, pc.reason, pc.to_dict())
        seq_s = clock() - t_seq
        warnings = list(pre.suggestions)
        post = None
        if o.postflight:
            img, _ = _steady(run, white_img)
            pc = checks.check_drift(ref.normalise(img), level_tol=o.level_tol)
            post = pc.to_dict()
            if pc.ok and abs(pc.stats["level"] - 1.0) > o.level_tol / 2:
                warnings.append(f"the white frame after the sequence is at {pc.stats['level']:.2f} of the one before "
                                "it: the exposure or the projector's brightness drifts (switch off auto exposure; let "
                                "the projector warm up)")
            run.emit("postflight", -1, ps.count, pc.reason or (warnings[-1] if warnings else ""), post)
            if not pc.ok:
                raise CaptureFailed(pc.reason)
        projector.show(black_img)
        total = clock() - run.t0
        record = {
            "format": CAPTURE_FORMAT, "version": 1, "procam": __version__, "status": "complete",
            "started": started, "finished": datetime.now(timezone.utc).isoformat(timespec="seconds"),
            "projector": projector.describe(), "camera": camera.describe(),
            "pattern_set": {"width": W, "height": H, "family": o.family, "order": o.order if o.family == "gray" else
                            ps.order, "step": o.step, "count": ps.count, "white": ps.white, "black": ps.black},
            "settings": {**{k: v for k, v in asdict(o).items() if k != "keep_failed"},
                         "settle_ms": round(o.settle_s * 1000.0, 3)},
            "preflight": pre_record, "postflight": post, "retries": run.retries,
            "timings": {"total_s": round(total, 4), "sequence_s": round(seq_s, 4),
                        "per_frame_s": round(seq_s / ps.count, 4)},
            "frames": frames, "warnings": warnings, "extra": extra or {},
        }
        files = writer.finish({"capture.json": json.dumps(to_jsonable(record), indent=1), **(extra_files or {})})
    run.emit("done", -1, ps.count, f"wrote {ps.count} frames to {out}", {"retries": run.retries})
    return CaptureResult(out, tuple(files), pre, run.retries, record, tuple(warnings))


def _preflight(run: _Run, white_img, black_img, ps):
    """White, black, white again -> Preflight; re-tried when the two whites disagree (a stale frame)."""
    o = run.opts
    exposure = getattr(run.camera, "exposure_ms", None)
    for attempt in range(o.retries + 1):
        pre, d, extra = _preflight_once(lambda image: _steady(run, image), white_img, black_img, o, exposure,
                                        getattr(run.camera, "name", ""))
        run.emit("preflight", -1, ps.count, pre.reason or "; ".join(pre.suggestions), d)
        if pre.ok:
            d["attempts"] = attempt + 1
            d.update(extra)
            return pre, d
        unstable = pre.repeat is not None and pre.repeat > 0.1 and pre.white_saturated <= o.max_saturated
        if not unstable or attempt == o.retries:
            raise CaptureFailed(f"pre-flight: {pre.reason}")
        run.retries += 1
    raise AssertionError("unreachable")


def _preflight_once(shoot, white_img, black_img, o: CaptureOptions, exposure, camera_name: str):
    """One pre-flight: (Preflight, its dict, the grabs / camera size / board found of the capture's record)."""
    w1, g1 = shoot(white_img)
    b, g2 = shoot(black_img)
    w2, g3 = shoot(white_img)
    if not (w1.shape == b.shape == w2.shape):
        raise CaptureFailed(f"camera {camera_name}: the frame size changed between frames "
                            f"({w1.shape[1]}x{w1.shape[0]}, {b.shape[1]}x{b.shape[0]})")
    corners = None
    if o.board is not None:
        from ..board.corners import detect_corners

        corners = detect_corners(w1, tuple(o.board))
        if corners is None:
            cols, rows = o.board
            raise CaptureFailed(f"chessboard with {cols}x{rows} inner corners not found in the pre-flight white "
                                f"frame: check --board (inner corners: {cols + 1}x{rows + 1} squares), that the "
                                "whole board is in view, lit by the projector and in focus")
    pre = checks.preflight(w1, b, w2, board_corners=corners, exposure_ms=exposure,
                           max_saturated=o.max_saturated, min_span=o.min_span)
    extra = {"grabs": [g1, g2, g3], "camera_size": [int(w1.shape[1]), int(w1.shape[0])],
             "board_found": None if o.board is None else True}
    return pre, pre.to_dict(), extra


def preflight_check(shoot, size, options: CaptureOptions = CaptureOptions(), *, exposure_ms: float | None = None,
                    camera_name: str = "") -> tuple[checks.Preflight, dict]:
    """The capture's pre-flight on its own, once (what :func:`capture_pose` does before the sequence): the projector
    shows white, black and white again, each grabbed by ``shoot(image) -> (frame, grabs)`` (``image`` (H, W) uint8 of
    the projector's ``size`` (width, height)); the board (``options.board``, inner corners) is found in the first
    white; :func:`procam.acquire.checks.preflight` judges the levels.

    Returns (:class:`~procam.acquire.checks.Preflight`, its dict with ``grabs``, ``camera_size`` and ``board_found``):
    a refused pre-flight is returned (``ok`` False, ``reason`` saying what to do); :class:`CaptureFailed` (one line)
    when the frame size changed between the frames or the board is not found."""
    W, H = (int(v) for v in size)
    pre, d, extra = _preflight_once(shoot, np.full((H, W), 255, np.uint8), np.zeros((H, W), np.uint8), options,
                                    exposure_ms, camera_name)
    return pre, {**d, **extra}


def _steady(run: _Run, image) -> tuple[np.ndarray, int]:
    """Show ``image`` and grab until two consecutive frames agree (streaming cameras only): a frame
    still in the camera's buffer from the previous image differs from the next one.  Returns the
    last frame and the number of grabs."""
    img, _, _, _ = run.shoot(image)
    if not getattr(run.camera, "streaming", True):
        return img, 1
    fs = checks.full_scale(img)
    tol = max(2.0, 0.02 * fs)
    for n in range(2, run.opts.retries + 3):
        nxt = to_gray(run.camera.grab().image)
        if nxt.shape == img.shape and np.median(np.abs(nxt.astype(np.float32) - img.astype(np.float32))) <= tol:
            return nxt, n
        img = nxt
    return img, run.opts.retries + 2


def steady_shooter(projector, camera, settle_s: float = 0.25):
    """``shoot(image) -> frame``: show ``image`` on the ``projector``, hold it ``settle_s`` seconds and grab by the
    capture loop's own rule (:func:`_steady`: a streaming camera until two frames agree) -- for a caller that shows
    images of its own (:func:`procam.world_check.capture_device`)."""
    import time

    run = _Run(projector, camera, CaptureOptions(settle_s=settle_s), None, time.monotonic)
    return lambda image: _steady(run, image)[0]


def _grab_frame(run: _Run, k: int, image, ps, ref, previous, partner, frames, writer: SequenceWriter) -> np.ndarray:
    """Show pattern ``k``, grab and check it, re-grab up to ``retries`` times; write it; return ``p``.

    A first-of-pair frame that keeps matching the frame before it through every re-grab (status
    ``"same"``; at once for cameras that do not stream) is kept as unverified: the two patterns
    coincide where the camera looks, and the pair check judges it with its inverse.
    """
    o = run.opts
    streaming = getattr(run.camera, "streaming", True)
    for attempt in range(o.retries + 1):
        img, frame, t_show, t_grab = run.shoot(image)
        if img.shape != tuple(ref.shape):
            raise CaptureFailed(f"camera {getattr(run.camera, 'name', '')}: frame {k} is {img.shape[1]}x{img.shape[0]}, "
                                f"the pre-flight frames were {ref.shape[1]}x{ref.shape[0]}")
        p = ref.normalise(img)
        fc = checks.check_frame(p, k, ps, previous, partner, level_tol=o.level_tol, stale_frac=o.stale_frac)
        if fc.status == "same" and (attempt == o.retries or not streaming):
            fc = checks.FrameCheck(True, "unverified", "", {**fc.stats, "note": "matches the frame before it"})
        if fc.ok:
            path = writer.add(k, img)
            frames[k] = {"index": k, "file": path.name, "pattern": describe_frame(k, ps),
                         "attempts": attempt + 1, "shown_s": round(t_show, 4), "grabbed_s": round(t_grab, 4),
                         "camera_timestamp": frame.timestamp, "camera": _jsonable_meta(frame.meta),
                         "check": fc.to_dict()}
            run.emit("frame", k, ps.count, "", fc.to_dict())
            return p
        if attempt == o.retries:
            raise CaptureFailed(f"{fc.reason} (still after {o.retries} re-grabs)")
        run.retries += 1
        run.emit("retry", k, ps.count, fc.reason, fc.to_dict())
    raise AssertionError("unreachable")


def capture_poses(out_dir, n_poses: int, projector, camera_for: Callable[[int], object],
                  options: CaptureOptions = CaptureOptions(), *, before_pose: Callable[[int], None] | None = None,
                  after_pose: Callable[[int, CaptureResult], None] | None = None,
                  progress: Callable[[int, Event], None] | None = None,
                  extra_files_for: Callable[[int], dict] | None = None) -> list[CaptureResult]:
    """Capture ``n_poses`` poses into ``out_dir/pose01``, ``pose02`` ...

    ``camera_for(i)`` returns the open camera for pose ``i`` (0-based; usually the same one),
    ``before_pose(i)`` is called before each pose (the CLI prompts there to move the board),
    ``after_pose(i, result)`` after each (the place for a verdict on the pose before the next one),
    ``progress(i, event)`` reports each pose's events.  The pose folders are checked before the
    first one is captured.  Returns the poses' results; a failure stops the session (poses already
    captured stay).
    """
    folders = pose_folders(out_dir, n_poses)
    results = []
    for i, folder in enumerate(folders):
        if before_pose is not None:
            before_pose(i)
        cb = (lambda e, i=i: progress(i, e)) if progress is not None else None
        extra = extra_files_for(i) if extra_files_for is not None else None
        results.append(capture_pose(folder, projector, camera_for(i), options, progress=cb, extra_files=extra,
                                    extra={"pose": i + 1, "poses": n_poses}))
        if after_pose is not None:
            after_pose(i, results[-1])
    return results


def pose_folders(out_dir, n_poses: int) -> list[Path]:
    """The folders of a session of ``n_poses`` poses, ``out_dir/pose01`` ..., each checked (it must not exist, or
    be empty: :func:`procam.capture.check_out_dir`)."""
    if n_poses < 1:
        raise ValueError(f"n_poses must be >= 1, got {n_poses}")
    digits = max(2, len(str(n_poses)))
    return [check_out_dir(Path(out_dir) / f"pose{i + 1:0{digits}d}") for i in range(n_poses)]
