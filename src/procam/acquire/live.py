"""Live advice while the board is placed: the advising loop, and the advising session over a capture's poses.

:func:`advise`
    The loop: grab a frame, :meth:`procam.advisor.Advisor.update`, hand the advice to a callback (the
    preview window, the JSON lines), until a key asks for the capture, ``auto`` finds the pose ready, or
    ``max_frames`` frames were seen.
:class:`LiveAdvice`
    One advising session over possibly several poses (``procam advise``, and ``procam capture --advise``
    before each pose): one :class:`~procam.advisor.Advisor` for the camera's frame size, the preview window
    (:class:`~procam.acquire.preview.PreviewWindow`) or a callback per frame, and after each captured pose a
    quick single-pose calibration (:meth:`LiveAdvice.learn`) whose ``R, T`` give the projector side of the
    next pose's advice when it is the best so far.
:func:`advise_camera`
    The camera mode's loop (:class:`~procam.advisor.CameraAdvisor`): photos for a camera calibrated once.
:func:`advisor_options`, :func:`load_calibration_for`, :func:`calibration_square`
    The session's options from the command line's numbers and files, checked (one-line errors naming the
    options).

Nothing is printed: what the session has to say goes to a ``notify(level, text)`` callback (level
``"info"`` or ``"warning"``); the simulator's live camera is :class:`procam.acquire.cameras.VirtualLiveCamera`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from ..errors import ProcamError
from .cameras.base import to_gray


@dataclass(frozen=True)
class AdviseResult:
    """How :func:`advise` ended: ``reason`` (``"key"``, ``"auto"``, ``"max-frames"``, ``"quit"``), the last
    :class:`~procam.advisor.Advice` (None if no frame was seen), the number of ``frames`` and ``t0``, the clock
    reading the advice's ``time_s`` counts from."""

    reason: str
    advice: object
    frames: int
    t0: float = 0.0


def advise(camera, advisor, *, on_advice: Callable | None = None, poll: Callable | None = None,
           auto: bool = False, max_frames: int | None = None, clock: Callable[[], float] = time.monotonic,
           use_camera_time: bool = True, t0: float | None = None) -> AdviseResult:
    """Run the advisor on the camera's live frames until the capture should start (or the loop ends).

    Parameters
    ----------
    camera : an open camera (``grab() -> Frame``).
    advisor : :class:`procam.advisor.Advisor` for the camera's frame size.
    on_advice : called with ``(frame image, advice)`` after each frame (draw the preview, print JSON).
    poll : called after each frame; returns None to go on, ``"capture"`` (a key asked for the capture)
        or ``"quit"``.
    auto : end as soon as the advice is ``ready`` (good, and the board still).
    max_frames : end after this many frames (scripts, tests).
    clock : time source when the camera's time stamps are not used.
    use_camera_time : use each frame's own time stamp (``Frame.timestamp``) for the stillness test.
    t0 : the clock reading that is time 0 (default: the first frame's): each advice's ``time_s`` is seconds since
        then, not the camera's or the machine's uptime clock.

    Returns
    -------
    :class:`AdviseResult`.
    """
    if max_frames is not None and max_frames < 1:
        raise ProcamError(f"--max-frames must be >= 1, got {max_frames}")
    n, last = 0, None
    while True:
        frame = camera.grab()
        img = to_gray(frame.image)
        t = frame.timestamp if use_camera_time and frame.timestamp is not None else clock()
        if t0 is None:
            t0 = t
        last = advisor.update(img, t - t0)
        n += 1
        if on_advice is not None:
            on_advice(img, last)
        what = poll() if poll is not None else None
        if what in ("capture", "quit"):
            return AdviseResult("key" if what == "capture" else "quit", last, n, t0)
        if auto and last.ready:
            return AdviseResult("auto", last, n, t0)
        if max_frames is not None and n >= max_frames:
            return AdviseResult("max-frames", last, n, t0)


def advise_camera(camera, advisor, *, on_advice: Callable | None = None, poll: Callable | None = None,
                  auto: bool = False, max_frames: int | None = None,
                  on_photo: Callable | None = None) -> AdviseResult:
    """The camera mode's loop: grab a frame, :meth:`procam.advisor.CameraAdvisor.update`, hand the advice to
    ``on_advice``; a key (``poll() == "capture"``) or, with ``auto``, the advice ``"take"`` takes the frame as a
    photo (:meth:`~procam.advisor.CameraAdvisor.take`, refitted by :func:`camera_fit` from two photos on;
    ``on_photo(advisor, name)`` after it); with ``auto`` and a
    camera that can follow the advice (the simulator's :meth:`VirtualLiveCamera.follow
    <procam.acquire.cameras.VirtualLiveCamera.follow>`: the simulated user), it moves the board as advised.  Ends
    when the advice is ``"enough"`` (reason ``"enough"``), on ``"quit"``, or after ``max_frames`` frames."""
    if max_frames is not None and max_frames < 1:
        raise ProcamError(f"--max-frames must be >= 1, got {max_frames}")
    n, last = 0, None
    while True:
        img = to_gray(camera.grab().image)
        last = advisor.update(img)
        n += 1
        if on_advice is not None:
            on_advice(img, last)
        if last.state == "enough":
            return AdviseResult("enough", last, n)
        what = poll() if poll is not None else None
        if what == "quit":
            return AdviseResult("quit", last, n)
        if (what == "capture" and last.corners is not None) or (auto and last.state == "take"):
            name = f"photo{len(advisor.views) + 1:02d}"
            advisor.take(img, name=name)
            if len(advisor.views) >= 2:
                advisor.set_fit(camera_fit(advisor.views))
            if on_photo is not None:
                on_photo(advisor, name)
        elif auto and last.state == "adjust" and hasattr(camera, "follow"):
            camera.follow(last)
        if max_frames is not None and n >= max_frames:
            return AdviseResult("max-frames", last, n)


