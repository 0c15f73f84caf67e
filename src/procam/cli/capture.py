"""``procam capture``: show the pattern sequence (Gray codes, or a phase family with ``--family``) on the
projector, grab and check a camera frame per pattern.

Importing this module registers the command on :data:`procam.cli._app.app`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from ..errors import ProcamError
from ._app import app, console, err_console, fail, given, is_tty, plain, refuse, text_on_stderr, user_errors
from ._options import (
    SIMULATED_CAMERA,
    SIMULATED_PROJECTOR,
    CameraSizeOpt,
    DisplayOpt,
    ExposureOpt,
    GainOpt,
    LiveAutoOpt,
    LiveCalibrationOpt,
    LiveJsonOpt,
    LiveMaxFramesOpt,
    LiveTargetOpt,
    SeedOpt,
    camera_settings,
    live_limits,
    number,
    parse_board,
    parse_size,
    pattern_sequence,
    phase_keywords,
    refuse_unread_camera,
    virtual_gain,
    seed_applies,
    value,
    with_pattern_options,
)


def _list_devices(camera: str | None) -> None:
    from ..acquire import cameras as cams
    from ..acquire.projector import choose_display, list_displays

    console.print("[bold]displays[/bold] (--display N)")
    try:
        displays = list_displays()
        try:
            default = choose_display(displays).index
        except ProcamError:
            default = None
        for d in displays:
            console.print(plain(f"  {d.label()}" + ("   <- default projector" if d.index == default else "")))
    except ProcamError as e:
        console.print(plain(f"  none: {e}"))
    console.print("[bold]cameras[/bold] (--camera)")
    found = cams.list_opencv_cameras()
    for c in found:
        console.print(plain(f"  {c['spec']:<12} {c['device']:<14} {c['name']}"))
    if not found:
        console.print("  no OpenCV (UVC/V4L2) camera found", highlight=False)
    if camera and camera.lower().startswith("genicam:"):
        _, arg = cams.parse_camera_spec(camera)
        for c in cams.list_genicam_cameras(arg.partition("#")[0]):
            console.print(plain(f"  {c['spec']}  {c['vendor']} {c['model']} serial {c['serial_number']}"))
    else:
        console.print("  GenICam cameras: add --camera genicam:PRODUCER.cti to list a producer's cameras", highlight=False)
    console.print("  folder:PATH (files saved by the camera's own software), virtual (the simulator)", highlight=False)


@app.command("capture")
@user_errors
@with_pattern_options(leave_out=("white_black",))
def capture_cmd(
    out_dir: Optional[Path] = typer.Argument(None, help="The pose folder to create (with --poses N: the folder that "
                                             "gets pose01 ... poseN). Must not exist, or be empty."),
    projector: Optional[str] = typer.Option(None, "--projector", "-p", help="Pattern size WIDTHxHEIGHT, the projector's "
                                            "native resolution (default: the display's size; 1920x1080 with --virtual)."),
    display: DisplayOpt = None,
    camera: str = typer.Option("opencv:0", "--camera", help="opencv:INDEX | genicam:PRODUCER.cti[#DEVICE] | "
                               "folder:PATH | virtual."),
    poses: int = typer.Option(1, "--poses", help="Capture N poses into OUT_DIR/pose01 ..., with a prompt to move the "
                              "board between them."),
    settle_ms: Optional[float] = typer.Option(None, "--settle-ms", help="Wait after showing each pattern before "
                                              "grabbing, ms (default 250; 0 with --virtual)."),
    exposure: ExposureOpt = None,
    gain: GainOpt = None,
    camera_size: CameraSizeOpt = None,
    retries: int = typer.Option(3, "--retries", help="Re-grabs allowed per frame before the capture stops."),
    square: Optional[float] = typer.Option(None, "--square", help="Square size, the unit of lengths (the instant "
                                           "verdict; --advise: of --calibration, whose own board is the default); "
                                           "default 1: lengths in squares."),
    board: Optional[str] = typer.Option(None, "--board", help="Inner corners COLSxROWS: the pre-flight finds the board "
                                        "and judges the exposure on it (default: on the projector's light)."),
    timeout: float = typer.Option(60.0, "--timeout", help="folder camera: seconds to wait for each new file."),
    keep_failed: bool = typer.Option(False, "--keep-failed", help="Keep the frames of a failed capture in a hidden "
                                     "partial folder."),
    list_devices: bool = typer.Option(False, "--list-devices", help="List the displays and cameras and exit."),
    virtual: bool = typer.Option(False, "--virtual", help="Demo without devices: a virtual projector and the "
                                 "simulator as the camera (writes truth.json too)."),
    seed: SeedOpt = 0,
    advise: bool = typer.Option(False, "--advise", help="Before each pose, a preview with live advice on the board's "
                                "pose (needs --board); Space/Enter starts the capture. Each captured pose is "
                                "calibrated at once: its R, T give the projector side of the next pose's advice."),
    auto: LiveAutoOpt = False,
    json_lines: LiveJsonOpt = False,
    calibration: LiveCalibrationOpt = None,
    target: LiveTargetOpt = 1.0,
    max_frames: LiveMaxFramesOpt = None,
    rig_spec: Optional[str] = typer.Option(None, "--rig", help="A rig pose: projectors NAME=DISPLAY,... shown in "
                                           "turn, the board still; OUT_DIR gets one sub-folder per projector and "
                                           "rig.json (docs/rigs.md). --virtual: two names."),
    **pattern_args,
):
    """Show the pattern sequence full screen on the projector (Gray codes, or a phase family with --family,
    docs/patterns.md), grab and check one camera frame per pattern, and write a pose folder that decode/calibrate
    read as is (images, patterns.json, capture.json)."""
    from ..acquire.orchestrate import Devices, capture_session
    from ..acquire.session import CaptureOptions

    if list_devices:
        _list_devices(camera)
        return
    if out_dir is None:
        fail("give the pose folder to create (OUT_DIR), or --list-devices")
    # every number and spec is checked before a device is opened
    size = parse_size(projector, "--projector") if projector else None
    if size and max(size) > 16384:
        fail(f"--projector {projector}: larger than 16384 pixels; give the projector's native resolution")
    if not 1 <= poses <= 99:
        fail(f"--poses must be between 1 and 99, got {poses}")
    if not 0 <= retries <= 20:
        fail(f"--retries must be between 0 and 20, got {retries}")
    number(settle_ms, "--settle-ms", lo=0, hi=10000, unit=" ms", what="a finite number")
    number(timeout, "--timeout", lo=0, hi=3600, lo_open=True, unit=" s", what="a finite number")
    cam_size = camera_settings(exposure, gain, camera_size, seed, display)
    live_limits(max_frames)
    order, step, family = value(pattern_args["order"]), pattern_args["step"], pattern_args["family"]
    number(square, "--square", lo=0, lo_open=True, hi=1e9, what="a square size")
    if not board:
        refuse(("square",), "is the size of the board's squares: it applies with --board (the instant verdict) or "
                            "--advise")
    board_size = parse_size(board, "--board") if board else None
    brd = parse_board(board, 1.0 if square is None else square) if board else None
    # --rig (issue 27): checked here, captured by procam.acquire.rig (cli/_rig.py)
    from . import _rig

    rig_projectors = _rig.capture_projectors(rig_spec, virtual, display, poses, advise) if rig_spec else None
    live = _live_advice(advise, auto, json_lines, calibration, square, target, max_frames, board, virtual)
    if virtual and camera not in ("opencv:0", "virtual"):
        fail(f"--virtual uses the simulator as the camera; leave out --camera {camera}")
    kind = _refuse_unused("virtual" if virtual else camera, virtual, rig_spec is not None)
    if kind == "virtual":
        virtual_gain(gain)
    if kind == "virtual" and step != 1:
        fail("the virtual camera renders step-1 sequences only; leave out --step")
    # the sequence, checked at the projector's size (or a 1920x1080 one until the display is known)
    pattern_sequence(size or (1920, 1080), **pattern_args)
    family = value(family)
    phase = {} if family == "gray" else phase_keywords(**{k: v for k, v in pattern_args.items()
                                                          if k not in ("order", "step")})
    phase.pop("white_black", None)  # a captured sequence always ends with white and black
    options = CaptureOptions(order=order, step=step, family=family, phase=phase, retries=retries, board=board_size,
                             keep_failed=keep_failed, settle_s=(settle_ms if settle_ms is not None else (0.0 if virtual else 250.0)) / 1000.0)
    rig = Devices(camera=camera, proj_size=size, display=display, virtual=virtual, cam_size=cam_size,
              exposure_ms=exposure, gain=gain, timeout_s=timeout, seed=seed)
    with text_on_stderr(json_lines), _Printer() as printer:     # --json: stdout carries the advice only
        if rig_projectors:  # --rig: one rig pose, each projector's session in turn (procam.acquire.rig)
            return _rig.capture(out_dir, rig_projectors, rig, options, board=brd, hooks=printer)
        capture_session(out_dir, poses, rig, options, board=brd, live=live, hooks=printer)


def _refuse_unused(camera: str, virtual: bool, rig: bool) -> str:
    """Refuse the device options the devices of this capture would ignore: the simulator (``--virtual``, ``--camera
    virtual``) has no exposure, file timeout or (but for a virtual rig's camera) resolution, a virtual projector no
    display, a real camera no seed (:func:`refuse_unread_camera`: the real cameras' own); returns the camera's kind."""
    from ..acquire.cameras import parse_camera_spec

    kind, _ = parse_camera_spec(camera)
    if kind == "virtual":
        refuse(("exposure",) if rig else ("camera_size", "exposure"), SIMULATED_CAMERA)
    if kind != "folder":
        refuse(("timeout",), "is how long a folder camera (--camera folder:PATH) waits for each file")
    if kind != "virtual":
        refuse(("seed",), seed_applies("--virtual or --camera virtual"))
    if virtual:
        refuse(("display",), SIMULATED_PROJECTOR)
    return refuse_unread_camera(camera)


def _live_advice(advise, auto, json_lines, calibration, square, target, max_frames, board, virtual):
    """The advising session of ``--advise`` (None without it), every option checked before a device opens."""
    if not advise:
        for flag in given("auto", "json_lines", "calibration", "max_frames", "target"):
            fail(f"{flag} belongs to --advise; add --advise")
        return None
    from ..acquire.live import advisor_options, calibration_square, load_calibration_for
    from ._live import live_advice

    if not board:
        fail("--advise needs --board COLSxROWS (the advisor finds and measures the board)")
    options = advisor_options(target, 0.5, 1.0)
    calib = None
    if calibration is not None and square is None:
        square = calibration_square(calibration)
    b = parse_board(board, 1.0 if square is None else square)
    source = ""
    if calibration is not None:
        calib, source = load_calibration_for(calibration, b)
    return live_advice(b, options, calibration=calib, source=source, json_lines=json_lines, auto=auto,
                       max_frames=max_frames if max_frames is not None else (30 if virtual else None))


def _describe_projector(proj) -> str:
    d = proj.describe()
    w, h = d["size"]
    if d["backend"] == "virtual":
        return f"virtual {w}x{h}"
    disp = d.get("display", {})
    return f"full-screen window {w}x{h} on display {disp.get('index')} at ({disp.get('x')}, {disp.get('y')})"


def _print_camera(cam) -> None:
    from rich.markup import escape

    d = cam.describe()
    size = d.get("size")
    console.print(plain(f"camera: {cam.name} ({d.get('api', d['backend'])}" + (f", {size[0]}x{size[1]}" if size else "")
                        + ")"))
    for note in d.get("notes", []):
        console.print(f"[yellow]note:[/yellow] {escape(str(note))}", highlight=False)


class _spinner:
    """A transient status line while something slow runs (nothing when not a terminal)."""

    def __init__(self, text):
        self.text = text
        self._status = None

    def __enter__(self):
        if is_tty():
            self._status = err_console.status(self.text)
            self._status.__enter__()
        return self

    def __exit__(self, *exc):
        if self._status is not None:
            self._status.__exit__(*exc)
        return False


class _Printer:
    """Prints a capture session (:class:`procam.acquire.orchestrate.Hooks`): the devices, each pose's pre-flight
    verdict, re-grabs and a progress bar, the files written, the instant verdict; prompts between poses."""

    def __init__(self):
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

        self.bar = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                            console=console.real, transient=True, disable=not is_tty())
        self.tasks = {}

    def __enter__(self):
        self.bar.__enter__()
        return self

    def __exit__(self, *exc):
        self.bar.__exit__(*exc)
        return False

    def projector(self, proj):
        console.print(plain(f"projector: {_describe_projector(proj)}"))

    def camera(self, cam):
        _print_camera(cam)

    def busy(self, text):
        return _spinner(text)

    def pose(self, i, poses, kind):
        if poses > 1:
            console.print(f"[bold]pose {i + 1}/{poses}[/bold]", highlight=False)
        if kind == "folder":
            console.print("take one shot per pattern with the camera's software; procam waits for each new file",
                          highlight=False)

    def place_board(self, i):
        typer.prompt(f"place the board for pose {i + 1} in the projector's light, then press Enter",
                     default="", show_default=False, prompt_suffix=" ", err=True)

    def captured(self, result):
        """Report a captured pose's files."""
        t = result.record["timings"]
        console.print(plain(f"wrote {len(result.files)} frames, patterns.json and capture.json to {result.folder} "
                            f"({result.retries} re-grabs, {t['total_s']:.1f} s)"))

    def verdict(self, result, check, png):
        from ._show import print_pose_check

        print_pose_check(check, png)

    def verdict_failed(self, result, error):
        from rich.markup import escape

        console.print(f"[yellow]check:[/yellow] {escape(str(error))}", highlight=False)

    def progress(self, i, e):
        from rich.markup import escape

        if e.kind == "preflight":
            d = e.data
            if d.get("ok"):
                console.print(f"pre-flight: white {d['white_level']:.0%} of full scale on the {d['region']} "
                              f"({d['white_saturated']:.1%} saturated), black {d['dark_level']:.0%}, "
                              f"contrast {d['contrast']:.0%}", highlight=False)
                for line in d.get("suggestions", []):
                    console.print(f"[yellow]advice:[/yellow] {escape(str(line))}", highlight=False)
            if i not in self.tasks:
                self.tasks[i] = self.bar.add_task(f"pose {i + 1}", total=e.total)
        elif e.kind == "frame":
            if i in self.tasks:
                self.bar.update(self.tasks[i], completed=e.index + 1)
        elif e.kind == "retry":
            console.print(f"[yellow]re-grab:[/yellow] {escape(e.message)}", highlight=False)
        elif e.kind == "postflight" and e.message:
            console.print(f"[yellow]post-flight:[/yellow] {escape(e.message)}", highlight=False)
