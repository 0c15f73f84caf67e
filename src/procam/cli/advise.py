"""``procam advise``: live advice on the board's pose before a capture (preview window or JSON lines).

Importing this module registers the command on :data:`procam.cli._app.app`.  :class:`LiveAdvice` is the
advising session ``procam capture --advise`` runs before each pose too (with a quick single-pose
calibration of each captured pose, whose ``R, T`` give the projector side of the next pose's advice).
"""

from __future__ import annotations

import math
import sys
import threading
from pathlib import Path
from typing import Optional

import typer

from ..errors import ProcamError
from ._app import BoardOpt, SquareOpt, app, fail, parse_board, parse_size, say, user_errors, warn


def parse_angles(text: str, option: str) -> tuple[float, float, float]:
    """``"PSI,NU[,PHI]"`` degrees -> a tuple (one-line error naming ``option``)."""
    parts = [p for p in (text or "").replace(";", ",").split(",") if p.strip()]
    try:
        vals = [float(p) for p in parts]
    except ValueError:
        vals = []
    if len(vals) not in (2, 3) or not all(math.isfinite(v) for v in vals):
        fail(f"{option} must be PSI,NU[,PHI] in degrees (e.g. 15,12,0), got {text!r}")
    if len(vals) == 2:
        vals.append(0.0)
    if any(abs(v) >= 80 for v in vals[:2]):
        fail(f"{option}: psi and nu must be within +-80 degrees, got {text!r}")
    return vals[0], vals[1], vals[2]


def advisor_options(target: float, still_s: float, still_px: float):
    """:class:`procam.advisor.AdvisorOptions` from the CLI's numbers (one-line errors naming the options)."""
    from ..advisor import AdvisorOptions

    for opt, v, lo, hi in (("--target", target, 0.0, 100.0), ("--still", still_s, 0.0, 60.0),
                           ("--still-px", still_px, 0.0, 1000.0)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and lo <= v <= hi) or (opt == "--target" and v <= 0):
            fail(f"{opt} must be a finite number {'> 0' if opt == '--target' else '>= 0'} and <= {hi:g}, got {v}")
    return AdvisorOptions(target_pct=float(target), still_s=float(still_s), still_px=float(still_px))


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


class _StdinKey:
    """A line on stdin (Enter) asks for the capture when there is no window (read by a daemon thread)."""

    def __init__(self):
        self.pressed = threading.Event()
        self._thread = None

    def start(self):
        if self._thread is None and sys.stdin is not None and sys.stdin.isatty():
            def read():
                for _ in sys.stdin:
                    self.pressed.set()
            self._thread = threading.Thread(target=read, daemon=True)
            self._thread.start()
        return self

    def poll(self):
        if self.pressed.is_set():
            self.pressed.clear()
            return "capture"
        return None


class LiveAdvice:
    """One advising session over possibly several poses (the CLI's side of :func:`procam.acquire.live.advise`).

    Parameters
    ----------
    board : :class:`procam.board.Board`.
    options : :class:`procam.advisor.AdvisorOptions`.
    calibration, source : a calibration to start from (intrinsics and, with R, T, the projector side).
    json_lines : print each frame's advice as one JSON line on stdout (no window).
    auto : end a pose's advice when it is ready (good and still).
    max_frames : end a pose's advice after this many frames.
    """

    def __init__(self, board, options, *, calibration=None, source: str = "", json_lines: bool = False,
                 auto: bool = False, max_frames: int | None = None):
        self.board = board
        self.options = options
        self.calibration, self.source = calibration, source
        self.json_lines, self.auto, self.max_frames = json_lines, auto, max_frames
        self.advisor = None
        self.window = None
        self.best = None   # (score, calibration, source) of the captured poses
        self._key = _StdinKey()

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
        return self.advisor

    def run(self, camera, what: str = ""):
        """Advise on ``camera``'s frames until a key, ``auto`` or ``max_frames`` ends it; returns the
        :class:`procam.acquire.live.AdviseResult` (``reason`` ``"quit"``: Esc or the window closed)."""
        from ..acquire import live
        from ..acquire.cameras import to_gray

        first = to_gray(camera.grab().image)
        advisor = self._advisor_for((first.shape[1], first.shape[0]))
        advisor.reset_motion()
        if not self.json_lines and self.window is None:
            from ..acquire.preview import PreviewWindow

            self.window = PreviewWindow(advisor.image_size, title=f"procam advise{' - ' + what if what else ''}").open()
        if not self.json_lines:
            say(f"advising{' for ' + what if what else ''}: place the board; Space or Enter in the preview window "
                "captures" + (", or it captures by itself when the pose is good and still" if self.auto else "")
                + "; Esc quits")
        else:
            self._key.start()

        def on_advice(img, advice):
            if self.json_lines:
                sys.stdout.write(advice.to_json() + "\n")
                sys.stdout.flush()
            else:
                self.window.show(img, advice)

        poll = self.window.poll if self.window is not None else self._key.poll
        return live.advise(camera, advisor, on_advice=on_advice, poll=poll, auto=self.auto, max_frames=self.max_frames)

    def learn(self, folder, name: str | None = None, checked=None):
        """Calibrate a captured pose quickly (single-pose) and use its R, T, K for the next advice when it is the
        best so far.  ``checked``: the pose's instant verdict (:class:`procam.check.PoseCheck`, or the
        ProcamError that stopped it) when the caller has it, whose calibration is then used as it is.  Returns the
        calibration or None (one warning line when it fails)."""
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
            warn(f"quick calibration of {folder}: {e}; the advice keeps what it knew")
            return None
        adv = calib.poses[0]["advice"]
        rel = [calib.std.get(k, float("inf")) / abs(K[0, 0]) for k, K in (("f_c", calib.camera.K),
                                                                          ("f_p", calib.projector.K))]
        score = max(rel) if all(math.isfinite(r) for r in rel) else float("inf")
        verdicts = [adv[k]["message"] for k in ("camera", "projector")
                    if isinstance(adv.get(k), dict) and (adv[k]["weak"] or adv[k]["degenerate"])]
        say(f"quick calibration of {Path(folder).name}: f_c = {calib.camera.K[0, 0]:.1f} ± {100 * rel[0]:.2g} %, "
            f"f_p = {calib.projector.K[0, 0]:.1f} ± {100 * rel[1]:.2g} %"
            + (f" ({'; '.join(verdicts)})" if verdicts else ""))
        if adv.get("failed"):
            warn(f"{folder}: the quick calibration failed (an impossible focal length); the advice keeps what it knew")
            return calib
        if self.best is None or score < self.best[0]:
            self.best = (score, calib, f"{name or Path(folder).name} (captured)")
            if self.advisor is not None:
                self.advisor.set_calibration(calib, self.best[2])
        return calib