def camera_fit(views):
    """The running camera-only fit of the camera mode's photos (:func:`procam.multi_pose.calibrate_camera`); its
    caveats are the camera file's to say (:func:`camera_calibration`), not each photo's."""
    import warnings

    from ..multi_pose import calibrate_camera

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return calibrate_camera(views)


def camera_calibration(advisor, path=None):
    """The camera-only calibration of the camera mode's photos (:func:`procam.method.calibrate`: its verdict and
    warnings, what it was calibrated from, its covariance), written to ``path`` (the camera file) when given."""
    from .. import method

    if len(advisor.views) < 2:
        raise ProcamError(f"advisor: {len(advisor.views)} photo(s) taken; a camera calibration needs at least 2")
    calib = method.calibrate(advisor.views, method="camera-only")
    if path is not None:
        from ..io import save_calibration

        save_calibration(calib, path)
    return calib


def advisor_options(target: float, still_s: float, still_px: float):
    """:class:`procam.advisor.AdvisorOptions` from the command line's numbers (``--target``, ``--still``,
    ``--still-px``); a :class:`ProcamError` naming the option when one is out of range."""
    from ..advisor import AdvisorOptions

    for opt, v, lo, hi in (("--target", target, 0.0, 100.0), ("--still", still_s, 0.0, 60.0),
                           ("--still-px", still_px, 0.0, 1000.0)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and lo <= v <= hi) or (opt == "--target" and v <= 0):
            raise ProcamError(f"{opt} must be a finite number {'> 0' if opt == '--target' else '>= 0'} and <= {hi:g}, "
                              f"got {v}")
    return AdvisorOptions(target_pct=float(target), still_s=float(still_s), still_px=float(still_px))


def calibration_square(path) -> float:
    """The square size of the board of the calibration file ``path`` (``--calibration`` without ``--square``)."""
    from ..io import load_calibration

    boards = [v.board for v in load_calibration(path).views if getattr(v, "board", None) is not None]
    if not boards:
        raise ProcamError(f"--calibration {path}: it does not say its board's square size; give --square (T is in "
                          "that unit)")
    return boards[0].square


def load_calibration_for(path: Path, board) -> tuple:
    """``(calibration, source)`` from ``--calibration``, checked against the board's square size (``T`` is in
    the calibration's length unit, which must be the board's)."""
    from ..io import load_calibration

    calib = load_calibration(path)
    boards = [v.board for v in calib.views if getattr(v, "board", None) is not None]
    if boards and calib.T is not None and not math.isclose(boards[0].square, board.square, rel_tol=1e-6):
        raise ProcamError(f"--calibration {path}: its board has squares of {boards[0].square:g} but --square is "
                          f"{board.square:g}; give the same square size (T is in that unit)")
    return calib, str(path)


