"""``procam advise``: live advice on the board's pose before a capture (preview window or JSON lines).

Importing this module registers the command on :data:`procam.cli._app.app`.  The advising session is
:class:`procam.acquire.live.LiveAdvice` (``procam capture --advise`` runs it before each pose too).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Optional

import typer

from ._app import BoardOpt, app, fail, parse_board, parse_size, say, text_on_stderr, user_errors
from ._live import live_advice


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


@app.command("advise")
@user_errors
def advise_cmd(
    board: BoardOpt,
    square: Optional[float] = typer.Option(None, "--square", help="Square size, the length unit of the advice's "
                                           "distances (default: the calibration's, else 1: lengths in squares)."),
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
    from ..acquire.live import advisor_options, calibration_square, load_calibration_for

    if calibration is not None and square is None:
        square = calibration_square(calibration)
    b = parse_board(board, 1.0 if square is None else square)
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
        from ..acquire.cameras import VirtualLiveCamera

        scene = simulate.preset("ideal")
        if (b.cols, b.rows, b.square) != (scene.board_cols, scene.board_rows, scene.square):
            scene = scene.replace(board_cols=b.cols, board_rows=b.rows, square=b.square)
        scene = simulate.with_board_pose(scene, pose or simulate.RECOMMENDED_POSE)
        cam = VirtualLiveCamera(scene, seed=seed)
    else:
        cam = cams.open_camera(camera, size=cam_size, exposure_ms=exposure, gain=gain)
    session = live_advice(b, options, calibration=calib, source=source, json_lines=json_lines, auto=auto,
                          max_frames=max_frames)
    try:
        with cam, text_on_stderr(json_lines):
            res = session.run(cam)
    finally:
        session.close()
    a = res.advice
    if not json_lines:
        say(f"stopped ({res.reason}) after {res.frames} frames: {a.state}: {a.message}")