@app.command("advise")
@user_errors
def advise_cmd(
    board: BoardOpt,
    square: SquareOpt,
    camera: str = typer.Option("opencv:0", "--camera", help="opencv:INDEX | genicam:PRODUCER.cti[#DEVICE] | virtual "
                               "(the simulator's view of the board under the projector's white light)."),
    calibration: Optional[Path] = typer.Option(None, "--calibration", help="A calibration of this camera (procam JSON "
                                               "or OpenCV YAML): its intrinsics, and with R, T the projector side."),
    json_lines: bool = typer.Option(False, "--json", help="Print the advice as one JSON line per frame on stdout, "
                                    "no window."),
    auto: bool = typer.Option(False, "--auto", help="Stop as soon as the pose is good and the board still."),
    max_frames: Optional[int] = typer.Option(None, "--max-frames", help="Stop after N frames (scripts)."),
    target: float = typer.Option(1.0, "--target", help="A pose is good when the predicted std of f_c and f_p are "
                                 "at most this % of f."),
    still: float = typer.Option(0.5, "--still", help="The board counts as still after this many seconds without "
                                "moving."),
    still_px: float = typer.Option(1.0, "--still-px", help="... moving more than this many pixels."),
    exposure: Optional[float] = typer.Option(None, "--exposure", help="Manual camera exposure in ms."),
    gain: Optional[float] = typer.Option(None, "--gain", help="Camera gain in the camera's unit."),
    camera_size: Optional[str] = typer.Option(None, "--camera-size", help="Camera resolution WIDTHxHEIGHT (OpenCV)."),
    virtual_pose: Optional[str] = typer.Option(None, "--virtual-pose", help="--camera virtual: the board's angles "
                                               "PSI,NU[,PHI] in the camera frame (default: the recommended pose)."),
    seed: int = typer.Option(0, "--seed", help="--camera virtual: noise seed."),
):
    """Show the camera's live frames with the detected board, its angles in the camera (and, with a calibration
    that has R, T, in the projector), the predicted std of f_c and f_p for that pose, and which way to turn the
    board; Space/Enter or --auto ends it."""
    from ..acquire import cameras as cams

    b = parse_board(board, square)
    options = advisor_options(target, still, still_px)
    if max_frames is not None and not 1 <= max_frames <= 10_000_000:
        fail(f"--max-frames must be >= 1, got {max_frames}")
    if seed < 0:
        fail(f"--seed must be >= 0, got {seed}")
    for opt, v in (("--exposure", exposure), ("--gain", gain)):
        if v is not None and not (math.isfinite(v) and v > 0 if opt == "--exposure" else math.isfinite(v) and v >= 0):
            fail(f"{opt} must be a finite number {'> 0' if opt == '--exposure' else '>= 0'}, got {v}")
    cam_size = parse_size(camera_size, "--camera-size") if camera_size else None
    pose = parse_angles(virtual_pose, "--virtual-pose") if virtual_pose else None
    kind, _ = cams.parse_camera_spec(camera)
    if kind == "folder":
        fail(f"--camera {camera}: a folder camera delivers no live frames; advise needs a streaming camera "
             "(opencv:, genicam:) or virtual")
    if pose is not None and kind != "virtual":
        fail("--virtual-pose applies to --camera virtual only")
    calib, source = (None, "")
    if calibration is not None:
        calib, source = load_calibration_for(calibration, b)

    if kind == "virtual":
        from .. import simulate
        from ..acquire.live import VirtualLiveCamera

        scene = simulate.preset("ideal")
        if (b.cols, b.rows, b.square) != (scene.board_cols, scene.board_rows, scene.square):
            scene = scene.replace(board_cols=b.cols, board_rows=b.rows, square=b.square)
        scene = simulate.with_board_pose(scene, pose or simulate.RECOMMENDED_POSE)
        cam = VirtualLiveCamera(scene, seed=seed)
    else:
        cam = cams.open_camera(camera, size=cam_size, exposure_ms=exposure, gain=gain)
    session = LiveAdvice(b, options, calibration=calib, source=source, json_lines=json_lines, auto=auto,
                         max_frames=max_frames)
    try:
        with cam:
            res = session.run(cam)
    finally:
        session.close()
    a = res.advice
    if not json_lines:
        say(f"stopped ({res.reason}) after {res.frames} frames: {a.state}: {a.message}")