class LiveAdvice:
    """One advising session over possibly several poses (see the module docstring).

    Parameters
    ----------
    board : :class:`procam.board.Board`.
    options : :class:`procam.advisor.AdvisorOptions`.
    calibration, source : a calibration to start from (intrinsics and, with R, T, the projector side).
    known_camera, known_source : the camera's intrinsics (a :class:`~procam.calibration.Device`) held known in the
        calibration to come (``procam calibrate POSE --camera FILE``), and where they come from: the advice
        predicts the projector's ± for that fit.
    window : show each frame with its advice in the preview window, whose keys end a pose's advice
        (Space/Enter: capture, Esc: quit); else no window.
    on_advice : called with ``(frame image, advice)`` after each frame (e.g. to print JSON lines).
    poll : without a window, called after each frame: ``"capture"`` ends a pose's advice (e.g. Enter on the
        terminal), None goes on.
    auto : end a pose's advice when it is ready (good and still).
    max_frames : end a pose's advice after this many frames.
    notify : called with ``(level, text)`` for what the session tells its user (``"info"``, ``"warning"``).
    """

    def __init__(self, board, options, *, calibration=None, source: str = "", window: bool = True,
                 on_advice: Callable | None = None, poll: Callable | None = None, auto: bool = False,
                 max_frames: int | None = None, notify: Callable[[str, str], None] | None = None,
                 known_camera=None, known_source: str = ""):
        self.board = board
        self.known_camera, self.known_source = known_camera, known_source
        self.options = options
        self.calibration, self.source = calibration, source
        self.window_wanted, self.on_advice, self.poll = window, on_advice, poll
        self.auto, self.max_frames = auto, max_frames
        self.notify = notify or (lambda level, text: None)
        self.advisor = None
        self.window = None
        self.best = None   # (score, calibration, source) of the captured poses
        self.t0 = None     # the clock reading of the session's first frame: time_s counts from it

    def close(self):
        if self.window is not None:
            self.window.close()
            self.window = None

    def _advisor_for(self, size):
        from ..advisor import Advisor

        if self.advisor is None or self.advisor.image_size != tuple(size):
            self.advisor = Advisor(self.board, size, self.options)
            calib, source = (self.best[1], self.best[2]) if self.best else (self.calibration, self.source)
            if calib is not None:
                self.advisor.set_calibration(calib, source)
            if self.known_camera is not None:
                self.advisor.set_camera(self.known_camera, self.known_source, known=True)
        return self.advisor

    def run(self, camera, what: str = "") -> AdviseResult:
        """Advise on ``camera``'s frames until a key, ``auto`` or ``max_frames`` ends it; returns the
        :class:`AdviseResult` (``reason`` ``"quit"``: Esc or the window closed)."""
        first = to_gray(camera.grab().image)
        advisor = self._advisor_for((first.shape[1], first.shape[0]))
        advisor.reset_motion()
        if self.window_wanted and self.window is None:
            from .preview import PreviewWindow

            self.window = PreviewWindow(advisor.image_size, title=f"procam advise{' - ' + what if what else ''}").open()
        if self.window_wanted:
            self.notify("info", f"advising{' for ' + what if what else ''}: place the board; Space or Enter in the "
                        "preview window captures" + (", or it captures by itself when the pose is good and still"
                                                     if self.auto else "") + "; Esc quits")

        def on_advice(img, advice):
            if self.on_advice is not None:
                self.on_advice(img, advice)
            if self.window is not None:
                self.window.show(img, advice)

        poll = self.window.poll if self.window is not None else self.poll
        res = advise(camera, advisor, on_advice=on_advice, poll=poll, auto=self.auto, max_frames=self.max_frames,
                     t0=self.t0)
        self.t0 = res.t0
        return res

    def learn(self, folder, name: str | None = None, checked=None):
        """Calibrate a captured pose quickly (single-pose) and use its R, T, K for the next advice when it is the
        best so far.  ``checked``: the pose's instant verdict (:class:`procam.check.PoseCheck`, or the
        ProcamError that stopped it) when the caller has it, whose calibration is then used as it is.  Returns the
        calibration or None (one warning when it fails)."""
        from .. import pipeline, single_pose

        try:
            if isinstance(checked, ProcamError):
                raise checked
            if checked is not None and checked.calibration is None:
                raise ProcamError("; ".join(checked.reasons) or checked.verdict)
            if checked is not None:
                calib = checked.calibration
            else:
                view, _ = pipeline.view_from_folder(folder, self.board)
                calib = single_pose.calibrate(view)  # a failed or degenerate pose comes back flagged
        except ProcamError as e:
            self.notify("warning", f"quick calibration of {folder}: {e}; the advice keeps what it knew")
            return None
        adv = calib.poses[0]["advice"]
        rel = [calib.std.get(k, float("inf")) / abs(K[0, 0]) for k, K in (("f_c", calib.camera.K),
                                                                          ("f_p", calib.projector.K))]
        score = max(rel) if all(math.isfinite(r) for r in rel) else float("inf")
        verdicts = [adv[k]["message"] for k in ("camera", "projector")
                    if isinstance(adv.get(k), dict) and (adv[k]["weak"] or adv[k]["degenerate"])]
        self.notify("info", f"quick calibration of {Path(folder).name}: f_c = {calib.camera.K[0, 0]:.1f} ± "
                    f"{100 * rel[0]:.2g} %, f_p = {calib.projector.K[0, 0]:.1f} ± {100 * rel[1]:.2g} %"
                    + (f" ({'; '.join(verdicts)})" if verdicts else ""))
        if adv.get("failed"):
            self.notify("warning", f"{folder}: the quick calibration failed (an impossible focal length); the advice "
                        "keeps what it knew")
            return calib
        if self.best is None or score < self.best[0]:
            self.best = (score, calib, f"{name or Path(folder).name} (captured)")
            if self.advisor is not None:
                self.advisor.set_calibration(calib, self.best[2])
                if self.known_camera is not None:
                    self.advisor.set_camera(self.known_camera, self.known_source, known=True)
        return calib
